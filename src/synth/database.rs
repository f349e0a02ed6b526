//! A synthetic 4D database: a rest mesh with an embedded rig, driven by
//! mocap clips with linear blend skinning, plus secondary dynamics (a damped
//! spring lag on soft tissue and loose clothing) so the surface motion is not
//! pure skinning. Each clip becomes one sequence; the skeleton that drove it
//! is kept as ground truth.
//!
//! Skinning: [`crate::deform::lbs::skin_into`]; softness:
//! [`crate::deform::soft::softness`]. Retargeting: [`crate::pose::retarget`] (the torso turns by the clip's
//! rotations since its neutral reference, the limbs take the clip's bone
//! directions, bone lengths are the character's).
//!
//! Dynamics: each vertex `x` follows its skinned position `t` as
//! `ẍ = ω² (t − x) − 2 ζ ω ẋ` (semi-implicit Euler, four substeps a frame),
//! and the output is `t + s (x − t)`, with softness `s` from 0 (head,
//! feet, and skin close to its bone) to 1 (far from the bone compared with
//! the body's typical skin-to-bone distance: a skirt, loose sleeves).

use crate::deform::lbs::skin_into;
use crate::deform::soft::softness;
use crate::embed::Embedding;
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::pose::retarget::{Reference, retarget};
use glam::DVec3;
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

/// Drives `rest` (with its rig) by the clip's canonical poses (metres,
/// Y-up) and their neutral `reference`, at the clip's frame rate (resample
/// the clip first for another rate).
pub fn drive(
    rest: &Mesh,
    rig: &Embedding,
    mocap: &[Pose],
    reference: &Reference,
    fps: f64,
    dynamics: Dynamics,
) -> Synthesised {
    let n = rest.vertex_count();
    let rest_pose: Pose = rig.joints.map(DVec3::from_array);
    let driven = retarget(&rest_pose, reference, mocap);
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
