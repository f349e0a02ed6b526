//! Query preparation (Huang et al. 2015, Sec. 5.2): a mocap clip as
//! canonical poses at the database frame rate, on the character's bones.
//!
//! The clip is read (BVH or ASF/AMC, any detected rig convention or a given
//! rig map), converted to metres and Y-up, resampled to the database's
//! frame rate and reduced to the 19 canonical joints, with the clip's
//! neutral reference pose. It is then retargeted to the character
//! ([`crate::pose::retarget`]): the torso turns by the clip's rotations since
//! that reference (the character keeps its captured attitude), the limbs
//! take the clip's bone directions, every bone the character's length, and
//! the root follows the clip's pelvis scaled by the ratio of leg lengths.
//! The result keeps the clip's global root trajectory (it places the
//! output); pose comparison aligns translation and heading per pair
//! (Eq. 28).

use crate::db::Character;
use crate::mocap::MocapError;
use crate::pose::Pose;
use crate::pose::retarget::{
    ClipNeutral, ClipPoses, character_neutral, clip_poses, retarget, retarget_with_neutral,
};
use crate::rig::{LoadOptions, load_clip};
use crate::rig::{RigError, detect_clip};
use std::path::{Path, PathBuf};

/// Errors of query preparation.
#[derive(Debug, thiserror::Error)]
pub enum QueryError {
    /// The clip could not be read.
    #[error(transparent)]
    Mocap(#[from] MocapError),
    /// The clip at the requested rate would not fit in memory.
    #[error("{path}: {source}")]
    Budget {
        /// The clip.
        path: PathBuf,
        /// The estimate.
        source: crate::util::budget::OverBudget,
    },
    /// The clip's rig could not be mapped to the canonical joints.
    #[error("{path}: {msg}")]
    Rig {
        /// The clip.
        path: PathBuf,
        /// What is missing.
        msg: String,
    },
}

/// A clip as canonical poses.
#[derive(Debug, Clone)]
pub struct ClipQuery {
    /// The clip's own joints (metres, Y-up), one pose per frame.
    pub poses: Vec<Pose>,
    /// The clip's neutral reference pose (metres, Y-up).
    pub reference: ClipNeutral,
    /// Frames per second (the requested rate).
    pub fps: f64,
    /// The rig convention used.
    pub convention: String,
    /// The source's frame rate.
    pub source_fps: f64,
}

/// The old name of [`ClipQuery`] (before session 40: "clip" names
/// skeletal input, "motion" a mesh's; issue 40).
#[deprecated(note = "renamed ClipQuery (old name MocapPoses)")]
pub type MocapPoses = ClipQuery; // old name

/// Reads a clip and turns it into canonical poses at `fps`.
pub fn load_mocap(path: &Path, opts: &LoadOptions, fps: f64) -> Result<ClipQuery, QueryError> {
    let mut clip = load_clip(path, opts)?;
    let source_fps = clip.fps();
    clip.to_metres_y_up();
    // Checked before allocating: a rate typo or a very long clip asks for
    // millions of frames (issue 18, item 12).
    let clip = clip
        .try_resampled(fps)
        .map_err(|source| QueryError::Budget {
            path: path.to_path_buf(),
            source,
        })?;
    let map = match &opts.rig_map {
        Some(m) => m.clone(),
        None => {
            detect_clip(&clip)
                .map_err(|e| QueryError::Rig {
                    path: path.to_path_buf(),
                    msg: format!("{e}; pass a rig map (see `mocap rigmap`)"),
                })?
                .map
        }
    };
    let ClipPoses { poses, reference } =
        clip_poses(&clip, &map).map_err(|e: RigError| QueryError::Rig {
            path: path.to_path_buf(),
            msg: e.to_string(),
        })?;
    Ok(ClipQuery {
        poses,
        reference,
        fps,
        convention: map.convention.clone(),
        source_fps,
    })
}

/// The clip's poses on the character's skeleton `rest` (see
/// [`crate::pose::retarget`]).
pub fn to_character(rest: &Pose, reference: &ClipNeutral, mocap: &[Pose]) -> Vec<Pose> {
    retarget(rest, reference, mocap)
        .into_iter()
        .map(|(p, _)| p)
        .collect()
}

/// How far above its rest frame a database character's frames stand
/// (metres): the median over its frames of the lowest vertex's height (the
/// floor the plausibility checks measure from,
/// [`crate::tools::eval::floor_height`]) minus the rest frame's lowest vertex
/// height. The retargeting stands the character's soles where they are at
/// rest; a database whose frames stand higher (a rest mesh scanned or
/// posed apart from the capture) would otherwise see every result sunk
/// into its floor by that much, and a swing foot passing low read as a
/// foot gliding on it. On the databases of the README it is small: 0.18 cm
/// on samba (its rest mesh is its frame 0), 0.11 cm on a `synth` database
/// of CMU 02_01, 02_03 and Bandai walk_normal (the kernel stands `synth`'s
/// walks on the rest frame's floor). The 1.27 cm once measured on the
/// synthetic database `synth3` was that database's age, not a floor: it
/// was made before the clip's ground was levelled
/// ([`crate::pose::retarget::ground_tilt`]) and the feet turned by the
/// clip's rotation, its 02_01 climbing CMU subject 02's sloping floor on
/// tipped feet; results on it floated 1.0 cm (median) with the lift and
/// sank 0.2-0.9 cm (penetration median) without it.
pub fn database_floor_lift(ch: &Character) -> f64 {
    database_floor_lift_on(ch, &ch.topology_metres())
}

/// [`database_floor_lift`] given the character's topology in metres
/// (`topology`, [`Character::topology_metres`]; a prepared character holds
/// it).
pub(crate) fn database_floor_lift_on(ch: &Character, topology: &crate::mesh::Mesh) -> f64 {
    let lowest = |f: &[[f64; 3]]| f.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    // Each frame's lowest point, kept with the frame cache: no scan of
    // every frame (the frames are memory-mapped, issue 43).
    let mut lows: Vec<f64> = crate::graph::FlatFrame::all(ch.frame_count())
        .map(|id| ch.lowest(id))
        .filter(|h| h.is_finite())
        .collect();
    let rest = lowest(topology.positions());
    if lows.is_empty() || !rest.is_finite() {
        return 0.0;
    }
    lows.sort_by(f64::total_cmp);
    lows[lows.len() / 2] - rest
}

/// The clip's poses on a loaded database character (measured from its
/// neutral pose, [`character_neutral`] of its rest frame's joints and frame
/// skeletons), raised by
/// [`database_floor_lift`]: the character stands on the floor its own
/// frames stand on. What `retarget` queries the database with and what
/// its joint-velocity error is measured against.
/// A prepared character ([`super::Prepared::analyse`]) holds the neutral
/// pose and the lift instead of finding them per call.
pub fn to_database(ch: &Character, reference: &ClipNeutral, mocap: &[Pose]) -> Vec<Pose> {
    let neutral = character_neutral(ch.rest_pose(), ch.poses());
    on_character(
        ch.rest_pose(),
        &neutral.pose,
        database_floor_lift(ch),
        reference,
        mocap,
    )
}

/// The clip's poses on the character's skeleton `rest` measured from its
/// neutral pose `neutral` ([`retarget_with_neutral`]), raised by `lift`
/// metres: [`to_database`] with the character's neutral pose and floor
/// lift given.
pub fn on_character(
    rest: &Pose,
    neutral: &Pose,
    lift: f64,
    reference: &ClipNeutral,
    mocap: &[Pose],
) -> Vec<Pose> {
    let lift = glam::DVec3::new(0.0, lift, 0.0);
    retarget_with_neutral(rest, neutral, reference, mocap)
        .into_iter()
        .map(|(p, _)| p.map(|q| q + lift))
        .collect()
}
