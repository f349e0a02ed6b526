//! Rotation-aware local steps of a region's solve (as-rigid-as-possible
//! after Sorkine & Alexa 2007, Sec. 3): after a solve, each vertex's best
//! rotation from the source frame's one-ring to the solved one-ring; the
//! source's Laplacian coordinate turned by it is the next solve's `δ₀`.
//! The factorisation is the region's own ([`super::part_laplacian`]), so a
//! step costs the rotations and one prefactored solve.
//!
//! The rotation is the polar factor of the one-ring's covariance
//! `Σⱼ (yᵢ − yⱼ)(sᵢ − sⱼ)ᵀ` (uniform weights, the Laplacian's own), found
//! by nalgebra's iterative extraction (Müller et al. 2016) started from the
//! vertex's previous rotation, so it stays on the side of the skin-blended
//! turn the first solve used.

use glam::{DQuat, DVec3};
use nalgebra::{Matrix3, Rotation3, UnitQuaternion};

/// Iterations of the rotation extraction per local step (it starts from
/// the previous rotation, which is close).
const EXTRACT_ITERATIONS: usize = 8;

/// One local step: for every region vertex `i`, the rotation `Rᵢ` (started
/// from `rots[i]`, written back) taking the source's one-ring edges
/// (`source`, local order) to the solved ones (`solved`), and
/// `delta[i] = Rᵢ · lsrc[i]` (`lsrc`: the source's Laplacian coordinates,
/// unturned). `lap` gives the one-rings (a row's off-diagonal columns).
///
/// With `zone` (each vertex's weight and its skin-blended turn,
/// [`super::step_zone`]) a vertex of weight 0 keeps its `rots` and
/// `delta` as they are, and one of weight `w` turns its coordinate by the
/// skin's turn slerped towards the fitted one by `w` (`rots` keeps the
/// fitted turn, the next step's start).
pub(crate) fn local_step(
    lap: &[Vec<(u32, f64)>],
    source: &[[f64; 3]],
    solved: &[[f64; 3]],
    lsrc: &[[f64; 3]],
    rots: &mut [DQuat],
    delta: &mut [[f64; 3]],
    zone: Option<(&[f64], &[DQuat])>,
) {
    for (i, row) in lap.iter().enumerate() {
        let w = zone.map_or(1.0, |(w, _)| w[i]);
        if w <= 0.0 {
            continue;
        }
        let (si, yi) = (DVec3::from_array(source[i]), DVec3::from_array(solved[i]));
        let mut cov = Matrix3::<f64>::zeros();
        for &(j, _) in row.iter().filter(|&&(j, _)| j as usize != i) {
            let e = si - DVec3::from_array(source[j as usize]);
            let f = yi - DVec3::from_array(solved[j as usize]);
            for a in 0..3 {
                for b in 0..3 {
                    cov[(a, b)] += f[a] * e[b];
                }
            }
        }
        let q = rots[i];
        let guess = Rotation3::from(UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            q.w, q.x, q.y, q.z,
        )));
        let r = Rotation3::from_matrix_eps(&cov, 1e-9, EXTRACT_ITERATIONS, guess);
        let u = UnitQuaternion::from_rotation_matrix(&r);
        let nq = DQuat::from_xyzw(u.i, u.j, u.k, u.w);
        let nq = if nq.is_finite() { nq.normalize() } else { q };
        rots[i] = nq;
        let turn = match zone {
            Some((_, skin)) if w < 1.0 => skin[i].slerp(nq, w),
            _ => nq,
        };
        delta[i] = (turn * DVec3::from_array(lsrc[i])).to_array();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A Laplacian's rows: (column, weight) pairs.
    type Rows = Vec<Vec<(u32, f64)>>;

    /// A fan: centre 0 and six neighbours, slightly out of plane, with its
    /// umbrella Laplacian (the centre's row averages the six; each
    /// neighbour's row is its difference from the centre).
    fn fan() -> (Vec<[f64; 3]>, Rows) {
        let mut s = vec![[0.0, 0.0, 0.3]];
        for k in 0..6 {
            let a = k as f64 * std::f64::consts::TAU / 6.0;
            s.push([a.cos(), a.sin(), 0.1 * (k % 2) as f64]);
        }
        let mut lap = vec![vec![(0u32, 1.0)]];
        lap[0].extend((1..7u32).map(|j| (j, -1.0 / 6.0)));
        for i in 1..7u32 {
            lap.push(vec![(i, 1.0), (0, -1.0)]);
        }
        (s, lap)
    }

    /// A rigidly turned ring: the step finds the turn, and the turned
    /// Laplacian coordinate is the solved one's.
    #[test]
    fn a_rigid_turn_is_found() {
        let (s, lap) = fan();
        let turn = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 0.5).normalize(), 1.1);
        let y: Vec<[f64; 3]> = s
            .iter()
            .map(|p| (turn * DVec3::from_array(*p) + DVec3::X).to_array())
            .collect();
        let mut ls = vec![[0.0; 3]; 7];
        super::super::part_laplacian::apply(&lap, &s, &mut ls);
        let mut ly = vec![[0.0; 3]; 7];
        super::super::part_laplacian::apply(&lap, &y, &mut ly);
        let mut rots = vec![DQuat::IDENTITY; 7];
        let mut delta = vec![[0.0; 3]; 7];
        // Each step's extraction starts from the last one's rotation (as
        // the deformer's steps and frames do): from the identity, eight
        // iterations leave 0.02 rad of a 1.1 rad turn; a few warm-started
        // steps converge.
        for _ in 0..4 {
            local_step(&lap, &s, &y, &ls, &mut rots, &mut delta, None);
        }
        assert!(rots[0].angle_between(turn) < 1e-3, "{:?}", rots[0]);
        let d = DVec3::from_array(delta[0]) - DVec3::from_array(ly[0]);
        assert!(d.length() < 1e-3 * DVec3::from_array(ly[0]).length(), "{d}");
    }

    /// In a zone ([`super::super::step_zone`]): a vertex of weight 0 keeps
    /// its rotation and coordinate; one of weight ½ turns its coordinate
    /// half way from its skin turn to the fitted one, and keeps the fitted
    /// one as the next start.
    #[test]
    fn a_zone_weight_slerps_from_the_skin_turn() {
        let (s, lap) = fan();
        let turn = DQuat::from_axis_angle(DVec3::X, 0.8);
        let y: Vec<[f64; 3]> = s
            .iter()
            .map(|p| (turn * DVec3::from_array(*p)).to_array())
            .collect();
        let mut ls = vec![[0.0; 3]; 7];
        super::super::part_laplacian::apply(&lap, &s, &mut ls);
        let skin = vec![DQuat::IDENTITY; 7];
        for (w0, want) in [
            (0.0, DQuat::IDENTITY),
            (0.5, DQuat::from_axis_angle(DVec3::X, 0.4)),
        ] {
            let mut w = vec![0.0; 7];
            w[0] = w0;
            let mut rots = vec![turn; 7];
            let mut delta = ls.clone();
            local_step(&lap, &s, &y, &ls, &mut rots, &mut delta, Some((&w, &skin)));
            let got = DVec3::from_array(delta[0]);
            let d = got - want * DVec3::from_array(ls[0]);
            assert!(d.length() < 1e-6, "w {w0}: {got} {d}");
            assert!(rots[0].angle_between(turn) < 1e-6, "{:?}", rots[0]);
            for i in 1..7 {
                assert_eq!(delta[i], ls[i], "vertex {i} of weight 0 moved");
                assert_eq!(rots[i], turn);
            }
        }
    }
}
