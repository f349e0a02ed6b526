//! Key-frames given as skeleton poses (Huang et al. 2015, Sec. 5.1: "each
//! key-frame a database frame or a skeleton pose"): the pose is resolved
//! to the database frame nearest by the skeleton measure the database
//! already uses for retrieval, `c_skel` of Eq. 28
//! ([`crate::pose::measure::skeleton_distance`]: joints summed after the floor
//! alignment in position and heading).
//!
//! A pose is written `CLIP.bvh:F` or `CLIP.amc:F` (frame `F` of a mocap
//! clip, at the database's frame rate, retargeted onto the character's
//! skeleton as `retarget` does), or `POSE.json`: the 19 canonical joints
//! ([`Canonical::ALL`] order) as `[x, y, z]` in
//! metres, Y up, on the character's skeleton (e.g. one of its own frames).

use crate::db::Character;
use crate::drive::query::{load_mocap, to_character};
use crate::graph::FlatFrame;
use crate::pose::Pose;
use crate::pose::measure::skeleton_distance;
use crate::rig::Canonical;
use crate::rig::LoadOptions;
use glam::DVec3;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// A key-frame pose that could not be read.
#[derive(Debug, thiserror::Error)]
pub enum PoseError {
    /// The clip or pose file could not be read.
    #[error("key-frame '{key}': {msg}")]
    Read {
        /// As written.
        key: String,
        /// What went wrong.
        msg: String,
    },
    /// The frame is past the clip's end.
    #[error("key-frame '{key}': {path} has {len} frames at {fps} fps (0 to {})", .len.saturating_sub(1))]
    Frame {
        /// As written.
        key: String,
        /// The clip.
        path: PathBuf,
        /// Its frames at the database's rate.
        len: usize,
        /// The rate.
        fps: f64,
    },
}

/// The database frame a pose key-frame resolved to.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Resolved {
    /// As written.
    pub key: String,
    /// The database frame (`SEQUENCE:FRAME`).
    pub frame: String,
    /// Its flat id.
    #[serde(skip)]
    pub id: FlatFrame,
    /// `c_skel` between the pose and that frame (metres, summed over the
    /// 19 joints).
    pub distance: f64,
    /// The next nearest frame outside that frame's ±2 neighbours, and its
    /// distance (how distinct the match is).
    pub runner_up: Option<(String, f64)>,
}

/// Is `key` a pose (a mocap clip frame or a pose file) rather than
/// `SEQUENCE:FRAME`?
pub(crate) fn is_pose_key(key: &str) -> bool {
    let lower = key.to_ascii_lowercase();
    let clip = lower
        .rsplit_once(':')
        .is_some_and(|(p, _)| p.ends_with(".bvh") || p.ends_with(".amc"));
    clip || lower.ends_with(".json")
}

/// Reads the pose of a pose key (module docs) on the character's skeleton.
pub(crate) fn read_pose(ch: &Character, key: &str, load: &LoadOptions) -> Result<Pose, PoseError> {
    let err = |msg: String| PoseError::Read {
        key: key.into(),
        msg,
    };
    if key.to_ascii_lowercase().ends_with(".json") {
        return read_json(Path::new(key)).map_err(err);
    }
    let Some((path, f)) = key.rsplit_once(':') else {
        return Err(err(
            "expected CLIP.bvh:FRAME, CLIP.amc:FRAME or POSE.json".into()
        ));
    };
    let f: usize = f
        .trim()
        .parse()
        .map_err(|_| err(format!("'{f}' is not a frame number")))?;
    let fps = ch.manifest().fps;
    let m = load_mocap(Path::new(path), load, fps).map_err(|e| err(e.to_string()))?;
    if f >= m.poses.len() {
        return Err(PoseError::Frame {
            key: key.into(),
            path: path.into(),
            len: m.poses.len(),
            fps,
        });
    }
    let q = to_character(ch.rest_pose(), &m.reference, &m.poses[f..=f]);
    q.into_iter()
        .next()
        .ok_or_else(|| err("the clip gave no pose".into()))
}

fn read_json(p: &Path) -> Result<Pose, String> {
    let text = crate::util::fsutil::read_small_text(p).map_err(|e| e.to_string())?;
    let v: Vec<[f64; 3]> = serde_json::from_str(&text).map_err(|e| {
        format!(
            "{}: {e} (expected {} [x, y, z] joints, metres, Y up)",
            p.display(),
            Canonical::COUNT
        )
    })?;
    if v.len() != Canonical::COUNT || v.iter().flatten().any(|x| !x.is_finite()) {
        return Err(format!(
            "{}: {} joints, expected {} finite [x, y, z] in the order {}",
            p.display(),
            v.len(),
            Canonical::COUNT,
            Canonical::ALL.map(|j| j.name()).join(", ")
        ));
    }
    let mut pose = [DVec3::ZERO; Canonical::COUNT];
    for (p, x) in pose.iter_mut().zip(&v) {
        *p = DVec3::from_array(*x);
    }
    Ok(pose)
}

/// The database frame nearest `pose` by `c_skel` (Eq. 28), with the
/// runner-up outside its ±2 neighbours (see [`Resolved`]).
pub fn nearest_frame(ch: &Character, key: &str, pose: &Pose) -> Resolved {
    let d: Vec<f64> = ch
        .poses()
        .iter()
        .map(|p| skeleton_distance(pose, p))
        .collect();
    let best = (0..d.len())
        .min_by(|&a, &b| d[a].total_cmp(&d[b]))
        .unwrap_or(0);
    let best = FlatFrame::from_index(best);
    let (sb, fb) = ch.graph().frame_of(best);
    let runner = (0..d.len())
        .filter(|&i| {
            let (s, f) = ch.graph().frame_of(FlatFrame::from_index(i));
            s != sb || f.abs_diff(fb) > 2
        })
        .min_by(|&a, &b| d[a].total_cmp(&d[b]));
    Resolved {
        key: key.into(),
        frame: super::key_name(ch, best),
        id: best,
        distance: d.get(best.index()).copied().unwrap_or(f64::INFINITY),
        runner_up: runner.map(|i| (super::key_name(ch, FlatFrame::from_index(i)), d[i])),
    }
}

/// The facing of a pose about the vertical (radians,
/// [`crate::pose::measure::rotate_yaw`]'s sense): the direction of the hips'
/// left-to-right axis, so that differences of facings are rotations.
pub fn facing(p: &Pose) -> f64 {
    let h = p[Canonical::LHip.index()] - p[Canonical::RHip.index()];
    h.x.atan2(h.z)
}
