//! The torso's and neck's rotations since the clip's reference: the fit to
//! the bones, the chest from the clip's own file joint with its twist from
//! the shoulders, and the neck's typical carriage read on upright frames.

use super::reference::{ClipNeutral, ClipNeutralSource, JointRotations, angle};
use crate::pose::{Pose, pose_rotations};
use crate::rig::Canonical;
use glam::{DQuat, DVec3};
use rayon::prelude::*;

use Canonical as C;

/// The rotations of the clip's upright frames: those whose trunk (pelvis
/// → chest) is within 10° of the clip's most upright. The neck's carriage is read on them: a
/// clip that spends most of its time bent over, head down (CMU 131_02),
/// would otherwise make head-down its neutral, and its upright frames
/// would throw the character's head back.
pub(super) fn upright(
    mocap: &[Pose],
    rotations: &[[DQuat; Canonical::COUNT]],
) -> Vec<[DQuat; Canonical::COUNT]> {
    let mut out = Vec::new();
    upright_into(mocap, rotations, &mut Vec::new(), &mut out);
    out
}

/// [`upright`] into `out` (cleared), with `tilt` a buffer for the
/// frames' trunk angles: no allocation once both hold the clip's frames.
pub(super) fn upright_into(
    mocap: &[Pose],
    rotations: &[[DQuat; Canonical::COUNT]],
    tilt: &mut Vec<f64>,
    out: &mut Vec<[DQuat; Canonical::COUNT]>,
) {
    // The trunk as the pelvis → chest line: where the neck sits on the
    // chest (a conversion drops the thorax's length) must not choose them.
    tilt.clear();
    tilt.extend(
        mocap
            .iter()
            .map(|p| angle(p[C::Chest.index()] - p[C::Pelvis.index()], DVec3::Y)),
    );
    let least = tilt
        .iter()
        .copied()
        .filter(|t| t.is_finite())
        .fold(f64::INFINITY, f64::min);
    out.clear();
    out.reserve(rotations.len());
    out.extend(
        rotations
            .iter()
            .zip(tilt.iter())
            .filter(|&(_, &t)| t <= least + 10f64.to_radians())
            .map(|(a, _)| *a),
    );
}

/// The clip's typical carriage of the neck: the mean (sign-aligned,
/// normalised) over frames of the neck's rotation relative to the chest
/// since the reference, `A_chest⁻¹ A_neck`.
pub(super) fn neck_carriage(rotations: &[[DQuat; Canonical::COUNT]]) -> DQuat {
    let (chest, neck) = (C::Chest.index(), C::Neck.index());
    let mut sum = glam::DVec4::ZERO;
    let mut sign_ref: Option<glam::DVec4> = None;
    for a in rotations {
        let l = glam::DVec4::from(a[chest].inverse() * a[neck]);
        if !l.is_finite() {
            continue;
        }
        let f = *sign_ref.get_or_insert(l);
        sum += if l.dot(f) < 0.0 { -l } else { l };
    }
    let q = DQuat::from_vec4(sum);
    if q.length_squared() > 1e-24 {
        q.normalize()
    } else {
        DQuat::IDENTITY
    }
}

/// The clip's global joint rotations since its reference per pose of
/// `mocap` (the poses turned by `tilt`, `r` the reference's pose as the
/// kernel uses it): the fit to the bones ([`pose_rotations`]), with the
/// chest (and the spine and neck on it) from the clip's own
/// joint rotations when the reference carries one per pose
/// ([`ClipNeutral::rotations`], [`torso_from_file`]).
pub(super) fn clip_rotations(
    r: &Pose,
    mocap: &[Pose],
    reference: &ClipNeutral,
    tilt: DQuat,
) -> Vec<[DQuat; Canonical::COUNT]> {
    clip_rotations_from(r, mocap, reference, tilt, None)
}

/// [`clip_rotations`] with the file joints' rotations at the reference
/// given (`at`, levelled as the poses are: the mean carriage of
/// [`torso_from_motion`](super::motion_ref::torso_from_motion)) instead of
/// the reference's own (`None`).
pub(super) fn clip_rotations_from(
    r: &Pose,
    mocap: &[Pose],
    reference: &ClipNeutral,
    tilt: DQuat,
    at: Option<JointRotations>,
) -> Vec<[DQuat; Canonical::COUNT]> {
    let mut rotations = Vec::new();
    clip_rotations_into(r, mocap, reference, (tilt, at), &mut rotations);
    rotations
}

/// [`clip_rotations_from`] into `rotations` (cleared and refilled, each
/// frame's in parallel as before): no allocation once it holds the
/// clip's frames (issue 45).
pub(super) fn clip_rotations_into(
    r: &Pose,
    mocap: &[Pose],
    reference: &ClipNeutral,
    (tilt, at): (DQuat, Option<JointRotations>),
    rotations: &mut Vec<[DQuat; Canonical::COUNT]>,
) {
    rotations.clear();
    rotations.resize(mocap.len(), [DQuat::IDENTITY; Canonical::COUNT]);
    rotations
        .par_iter_mut()
        .zip(mocap.par_iter())
        .for_each(|(a, m)| *a = pose_rotations(r, m));
    let file = &reference.rotations;
    // The reference's own file rotations: the rest skeleton's are the
    // identity; a frame's, turned as the poses are.
    let at_ref: Option<JointRotations> = at.or_else(|| match reference.source {
        ClipNeutralSource::Rest => Some([Some(DQuat::IDENTITY); Canonical::COUNT]),
        ClipNeutralSource::Frame(i) => file.get(i).map(|w| w.map(|q| q.map(|q| tilt * q))),
    });
    if let Some(at_ref) = at_ref
        && file.len() == mocap.len()
    {
        rotations
            .par_iter_mut()
            .zip(mocap.par_iter().zip(file.par_iter()))
            .for_each(|(a, (m, w))| {
                torso_from_file(a, r, m, &w.map(|q| q.map(|q| tilt * q)), &at_ref)
            });
    }
}

/// Replaces the chest's rotation in `a` (the rotations taking the
/// reference `r`'s bones onto `m`'s) by its file joint's rotation since
/// the reference (`w · w_ref⁻¹`, when both are known) with its twist about
/// the spine taken from the shoulders ([`shoulder_twist`]), and re-derives the
/// single-child spine and neck (the least rotation of their bone,
/// composed on the parent's, as [`pose_rotations`] does). The pelvis keeps
/// the fit to its hips and spine bones (see [`retarget_with_neutral`](super::retarget_with_neutral)).
pub(super) fn torso_from_file(
    a: &mut [DQuat; Canonical::COUNT],
    r: &Pose,
    m: &Pose,
    w: &JointRotations,
    w_ref: &JointRotations,
) {
    for c in [C::Pelvis, C::Spine, C::Chest, C::Neck] {
        let j = c.index();
        if c == C::Pelvis {
            continue;
        }
        if c == C::Chest {
            if let (Some(q), Some(q0)) = (w[j], w_ref[j])
                && (q * q0.inverse()).is_finite()
            {
                a[j] = shoulder_twist((q * q0.inverse()).normalize(), r, m);
            }
            continue;
        }
        let pr = c.parent().map_or(DQuat::IDENTITY, |p| a[p.index()]);
        let k = if c == C::Spine { C::Chest } else { C::Head }.index();
        let from = (pr * (r[k] - r[j])).normalize_or_zero();
        let to = (m[k] - m[j]).normalize_or_zero();
        a[j] = if from == DVec3::ZERO || to == DVec3::ZERO {
            pr
        } else {
            (DQuat::from_rotation_arc(from, to) * pr).normalize()
        };
    }
}

/// The chest's file rotation `f` (since the reference `r`) turned about
/// the chest's own axis (the reference's spine → chest bone, carried by
/// `f`) so that it carries the reference's shoulder line
/// (right → left shoulder) onto `m`'s, seen along that axis: the swing
/// from the file, the twist from the shoulders.
///
/// A file joint's rotation states the chest's twist only when whatever
/// wrote the file knew it. `db skeleton`'s BVH turns `Spine1` by the
/// fitted chest → neck bone alone (the shoulders hang from zero-offset
/// clavicles of their own), a lone bone whose twist no joint observes;
/// on the samba dancer's own skeleton it sat 20° (mean over the frames)
/// off the chest's fit to its neck and shoulders, all of it about the
/// spine, and the self-transfer's vertex error rose from 3.55 to 3.81 %
/// of the height (20 markers). The shoulder line is the same whichever
/// joint carries the neck and clavicles and wherever they sit on the
/// chest (an AMC clip and its cgspeed BVH conversion, which drops the
/// thorax's length), so the two still drive the character alike.
/// `f` unchanged when the axis or either shoulder line (seen along it) has
/// no length.
pub(super) fn shoulder_twist(f: DQuat, r: &Pose, m: &Pose) -> DQuat {
    let (spine, chest) = (C::Spine.index(), C::Chest.index());
    let (l, rt) = (C::LShoulder.index(), C::RShoulder.index());
    let up = (f * (r[chest] - r[spine])).normalize_or_zero();
    if up == DVec3::ZERO {
        return f;
    }
    let across = |v: DVec3| (v - up * v.dot(up)).normalize_or_zero();
    let from = across(f * (r[l] - r[rt]));
    let to = across(m[l] - m[rt]);
    if from == DVec3::ZERO || to == DVec3::ZERO {
        return f;
    }
    let turn = from.cross(to).dot(up).atan2(from.dot(to));
    (DQuat::from_axis_angle(up, turn) * f).normalize()
}
