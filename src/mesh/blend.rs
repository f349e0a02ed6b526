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
use super::stray::StrayVertices;
use glam::{DMat3, DQuat, DVec3};
use rayon::prelude::*;

/// A symmetric 3×3 matrix `[xx, yy, zz, xy, xz, yz]`.
pub(crate) type Sym3 = [f64; 6];

/// Packs the symmetric part of a matrix.
#[inline]
pub(crate) fn sym3(m: DMat3) -> Sym3 {
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
#[inline(always)]
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
    /// Each vertex in no triangle's offset from its carrier
    /// ([`crate::mesh::stray`]), blended as the centroid is; empty when
    /// every vertex is in a triangle.
    pub stray: Vec<[f64; 3]>,
}

/// A blender for one topology: reference frames and the prefactored Poisson system.
pub struct Blender {
    triangles: Vec<[u32; 3]>,
    rest: RestFrames,
    poisson: Poisson,
    n: usize,
    /// Vertices in no triangle, placed at their carrier's position plus
    /// the inputs' offsets blended ([`crate::mesh::stray`]).
    stray: Option<StrayVertices>,
}

/// Scratch for [`Blender::blend`]: no allocation per blended frame.
pub struct BlendWorkspace {
    edges: Vec<[DVec3; 3]>,
    transforms: Vec<DMat3>,
    gradients: Vec<DMat3>,
    pw: PoissonWorkspace,
    x: Vec<[f64; 3]>,
    /// The blended offsets of the vertices in no triangle.
    stray: Vec<[f64; 3]>,
}

impl Blender {
    /// Builds the blender for a reference mesh (any frame of the character
    /// works; the topology's rest frame is the natural choice).
    pub fn new(reference: &Mesh) -> Result<Blender, SolveError> {
        let stray = StrayVertices::of(reference.positions(), reference.triangles());
        Ok(Blender {
            triangles: reference.triangles().to_vec(),
            rest: RestFrames::new(reference.positions(), reference.triangles()),
            poisson: Poisson::new(reference)?,
            n: reference.vertex_count(),
            stray,
        })
    }

    /// Scratch space.
    pub fn workspace(&self) -> BlendWorkspace {
        BlendWorkspace {
            edges: vec![[DVec3::ZERO; 3]; self.triangles.len()],
            transforms: vec![DMat3::IDENTITY; self.triangles.len()],
            gradients: vec![DMat3::IDENTITY; self.triangles.len()],
            pw: self.poisson.workspace(),
            x: vec![[0.0; 3]; self.n],
            stray: vec![[0.0; 3]; self.stray.as_ref().map_or(0, StrayVertices::len)],
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
        // One polar decomposition per triangle, each on its own, in
        // closed form ([`RestFrames::polar`]), split over the threads (the
        // same bits as in order; a live frame blended from two database
        // frames spent 10.7 ms here on one thread with Newton's iteration).
        let rest = &self.rest;
        ws.gradients
            .par_iter()
            .zip(out.rotation.par_iter_mut())
            .zip(out.stretch.par_iter_mut())
            .enumerate()
            .with_min_len(1024)
            .for_each(|(t, ((g, r), s))| {
                let (q, st) = rest.polar(t, *g);
                *r = q;
                *s = sym3(st);
            });
        let s: DVec3 = positions.iter().map(|p| super::frames::dvec(*p)).sum();
        out.centroid = s / positions.len().max(1) as f64;
        out.stray.clear();
        if let Some(st) = &self.stray {
            st.offsets_into(positions, &mut out.stray);
        }
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
        blend_edges(a, b, alpha, self.poisson.corner_vectors(), &mut ws.edges);
        self.poisson.assemble_shares(&ws.edges, &mut ws.pw);
        let c = a.centroid * (1.0 - alpha) + b.centroid * alpha;
        for ((o, p), q) in ws.stray.iter_mut().zip(&a.stray).zip(&b.stray) {
            *o = std::array::from_fn(|d| p[d] * (1.0 - alpha) + q[d] * alpha);
        }
        self.finish(c, out, ws);
    }

    /// Weighted N-way blend. Weights are normalised to sum to 1.
    pub(crate) fn blend_many(
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
        ws.stray.fill([0.0; 3]);
        for (g, w) in inputs {
            for (o, p) in ws.stray.iter_mut().zip(&g.stray) {
                for d in 0..3 {
                    o[d] += p[d] * (w / total);
                }
            }
        }
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
        if let Some(s) = &self.stray {
            s.carry_offsets(&ws.stray, &mut ws.x);
        }
        let shift = c - centroid(&ws.x);
        for (o, x) in out.iter_mut().zip(&ws.x) {
            *o = (DVec3::from_array(*x) + shift).to_array();
        }
    }
}

/// The blended target edges of every triangle,
/// `R(α) S(α) e_k` with `R(α)` the slerp of the inputs' rotations and `S(α)`
/// the lerp of their stretches (Casas 2013, Eq. 1), `e_k` the weighted
/// reference edges. One independent pass over the triangles; on x86-64 it
/// runs in an AVX2+FMA build of the same code when the CPU has them.
fn blend_edges(
    a: &FrameGradients,
    b: &FrameGradients,
    alpha: f64,
    g: &[[DVec3; 3]],
    out: &mut [[DVec3; 3]],
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
        // SAFETY: the CPU has the features the function is compiled for.
        unsafe { blend_edges_avx2(a, b, alpha, g, out) };
        return;
    }
    blend_edges_body::<false>(a, b, alpha, g, out);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn blend_edges_avx2(
    a: &FrameGradients,
    b: &FrameGradients,
    alpha: f64,
    g: &[[DVec3; 3]],
    out: &mut [[DVec3; 3]],
) {
    // Unfused: `mul_add` inside the lane closures (not inlined into this
    // function, so built without FMA) became a call into libm's `fma`.
    blend_edges_body::<false>(a, b, alpha, g, out);
}

/// `a · b + c`, fused where the build has FMA.
#[inline(always)]
fn madd<const FMA: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FMA { a.mul_add(b, c) } else { a * b + c }
}

/// `m · v` for a column-major 3×3 `m`.
#[inline(always)]
fn mat_vec<const FMA: bool>(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    std::array::from_fn(|r| madd::<FMA>(m[0][r], v[0], madd::<FMA>(m[1][r], v[1], m[2][r] * v[2])))
}

/// Lanes processed together: four triangles' arithmetic is done lane by
/// lane on `[f64; LANES]` arrays, which the compiler maps onto SIMD registers.
const LANES: usize = 4;
type Lane = [f64; LANES];

#[inline(always)]
fn lanes(f: impl FnMut(usize) -> f64) -> Lane {
    std::array::from_fn(f)
}

#[inline(always)]
fn blend_edges_body<const FMA: bool>(
    a: &FrameGradients,
    b: &FrameGradients,
    alpha: f64,
    g: &[[DVec3; 3]],
    out: &mut [[DVec3; 3]],
) {
    let n = out.len();
    let full = n - n % LANES;
    for (((qa, qb), (sa, sb)), (gt, ot)) in a.rotation[..full]
        .chunks_exact(LANES)
        .zip(b.rotation[..full].chunks_exact(LANES))
        .zip(
            a.stretch[..full]
                .chunks_exact(LANES)
                .zip(b.stretch[..full].chunks_exact(LANES)),
        )
        .zip(
            g[..full]
                .chunks_exact(LANES)
                .zip(out[..full].chunks_exact_mut(LANES)),
        )
    {
        let qa: [Lane; 4] = std::array::from_fn(|c| lanes(|l| qa[l].to_array()[c]));
        let qb: [Lane; 4] = std::array::from_fn(|c| lanes(|l| qb[l].to_array()[c]));
        let dot = lanes(|l| {
            madd::<FMA>(
                qa[0][l],
                qb[0][l],
                madd::<FMA>(
                    qa[1][l],
                    qb[1][l],
                    madd::<FMA>(qa[2][l], qb[2][l], qa[3][l] * qb[3][l]),
                ),
            )
        });
        let (wa, wb) = slerp_weight_lanes::<FMA>(dot, alpha);
        let q: [Lane; 4] =
            std::array::from_fn(|c| lanes(|l| madd::<FMA>(qa[c][l], wa[l], qb[c][l] * wb[l])));
        let st: [Lane; 6] =
            std::array::from_fn(|c| lanes(|l| madd::<FMA>(sb[l][c] - sa[l][c], alpha, sa[l][c])));
        let m = rot_sym_lanes::<FMA>(&q, &st);
        // Each triangle's three corner vectors through its own M.
        let gv: [[Lane; 3]; 3] =
            std::array::from_fn(|k| std::array::from_fn(|c| lanes(|l| gt[l][k].to_array()[c])));
        for k in 0..3 {
            let r: [Lane; 3] = std::array::from_fn(|row| {
                lanes(|l| {
                    madd::<FMA>(
                        m[0][row][l],
                        gv[k][0][l],
                        madd::<FMA>(m[1][row][l], gv[k][1][l], m[2][row][l] * gv[k][2][l]),
                    )
                })
            });
            for l in 0..LANES {
                ot[l][k] = DVec3::new(r[0][l], r[1][l], r[2][l]);
            }
        }
    }
    for t in full..n {
        let (qa, qb) = (a.rotation[t], b.rotation[t]);
        let [wa, wb] = slerp_weight(qa.dot(qb), alpha);
        let q = (qa * wa + qb * wb).to_array();
        let (sa, sb) = (&a.stretch[t], &b.stretch[t]);
        let st: Sym3 = std::array::from_fn(|k| madd::<FMA>(sb[k] - sa[k], alpha, sa[k]));
        let m = rot_sym::<FMA>(q, st);
        out[t] = g[t].map(|v| DVec3::from_array(mat_vec::<FMA>(&m, v.to_array())));
    }
}

/// [`rot_sym`] lane by lane: `m[col][row]`.
#[inline(always)]
fn rot_sym_lanes<const FMA: bool>(q: &[Lane; 4], st: &[Lane; 6]) -> [[Lane; 3]; 3] {
    let [x, y, z, w] = q;
    let x2 = lanes(|l| x[l] + x[l]);
    let y2 = lanes(|l| y[l] + y[l]);
    let z2 = lanes(|l| z[l] + z[l]);
    let p = |a: &Lane, b: &Lane| lanes(|l| a[l] * b[l]);
    let (xx, xy, xz) = (p(x, &x2), p(x, &y2), p(x, &z2));
    let (yy, yz, zz) = (p(y, &y2), p(y, &z2), p(z, &z2));
    let (wx, wy, wz) = (p(w, &x2), p(w, &y2), p(w, &z2));
    let r = [
        [
            lanes(|l| 1.0 - (yy[l] + zz[l])),
            lanes(|l| xy[l] + wz[l]),
            lanes(|l| xz[l] - wy[l]),
        ],
        [
            lanes(|l| xy[l] - wz[l]),
            lanes(|l| 1.0 - (xx[l] + zz[l])),
            lanes(|l| yz[l] + wx[l]),
        ],
        [
            lanes(|l| xz[l] + wy[l]),
            lanes(|l| yz[l] - wx[l]),
            lanes(|l| 1.0 - (xx[l] + yy[l])),
        ],
    ];
    // Columns of S: (s0, s3, s4), (s3, s1, s5), (s4, s5, s2).
    let cols = [[0, 3, 4], [3, 1, 5], [4, 5, 2]];
    std::array::from_fn(|c| {
        let [i, j, k] = cols[c];
        std::array::from_fn(|row| {
            lanes(|l| {
                madd::<FMA>(
                    r[0][row][l],
                    st[i][l],
                    madd::<FMA>(r[1][row][l], st[j][l], r[2][row][l] * st[k][l]),
                )
            })
        })
    })
}

/// `R · S` (column-major) for a quaternion `[x, y, z, w]` (unit up to the
/// slerp's approximation error, < 1e-7: no normalisation) and symmetric `S`.
#[inline(always)]
fn rot_sym<const FMA: bool>(q: [f64; 4], st: Sym3) -> [[f64; 3]; 3] {
    let [x, y, z, w] = q;
    let (x2, y2, z2) = (x + x, y + y, z + z);
    let (xx, xy, xz) = (x * x2, x * y2, x * z2);
    let (yy, yz, zz) = (y * y2, y * z2, z * z2);
    let (wx, wy, wz) = (w * x2, w * y2, w * z2);
    let r = [
        [1.0 - (yy + zz), xy + wz, xz - wy],
        [xy - wz, 1.0 - (xx + zz), yz + wx],
        [xz + wy, yz - wx, 1.0 - (xx + yy)],
    ];
    [
        mat_vec::<FMA>(&r, [st[0], st[3], st[4]]),
        mat_vec::<FMA>(&r, [st[3], st[1], st[5]]),
        mat_vec::<FMA>(&r, [st[4], st[5], st[2]]),
    ]
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
/// and one is selected), so the per-triangle pass has no unpredictable branch.
#[inline(always)]
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

/// [`slerp_weight`] lane by lane, written as whole-lane steps so that every
/// step (including the square roots and divisions) becomes one SIMD operation.
#[inline(always)]
fn slerp_weight_lanes<const FMA: bool>(dot: Lane, t: f64) -> (Lane, Lane) {
    let sign = lanes(|l| if dot[l] < 0.0 { -1.0 } else { 1.0 });
    let d = lanes(|l| (dot[l] * sign[l]).min(1.0));
    let n = lanes(|l| madd::<FMA>(2.0 * t * (1.0 - t), d[l], (1.0 - t) * (1.0 - t) + t * t).sqrt());
    let mut p = [ACOS_POLY[0]; LANES];
    for &c in &ACOS_POLY[1..] {
        p = lanes(|l| madd::<FMA>(p[l], d[l], c));
    }
    let th = lanes(|l| (1.0 - d[l]).sqrt() * p[l]);
    let near = lanes(|l| if d[l] > 0.99999 { 1.0 } else { 0.0 });
    let s = lanes(|l| madd::<FMA>(-d[l], d[l], 1.0).sqrt());
    let inv_s = lanes(|l| 1.0 / if near[l] > 0.0 { 1.0 } else { s[l] });
    let y = lanes(|l| t * th[l]);
    let y2 = lanes(|l| y[l] * y[l]);
    let mut sn = [SIN_TAYLOR[0]; LANES];
    let mut cs = [COS_TAYLOR[0]; LANES];
    for k in 1..SIN_TAYLOR.len() {
        sn = lanes(|l| madd::<FMA>(sn[l], y2[l], SIN_TAYLOR[k]));
        cs = lanes(|l| madd::<FMA>(cs[l], y2[l], COS_TAYLOR[k]));
    }
    let sn = lanes(|l| sn[l] * y[l]);
    let inv_n = lanes(|l| 1.0 / n[l]);
    let wa = lanes(|l| {
        if near[l] > 0.0 {
            (1.0 - t) * inv_n[l]
        } else {
            (s[l] * cs[l] - d[l] * sn[l]) * inv_s[l]
        }
    });
    let wb = lanes(|l| {
        sign[l]
            * if near[l] > 0.0 {
                t * inv_n[l]
            } else {
                sn[l] * inv_s[l]
            }
    });
    (wa, wb)
}

/// Taylor coefficients of `sin(y)/y` and `cos(y)` in `y²`, highest first
/// (to degree 17 and 16).
const SIN_TAYLOR: [f64; 9] = [
    1.0 / 355687428096000.0,
    -1.0 / 1307674368000.0,
    1.0 / 6227020800.0,
    -1.0 / 39916800.0,
    1.0 / 362880.0,
    -1.0 / 5040.0,
    1.0 / 120.0,
    -1.0 / 6.0,
    1.0,
];
const COS_TAYLOR: [f64; 9] = [
    1.0 / 20922789888000.0,
    -1.0 / 87178291200.0,
    1.0 / 479001600.0,
    -1.0 / 3628800.0,
    1.0 / 40320.0,
    -1.0 / 720.0,
    1.0 / 24.0,
    -1.0 / 2.0,
    1.0,
];

/// acos on [0, 1], Abramowitz & Stegun 4.4.46, |error| ≤ 2e-8.
#[inline(always)]
fn fast_acos(x: f64) -> f64 {
    let p = ACOS_POLY[1..].iter().fold(ACOS_POLY[0], |p, &c| p * x + c);
    (1.0 - x).sqrt() * p
}

/// Coefficients of Abramowitz & Stegun 4.4.46, highest first:
/// `acos x ≈ √(1 − x) · Σ a_k x^k` on [0, 1].
const ACOS_POLY: [f64; 8] = [
    -0.0012624911,
    0.0066700901,
    -0.0170881256,
    0.0308918810,
    -0.0501743046,
    0.0889789874,
    -0.2145988016,
    1.5707963050,
];

/// (sin y, cos y) for y in [0, π/2] by Taylor series to degree 17/16
/// ([`SIN_TAYLOR`], [`COS_TAYLOR`]; error < 1e-12).
#[inline(always)]
fn fast_sin_cos(y: f64) -> (f64, f64) {
    let y2 = y * y;
    let (mut s, mut c) = (SIN_TAYLOR[0], COS_TAYLOR[0]);
    for (ks, kc) in SIN_TAYLOR[1..].iter().zip(&COS_TAYLOR[1..]) {
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
    fn lane_kernel_matches_the_per_triangle_formula() {
        // 21 triangles: five full lanes of four and a tail of one.
        let m1 = crate::mesh::subdivide::icosahedron();
        let tris: Vec<[u32; 3]> = m1.triangles()[..20]
            .iter()
            .chain(&m1.triangles()[..1])
            .copied()
            .collect();
        let m1 = Mesh::new(m1.positions().to_vec(), tris).unwrap();
        let m2: Vec<[f64; 3]> = m1
            .positions()
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let q = DQuat::from_rotation_y(0.4 * i as f64) * DQuat::from_rotation_x(0.3);
                (q * DVec3::from_array(*p) * (1.0 + 0.05 * i as f64)).to_array()
            })
            .collect();
        let (b, _, g1, g2) = setup(&m1, &m2);
        let cv = b.poisson.corner_vectors();
        for alpha in [0.0, 0.3, 1.0] {
            let mut lanes_out = vec![[DVec3::ZERO; 3]; cv.len()];
            blend_edges(&g1, &g2, alpha, cv, &mut lanes_out);
            let mut plain = lanes_out.clone();
            blend_edges_body::<false>(&g1, &g2, alpha, cv, &mut plain);
            for t in 0..cv.len() {
                let r = slerp(g1.rotation[t], g2.rotation[t], alpha);
                let (sa, sb) = (&g1.stretch[t], &g2.stretch[t]);
                let s: Sym3 = std::array::from_fn(|k| sa[k] + (sb[k] - sa[k]) * alpha);
                let m = rot_times_sym(r, &s);
                for k in 0..3 {
                    let want = m * cv[t][k];
                    let tol = 1e-6 * want.length().max(1e-3);
                    assert!((lanes_out[t][k] - want).length() < tol, "{t} {k}");
                    assert!((plain[t][k] - want).length() < tol, "{t} {k}");
                }
            }
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
