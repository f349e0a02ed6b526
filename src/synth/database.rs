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
//! and the output is `t + λ s (x − t)`, with softness `s` from 0 (head,
//! feet, and skin close to its bone) to 1 (far from the bone compared with
//! the body's typical skin-to-bone distance: a skirt, loose sleeves), and
//! `λ` 1 except where the lag turns triangles over (below).
//!
//! Clean frames (issue 42: every frame turned 58-115 triangles over, with
//! folded slivers across the waist beside the hands). Three causes, each
//! fixed here:
//!
//! - **Skin weights leaking across a gap** ([`part_bound_skin`]): bone heat
//!   heats a vertex from its *nearest* bone without a visibility test, so
//!   the waist beside a hand hanging at the hip took weight from the
//!   forearm and wrist and was dragged along with the hand. An arm
//!   joint's weight stays only on its own part and the parts next to it,
//!   and an arm takes no weight from a leg.
//! - **The lag**: where neighbouring vertices lag by different amounts (the
//!   edge of the soft region, a hem pressed between the legs) the lag turns
//!   triangles over. It is damped before it can: `λ` is lowered wherever
//!   the lag would change an edge by more than a quarter of its rest
//!   length, and the damping spread and smoothed over a few rings
//!   ([`lag_damping`]), so the cloth stays smooth. (An earlier version
//!   halved `λ` in patches around the turned-over triangles and repaired
//!   what was left in patches of up to seven rings: on the synth3 walk,
//!   CMU 02_01 frames 4 and 60, the front-left hem came out as a crumpled,
//!   faceted patch.) Where triangles are still turned over `λ` is halved
//!   on their vertices and two rings around and smoothed again, up to eight
//!   times (then 0: the skinned surface), frame by frame, until none is
//!   turned over against the rest frame.
//! - **Skinning itself** folds a few triangles where a joint bends hard
//!   (the crotch under a high knee): those are rebuilt by the
//!   deformation's repair ([`crate::deform::unflip::unflip`]) against the
//!   rest frame, turned by the neighbourhoods' rotations
//!   ([`RestTriangles::turns`]), on the skinned frame and again, in wider
//!   patches, on the output.
//!
//! Turned over is the evaluation's test ([`RestTriangles`]): the frames a
//! synthetic database writes are held to what `eval` counts.

use crate::deform::lbs::skin_into;
use crate::deform::soft::softness;
use crate::deform::unflip::{Adjacency, RepairOptions, unflip};
use crate::embed::Embedding;
use crate::embed::parts::Part;
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::pose::retarget::{ClipNeutral, on_character_with_grounds};
use crate::rig::Canonical;
use crate::tools::eval::triangles::{RestTriangles, TurnScratch};
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
    /// The height of the ground under each foot (left, right) above the
    /// character's floor per frame, from the same run of the pose kernel
    /// that drove the frames ([`crate::pose::retarget::OnCharacter`]): what
    /// the plausibility checks stand the feet on, without running the
    /// kernel a second time (issue 40, "prepared once").
    pub foot_grounds: [Vec<f64>; 2],
}

/// Drives `rest` (with its rig) by the clip's canonical poses (metres,
/// Y-up) and their neutral `reference`, at the clip's frame rate (resample
/// the clip first for another rate).
pub fn drive(
    rest: &Mesh,
    rig: &Embedding,
    mocap: &[Pose],
    reference: &ClipNeutral,
    fps: f64,
    dynamics: Dynamics,
) -> Synthesised {
    let n = rest.vertex_count();
    let rest_pose: Pose = rig.joints.map(DVec3::from_array);
    // One run of the kernel: the frames (`retarget`'s, bit for bit) and
    // the ground under each foot.
    let on = on_character_with_grounds(&rest_pose, &rest_pose, reference, mocap);
    let (driven, foot_grounds) = (on.frames, on.foot_grounds);
    let soft: Vec<f64> = softness(rest, rig)
        .into_iter()
        .map(|s| (s * dynamics.amount).clamp(0.0, 1.0))
        .collect();
    let skin_rig = Embedding {
        skin: part_bound_skin(rig),
        ..rig.clone()
    };
    let mut skinned = vec![[0.0; 3]; n * driven.len()];
    skinned
        .par_chunks_mut(n.max(1))
        .zip(driven.par_iter())
        .for_each(|(out, (pose, g))| {
            skin_into(rest.positions(), &skin_rig, &rest_pose, pose, g, out);
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
    clean_frames(rest, &mut skinned, &mut positions);
    Synthesised {
        positions,
        skinned,
        poses,
        foot_grounds,
    }
}

/// The rig's skin weights with the weights that leak between an arm and
/// the rest of the body taken away — an arm joint's weight on a vertex of
/// a part neither its own nor next to it (parent or child: the shoulder
/// keeps the chest's), and a leg joint's weight on an arm — and the rest
/// scaled to sum to 1 (a vertex left without weight keeps its own). The
/// legs and the torso keep theirs: a skirt spans the hips and thighs. See
/// the module docs.
pub(crate) fn part_bound_skin(rig: &Embedding) -> Vec<([u8; 4], [f64; 4])> {
    let arm = |p: Part| {
        matches!(
            p,
            Part::LUpperArm | Part::LForearm | Part::RUpperArm | Part::RForearm
        )
    };
    let leg = |p: Part| {
        matches!(
            p,
            Part::LThigh | Part::LShin | Part::LFoot | Part::RThigh | Part::RShin | Part::RFoot
        )
    };
    let near = |own: Part, p: Part| {
        let next = own == p || own.parent() == Some(p) || p.parent() == Some(own);
        !(arm(p) && !next || arm(own) && leg(p))
    };
    rig.skin
        .iter()
        .enumerate()
        .map(|(v, &(js, ws))| {
            let Some(&own) = rig.labels.get(v).and_then(|&l| Part::ALL.get(l as usize)) else {
                return (js, ws);
            };
            let mut kept = ws;
            for (k, &j) in js.iter().enumerate() {
                let part = Canonical::ALL.get(j as usize).map(|&c| Part::of_joint(c));
                if part.is_none_or(|p| !near(own, p)) {
                    kept[k] = 0.0;
                }
            }
            let sum: f64 = kept.iter().sum();
            if sum > 0.0 && sum.is_finite() {
                (js, kept.map(|w| w / sum))
            } else {
                (js, ws)
            }
        })
        .collect()
}

/// Repair passes on the output (see [`clean_frames`]).
const WIDE_PASSES: usize = 7;

/// Lag halvings before a vertex's lag is dropped (see the module docs).
const LAG_ROUNDS: usize = 8;

/// The most the lag may change an edge, as a share of its rest length,
/// before it is damped ([`lag_damping`]). Measured on the synth3 walk (CMU
/// 02_01 at 25 fps, `eval --surface` against the samba capture): 0.25
/// and 0.15 give the same creases (left thigh 493 and 505
/// edge-frames); 0.25 keeps more of the lag.
const LAG_STRAIN: f64 = 0.25;

/// Rings over which a damped vertex's `λ` is spread at its least.
const LAG_SPREAD: usize = 2;

/// Smoothing steps of the damping field (each only lowers it).
const LAG_SMOOTH: usize = 6;

/// Smoothing steps after each halving of the fallback (see the module docs).
const LAG_RESMOOTH: usize = 2;

/// Each frame made free of triangles turned over against the rest frame:
/// the skinned frame repaired, then the lag (`positions` − the skinned
/// frame as it was) taken back where it turns triangles over. Frames in
/// parallel. See the module docs.
fn clean_frames(rest: &Mesh, skinned: &mut [[f64; 3]], positions: &mut [[f64; 3]]) {
    let n = rest.vertex_count();
    let tris = rest.triangles();
    let Ok(rt) = RestTriangles::new(rest.positions(), tris) else {
        return;
    };
    if n == 0 {
        return;
    }
    let adj = Adjacency::new(n, tris);
    skinned
        .par_chunks_mut(n)
        .zip(positions.par_chunks_mut(n))
        .for_each(|(sk, out)| {
            let lag: Vec<DVec3> = out
                .iter()
                .zip(sk.iter())
                .map(|(o, s)| DVec3::from_array(*o) - DVec3::from_array(*s))
                .collect();
            let mut scratch = TurnScratch::default();
            let bad = rt.turned_over(sk, &mut scratch);
            if !bad.is_empty() {
                let (mut seeds, mut turn) = (Vec::new(), Vec::new());
                rt.turns(sk, &mut seeds, &mut turn);
                unflip(
                    tris,
                    &adj,
                    rest.positions(),
                    sk,
                    &turn,
                    bad,
                    &RepairOptions::default(),
                );
            }
            // The skinned frame the lag is measured from stays as written
            // by the repair; what is left turned over is repaired once more
            // on the output below.
            let mut lambda = lag_damping(rest.positions(), &adj, &lag);
            for round in 0..=LAG_ROUNDS {
                for ((o, s), (l, d)) in out.iter_mut().zip(sk.iter()).zip(lambda.iter().zip(&lag)) {
                    *o = (DVec3::from_array(*s) + *d * *l).to_array();
                }
                let bad = rt.turned_over(out, &mut scratch);
                if bad.is_empty() || round == LAG_ROUNDS {
                    break;
                }
                let mut on = vec![false; n];
                for &t in &bad {
                    for &v in &tris[t as usize] {
                        on[v as usize] = true;
                    }
                }
                for _ in 0..2 {
                    let before = on.clone();
                    for (v, _) in before.iter().enumerate().filter(|x| *x.1) {
                        for &w in &adj.vertices[v] {
                            on[w as usize] = true;
                        }
                    }
                }
                let last = round + 1 == LAG_ROUNDS;
                for (l, _) in lambda.iter_mut().zip(&on).filter(|x| *x.1) {
                    *l = if last { 0.0 } else { *l * 0.5 };
                }
                if !last {
                    for _ in 0..LAG_RESMOOTH {
                        blur_at_most(&adj, &mut lambda);
                    }
                }
            }
            // What skinning's own repair left (and the lag's edges):
            // repaired on the output, in wider patches.
            // Three passes of 5 rounds; a frame still not clean after them
            // (the tour's run CMU 02_03 kept 1 triangle in frame 20) gets
            // wider patches and more smoothing, pass by pass.
            for pass in 0..WIDE_PASSES {
                let bad = rt.turned_over(out, &mut scratch);
                if bad.is_empty() {
                    break;
                }
                let wider = pass.saturating_sub(2);
                let wide = RepairOptions {
                    rounds: (5 + wider).min(7),
                    smooth: 60 << wider,
                    ..RepairOptions::default()
                };
                let (mut seeds, mut turn) = (Vec::new(), Vec::new());
                rt.turns(out, &mut seeds, &mut turn);
                unflip(tris, &adj, rest.positions(), out, &turn, bad, &wide);
            }
        });
}

/// One Jacobi step of umbrella smoothing of `l`, each value kept at most
/// what it was (a damped vertex's neighbours are pulled down, never the
/// vertex up).
fn blur_at_most(adj: &Adjacency, l: &mut [f64]) {
    let before = l.to_vec();
    for (v, x) in l.iter_mut().enumerate() {
        let nb = &adj.vertices[v];
        let sum: f64 = nb.iter().map(|&w| before[w as usize]).sum::<f64>() + before[v];
        *x = x.min(sum / (nb.len() + 1) as f64);
    }
}

/// The lag's damping `λ` per vertex, before any triangle is tested: where
/// the lag would stretch or squeeze an edge by more than [`LAG_STRAIN`] of
/// its rest length (neighbours lagging by different amounts: a hem pressed
/// between the legs) `λ` scales it down to that, and the field is spread
/// (taken at its least over [`LAG_SPREAD`] rings, then smoothed
/// [`LAG_SMOOTH`] times) so the damped cloth stays smooth instead of
/// stepping between damped and free patches.
fn lag_damping(rest: &[[f64; 3]], adj: &Adjacency, lag: &[DVec3]) -> Vec<f64> {
    let c = LAG_STRAIN;
    let mut l: Vec<f64> = (0..lag.len())
        .map(|v| {
            let p = DVec3::from_array(rest[v]);
            let r = adj.vertices[v]
                .iter()
                .map(|&w| {
                    let e = p.distance(DVec3::from_array(rest[w as usize])).max(1e-12);
                    lag[v].distance(lag[w as usize]) / e
                })
                .fold(0.0f64, f64::max);
            if r > c { c / r } else { 1.0 }
        })
        .collect();
    for _ in 0..LAG_SPREAD {
        let before = l.clone();
        for (v, x) in l.iter_mut().enumerate() {
            for &w in &adj.vertices[v] {
                *x = x.min(before[w as usize]);
            }
        }
    }
    for _ in 0..LAG_SMOOTH {
        blur_at_most(adj, &mut l);
    }
    l
}
