//! Canonical poses (joint positions) and the rotations that explain them.
//!
//! A [`Pose`] is the 19 canonical joint positions of one frame. Given a rest
//! pose, [`pose_rotations`] finds for each joint the global rotation that
//! turns its rest bones onto the posed ones: the rotation of least angle
//! (composed on the parent's) for a joint with one child, the best-fitting
//! rotation (Kabsch, via the polar decomposition of `Σ d oᵀ`) for a joint
//! with several; end joints inherit their parent's. Twist about a bone is
//! not observable from positions and is carried down from the parent. This
//! drives linear blend skinning of a rest mesh, and turns extracted
//! skeletons into BVH clips any mocap viewer can play.

use crate::mocap::{Channel, Clip, ClipError, Joint, JointId, PointConvention, Units, UpAxis};
use crate::pose::{Pose, children, pose_rotations};
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

/// MotionBuilder names of the canonical joints (understood by every mocap
/// viewer and by the rig detector).
pub(crate) const BVH_NAMES: [&str; Canonical::COUNT] = [
    "Hips",
    "Spine",
    "Spine1",
    "Neck",
    "Head",
    "LeftArm",
    "LeftForeArm",
    "LeftHand",
    "RightArm",
    "RightForeArm",
    "RightHand",
    "LeftUpLeg",
    "LeftLeg",
    "LeftFoot",
    "LeftToeBase",
    "RightUpLeg",
    "RightLeg",
    "RightFoot",
    "RightToeBase",
];

/// A BVH-ready clip of poses on a skeleton whose bone offsets are `rest`'s:
/// the root carries the pelvis position, every joint its local rotation.
/// Playing it reproduces each pose's bone directions with `rest`'s lengths.
pub(crate) fn pose_clip(rest: &Pose, poses: &[Pose], fps: f64) -> Result<Clip, ClipError> {
    let kids = children();
    let joints: Vec<Joint> = Canonical::ALL
        .iter()
        .map(|&j| Joint {
            name: BVH_NAMES[j.index()].to_string(),
            parent: j.parent().map(|p| JointId(p.index() as u32)),
            offset: match j.parent() {
                Some(p) => rest[j.index()] - rest[p.index()],
                None => rest[j.index()],
            },
            channels: if j.parent().is_none() {
                Channel::ROOT6.to_vec()
            } else {
                Channel::ROT_ZYX.to_vec()
            },
            tail: kids[j.index()]
                .is_empty()
                .then_some(DVec3::new(0.0, 0.0, 0.0)),
        })
        .collect();
    let n = Canonical::COUNT;
    let mut rotations = Vec::with_capacity(poses.len() * n);
    let mut translations = Vec::with_capacity(poses.len() * n);
    for pose in poses {
        let g = pose_rotations(rest, pose);
        for j in Canonical::ALL {
            let local = match j.parent() {
                Some(p) => g[p.index()].inverse() * g[j.index()],
                None => g[j.index()],
            };
            rotations.push(local.normalize());
            translations.push(match j.parent() {
                Some(p) => rest[j.index()] - rest[p.index()],
                None => pose[j.index()],
            });
        }
    }
    extracted_clip(joints, fps, rotations, translations)
}

/// A clip of skeletons extracted from a Y-up mesh sequence: `rotations`
/// (local) and `translations` hold one entry per joint per frame, frame
/// after frame.
pub(crate) fn extracted_clip(
    joints: Vec<Joint>,
    fps: f64,
    rotations: Vec<DQuat>,
    translations: Vec<DVec3>,
) -> Result<Clip, ClipError> {
    Clip::new(
        joints,
        1.0 / fps.max(1e-9),
        rotations,
        translations,
        Units {
            metres_per_unit: 1.0,
            name: "m".into(),
            reason: "extracted from a mesh in metres".into(),
        },
        UpAxis::Y,
        PointConvention::JointOrigins,
    )
}

/// Length of every bone (child joint to its parent), indexed by the child.
pub fn bone_lengths(p: &Pose) -> [f64; Canonical::COUNT] {
    std::array::from_fn(|i| {
        let c = Canonical::ALL[i];
        c.parent().map_or(0.0, |par| p[i].distance(p[par.index()]))
    })
}

/// The rotation about the vertical (Y) axis that best aligns point set `b`
/// onto `a` in least squares, from the horizontal cross terms
/// `c = Σ (a_x b_x + a_z b_z)` and `s = Σ (a_x b_z − a_z b_x)` of the two sets
/// (both centred). Returns `(cos θ, sin θ)` of the angle that turns `b`
/// towards `a` with [`rotate_yaw`], and the aligned dot product gain
/// `√(c² + s²)` (the maximum of `Σ a · R b` over θ, minus the vertical part).
pub(crate) fn yaw_fit(c: f64, s: f64) -> (f64, f64, f64) {
    let m = c.hypot(s);
    if m <= f64::MIN_POSITIVE {
        (1.0, 0.0, 0.0)
    } else {
        (c / m, s / m, m)
    }
}

/// Rotates `p` about the Y axis by the angle with cosine `c` and sine `s`
/// (right-handed: +X turns towards −Z).
pub fn rotate_yaw(p: DVec3, c: f64, s: f64) -> DVec3 {
    DVec3::new(c * p.x + s * p.z, p.y, -s * p.x + c * p.z)
}

/// Skeleton dissimilarity `c_skel` (Huang et al. 2015, Eq. 28): the sum over
/// joints of the distance between corresponding joints, with equal weights,
/// after the two poses are pre-aligned in translation (horizontal centroids
/// of the joints brought together; height is kept, so a crouch still
/// differs from a stand) and in heading (the least-squares rotation about
/// the vertical axis, [`yaw_fit`]). Metres; 0 for a pose and any copy of it
/// moved on the floor and turned about Y.
pub(crate) fn skeleton_distance(a: &Pose, b: &Pose) -> f64 {
    let (cos, sin, ca, cb) = floor_fit(a, b);
    a.iter()
        .zip(b)
        .map(|(p, q)| (*p - ca).distance(rotate_yaw(*q - cb, cos, sin)))
        .sum()
}

/// The floor alignment of `b` onto `a`: `(cos θ, sin θ, c_a, c_b)` with
/// `c` the horizontal centroids, such that `rotate_yaw(q − c_b) + c_a`
/// best matches `a` in least squares.
pub(crate) fn floor_fit(a: &Pose, b: &Pose) -> (f64, f64, DVec3, DVec3) {
    let ca = horizontal_centroid(a);
    let cb = horizontal_centroid(b);
    let (mut c, mut s) = (0.0, 0.0);
    for (p, q) in a.iter().zip(b) {
        let (p, q) = (*p - ca, *q - cb);
        c += p.x * q.x + p.z * q.z;
        s += p.x * q.z - p.z * q.x;
    }
    let (cos, sin, _) = yaw_fit(c, s);
    (cos, sin, ca, cb)
}

/// Mean of the joints' X and Z (Y = 0).
pub(crate) fn horizontal_centroid(p: &Pose) -> DVec3 {
    let s: DVec3 = p.iter().copied().sum();
    DVec3::new(s.x, 0.0, s.z) / p.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rest() -> Pose {
        let bones = crate::synth::clips::skeleton();
        let mut p = [DVec3::ZERO; Canonical::COUNT];
        for (i, (_, parent, off, _)) in bones.iter().enumerate() {
            p[i] = parent.map_or(DVec3::ZERO, |q| p[q]) + DVec3::from_array(*off);
        }
        p
    }

    #[test]
    fn rotations_reproduce_a_rigidly_posed_skeleton() {
        let r = rest();
        let q = DQuat::from_rotation_y(0.8) * DQuat::from_rotation_x(0.2);
        let t = DVec3::new(0.3, 0.1, -2.0);
        let posed: Pose = r.map(|p| q * p + t);
        let g = pose_rotations(&r, &posed);
        for j in Canonical::ALL {
            assert!(g[j.index()].angle_between(q) < 1e-9, "{j:?}");
        }
        // And as a clip, FK returns the posed joints.
        let clip = pose_clip(&r, &[posed], 30.0).unwrap();
        let w = clip.world_positions(0);
        for j in Canonical::ALL {
            assert!((w[j.index()] - posed[j.index()]).length() < 1e-9, "{j:?}");
        }
    }

    #[test]
    fn skeleton_distance_ignores_floor_motion_and_heading() {
        let r = rest();
        let q = DQuat::from_rotation_y(2.4);
        let moved: Pose = r.map(|p| q * p + DVec3::new(1.5, 0.0, -0.7));
        assert!(skeleton_distance(&r, &moved) < 1e-9);
        assert!(skeleton_distance(&moved, &r) < 1e-9);
        // Lifting the whole pose is not aligned away (Eq. 28 keeps height).
        let lifted: Pose = r.map(|p| p + DVec3::new(0.0, 0.1, 0.0));
        assert!((skeleton_distance(&r, &lifted) - 1.9).abs() < 1e-9);
        // A bent elbow costs the forearm's displacement.
        let mut bent = r;
        bent[Canonical::LWrist.index()] += DVec3::new(0.0, 0.05, 0.0);
        let d = skeleton_distance(&r, &bent);
        assert!(d > 0.04 && d < 0.06, "{d}");
    }
}
