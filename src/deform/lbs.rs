//! Linear blend skinning (Magnenat-Thalmann et al. 1988; Huang et al. 2015,
//! Sec. 5.2.3): [`skin_into`] poses rest positions by the rig's weights, and
//! the positions of a fixed set of constraint vertices
//! ([`constraint_vertices`]) become the soft constraints `x_c` of Eq. 32
//! when a retrieved frame, bound to its own extracted skeleton, is skinned
//! to the query pose. `synth` drives its synthetic databases with the same
//! kernel.

use crate::db::Character;
use crate::embed::Embedding;
use crate::embed::bones_of;
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

/// Linear blend skinning of `rest` positions into `out` (one entry per
/// vertex): `x' = Σ_j w_j (g_j (x − r_j) + p_j)` with the rig's four
/// weights per vertex, `r` the `rest_pose` joints, `p` the `pose` joints
/// and `g` each joint's global rotation from rest to pose
/// ([`crate::pose::pose_rotations`]). O(4 V), no allocation.
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

/// Constraint vertices of a character, chosen once: bound (≥ 95 %) to one
/// bone, projecting into the middle 60 % of that bone on the rest frame
/// (LBS collapses near joints), and not loose (skin no farther from its
/// bone than 1.5× the body's median, see
/// [`super::soft::softness`]: LBS would weld a skirt to a
/// thigh), every `stride`-th such vertex.
pub fn constraint_vertices(ch: &Character, stride: usize) -> Vec<u32> {
    let bones = bones_of(ch.rig());
    let rest = ch.topology().positions();
    let soft = super::soft::softness(ch.topology(), ch.rig());
    // A vertex in no triangle is carried, not solved ([`crate::mesh::stray`]):
    // never a constraint, nor counted (the others' choice stays the same
    // wherever such vertices are numbered).
    let mut stray = vec![false; rest.len()];
    for v in ch.topology().unreferenced() {
        stray[v] = true;
    }
    let mut out = Vec::new();
    let mut count = 0usize;
    for (v, (js, ws)) in ch.rig().skin.iter().enumerate() {
        if stray[v] {
            continue;
        }
        let (k, w) = ws
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(k, w)| (k, *w))
            .unwrap_or((0, 0.0));
        if w < 0.95 || soft[v] > 0.0 {
            continue;
        }
        let joint = js[k] as usize;
        let Some(b) = bones.iter().find(|b| b.joint.index() == joint) else {
            continue;
        };
        let p = DVec3::from_array(rest[v]);
        let ab = b.b - b.a;
        let t = (p - b.a).dot(ab) / ab.length_squared().max(1e-12);
        if !(0.2..=0.8).contains(&t) {
            continue;
        }
        if count % stride.max(1) == 0 {
            out.push(v as u32);
        }
        count += 1;
    }
    out
}
