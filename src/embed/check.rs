//! A self-check of an embedding: what a rigger looks at before using one.
//! Left and right limbs symmetric (bone lengths, and joint distances from
//! the body's mid-plane), the pelvis on the mid-plane, every joint inside
//! the body (generalised winding number, [`super::surface`]), every part
//! non-empty and one connected region. Each problem is a [`Warning`]
//! naming the joint (or part) and the distance, in the mesh's units and as
//! a percentage of the height.
//!
//! The mid-plane here is estimated afresh from the joints the pelvis and
//! hips do not depend on (spine, chest, neck, head, and the midpoints of
//! the knees, ankles and shoulders: their median offset along the
//! embedding's left), so a pelvis placed off the middle is caught rather
//! than taken as the middle.

use super::Embedding;
use super::midplane::MidPlane;
use super::parts::{Part, neighbours, piece_counts};
use super::surface::{distance_to_surface, winding_number};
use crate::mesh::Mesh;
use crate::rig::Canonical;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Tolerances of the self-check, as fractions of the body height (bone
/// lengths: of the longer bone).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CheckOptions {
    /// The pelvis's distance from the mid-plane. Default value: 0.01.
    pub pelvis_offset: f64,
    /// Difference of the two hips' distances from the mid-plane. Default
    /// value: 0.01.
    pub hip_symmetry: f64,
    /// Difference of left and right limb joints' distances from the
    /// mid-plane (shoulders, elbows, wrists, knees, ankles, toes). Default
    /// value: 0.03.
    pub limb_symmetry: f64,
    /// Distance of spine, chest, neck and head from the mid-plane. Default
    /// value: 0.03.
    pub central_offset: f64,
    /// Relative difference of a left bone's length and its right twin's.
    /// Default value: 0.05.
    pub bone_ratio: f64,
    /// Least distance across between a left joint and its right twin.
    /// Default value: 0.02.
    pub twin_separation: f64,
}

impl Default for CheckOptions {
    fn default() -> Self {
        CheckOptions {
            pelvis_offset: 0.01,
            hip_symmetry: 0.01,
            limb_symmetry: 0.03,
            central_offset: 0.03,
            bone_ratio: 0.05,
            twin_separation: 0.02,
        }
    }
}

/// What kind of problem a warning reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Problem {
    /// A central joint (pelvis, spine, chest, neck, head) off the mid-plane.
    OffMidPlane,
    /// A left joint and its right twin at different distances from the
    /// mid-plane.
    Asymmetric,
    /// A left joint and its right twin (nearly) at one place across: both
    /// limbs' joints put in the middle of the two.
    Merged,
    /// A left bone and its right twin of different lengths.
    BoneLengths,
    /// A joint outside the body.
    Outside,
    /// A part with no vertex.
    EmptyPart,
    /// A part in several pieces.
    SplitPart,
    /// The embedding was made for another mesh.
    Mismatch,
}

/// One problem of an embedding.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Warning {
    /// What kind.
    pub problem: Problem,
    /// The joint (for symmetry problems the left one of the pair) or part.
    pub joint: String,
    /// How far off, in the mesh's units (0 for part problems).
    pub distance: f64,
    /// `distance` as a percentage of the height.
    pub percent_of_height: f64,
    /// The whole message.
    pub message: String,
}

/// A left bone and its right twin.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BonePair {
    /// The left bone's child joint (e.g. `l_knee` for the left thigh).
    pub joint: String,
    /// Left length.
    pub left: f64,
    /// Right length.
    pub right: f64,
    /// `|left − right| / max(left, right)`.
    pub ratio: f64,
}

/// A part's size and connectedness.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PartCheck {
    /// The part.
    pub part: String,
    /// Labelled vertices.
    pub vertices: usize,
    /// Connected pieces (1 is right).
    pub pieces: usize,
}

/// The self-check of an embedding.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EmbedCheck {
    /// The body height the percentages are of.
    pub height: f64,
    /// The mid-plane the symmetry is measured about.
    pub mid_plane: MidPlane,
    /// Signed distance of the pelvis from the mid-plane (positive: left).
    pub pelvis_offset: f64,
    /// The same as a percentage of the height.
    pub pelvis_offset_percent: f64,
    /// Distances of the left and right hips from the mid-plane (each
    /// positive on its own side).
    pub hip_distances: [f64; 2],
    /// `|d_left − d_right|` of the hips as a percentage of the height.
    pub hip_asymmetry_percent: f64,
    /// Left/right bone pairs.
    pub bones: Vec<BonePair>,
    /// Joints found outside the body.
    pub outside: Vec<String>,
    /// Every part's size and pieces.
    pub parts: Vec<PartCheck>,
    /// The tolerances used.
    pub options: CheckOptions,
    /// Every problem found; empty when the embedding passes.
    pub warnings: Vec<Warning>,
}

impl EmbedCheck {
    /// Whether no problem was found.
    pub fn passed(&self) -> bool {
        self.warnings.is_empty()
    }
}

/// The mirror twin of each left joint.
const PAIRS: [(Canonical, Canonical); 7] = [
    (Canonical::LShoulder, Canonical::RShoulder),
    (Canonical::LElbow, Canonical::RElbow),
    (Canonical::LWrist, Canonical::RWrist),
    (Canonical::LHip, Canonical::RHip),
    (Canonical::LKnee, Canonical::RKnee),
    (Canonical::LAnkle, Canonical::RAnkle),
    (Canonical::LToe, Canonical::RToe),
];

/// [`check_with`] at the default tolerances.
pub fn check(e: &Embedding, mesh: &Mesh) -> EmbedCheck {
    check_with(e, mesh, &CheckOptions::default())
}

/// The self-check of embedding `e` of `mesh` at tolerances `o`.
/// O(#joints · #F) for the inside test, O(#V) for the parts.
pub fn check_with(e: &Embedding, mesh: &Mesh, o: &CheckOptions) -> EmbedCheck {
    use Canonical as C;
    let h = e.height.max(1e-12);
    let pct = |d: f64| 100.0 * d / h;
    let j = |c: C| DVec3::from_array(e.joints[c.index()]);
    let left = DVec3::from_array(e.left).normalize_or(DVec3::X);
    let mid = |a: C, b: C| (j(a) + j(b)) * 0.5;
    let plane = MidPlane::median_of(
        left,
        &[
            j(C::Spine),
            j(C::Chest),
            j(C::Neck),
            j(C::Head),
            mid(C::LKnee, C::RKnee),
            mid(C::LAnkle, C::RAnkle),
            mid(C::LShoulder, C::RShoulder),
        ],
    );
    let mut warnings = Vec::new();
    let mut warn = |problem: Problem, joint: &str, distance: f64, message: String| {
        tracing::warn!(target: crate::util::fsutil::WARNING, joint, "{message}");
        warnings.push(Warning {
            problem,
            joint: joint.to_string(),
            distance,
            percent_of_height: pct(distance),
            message,
        });
    };

    // Central joints on the mid-plane.
    let pelvis_offset = plane.distance(j(C::Pelvis));
    for (c, tol) in [
        (C::Pelvis, o.pelvis_offset),
        (C::Spine, o.central_offset),
        (C::Chest, o.central_offset),
        (C::Neck, o.central_offset),
        (C::Head, o.central_offset),
    ] {
        let d = plane.distance(j(c)).abs();
        if d > tol * h {
            warn(
                Problem::OffMidPlane,
                c.name(),
                d,
                format!(
                    "{} is {d:.4} ({:.2}% of the height) off the body's mid-plane (tolerance {:.1}%)",
                    c.name(),
                    pct(d),
                    100.0 * tol
                ),
            );
        }
    }
    // Twins at the same distance from the mid-plane.
    let mut hip_distances = [0.0; 2];
    for (l, r) in PAIRS {
        let (dl, dr) = (plane.distance(j(l)), -plane.distance(j(r)));
        if l == C::LHip {
            hip_distances = [dl, dr];
        }
        let tol = if l == C::LHip {
            o.hip_symmetry
        } else {
            o.limb_symmetry
        };
        if dl + dr < o.twin_separation * h {
            warn(
                Problem::Merged,
                l.name(),
                dl + dr,
                format!(
                    "{} and {} are only {:.4} apart across the body ({:.2}% of the height; at least {:.0}% expected): both placed between the two limbs?",
                    l.name(),
                    r.name(),
                    dl + dr,
                    pct(dl + dr),
                    100.0 * o.twin_separation
                ),
            );
        }
        let d = (dl - dr).abs();
        if d > tol * h {
            warn(
                Problem::Asymmetric,
                l.name(),
                d,
                format!(
                    "{} and {} are {dl:.4} and {dr:.4} from the mid-plane: {d:.4} apart ({:.2}% of the height; tolerance {:.1}%)",
                    l.name(),
                    r.name(),
                    pct(d),
                    100.0 * tol
                ),
            );
        }
    }
    // Twin bones of one length.
    let mut bones = Vec::new();
    for (l, r) in PAIRS {
        let (Some(pl), Some(pr)) = (l.parent(), r.parent()) else {
            continue;
        };
        let (a, b) = (j(l).distance(j(pl)), j(r).distance(j(pr)));
        let ratio = (a - b).abs() / a.max(b).max(1e-12);
        if ratio > o.bone_ratio {
            warn(
                Problem::BoneLengths,
                l.name(),
                (a - b).abs(),
                format!(
                    "the bones to {} and {} are {a:.4} and {b:.4} long ({:.1}% apart; tolerance {:.0}%)",
                    l.name(),
                    r.name(),
                    100.0 * ratio,
                    100.0 * o.bone_ratio
                ),
            );
        }
        bones.push(BonePair {
            joint: l.name().to_string(),
            left: a,
            right: b,
            ratio,
        });
    }
    // Joints inside the body.
    let (p, t) = (mesh.positions(), mesh.triangles());
    let mut outside = Vec::new();
    for c in Canonical::ALL {
        if winding_number(p, t, j(c)).abs() > 0.5 {
            continue;
        }
        let d = distance_to_surface(p, t, j(c));
        outside.push(c.name().to_string());
        warn(
            Problem::Outside,
            c.name(),
            d,
            format!(
                "{} is outside the body, {d:.4} from its surface ({:.2}% of the height)",
                c.name(),
                pct(d)
            ),
        );
    }
    // Parts: non-empty, one piece.
    let mut parts = Vec::new();
    if e.labels.len() == p.len() {
        let pieces = piece_counts(&e.labels, &neighbours(p.len(), t));
        let mut sizes = [0usize; Part::COUNT];
        for &l in &e.labels {
            if let Some(s) = sizes.get_mut(l as usize) {
                *s += 1;
            }
        }
        for part in Part::ALL {
            let (n, k) = (sizes[part.index()], pieces[part.index()]);
            if n == 0 {
                warn(
                    Problem::EmptyPart,
                    part.name(),
                    0.0,
                    format!("part {} has no vertex", part.name()),
                );
            } else if k != 1 {
                warn(
                    Problem::SplitPart,
                    part.name(),
                    0.0,
                    format!("part {} is in {k} pieces", part.name()),
                );
            }
            parts.push(PartCheck {
                part: part.name().to_string(),
                vertices: n,
                pieces: k,
            });
        }
    } else {
        warn(
            Problem::Mismatch,
            "",
            0.0,
            format!(
                "the embedding labels {} vertices, the mesh has {}",
                e.labels.len(),
                p.len()
            ),
        );
    }
    EmbedCheck {
        height: h,
        mid_plane: plane,
        pelvis_offset,
        pelvis_offset_percent: pct(pelvis_offset),
        hip_distances,
        hip_asymmetry_percent: pct((hip_distances[0] - hip_distances[1]).abs()),
        bones,
        outside,
        parts,
        options: *o,
        warnings,
    }
}
