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
    /// Each triangle's unit first edge and unit normal in the reference
    /// (zero for a degenerate triangle): the orthonormal frame
    /// [`RestFrames::polar`] reduces a gradient to its plane with.
    planes: Vec<[DVec3; 2]>,
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
        let mut planes = Vec::with_capacity(triangles.len());
        let inv = triangles
            .iter()
            .enumerate()
            .map(|(t, tri)| {
                let [a, b, c] = tri.map(|v| dvec(positions[v as usize]));
                let m = triangle_frame(a, b, c);
                let d = m.determinant();
                if d.abs() <= f64::MIN_POSITIVE || !d.is_finite() {
                    degenerate.push(t as u32);
                    planes.push([DVec3::ZERO; 2]);
                    DMat3::ZERO
                } else {
                    let u = (b - a).normalize_or_zero();
                    planes.push([u, (b - a).cross(c - a).normalize_or_zero()]);
                    m.inverse()
                }
            })
            .collect();
        RestFrames {
            inv,
            planes,
            degenerate,
        }
    }

    /// The polar decomposition `g = R S` of triangle `t`'s gradient `g`
    /// ([`RestFrames::gradients_into`]), as [`polar`] gives it, in closed
    /// form. Such a gradient maps the reference triangle's plane onto the
    /// deformed one's and its normal onto the deformed normal, scaled: in
    /// orthonormal frames of the two planes it is `diag(A, s)` with `A`
    /// 2×2 of positive determinant, whose polar decomposition is a plane
    /// rotation by `atan2(a₂₁ − a₁₂, a₁₁ + a₂₂)` (Higham 1986, Sec. 2, the
    /// 2×2 case). One pass instead of [`polar`]'s Newton iteration (about
    /// ten 3×3 inverses); [`polar`] itself where the frames do not exist
    /// (a triangle degenerate in either mesh, a gradient not finite).
    #[inline]
    pub fn polar(&self, t: usize, g: DMat3) -> (DQuat, DMat3) {
        plane_polar(g, self.planes[t]).unwrap_or_else(|| polar(g))
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

/// [`RestFrames::polar`]'s closed form, `None` where a frame is missing.
#[inline]
fn plane_polar(g: DMat3, [u1, rest_n]: [DVec3; 2]) -> Option<(DQuat, DMat3)> {
    let u2 = rest_n.cross(u1);
    let (a, b, c) = (g * u1, g * u2, g * rest_n);
    let s3 = c.length();
    let n = c / s3;
    let v1 = (a - n * n.dot(a)).normalize_or_zero();
    let v2 = n.cross(v1);
    let [a11, a12, a21, a22] = [v1.dot(a), v1.dot(b), v2.dot(a), v2.dot(b)];
    let det = a11 * a22 - a12 * a21;
    if !(s3 > 1e-150 && det > 0.0 && det.is_finite() && v1 != DVec3::ZERO) {
        return None;
    }
    let (y, x) = (a21 - a12, a11 + a22);
    let h = (x * x + y * y).sqrt();
    let (cos, sin) = (x / h, y / h);
    let (w1, w2) = (v1 * cos + v2 * sin, v2 * cos - v1 * sin);
    let outer = |p: DVec3, q: DVec3| DMat3::from_cols(p * q.x, p * q.y, p * q.z);
    let r = outer(w1, u1) + outer(w2, u2) + outer(n, rest_n);
    let s = r.transpose() * g;
    let s = (s + s.transpose()) * 0.5;
    Some((DQuat::from_mat3(&r).normalize(), s))
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

    /// The closed form agrees with Newton's iteration on triangles of
    /// every shape (slivers, needles, large and tiny), deformed by random
    /// stretches, shears, rotations and scales, including near-flattening
    /// ones; and it falls back to [`polar`] where a triangle is degenerate.
    #[test]
    fn plane_polar_is_newtons_polar() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let v3 = |r: &mut dyn FnMut() -> f64| DVec3::new(r(), r(), r());
        let (mut worst_r, mut worst_s) = (0.0f64, 0.0f64);
        for case in 0..20_000 {
            let scale = 10f64.powf(3.0 * rnd());
            let mut p = [v3(&mut rnd), v3(&mut rnd), v3(&mut rnd)].map(|v| v * scale);
            if case % 7 == 0 {
                // A sliver: the third vertex nearly on the first edge.
                p[2] = p[0] + (p[1] - p[0]) * 0.4 + v3(&mut rnd) * scale * 1e-4;
            }
            let q = DQuat::from_scaled_axis(v3(&mut rnd) * 3.0);
            let mut m = DMat3::from_cols(v3(&mut rnd), v3(&mut rnd), v3(&mut rnd)) * 0.6
                + DMat3::from_quat(q);
            if case % 5 == 0 {
                m = DMat3::from_quat(q) * (1.0 + 0.2 * rnd());
            }
            let d: Vec<[f64; 3]> = p
                .iter()
                .map(|v| (m * *v + v3(&mut rnd)).to_array())
                .collect();
            let rest = RestFrames::new(&p.map(|v| v.to_array()), &[[0, 1, 2]]);
            let g = rest.gradients(&d, &[[0, 1, 2]])[0];
            let (qa, sa) = polar(g);
            let (qb, sb) = rest.polar(0, g);
            let fr = frob(sa).max(1e-300);
            worst_r = worst_r.max(1.0 - qa.dot(qb).abs());
            worst_s = worst_s.max(frob(sa - sb) / fr);
        }
        assert!(worst_r < 1e-12, "rotations differ by {worst_r}");
        assert!(worst_s < 1e-9, "stretches differ by {worst_s}");
        // Degenerate rest triangle: Newton's (the identity).
        let rest = RestFrames::new(&[[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], &[[0, 1, 2]]);
        assert_eq!(rest.polar(0, DMat3::IDENTITY), polar(DMat3::IDENTITY));
        // Deformed triangle collapsed to a line: the fallback's rotation.
        let rest = RestFrames::new(&[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], &[[0, 1, 2]]);
        let flat = [[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        let g = rest.gradients(&flat, &[[0, 1, 2]])[0];
        assert_eq!(rest.polar(0, g), polar(g));
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
