//! Dual-quaternion skinning (Kavan, Collins, Žára, O'Sullivan,
//! *Geometric Skinning with Approximate Dual Quaternion Blending*, ACM TOG
//! 27(4), 2008, Sec. 3 and Algorithm 1): the bones' rigid motions blended
//! as unit dual quaternions instead of as matrices ([`super::lbs`]), so a
//! vertex weighted between two bones turning about their joint keeps its
//! distance from the joint (LBS pulls it towards the joint: the collapse
//! behind a bent knee, the candy wrapper of a twisted forearm).
//!
//! The deformation can take its positional constraints (`x_c` of Huang et
//! al. 2015, Eq. 32) from it instead of from LBS
//! ([`super::DeformOptions::constraint_skin`]).

use crate::embed::Embedding;
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

/// The skinning that places the deformation's positional constraints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ConstraintSkin {
    /// Linear blend skinning, as Huang et al. 2015 (Sec. 5.2.3).
    #[default]
    Linear,
    /// Dual-quaternion skinning ([`skin_into`]).
    DualQuaternion,
    /// Each vertex moved rigidly by its heaviest bone ([`rigid_into`]):
    /// the end of a thigh's region inside the shin held where the shin
    /// alone would put it.
    Rigid,
}

/// Each of `rest` moved rigidly by its heaviest bone,
/// `x ↦ g_j (x − r_j) + p_j` (inputs as [`skin_into`]).
pub fn rigid_into(
    rest: &[[f64; 3]],
    rig: &Embedding,
    rest_pose: &Pose,
    pose: &Pose,
    g: &[DQuat; Canonical::COUNT],
    out: &mut [[f64; 3]],
) {
    for ((o, p), (js, ws)) in out.iter_mut().zip(rest).zip(&rig.skin) {
        let j = js
            .iter()
            .zip(ws)
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(&j, _)| j as usize);
        *o = (g[j] * (DVec3::from_array(*p) - rest_pose[j]) + pose[j]).to_array();
    }
}

/// Dual-quaternion skinning of `rest` positions into `out`, with the same
/// inputs as [`super::lbs::skin_into`]: joint `j` moves a point by
/// `x ↦ g_j (x − r_j) + p_j`, i.e. the unit dual quaternion
/// `q̂_j = g_j + ε ½ t_j g_j` with `t_j = p_j − g_j r_j`; a vertex blends
/// its four `w_j q̂_j` (each turned to the hemisphere of its heaviest
/// bone's, as Kavan et al. do for antipodality), divides by the real
/// part's norm and applies the result by Algorithm 1 of the paper (which
/// needs no orthogonal dual part). Equal to LBS where a vertex has one
/// bone. O(4 V), no allocation.
pub fn skin_into(
    rest: &[[f64; 3]],
    rig: &Embedding,
    rest_pose: &Pose,
    pose: &Pose,
    g: &[DQuat; Canonical::COUNT],
    out: &mut [[f64; 3]],
) {
    skin_weights_into(rest, &rig.skin, rest_pose, pose, g, out);
}

/// [`skin_into`] with the weights given: up to four (joint index, weight)
/// per vertex, as [`Embedding::skin`] holds them.
fn skin_weights_into(
    rest: &[[f64; 3]],
    skin: &[([u8; 4], [f64; 4])],
    rest_pose: &Pose,
    pose: &Pose,
    g: &[DQuat; Canonical::COUNT],
    out: &mut [[f64; 3]],
) {
    for ((o, p), (js, ws)) in out.iter_mut().zip(rest).zip(skin) {
        let heaviest = js
            .iter()
            .zip(ws)
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(&j, _)| j as usize);
        let pivot = g[heaviest];
        let (mut real, mut dual) = (DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0), [0.0f64; 4]);
        for (&j, &w) in js.iter().zip(ws) {
            if w == 0.0 {
                continue;
            }
            let j = j as usize;
            let q = g[j];
            let t = pose[j] - q * rest_pose[j];
            // ½ t q, t a pure quaternion.
            let d = DQuat::from_xyzw(t.x, t.y, t.z, 0.0) * q;
            let s = if q.dot(pivot) < 0.0 { -w } else { w };
            real = DQuat::from_xyzw(
                real.x + s * q.x,
                real.y + s * q.y,
                real.z + s * q.z,
                real.w + s * q.w,
            );
            for (a, b) in dual.iter_mut().zip([d.x, d.y, d.z, d.w]) {
                *a += 0.5 * s * b;
            }
        }
        let norm = real.length();
        if norm.is_nan() || norm <= 1e-12 {
            // No weight (or bones that cancel): the rest position.
            *o = *p;
            continue;
        }
        let (r0, d0) = (real.xyz() / norm, real.w / norm);
        let (re, de) = (DVec3::new(dual[0], dual[1], dual[2]) / norm, dual[3] / norm);
        let x = DVec3::from_array(*p);
        let x = x + 2.0 * r0.cross(r0.cross(x) + d0 * x);
        let t = 2.0 * (d0 * re - de * r0 + r0.cross(re));
        *o = (x + t).to_array();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    type Skin = Vec<([u8; 4], [f64; 4])>;

    /// Vertices skinned to the hip and the knee, each with its weight on
    /// the knee.
    fn rig(weights: &[f64]) -> Skin {
        let (h, k) = (
            Canonical::LHip.index() as u8,
            Canonical::LKnee.index() as u8,
        );
        weights
            .iter()
            .map(|&w| ([h, k, 0, 0], [1.0 - w, w, 0.0, 0.0]))
            .collect()
    }

    /// Linear blend skinning ([`super::super::lbs::skin_into`]'s sum).
    fn lbs(
        rest: &[[f64; 3]],
        skin: &Skin,
        rest_pose: &Pose,
        pose: &Pose,
        g: &[DQuat; Canonical::COUNT],
    ) -> Vec<[f64; 3]> {
        rest.iter()
            .zip(skin)
            .map(|(p, (js, ws))| {
                let p = DVec3::from_array(*p);
                let x: DVec3 = js
                    .iter()
                    .zip(ws)
                    .map(|(&j, &w)| {
                        (g[j as usize] * (p - rest_pose[j as usize]) + pose[j as usize]) * w
                    })
                    .sum();
                x.to_array()
            })
            .collect()
    }

    /// A two-bone leg along −y, the knee at the origin, bent 90° about x
    /// at the knee (the thigh still): LBS pulls a vertex weighted half and
    /// half towards the knee by cos 45°, dual quaternions keep its
    /// distance; vertices on one bone move rigidly with it under both.
    #[test]
    fn a_bent_knee_keeps_its_radius() {
        let mut rest_pose = [DVec3::ZERO; Canonical::COUNT];
        rest_pose[Canonical::LHip.index()] = DVec3::new(0.0, 0.4, 0.0);
        let mut pose = rest_pose;
        // Moved as a whole: 1 m along x.
        for p in pose.iter_mut() {
            *p += DVec3::X;
        }
        let mut g = [DQuat::IDENTITY; Canonical::COUNT];
        g[Canonical::LKnee.index()] = DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2);
        // Behind the knee, on the knee bone's side, and down the shin.
        let rest = [[0.0, 0.0, -0.05], [0.0, -0.2, 0.0], [0.0, 0.2, 0.0]];
        let r = rig(&[0.5, 1.0, 0.0]);
        let lbs = lbs(&rest, &r, &rest_pose, &pose, &g);
        let mut dqs = [[0.0; 3]; 3];
        skin_weights_into(&rest, &r, &rest_pose, &pose, &g, &mut dqs);
        let knee = pose[Canonical::LKnee.index()];
        let dist = |p: [f64; 3]| (DVec3::from_array(p) - knee).length();
        assert!((dist(dqs[0]) - 0.05).abs() < 1e-12, "{dqs:?}");
        let c = std::f64::consts::FRAC_PI_4.cos();
        assert!((dist(lbs[0]) - 0.05 * c).abs() < 1e-12, "{lbs:?}");
        for k in 1..3 {
            for d in 0..3 {
                assert!(
                    (lbs[k][d] - dqs[k][d]).abs() < 1e-12,
                    "{k}: {lbs:?} {dqs:?}"
                );
            }
        }
        // The shin vertex turned 90° about x: −y goes to −z.
        assert!((DVec3::from_array(dqs[1]) - (knee - 0.2 * DVec3::Z)).length() < 1e-12);
    }

    /// Quaternions of opposite sign are one rotation: a bone given as
    /// `−q` skins as `q` does.
    #[test]
    fn the_sign_of_a_rotation_does_not_matter() {
        let rest_pose = [DVec3::new(0.1, 0.2, 0.3); Canonical::COUNT];
        let pose = [DVec3::new(-0.2, 0.5, 0.0); Canonical::COUNT];
        let q = DQuat::from_rotation_z(0.7);
        let mut g = [DQuat::from_rotation_y(0.3); Canonical::COUNT];
        g[Canonical::LKnee.index()] = q;
        let rest = [[0.3, -0.1, 0.2]];
        let r = rig(&[0.4]);
        let (mut a, mut b) = ([[0.0; 3]; 1], [[0.0; 3]; 1]);
        skin_weights_into(&rest, &r, &rest_pose, &pose, &g, &mut a);
        g[Canonical::LKnee.index()] = -q;
        skin_weights_into(&rest, &r, &rest_pose, &pose, &g, &mut b);
        for d in 0..3 {
            assert!((a[0][d] - b[0][d]).abs() < 1e-12, "{a:?} {b:?}");
        }
    }
}
