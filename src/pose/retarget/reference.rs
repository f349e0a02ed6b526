//! The clip's neutral reference pose (its rest skeleton when that stands
//! upright, else its most neutral frame) and the character's neutral pose:
//! what the kernel measures every rotation from.

use crate::mocap::Clip;
use crate::pose::Pose;
use crate::rig::{Canonical, RigError, RigMap};
use glam::{DQuat, DVec3};
use serde::Serialize;
use std::sync::Arc;

use Canonical as C;

/// Where a clip's neutral reference pose comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ClipNeutralSource {
    /// The clip's rest (bind) skeleton, which stands upright.
    Rest,
    /// The clip's most neutral frame (the rest skeleton was not upright).
    Frame(usize),
}

/// The old name of [`ClipNeutralSource`] (before session 40).
#[deprecated(note = "renamed ClipNeutralSource (old name ReferenceSource)")]
pub type ReferenceSource = ClipNeutralSource; // old name

impl std::fmt::Display for ClipNeutralSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ClipNeutralSource::Rest => write!(f, "rest skeleton"),
            ClipNeutralSource::Frame(i) => write!(f, "most neutral frame ({i})"),
        }
    }
}

/// A clip's neutral reference pose.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipNeutral {
    /// Canonical joint positions (the clip's units and axes).
    pub pose: Pose,
    /// Where it came from.
    pub source: ClipNeutralSource,
    /// The clip's own joint rotations per frame ([`JointRotations`], one
    /// per pose the reference was chosen among, in the clip's axes; empty
    /// when not known). [`retarget`](super::retarget) turns the chest by them
    /// when it is given that many poses, those the reference came with:
    /// poses changed since (moved, turned, resampled) must take a reference
    /// without them ([`ClipNeutral::without_rotations`]).
    pub rotations: Arc<[JointRotations]>,
}

/// The old name of [`ClipNeutral`] (before session 40: "neutral" names a
/// skeleton's neutral pose, "rest" a mesh's rest frame; issue 40).
#[deprecated(note = "renamed ClipNeutral (old name Reference)")]
pub type Reference = ClipNeutral; // old name

impl ClipNeutral {
    /// The reference with no joint rotations: [`retarget`](super::retarget) turns the torso
    /// by the fit to the poses' bones alone.
    pub fn without_rotations(&self) -> ClipNeutral {
        ClipNeutral {
            rotations: Arc::from(Vec::new()),
            ..self.clone()
        }
    }
}

/// Per canonical joint, the world rotation of the clip's file joint mapped
/// to it (the rotation carrying that joint's own bones), `None` for a
/// joint the map derives; the clip's axes. See [`RigMap::poses_and_rotations`].
pub type JointRotations = [Option<DQuat>; Canonical::COUNT];

/// A clip as canonical poses with its neutral reference.
#[derive(Debug, Clone)]
pub struct ClipPoses {
    /// One pose per frame (the clip's units and axes).
    pub poses: Vec<Pose>,
    /// The neutral reference the retargeting measures rotations from
    /// (with the file joints' rotations of every frame).
    pub reference: ClipNeutral,
}

/// Canonical poses of every frame of `clip` and its neutral reference.
/// Convert the clip to metres, Y-up, first (`Clip::to_metres_y_up`): the
/// reference is chosen against the vertical.
pub fn clip_poses(clip: &Clip, map: &RigMap) -> Result<ClipPoses, RigError> {
    let (poses, rotations) = map.poses_and_rotations(clip)?;
    let rest = map.rest_pose(clip)?;
    let mut reference = choose_reference(Some(&rest), &poses)?;
    reference.rotations = Arc::from(rotations);
    Ok(ClipPoses { poses, reference })
}

/// Mean length of the two legs (hip to knee to ankle).
pub fn leg_length(p: &Pose) -> f64 {
    let d = |a: C, b: C| p[a.index()].distance(p[b.index()]);
    0.5 * (d(C::LHip, C::LKnee)
        + d(C::LKnee, C::LAnkle)
        + d(C::RHip, C::RKnee)
        + d(C::RKnee, C::RAnkle))
}

pub(super) fn angle(a: DVec3, b: DVec3) -> f64 {
    let (a, b) = (a.normalize_or_zero(), b.normalize_or_zero());
    if a == DVec3::ZERO || b == DVec3::ZERO {
        return std::f64::consts::PI;
    }
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// Trunk tilt from the vertical (pelvis → neck), radians.
pub(super) fn trunk_tilt(p: &Pose) -> f64 {
    angle(p[C::Neck.index()] - p[C::Pelvis.index()], DVec3::Y)
}

/// Knee bend of one leg (0 = straight), radians.
pub(super) fn knee_bend(p: &Pose, hip: C, knee: C, ankle: C) -> f64 {
    let (h, k, a) = (p[hip.index()], p[knee.index()], p[ankle.index()]);
    angle(k - h, a - k)
}

/// How far `p` is from standing neutrally: trunk tilt plus the mean knee
/// bend (radians).
pub(super) fn neutrality(p: &Pose) -> f64 {
    trunk_tilt(p)
        + 0.5
            * (knee_bend(p, C::LHip, C::LKnee, C::LAnkle)
                + knee_bend(p, C::RHip, C::RKnee, C::RAnkle))
}

/// Canonical bones (child, parent) of the torso and legs, whose lengths the
/// rest skeleton must share with the motion to stand in for it.
pub(super) fn bone_lengths(p: &Pose) -> impl Iterator<Item = f64> + '_ {
    Canonical::ALL
        .iter()
        .filter_map(move |c| c.parent().map(|q| p[c.index()].distance(p[q.index()])))
}

/// Whether the rest skeleton stands upright (a T- or A-pose) with the
/// motion's bone lengths.
pub(super) fn rest_is_neutral(rest: &Pose, poses: &[Pose]) -> bool {
    let leg_ok = |hip: C, ankle: C| {
        angle(rest[ankle.index()] - rest[hip.index()], -DVec3::Y) < 30f64.to_radians()
    };
    if trunk_tilt(rest) >= 20f64.to_radians()
        || !leg_ok(C::LHip, C::LAnkle)
        || !leg_ok(C::RHip, C::RAnkle)
    {
        return false;
    }
    // Bone lengths as in the motion (a file whose position channels replace
    // the offsets has a rest skeleton of other proportions).
    let Some(mid) = poses.get(poses.len() / 2) else {
        return true;
    };
    let scale = leg_length(rest).max(1e-12);
    bone_lengths(rest)
        .zip(bone_lengths(mid))
        .all(|(a, b)| (a - b).abs() <= 0.1 * b.max(a) + 0.02 * scale)
}

/// Chooses the clip's neutral reference: its rest skeleton when given and
/// upright with the motion's proportions, else its most neutral frame.
/// Refuses a degenerate skeleton (legs or trunk of no length, non-finite
/// joints), which could only retarget to garbage.
pub fn choose_reference(rest: Option<&Pose>, poses: &[Pose]) -> Result<ClipNeutral, RigError> {
    let Some(first) = poses.first() else {
        return Err(RigError::Degenerate {
            reason: "the clip has no frames".into(),
        });
    };
    if let Some(r) = rest
        && r.iter().all(|p| p.is_finite())
        && leg_length(r) > 0.0
        && rest_is_neutral(r, poses)
    {
        return Ok(ClipNeutral {
            pose: *r,
            source: ClipNeutralSource::Rest,
            rotations: Arc::from(Vec::new()),
        });
    }
    let mut best: Option<(f64, usize)> = None;
    for (i, p) in poses.iter().enumerate() {
        if !p.iter().all(|x| x.is_finite()) {
            continue;
        }
        let s = neutrality(p);
        if best.is_none_or(|(b, _)| s < b) {
            best = Some((s, i));
        }
    }
    let (_, i) = best.ok_or_else(|| RigError::Degenerate {
        reason: "every frame has a non-finite joint".into(),
    })?;
    let pose = poses[i];
    let size = leg_length(&pose)
        .max(pose[C::Neck.index()].distance(pose[C::Pelvis.index()]))
        .max(leg_length(first));
    let trunk = pose[C::Neck.index()].distance(pose[C::Pelvis.index()]);
    if !(leg_length(&pose) > 1e-6 * size.max(1e-300) && trunk > 1e-6 * size.max(1e-300)) {
        return Err(RigError::Degenerate {
            reason: format!(
                "legs {:.3e} and trunk {:.3e} long at frame {i}: the skeleton has no extent",
                leg_length(&pose),
                trunk
            ),
        });
    }
    Ok(ClipNeutral {
        pose,
        source: ClipNeutralSource::Frame(i),
        rotations: Arc::from(Vec::new()),
    })
}

/// Where a character's neutral pose comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NeutralSource {
    /// Its rest frame (the mesh the rig was embedded on), which stands
    /// upright.
    Rest,
    /// The database frame nearest neutral (the rest frame did not stand
    /// upright).
    Frame(usize),
}

/// The character's neutral pose: what a clip standing neutrally gives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CharacterNeutral {
    /// Canonical joint positions (the character's rest frame's space).
    pub pose: Pose,
    /// Where it came from.
    pub source: NeutralSource,
}

/// How far a character's pose is from standing neutrally (radians): the
/// trunk's tilt from the vertical, plus the mean knee bend, plus the mean
/// angle of the thighs from the vertical (legs under the body, feet
/// together), plus half the neck's bend from the trunk's line. 0 for a
/// body standing straight with its legs under it and its head over its
/// trunk, whatever its arms do (the limbs take the clip's directions).
pub fn neutral_score(p: &Pose) -> f64 {
    let thigh = |hip: C, knee: C| angle(p[knee.index()] - p[hip.index()], -DVec3::Y);
    let neck = angle(
        p[C::Head.index()] - p[C::Neck.index()],
        p[C::Neck.index()] - p[C::Pelvis.index()],
    );
    neutrality(p) + 0.5 * (thigh(C::LHip, C::LKnee) + thigh(C::RHip, C::RKnee)) + 0.5 * neck
}

/// Chooses the character's neutral pose: its rest frame `rest` when that
/// stands upright (trunk within 20° of the vertical, each hip → ankle
/// within 30° of straight down), else the frame of `frames` (the
/// database's per-frame skeletons, the rest frame's space) with the least
/// [`neutral_score`]; the rest frame when no frame is finite.
pub fn character_neutral(rest: &Pose, frames: &[Pose]) -> CharacterNeutral {
    let leg_ok = |hip: C, ankle: C| {
        angle(rest[ankle.index()] - rest[hip.index()], -DVec3::Y) < 30f64.to_radians()
    };
    let upright = trunk_tilt(rest) < 20f64.to_radians()
        && leg_ok(C::LHip, C::LAnkle)
        && leg_ok(C::RHip, C::RAnkle);
    let as_rest = CharacterNeutral {
        pose: *rest,
        source: NeutralSource::Rest,
    };
    if upright {
        return as_rest;
    }
    frames
        .iter()
        .enumerate()
        .filter(|(_, p)| p.iter().all(|x| x.is_finite()))
        .map(|(i, p)| (neutral_score(p), i))
        .filter(|(s, _)| s.is_finite())
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map_or(as_rest, |(_, i)| CharacterNeutral {
            pose: frames[i],
            source: NeutralSource::Frame(i),
        })
}
