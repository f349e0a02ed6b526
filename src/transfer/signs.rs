//! Sign choice for the marker quaternions (de Aguiar et al. 2007, Sec. 4.3).
//!
//! `q` and `−q` are the same rotation, but the harmonic interpolation of
//! Eq. 2 averages quaternion *components*: between two markers of opposite
//! sign the field passes through zero and the triangles there get arbitrary
//! rotations — the mesh collapses ("candy wrapper"). The naive convention
//! `w ≥ 0` is exactly wrong near 180° (small `w`, the paper's detector):
//! markers at 179° and 181° get opposite signs although they are 2° apart.
//!
//! The paper's remedy is an intermediate reference pose. Changing the
//! reference by a rigid rotation `R` leaves the cotangent Laplacian (and
//! its factorisation) unchanged and multiplies every quaternion by `R⁻¹`,
//! a linear isometry of R⁴ that commutes with the harmonic interpolation;
//! what it changes is only which sign is "near". So we pick signs against
//! the frame's mean rotation (the dominant eigenvector of `Σ q qᵀ`, the
//! rotation average of Markley et al. 2007) as the intermediate reference,
//! its own sign kept continuous from frame to frame. Markers then take the
//! short way round from the body's mean turn, whatever the global heading.

use glam::{DQuat, DVec4};
use nalgebra::{Matrix4, SymmetricEigen};

/// How marker quaternion signs are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SignMode {
    /// Continuous in time and consistent with the frame's mean rotation
    /// (default).
    #[default]
    Consistent,
    /// `w ≥ 0` per marker: the naive convention, kept to show the collapse.
    Hemisphere,
}

/// The frame's mean rotation: the unit quaternion maximising `Σ (q·m)²`.
pub(crate) fn mean_rotation(q: &[DQuat]) -> DQuat {
    let mut m = Matrix4::<f64>::zeros();
    for x in q {
        let v = DVec4::from(*x);
        let a = [v.x, v.y, v.z, v.w];
        for i in 0..4 {
            for j in 0..4 {
                m[(i, j)] += a[i] * a[j];
            }
        }
    }
    let e = SymmetricEigen::new(m);
    let mut best = 0;
    for i in 1..4 {
        if e.eigenvalues[i] > e.eigenvalues[best] {
            best = i;
        }
    }
    let c = e.eigenvectors.column(best);
    let r = DQuat::from_xyzw(c[0], c[1], c[2], c[3]);
    if r.is_finite() && r.length() > 0.5 {
        r.normalize()
    } else {
        DQuat::IDENTITY
    }
}

/// Flips signs of `q` in place so that every marker lies within 90° (in
/// quaternion space) of the frame's mean rotation, whose own sign follows
/// `prev_mean` (last frame's) for continuity in time. Returns the number of
/// near-singular markers (turned over 160° from the reference pose,
/// `|w| < 0.17`) and the signed mean to pass to the next frame.
pub(crate) fn orient(q: &mut [DQuat], prev_mean: Option<DQuat>, mode: SignMode) -> (usize, DQuat) {
    let singular = q.iter().filter(|x| x.w.abs() < 0.17).count();
    let mut mean = mean_rotation(q);
    match mode {
        SignMode::Hemisphere => {
            for x in q.iter_mut() {
                if x.w < 0.0 {
                    *x = -*x;
                }
            }
        }
        SignMode::Consistent => {
            let flip = match prev_mean {
                Some(p) => mean.dot(p) < 0.0,
                None => mean.w < 0.0,
            };
            if flip {
                mean = -mean;
            }
            for x in q.iter_mut() {
                if x.dot(mean) < 0.0 {
                    *x = -*x;
                }
            }
        }
    }
    (singular, mean)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn near_half_turns_get_one_sign() {
        let mut q = vec![
            DQuat::from_axis_angle(DVec3::Y, 179f64.to_radians()),
            DQuat::from_axis_angle(DVec3::Y, 181f64.to_radians()),
            DQuat::from_axis_angle(DVec3::Y, 178f64.to_radians()),
        ];
        orient(&mut q, None, SignMode::Consistent);
        assert!(q[0].dot(q[1]) > 0.99 && q[0].dot(q[2]) > 0.99);
        let mut h = q.clone();
        orient(&mut h, None, SignMode::Hemisphere);
        assert!(h[0].dot(h[1]) < -0.99, "the naive convention splits them");
    }

    #[test]
    fn signs_follow_the_previous_frame() {
        let prev = -DQuat::from_axis_angle(DVec3::X, 0.3);
        let mut q = vec![
            DQuat::from_axis_angle(DVec3::X, 0.35),
            -DQuat::from_axis_angle(DVec3::X, 0.4),
        ];
        let (_, mean) = orient(&mut q, Some(prev), SignMode::Consistent);
        assert!(q[0].dot(prev) > 0.99 && q[1].dot(prev) > 0.99);
        assert!(mean.dot(prev) > 0.99);
    }

    #[test]
    fn mean_of_equal_rotations_is_that_rotation() {
        let r = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 2.0);
        let m = mean_rotation(&[r, -r, r]);
        assert!(m.dot(r).abs() > 1.0 - 1e-9);
    }
}
