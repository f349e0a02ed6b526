//! Non-linear mesh blending `G(M1, M2, α)` (Casas et al. 2013, Eqs. 1-2;
//! Huang et al. 2015, Sec. 4.4), and its N-way weighted form.
//!
//! Every input is described by per-triangle deformation gradients from one
//! fixed reference mesh (the character's topology mesh), split by polar
//! decomposition into rotation `R` and stretch `S`. The blend interpolates
//! rotations spherically (slerp; for N inputs, the normalised weighted sum of
//! sign-aligned quaternions) and stretches linearly, and stitches the
//! triangles back together with a Poisson solve on the reference's
//! prefactored Laplacian. The result is translated so its centroid is the
//! weighted mean of the inputs' centroids.
//!
//! Cost per blended frame: one pass over the triangles (slerp, lerp, 3×3
//! products, right-hand side) plus one prefactored 3-column solve. The polar
//! decompositions are per input frame ([`Blender::decompose`]), so they can
//! be cached and reused across blends.

use super::Mesh;
use super::frames::RestFrames;
use super::poisson::{Poisson, PoissonWorkspace, centroid};
use super::solver::SolveError;
use glam::{DMat3, DQuat, DVec3};

/// A symmetric 3×3 matrix `[xx, yy, zz, xy, xz, yz]`.
pub type Sym3 = [f64; 6];

/// Packs the symmetric part of a matrix.
#[inline]
pub fn sym3(m: DMat3) -> Sym3 {
    [
        m.x_axis.x,
        m.y_axis.y,
        m.z_axis.z,
        0.5 * (m.y_axis.x + m.x_axis.y),
        0.5 * (m.z_axis.x + m.x_axis.z),
        0.5 * (m.z_axis.y + m.y_axis.z),
    ]
}

/// `R · S` for a unit quaternion `R` (unnormalised input is taken as is) and symmetric `S`.
#[inline]
fn rot_times_sym(q: DQuat, s: &Sym3) -> DMat3 {
    let r = DMat3::from_quat(q);
    let cols = [
        DVec3::new(s[0], s[3], s[4]),
        DVec3::new(s[3], s[1], s[5]),
        DVec3::new(s[4], s[5], s[2]),
    ];
    DMat3::from_cols(r * cols[0], r * cols[1], r * cols[2])
}

/// One input frame as rotations, stretches and centroid.
#[derive(Debug, Clone, Default)]
pub struct FrameGradients {
    /// Rotation per triangle.
    pub rotation: Vec<DQuat>,
    /// Symmetric stretch per triangle, as `[xx, yy, zz, xy, xz, yz]`.
    pub stretch: Vec<Sym3>,
    /// Mean vertex position.
    pub centroid: DVec3,
}

/// A blender for one topology: reference frames and the prefactored Poisson system.
pub struct Blender {
    triangles: Vec<[u32; 3]>,
    rest: RestFrames,
    poisson: Poisson,
    n: usize,
}

/// Scratch for [`Blender::blend`]: no allocation per blended frame.
pub struct BlendWorkspace {
    cos: Vec<f64>,
    weights: Vec<[f64; 2]>,
    transforms: Vec<DMat3>,
    gradients: Vec<DMat3>,
    pw: PoissonWorkspace,
    x: Vec<[f64; 3]>,
}

impl Blender {
    /// Builds the blender for a reference mesh (any frame of the character
    /// works; the topology's rest frame is the natural choice).
    pub fn new(reference: &Mesh) -> Result<Blender, SolveError> {
        Ok(Blender {
            triangles: reference.triangles().to_vec(),
            rest: RestFrames::new(reference.positions(), reference.triangles()),
            poisson: Poisson::new(reference)?,
            n: reference.vertex_count(),
        })
    }

    /// Scratch space.
    pub fn workspace(&self) -> BlendWorkspace {
        BlendWorkspace {
            cos: vec![0.0; self.triangles.len()],
            weights: vec![[1.0, 0.0]; self.triangles.len()],
            transforms: vec![DMat3::IDENTITY; self.triangles.len()],
            gradients: vec![DMat3::IDENTITY; self.triangles.len()],
            pw: self.poisson.workspace(),
            x: vec![[0.0; 3]; self.n],
        }
    }

    /// Decomposes one frame (positions with the reference's topology).
    pub fn decompose(&self, positions: &[[f64; 3]], ws: &mut BlendWorkspace) -> FrameGradients {
        let mut out = FrameGradients::default();
        self.decompose_into(positions, ws, &mut out);
        out
    }

    /// [`Blender::decompose`] into an existing value (reusing its buffers).
    pub fn decompose_into(
        &self,
        positions: &[[f64; 3]],
        ws: &mut BlendWorkspace,
        out: &mut FrameGradients,
    ) {
        self.rest
            .gradients_into(positions, &self.triangles, &mut ws.gradients);
        out.rotation.resize(self.triangles.len(), DQuat::IDENTITY);
        out.stretch
            .resize(self.triangles.len(), [1.0, 1.0, 1.0, 0.0, 0.0, 0.0]);
        for ((g, r), s) in ws
            .gradients
            .iter()
            .zip(&mut out.rotation)
            .zip(&mut out.stretch)
        {
            let (q, st) = super::frames::polar(*g);
            *r = q;
            *s = sym3(st);
        }
        let s: DVec3 = positions.iter().map(|p| super::frames::dvec(*p)).sum();
        out.centroid = s / positions.len().max(1) as f64;
    }

    /// `G(a, b, α)`: the non-linear blend of two decomposed frames, written to `out`.
    pub fn blend(
        &self,
        a: &FrameGradients,
        b: &FrameGradients,
        alpha: f64,
        out: &mut [[f64; 3]],
        ws: &mut BlendWorkspace,
    ) {
        // Slerp weights in a separate pass over plain arrays: the per-triangle
        // chain (acos, sin, cos, divisions) is latency-bound, and independent
        // array lanes let the CPU overlap (and the compiler vectorise) them.
        for ((c, qa), qb) in ws.cos.iter_mut().zip(&a.rotation).zip(&b.rotation) {
            *c = qa.dot(*qb);
        }
        slerp_weights(&ws.cos, alpha, &mut ws.weights);
        self.poisson.assemble_with(&mut ws.pw, |t| {
            let [wa, wb] = ws.weights[t];
            // Unit up to the approximation error (< 1e-7): no normalisation.
            let r = a.rotation[t] * wa + b.rotation[t] * wb;
            let (sa, sb) = (&a.stretch[t], &b.stretch[t]);
            let s: Sym3 = std::array::from_fn(|k| sa[k] + (sb[k] - sa[k]) * alpha);
            rot_times_sym(r, &s)
        });
        let c = a.centroid * (1.0 - alpha) + b.centroid * alpha;
        self.finish(c, out, ws);
    }

    /// Weighted N-way blend. Weights are normalised to sum to 1.
    pub fn blend_many(
        &self,
        inputs: &[(&FrameGradients, f64)],
        out: &mut [[f64; 3]],
        ws: &mut BlendWorkspace,
    ) {
        let total: f64 = inputs.iter().map(|x| x.1).sum();
        let total = if total.abs() > 0.0 { total } else { 1.0 };
        let Some((first, _)) = inputs.first() else {
            return;
        };
        for (t, tr) in ws.transforms.iter_mut().enumerate() {
            let q0 = first.rotation[t];
            let mut q = DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0);
            let mut s = [0.0; 6];
            for (g, w) in inputs {
                let w = w / total;
                let qi = if g.rotation[t].dot(q0) < 0.0 {
                    -g.rotation[t]
                } else {
                    g.rotation[t]
                };
                q += qi * w;
                for (sk, gk) in s.iter_mut().zip(&g.stretch[t]) {
                    *sk += gk * w;
                }
            }
            let q = if q.length_squared() > 0.0 {
                q.normalize()
            } else {
                q0
            };
            *tr = rot_times_sym(q, &s);
        }
        let c: DVec3 = inputs.iter().map(|(g, w)| g.centroid * (w / total)).sum();
        self.stitch(c, out, ws);
    }

    /// Reconstructs from `ws.transforms` and places the centroid at `c`.
    fn stitch(&self, c: DVec3, out: &mut [[f64; 3]], ws: &mut BlendWorkspace) {
        self.poisson.assemble(&ws.transforms, &mut ws.pw);
        self.finish(c, out, ws);
    }

    /// Solves the assembled system and places the centroid at `c`.
    fn finish(&self, c: DVec3, out: &mut [[f64; 3]], ws: &mut BlendWorkspace) {
        self.poisson.solve(&mut ws.pw, &mut ws.x);
        let shift = c - centroid(&ws.x);
        for (o, x) in out.iter_mut().zip(&ws.x) {
            *o = (DVec3::from_array(*x) + shift).to_array();
        }
    }
}

/// Spherical linear interpolation along the shorter arc, without library
/// transcendentals (the per-triangle slerp dominates a blend's cost):
/// `θ = acos(cos θ)` by Abramowitz & Stegun 4.4.46 (|error| ≤ 2e-8 rad) and
/// `sin tθ`, `cos tθ` by their Taylor series to degree 17/16 on `[0, π/2]`
/// (error below 1e-12), then `sin((1−t)θ) = sin θ cos tθ − cos θ sin tθ`.
/// Normalised lerp when the quaternions are within 0.0045 rad (d > 0.99999),
/// where the two agree to 2e-9 rad (the error grows as the cube of the angle). The
/// result is normalised, so weights' small errors never change its length.
#[inline]
pub fn slerp(a: DQuat, b: DQuat, t: f64) -> DQuat {
    let [wa, wb] = slerp_weight(a.dot(b), t);
    (a * wa + b * wb).normalize()
}

/// The weights `(w_a, w_b)` with `slerp(a, b, t) ∝ w_a a + w_b b`, from
/// `cos θ = a · b` (negative: the shorter arc, through `−b`).
///
/// Branch-free (both the slerp and the normalised-lerp weights are computed
/// and one is selected), so [`slerp_weights`] vectorises.
#[inline]
fn slerp_weight(dot: f64, t: f64) -> [f64; 2] {
    let sign = if dot < 0.0 { -1.0 } else { 1.0 };
    let d = (dot * sign).min(1.0);
    let near = d > 0.99999;
    // Normalised lerp, with the normalisation folded into the weights.
    let n = ((1.0 - t) * (1.0 - t) + t * t + 2.0 * t * (1.0 - t) * d).sqrt();
    let th = fast_acos(d);
    let s = (1.0 - d * d).sqrt();
    let s = if near { 1.0 } else { s };
    let (st, ct) = fast_sin_cos(t * th);
    let (wa, wb) = ((s * ct - d * st) / s, st / s);
    if near {
        [(1.0 - t) / n, t * sign / n]
    } else {
        [wa, sign * wb]
    }
}

/// [`slerp_weight`] for every entry of `cos`.
fn slerp_weights(cos: &[f64], t: f64, out: &mut [[f64; 2]]) {
    for (o, &c) in out.iter_mut().zip(cos) {
        *o = slerp_weight(c, t);
    }
}

/// acos on [0, 1], Abramowitz & Stegun 4.4.46, |error| ≤ 2e-8.
#[inline]
fn fast_acos(x: f64) -> f64 {
    let p = -0.0012624911f64;
    let p = p * x + 0.0066700901;
    let p = p * x + -0.0170881256;
    let p = p * x + 0.0308918810;
    let p = p * x + -0.0501743046;
    let p = p * x + 0.0889789874;
    let p = p * x + -0.2145988016;
    let p = p * x + 1.5707963050;
    (1.0 - x).sqrt() * p
}

/// (sin y, cos y) for y in [0, π/2] by Taylor series (error < 1e-12).
#[inline]
fn fast_sin_cos(y: f64) -> (f64, f64) {
    let y2 = y * y;
    // sin: y (1 − y²/3! + y⁴/5! − … − y¹⁶/17!) ; cos: 1 − y²/2! + … + y¹⁶/16!
    let mut s: f64 = 1.0 / 355687428096000.0; // 1/17!
    let mut c: f64 = 1.0 / 20922789888000.0; // 1/16!
    for (ks, kc) in [
        (-1.0 / 1307674368000.0, -1.0 / 87178291200.0),
        (1.0 / 6227020800.0, 1.0 / 479001600.0),
        (-1.0 / 39916800.0, -1.0 / 3628800.0),
        (1.0 / 362880.0, 1.0 / 40320.0),
        (-1.0 / 5040.0, -1.0 / 720.0),
        (1.0 / 120.0, 1.0 / 24.0),
        (-1.0 / 6.0, -1.0 / 2.0),
        (1.0, 1.0),
    ] {
        s = s * y2 + ks;
        c = c * y2 + kc;
    }
    (s * y, c)
}

/// Convenience: `G(m1, m2, α)` with `m1` as the reference. For many blends on
/// one character build a [`Blender`] once instead.
pub fn blend(m1: &Mesh, m2: &[[f64; 3]], alpha: f64) -> Result<Vec<[f64; 3]>, SolveError> {
    let b = Blender::new(m1)?;
    let mut ws = b.workspace();
    let g1 = b.decompose(m1.positions(), &mut ws);
    let g2 = b.decompose(m2, &mut ws);
    let mut out = vec![[0.0; 3]; m1.vertex_count()];
    b.blend(&g1, &g2, alpha, &mut out, &mut ws);
    Ok(out)
}

/// Plain vertex lerp `(1 − α) a + α b`, for comparison.
pub fn linear_blend(a: &[[f64; 3]], b: &[[f64; 3]], alpha: f64) -> Vec<[f64; 3]> {
    let al = alpha;
    a.iter()
        .zip(b)
        .map(|(p, q)| std::array::from_fn(|k| p[k] * (1.0 - al) + q[k] * al))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An icosahedron subdivided twice (162 vertices): small, closed, curved.
    fn bumpy() -> Mesh {
        let m = crate::mesh::subdivide::midpoint(&crate::mesh::subdivide::icosahedron());
        crate::mesh::subdivide::midpoint(&m)
    }

    /// A blender on `m1` and the decompositions of `m1` and `m2`.
    fn setup(
        m1: &Mesh,
        m2: &[[f64; 3]],
    ) -> (Blender, BlendWorkspace, FrameGradients, FrameGradients) {
        let b = Blender::new(m1).unwrap();
        let mut ws = b.workspace();
        let g1 = b.decompose(m1.positions(), &mut ws);
        let g2 = b.decompose(m2, &mut ws);
        (b, ws, g1, g2)
    }

    fn close(a: &[[f64; 3]], b: &[[f64; 3]], tol: f64) -> bool {
        a.iter()
            .zip(b)
            .all(|(p, q)| (0..3).all(|k| (p[k] - q[k]).abs() <= tol))
    }

    #[test]
    fn fast_slerp_matches_glam() {
        let a = DQuat::from_euler(glam::EulerRot::ZYX, 0.3, -1.1, 0.8);
        for (k, ang) in [0.001, 0.02, 0.5, 2.0, 3.1].into_iter().enumerate() {
            let b = DQuat::from_axis_angle(DVec3::new(1.0, k as f64, -0.5).normalize(), ang) * a;
            for t in [0.0, 0.1, 0.5, 0.93, 1.0] {
                let (x, y) = (slerp(a, b, t), a.slerp(b, t));
                assert!(
                    x.angle_between(y) < 1e-7,
                    "{ang} {t}: {}",
                    x.angle_between(y)
                );
            }
            assert!(slerp(a, -b, 0.3).angle_between(a.slerp(b, 0.3)) < 1e-7);
        }
        for k in 0..=1000 {
            let y = std::f64::consts::FRAC_PI_2 * k as f64 / 1000.0;
            let (s, c) = fast_sin_cos(y);
            assert!(
                (s - y.sin()).abs() < 1e-12 && (c - y.cos()).abs() < 1e-12,
                "{y}"
            );
            let x = k as f64 / 1000.0;
            assert!((fast_acos(x) - x.acos()).abs() < 3e-8, "{x}");
        }
    }

    #[test]
    fn endpoints_and_identity() {
        let m1 = bumpy();
        let m2: Vec<[f64; 3]> = m1
            .positions()
            .iter()
            .map(|p| [p[0] * 1.3, p[1] + 0.2 * p[0] * p[0], p[2]])
            .collect();
        let (b, mut ws, g1, g2) = setup(&m1, &m2);
        let mut out = vec![[0.0; 3]; m1.vertex_count()];
        let diag = m1.bounds().diagonal();
        b.blend(&g1, &g2, 0.0, &mut out, &mut ws);
        assert!(close(&out, m1.positions(), 1e-5 * diag));
        b.blend(&g1, &g2, 1.0, &mut out, &mut ws);
        assert!(close(&out, &m2, 1e-5 * diag));
        b.blend(&g1, &g1, 0.37, &mut out, &mut ws);
        assert!(close(&out, m1.positions(), 1e-5 * diag));
    }

    #[test]
    fn rigid_rotation_blends_to_the_partial_rotation() {
        let m1 = bumpy();
        let axis = DVec3::new(0.3, 1.0, -0.2).normalize();
        let rot = DQuat::from_axis_angle(axis, 2.0);
        let m2: Vec<[f64; 3]> = m1
            .positions()
            .iter()
            .map(|p| (rot * super::super::frames::dvec(*p)).to_array())
            .collect();
        let (b, mut ws, g1, g2) = setup(&m1, &m2);
        let mut out = vec![[0.0; 3]; m1.vertex_count()];
        let c1 = g1.centroid;
        for alpha in [0.25, 0.5, 0.8] {
            b.blend(&g1, &g2, alpha, &mut out, &mut ws);
            let ra = DQuat::from_axis_angle(axis, 2.0 * alpha);
            let c = c1 * (1.0 - alpha) + (rot * c1) * alpha;
            let want: Vec<[f64; 3]> = m1
                .positions()
                .iter()
                .map(|p| (ra * (super::super::frames::dvec(*p) - c1) + c).to_array())
                .collect();
            assert!(
                close(&out, &want, 1e-5 * m1.bounds().diagonal()),
                "alpha {alpha}"
            );
        }
    }
}
