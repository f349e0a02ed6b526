//! A synthetic 4D database: a rest mesh with an embedded rig, driven by
//! mocap clips with linear blend skinning, plus secondary dynamics (a damped
//! spring lag on soft tissue and loose clothing) so the surface motion is not
//! pure skinning. Each clip becomes one sequence; the skeleton that drove it
//! is kept as ground truth.
//!
//! Retargeting: every frame's canonical bone directions come from the clip;
//! bone lengths from the character. The root follows the clip's pelvis,
//! scaled by the ratio of leg lengths. Rotations per joint come from
//! [`pose_rotations`] (least rotation per bone, Kabsch at branching joints).
//!
//! Dynamics: each vertex `x` follows its skinned position `t` as
//! `ẍ = ω² (t − x) − 2 ζ ω ẋ` (semi-implicit Euler, four substeps a frame),
//! and the output is `t + s (x − t)`, with softness `s` from 0 (head,
//! feet, and skin close to its bone) to 1 (far from the bone compared with
//! the body's typical skin-to-bone distance: a skirt, loose sleeves).

use crate::mesh::Mesh;
use crate::mocap::Clip;
use crate::rig::embed::Embedding;
use crate::rig::embed::heat::nearest_bones;
use crate::rig::embed::parts::Part;
use crate::rig::{Canonical, RigError, RigMap};
use crate::skeleton::{Pose, pose_rotations};
use glam::{DQuat, DVec3};
use rayon::prelude::*;

/// Secondary-motion settings.
#[derive(Debug, Clone, Copy)]
pub struct Dynamics {
    /// Natural frequency of the spring (Hz).
    pub frequency: f64,
    /// Damping ratio.
    pub damping: f64,
    /// Scale of the softness map (0 turns the dynamics off).
    pub amount: f64,
}

impl Default for Dynamics {
    fn default() -> Self {
        Dynamics {
            frequency: 2.5,
            damping: 0.35,
            amount: 1.0,
        }
    }
}

/// One synthesised sequence.
pub struct Synthesised {
    /// Positions, frame after frame.
    pub positions: Vec<[f64; 3]>,
    /// The skinned positions without dynamics, frame after frame.
    pub skinned: Vec<[f64; 3]>,
    /// The character's skeleton that drove each frame (ground truth).
    pub poses: Vec<Pose>,
}

/// Canonical joint positions of every frame of a clip. Rig maps name a
/// canonical joint by the bone that starts there, so this is the joint
/// origin (also for ASF/AMC clips, whose points are bone ends).
pub fn clip_poses(clip: &Clip, map: &RigMap) -> Result<Vec<Pose>, RigError> {
    map.poses(clip)
}

fn leg_length(p: &Pose) -> f64 {
    use Canonical as C;
    let d = |a: C, b: C| p[a.index()].distance(p[b.index()]);
    0.5 * (d(C::LHip, C::LKnee)
        + d(C::LKnee, C::LAnkle)
        + d(C::RHip, C::RKnee)
        + d(C::RKnee, C::RAnkle))
}

/// The character's joint rotations and positions in each mocap pose.
///
/// The mocap's own rotation of every joint since its first frame,
/// `G_m(t)`, is composed with a fixed offset `O` that turns the character's
/// rest bones onto the mocap's first-frame bones: `G(t) = G_m(t) O`. Joint
/// positions are forward kinematics of `G(t)` on the character's rest bone
/// offsets, the root following the mocap's pelvis scaled by the ratio of
/// leg lengths. Skinning with these rotations and positions is consistent
/// (no tearing where a branching joint's children disagree).
pub fn retarget(rest: &Pose, mocap: &[Pose]) -> Vec<(Pose, [DQuat; Canonical::COUNT])> {
    let Some(first) = mocap.first() else {
        return Vec::new();
    };
    let s = leg_length(rest) / leg_length(first).max(1e-9);
    let root = Canonical::Pelvis.index();
    let offset = pose_rotations(rest, first);
    mocap
        .iter()
        .map(|m| {
            let gm = pose_rotations(first, m);
            let g: [DQuat; Canonical::COUNT] =
                std::array::from_fn(|j| (gm[j] * offset[j]).normalize());
            let mut t = [DVec3::ZERO; Canonical::COUNT];
            t[root] = rest[root] + (m[root] - first[root]) * s;
            for c in Canonical::ALL.iter().skip(1) {
                let p = c.parent().map_or(root, |p| p.index());
                t[c.index()] = t[p] + g[p] * (rest[c.index()] - rest[p]);
            }
            (t, g)
        })
        .collect()
}

/// Softness of every vertex in [0, 1]: 0 up to 1.5 times the body's median
/// distance from skin to bone, rising to 1 at 2.5 times (a skirt, a loose
/// sleeve); always 0 on the head and feet.
pub fn softness(rest: &Mesh, rig: &Embedding) -> Vec<f64> {
    let est_bones = crate::rig::embed::bones_of(rig);
    let near = nearest_bones(rest.positions(), &est_bones);
    let mut all: Vec<f64> = near.iter().map(|x| x.1).collect();
    all.sort_by(f64::total_cmp);
    let med = all.get(all.len() / 2).copied().unwrap_or(1.0).max(1e-9);
    near.iter()
        .enumerate()
        .map(|(v, &(_, d))| {
            let p = Part::ALL[rig.labels[v] as usize];
            if matches!(p, Part::Head | Part::LFoot | Part::RFoot) {
                return 0.0;
            }
            (d / med - 1.5).clamp(0.0, 1.0)
        })
        .collect()
}

/// Drives `rest` (with its rig) by the clip's canonical poses, at the clip's
/// frame rate (resample the clip first for another rate).
pub fn synthesise(
    rest: &Mesh,
    rig: &Embedding,
    mocap: &[Pose],
    fps: f64,
    dynamics: Dynamics,
) -> Synthesised {
    let n = rest.vertex_count();
    let rest_pose: Pose = rig.joints.map(DVec3::from_array);
    let driven = retarget(&rest_pose, mocap);
    let soft: Vec<f64> = softness(rest, rig)
        .into_iter()
        .map(|s| (s * dynamics.amount).clamp(0.0, 1.0))
        .collect();
    let mut skinned = vec![[0.0; 3]; n * driven.len()];
    skinned
        .par_chunks_mut(n.max(1))
        .zip(driven.par_iter())
        .for_each(|(out, (pose, g))| {
            skin_into(rest.positions(), rig, &rest_pose, pose, g, out);
        });
    let poses: Vec<Pose> = driven.into_iter().map(|(p, _)| p).collect();
    // Dynamics, frame after frame; vertices in parallel.
    let mut positions = skinned.clone();
    let omega = std::f64::consts::TAU * dynamics.frequency;
    let (sub, dt) = (4, 1.0 / (fps.max(1e-6) * 4.0));
    let mut state: Vec<(DVec3, DVec3)> = (0..n)
        .map(|v| {
            (
                DVec3::from_array(skinned.get(v).copied().unwrap_or([0.0; 3])),
                DVec3::ZERO,
            )
        })
        .collect();
    for f in 1..poses.len() {
        let prev = &skinned[(f - 1) * n..f * n];
        let cur = &skinned[f * n..(f + 1) * n];
        let out = &mut positions[f * n..(f + 1) * n];
        state
            .par_iter_mut()
            .zip(out.par_iter_mut())
            .enumerate()
            .for_each(|(v, ((x, vel), o))| {
                let (a, b) = (DVec3::from_array(prev[v]), DVec3::from_array(cur[v]));
                for k in 0..sub {
                    let target = a.lerp(b, (k + 1) as f64 / sub as f64);
                    let acc =
                        (target - *x) * (omega * omega) - *vel * (2.0 * dynamics.damping * omega);
                    *vel += acc * dt;
                    *x += *vel * dt;
                }
                *o = (b + (*x - b) * soft[v]).to_array();
            });
    }
    Synthesised {
        positions,
        skinned,
        poses,
    }
}

/// Linear blend skinning of the rest positions into `out`.
pub fn skin_into(
    rest: &[[f64; 3]],
    rig: &Embedding,
    rest_pose: &Pose,
    pose: &Pose,
    g: &[DQuat; Canonical::COUNT],
    out: &mut [[f64; 3]],
) {
    for ((o, p), (js, ws)) in out.iter_mut().zip(rest).zip(&rig.skin) {
        let p = DVec3::from_array(*p);
        let mut acc = DVec3::ZERO;
        for (&j, &w) in js.iter().zip(ws) {
            if w == 0.0 {
                continue;
            }
            let j = j as usize;
            acc += (g[j] * (p - rest_pose[j]) + pose[j]) * w;
        }
        *o = acc.to_array();
    }
}
