//! Per-triangle deformation gradients between a reference and a deformed
//! mesh (Sumner & Popović 2004, "Deformation Transfer", Sec. 3), and their
//! polar decomposition into rotation and stretch (Casas et al. 2013, Eq. 1;
//! de Aguiar et al. 2007, Sec. 4.1).
//!
//! A triangle (v1, v2, v3) gets a fourth vertex off its plane,
//! `v4 = v1 + (v2 − v1) × (v3 − v1) / √|(v2 − v1) × (v3 − v1)|`, so that
//! the frame `V = [v2 − v1, v3 − v1, v4 − v1]` is invertible. The gradient
//! is `T = Ṽ V⁻¹`, the affine map taking the reference triangle to the
//! deformed one. `T = R S` with `R` a rotation and `S` symmetric.

use glam::{DMat3, DQuat, DVec3};

/// The frame matrix of a triangle (columns: two edges and the scaled normal).
pub(crate) fn triangle_frame(a: DVec3, b: DVec3, c: DVec3) -> DMat3 {
    let (e1, e2) = (b - a, c - a);
    let n = e1.cross(e2);
    let len = n.length();
    let n = if len > 0.0 {
        n / len.sqrt()
    } else {
        DVec3::ZERO
    };
    DMat3::from_cols(e1, e2, n)
}

/// Inverted reference frames, computed once per reference mesh.
#[derive(Debug, Clone)]
pub struct RestFrames {
    inv: Vec<DMat3>,
    /// Triangles whose reference frame is singular (zero area); their gradient is the identity.
    pub degenerate: Vec<u32>,
}

#[inline]
pub(crate) fn dvec(p: [f64; 3]) -> DVec3 {
    DVec3::from_array(p)
}

impl RestFrames {
    /// Frames of the reference positions.
    pub fn new(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> RestFrames {
        let mut degenerate = Vec::new();
        let inv = triangles
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                let [a, b, c] = tri.map(|v| dvec(positions[v as usize]));
                let m = triangle_frame(a, b, c);
                let d = m.determinant();
                if d.abs() <= f64::MIN_POSITIVE || !d.is_finite() {
                    degenerate.push(t as u32);
                    DMat3::ZERO
                } else {
                    m.inverse()
                }
            })
            .collect();
        RestFrames { inv, degenerate }
    }

    /// Deformation gradients of `positions` relative to the reference, into `out`.
    pub(crate) fn gradients_into(
        &self,
        positions: &[[f64; 3]],
        triangles: &[[u32; 3]],
        out: &mut [DMat3],
    ) {
        for ((o, tri), inv) in out.iter_mut().zip(triangles).zip(&self.inv) {
            if *inv == DMat3::ZERO {
                *o = DMat3::IDENTITY;
                continue;
            }
            let [a, b, c] = tri.map(|v| dvec(positions[v as usize]));
            *o = triangle_frame(a, b, c) * *inv;
        }
    }

    /// Deformation gradients of `positions` relative to the reference.
    pub fn gradients(&self, positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<DMat3> {
        let mut out = vec![DMat3::IDENTITY; triangles.len()];
        self.gradients_into(positions, triangles, &mut out);
        out
    }
}

/// Polar decomposition `m = R S`: `R` a rotation (as a unit quaternion), `S`
/// symmetric. Scaled Newton iteration (Higham 1986), about ten 3×3 inverses;
/// an SVD where `det m ≤ 0` (an inverted triangle: `R` is then the nearest
/// rotation and `S` has a negative eigenvalue).
pub fn polar(m: DMat3) -> (DQuat, DMat3) {
    let det = m.determinant();
    let r = if det > 1e-300 && m.is_finite() {
        newton_polar(m).unwrap_or_else(|| svd_rotation(m))
    } else {
        svd_rotation(m)
    };
    let s = r.transpose() * m;
    let s = (s + s.transpose()) * 0.5;
    (DQuat::from_mat3(&r).normalize(), s)
}

fn newton_polar(m: DMat3) -> Option<DMat3> {
    let mut x = m;
    for _ in 0..30 {
        let inv_t = x.inverse().transpose();
        let (nx, ni) = (frob(x), frob(inv_t));
        let g = (ni / nx).sqrt();
        let next = (x * g + inv_t * (1.0 / g)) * 0.5;
        let delta = frob(next - x);
        x = next;
        if delta <= 1e-13 * frob(x) {
            return Some(x);
        }
    }
    None
}

fn frob(m: DMat3) -> f64 {
    (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared()).sqrt()
}

fn svd_rotation(m: DMat3) -> DMat3 {
    if !m.is_finite() {
        return DMat3::IDENTITY;
    }
    let a = nalgebra::Matrix3::from_column_slice(&m.to_cols_array());
    let svd = a.svd(true, true);
    let (Some(u), Some(vt)) = (svd.u, svd.v_t) else {
        return DMat3::IDENTITY;
    };
    let mut r = u * vt;
    if r.determinant() < 0.0 {
        // Flip the axis of the smallest singular value.
        let k = (0..3)
            .min_by(|&i, &j| svd.singular_values[i].total_cmp(&svd.singular_values[j]))
            .unwrap_or(2);
        let mut u2 = u;
        u2.column_mut(k).neg_mut();
        r = u2 * vt;
    }
    DMat3::from_cols_slice(r.as_slice())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polar_recovers_rotation_and_symmetric_stretch() {
        let r = DQuat::from_euler(glam::EulerRot::ZYX, 0.7, -0.4, 2.1);
        let s = DMat3::from_cols(
            DVec3::new(1.3, 0.2, 0.1),
            DVec3::new(0.2, 0.8, -0.05),
            DVec3::new(0.1, -0.05, 1.1),
        );
        let m = DMat3::from_quat(r) * s;
        let (q, s2) = polar(m);
        assert!(q.dot(r).abs() > 1.0 - 1e-12);
        assert!(frob(s2 - s) < 1e-10);
        // Inverted: still a proper rotation.
        let (q, _) = polar(DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0)));
        assert!((DMat3::from_quat(q).determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn gradient_of_an_affine_map_is_that_map() {
        let p = [[0.0f64, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let t = [[0u32, 1, 2]];
        let rest = RestFrames::new(&p, &t);
        let r = DMat3::from_quat(DQuat::from_rotation_y(0.5));
        let q: Vec<[f64; 3]> = p
            .iter()
            .map(|v| (r * dvec(*v) + DVec3::ONE).to_array())
            .collect();
        let g = rest.gradients(&q, &t);
        assert!(frob(g[0] - r) < 1e-6);
    }
}
