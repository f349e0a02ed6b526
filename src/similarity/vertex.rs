//! Vertex distance with a velocity term (Casas et al. 2013, Sec. 3.2.1;
//! Huang et al. 2015, Fig. 4c).
//!
//! `d(M_i, M_j) = (1/N_v) (‖X_i − X_j‖² + λ ‖V_i − V_j‖²)`, with
//! `V(t) = X(t) − X(t−1)` (per frame; the first frame of a sequence uses
//! the forward difference). Corresponding vertices are known, but two frames
//! of a capture stand at different places and headings, so the distance is
//! taken after the rigid motion on the floor that minimises it: horizontal
//! centroids together, and the rotation about the vertical in closed form
//! (`Σ a·R b = Y + C cos θ + S sin θ` is largest at `√(C² + S²)`), applied
//! to positions and velocities alike. We report `√d`, an RMS distance in
//! the file's length unit, so thresholds read as lengths.
//!
//! Per frame we store the centred positions and the scaled velocities as
//! one struct-of-arrays block of `2 N_v` f32 points (24 bytes per vertex);
//! a pair costs five dot products of length `2 N_v`, accumulated in f64.

use glam::DVec3;

/// Options of the vertex measure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VertexOptions {
    /// Weight λ of the velocity term. Default: 1 (velocities per frame).
    pub velocity_weight: f64,
}

impl Default for VertexOptions {
    fn default() -> Self {
        VertexOptions {
            velocity_weight: 1.0,
        }
    }
}

/// Writes frame `t`'s block (`6 N_v` f32: x, y, z of the `2 N_v` points) and
/// returns its squared norm. `prev` is the previous frame of the same
/// sequence (or `None` at the first, with `next` the following one).
pub fn describe(
    x: &[DVec3],
    prev: Option<&[DVec3]>,
    next: Option<&[DVec3]>,
    opts: &VertexOptions,
    out: &mut [f32],
) -> f64 {
    let n = x.len();
    let c = x.iter().copied().sum::<DVec3>() / n.max(1) as f64;
    let c = DVec3::new(c.x, 0.0, c.z);
    let w = opts.velocity_weight.max(0.0).sqrt();
    let m = 2 * n;
    let (ox, rest) = out.split_at_mut(m);
    let (oy, oz) = rest.split_at_mut(m);
    let mut norm = 0.0;
    for i in 0..n {
        let p = x[i] - c;
        let v = match (prev, next) {
            (Some(q), _) => x[i] - q[i],
            (None, Some(q)) => q[i] - x[i],
            (None, None) => DVec3::ZERO,
        } * w;
        for (k, q) in [(i, p), (n + i, v)] {
            ox[k] = q.x as f32;
            oy[k] = q.y as f32;
            oz[k] = q.z as f32;
            norm += (ox[k] as f64).powi(2) + (oy[k] as f64).powi(2) + (oz[k] as f64).powi(2);
        }
    }
    norm
}

/// `√d` between two blocks of [`describe`] with squared norms `na`, `nb`,
/// for `n` vertices.
pub fn distance(a: &[f32], na: f64, b: &[f32], nb: f64, n: usize) -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
            // SAFETY: the CPU has the features the function is built for.
            return unsafe { distance_avx2(a, na, b, nb, n) };
        }
    }
    distance_body(a, na, b, nb, n)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn distance_avx2(a: &[f32], na: f64, b: &[f32], nb: f64, n: usize) -> f64 {
    distance_body(a, na, b, nb, n)
}

#[inline(always)]
#[allow(clippy::needless_range_loop)] // explicit lanes vectorise
fn distance_body(a: &[f32], na: f64, b: &[f32], nb: f64, n: usize) -> f64 {
    let m = 2 * n;
    let (ax, ay, az) = (&a[..m], &a[m..2 * m], &a[2 * m..3 * m]);
    let (bx, by, bz) = (&b[..m], &b[m..2 * m], &b[2 * m..3 * m]);
    // Lanes of [xx + zz, xz − zx, yy].
    let mut acc = [[0.0f64; 4]; 3];
    let full = m / 4 * 4;
    for q in (0..full).step_by(4) {
        for l in 0..4 {
            let i = q + l;
            let (px, py, pz) = (ax[i] as f64, ay[i] as f64, az[i] as f64);
            let (qx, qy, qz) = (bx[i] as f64, by[i] as f64, bz[i] as f64);
            acc[0][l] += px * qx + pz * qz;
            acc[1][l] += px * qz - pz * qx;
            acc[2][l] += py * qy;
        }
    }
    for i in full..m {
        let (px, py, pz) = (ax[i] as f64, ay[i] as f64, az[i] as f64);
        let (qx, qy, qz) = (bx[i] as f64, by[i] as f64, bz[i] as f64);
        acc[0][0] += px * qx + pz * qz;
        acc[1][0] += px * qz - pz * qx;
        acc[2][0] += py * qy;
    }
    let sum = |l: [f64; 4]| (l[0] + l[1]) + (l[2] + l[3]);
    let (c, s, y) = (sum(acc[0]), sum(acc[1]), sum(acc[2]));
    let d = (na + nb - 2.0 * (y + c.hypot(s))) / n.max(1) as f64;
    d.max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn distance_ignores_floor_motion_and_sees_shape() {
        let x: Vec<DVec3> = (0..37)
            .map(|i| {
                let t = i as f64 * 0.37;
                DVec3::new(t.sin(), (t * 1.3).cos() + 1.0, (t * 0.7).sin() * 0.5)
            })
            .collect();
        let prev: Vec<DVec3> = x.iter().map(|p| *p * 0.99).collect();
        let q = DQuat::from_rotation_y(1.1);
        let t = DVec3::new(2.0, 0.0, -1.0);
        let x2: Vec<DVec3> = x.iter().map(|p| q * *p + t).collect();
        let prev2: Vec<DVec3> = prev.iter().map(|p| q * *p + t).collect();
        let o = VertexOptions::default();
        let n = x.len();
        let mut a = vec![0.0; 6 * n];
        let mut b = vec![0.0; 6 * n];
        let na = describe(&x, Some(&prev), None, &o, &mut a);
        let nb = describe(&x2, Some(&prev2), None, &o, &mut b);
        assert!(distance(&a, na, &a, na, n) < 1e-7);
        assert!(distance(&a, na, &b, nb, n) < 1e-3);
        assert!(distance(&b, nb, &a, na, n) < 1e-3);
        // Same positions, different velocity: only the velocity term.
        let mut c = vec![0.0; 6 * n];
        let nc = describe(&x, Some(&x), None, &o, &mut c);
        let d = distance(&a, na, &c, nc, n);
        let v_rms = (x
            .iter()
            .zip(&prev)
            .map(|(p, q)| (*p - *q).length_squared())
            .sum::<f64>()
            / n as f64)
            .sqrt();
        assert!((d - v_rms).abs() < 1e-5 * v_rms.max(1.0), "{d} {v_rms}");
    }
}
