//! What the automatic rig found: the landmarks, the body's axes, the
//! joints and how they were found, the confidence and the notes.

use crate::embed::landmarks::{Landmarks, Mark};
use glam::DVec3;
use serde::Serialize;

/// A joint the automatic rig found.
#[derive(Debug, Clone, Serialize)]
pub struct FoundJoint {
    /// Landmark name (`l_knee`...; `l_hip`/`r_hip` for the hips, which are
    /// no landmarks but set the groin).
    pub name: String,
    /// Position on the topology mesh.
    pub position: [f64; 3],
    /// Found from the motion (else placed by proportion).
    pub by_motion: bool,
    /// How much it bends in the capture (degrees).
    pub articulation_deg: f64,
}

/// The automatic rig of a capture.
#[derive(Debug, Clone, Serialize)]
pub struct AutoRig {
    /// The landmarks: points on the topology mesh, or, when the parts were
    /// found on another rest frame, fixed to that frame's surface
    /// ([`Mark::Surface`]; where they were found on it, carried to any
    /// other frame with their triangle).
    #[serde(skip)]
    pub landmarks: Landmarks,
    /// Up, facing and left (unit, the files' coordinates).
    pub up: [f64; 3],
    /// Facing.
    pub facing: [f64; 3],
    /// The character's left.
    pub left: [f64; 3],
    /// Height along up of the rest frame.
    pub height: f64,
    /// The rest frame the parts were found in (`None`: the topology mesh).
    pub rest_frame: Option<usize>,
    /// Frames of the capture used.
    pub frames_used: usize,
    /// Rigid parts found.
    pub parts: usize,
    /// Rigid part of each vertex.
    #[serde(skip)]
    pub labels: Vec<u32>,
    /// Limb joints, by motion or by proportion.
    pub joints: Vec<FoundJoint>,
    /// 0-1: the share of the twelve limb joints the motion showed, times
    /// the left/right agreement of the limbs' lengths.
    pub confidence: f64,
    /// The body has no head ([`super::neck`]): its landmarks have no chin
    /// and no head top, and their file says `"absent": ["head"]`.
    pub headless: bool,
    /// How far below the body's top the trunk begins (a fraction of the
    /// height, [`super::neck::NeckReading::trunk_depth`]).
    pub trunk_depth: f64,
    /// What was found and assumed, one line each.
    pub notes: Vec<String>,
}

impl AutoRig {
    /// The landmarks as the JSON a landmarks file holds (points rounded to
    /// 10 µm, surface marks in full, with the mesh's vertex count; a
    /// headless body's `"absent": ["head"]`).
    pub fn landmarks_json(&self, vertex_count: usize) -> String {
        let r = |x: f64| (x * 1e5).round() / 1e5;
        let mut lines = vec![format!("  \"vertex_count\": {vertex_count}")];
        if self.headless {
            lines.push("  \"absent\": [\"head\"]".into());
        }
        for (l, mark) in &self.landmarks.marks {
            match mark {
                Mark::Point(p) => lines.push(format!(
                    "  \"{}\": [{}, {}, {}]",
                    l.name(),
                    r(p[0]),
                    r(p[1]),
                    r(p[2])
                )),
                Mark::Surface(a) => lines.push(format!("  \"{}\": {}", l.name(), a.to_json())),
                Mark::Vertex(v) => lines.push(format!("  \"{}\": {v}", l.name())),
            }
        }
        format!("{{\n{}\n}}\n", lines.join(",\n"))
    }

    /// One line for `db init`: the confidence and what was found.
    pub fn summary(&self) -> String {
        let by_motion = self.joints.iter().filter(|j| j.by_motion).count();
        let guessed: Vec<&str> = self
            .joints
            .iter()
            .filter(|j| !j.by_motion)
            .map(|j| j.name.as_str())
            .collect();
        format!(
            "automatic rig: confidence {:.2}; {} rigid parts in {} frames; {by_motion} of {} limb joints found by the motion{}; up {}, facing {}{}",
            self.confidence,
            self.parts,
            self.frames_used,
            self.joints.len(),
            if guessed.is_empty() {
                String::new()
            } else {
                format!(" (by proportion: {})", guessed.join(", "))
            },
            axis_name(DVec3::from_array(self.up)),
            axis_name(DVec3::from_array(self.facing)),
            if self.headless { "; no head" } else { "" },
        )
    }
}

/// "+Y", or the direction's coordinates when off the axes.
pub(crate) fn axis_name(v: DVec3) -> String {
    let a = crate::embed::axes::nearest_axis(v);
    if a.dot(v) > 0.95 {
        let k = if a.x != 0.0 {
            "X"
        } else if a.y != 0.0 {
            "Y"
        } else {
            "Z"
        };
        format!("{}{k}", if a.dot(DVec3::ONE) > 0.0 { "+" } else { "-" })
    } else {
        format!("({:.2}, {:.2}, {:.2})", v.x, v.y, v.z)
    }
}
