//! Real-time hybrid non-linear blending (Casas et al. 2013, Sec. 3.1.2,
//! Eq. 3).
//!
//! The non-linear blend `M_NL(t, w) = b(M, w)` (slerped rotations and
//! lerped stretches, Poisson-stitched: [`crate::mesh::blend::Blender`],
//! Eqs. 1-2) costs a sparse solve; the linear blend `M_L(t, w)` costs a
//! weighted sum. Eq. 3 keeps the linear cost and the non-linear accuracy:
//! the non-linear displacement `D_NL(t, w_j) = M_NL(t, w_j) − M_L(t, w_j)`
//! is precomputed at intermediate weights `w_j`, and at run time
//! `M(t, w) = Σ_j g(w, w_j) (M_L(t, w_j) + D_NL(t, w_j))` with `g` the
//! linear blend of the nearest pair of references. We store the references
//! `M_L + D_NL = M_NL(t, w_j)` themselves (the same bytes as `D_NL`, one
//! f32 triple per vertex and phase sample), so a frame is one bilinear
//! blend (two weights × two phase samples): the cost of a linear blend.
//!
//! The `w_j` are placed by recursive bisection of the weight interval
//! between each pair of neighbouring sequences: an interval is split at its
//! middle (a new reference, computed non-linearly) while the approximation
//! error against the true non-linear blend, tested at ¼, ½ and ¾ of the
//! interval for every phase sample, exceeds `ε` (default 5 mm, the
//! paper's Fig. 4). Exact at the references by construction.

use crate::mesh::blend::{Blender, FrameGradients};
use serde::{Deserialize, Serialize};

/// Options of the bisection.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HybridOptions {
    /// Largest approximation error allowed (metres). Default: 0.005 (5 mm,
    /// Casas et al. 2013, Fig. 4).
    pub epsilon: f64,
    /// Deepest bisection level (a cap; reaching it is reported). Default: 6.
    pub max_depth: usize,
}

impl Default for HybridOptions {
    fn default() -> Self {
        HybridOptions {
            epsilon: 0.005,
            max_depth: 6,
        }
    }
}

/// Where the references between two neighbouring sequences lie.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairRefs {
    /// ClipNeutral weights in `[0, 1]`, increasing; the first is 0 (sequence
    /// `a`), the last 1 (sequence `a + 1`).
    pub weights: Vec<f64>,
    /// The block of each reference (an index into [`HybridBlend::blocks`]).
    pub blocks: Vec<usize>,
    /// Largest error (metres) against the true non-linear blend over the
    /// tested weights of the final intervals.
    pub max_error: f64,
    /// Every tested weight with its largest error over phases (metres),
    /// for the final intervals (the ones kept).
    pub tested: Vec<(f64, f64)>,
    /// True when `max_depth` stopped a bisection before `ε` was met.
    pub capped: bool,
}

/// The hybrid blend of a space: phase-sampled reference meshes.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct HybridBlend {
    /// Vertices.
    pub n: usize,
    /// Phase samples per cycle, `K`.
    pub grid: usize,
    /// ClipNeutral blocks, `K · n · 3` f32 each (phase-major), body frames in
    /// metres; the first `N` are the space's sequences.
    pub blocks: Vec<Vec<f32>>,
    /// Per pair of neighbouring sequences, its references.
    pub pairs: Vec<PairRefs>,
}

/// `out = lerp(lerp(a0, a1, f), lerp(b0, b1, f), t)` over `n` vertices:
/// the whole per-frame cost of Eq. 3.
#[inline]
fn bilerp(a0: &[f32], a1: &[f32], b0: &[f32], b1: &[f32], f: f32, t: f32, out: &mut [[f64; 3]]) {
    let (wa0, wa1, wb0, wb1) = ((1.0 - f) * (1.0 - t), f * (1.0 - t), (1.0 - f) * t, f * t);
    for (v, o) in out.iter_mut().enumerate() {
        let i = 3 * v;
        for c in 0..3 {
            o[c] = (wa0 * a0[i + c] + wa1 * a1[i + c] + wb0 * b0[i + c] + wb1 * b1[i + c]) as f64;
        }
    }
}

impl HybridBlend {
    /// Bytes of the stored non-linear references (the intermediate ones,
    /// not the sequences themselves): the memory of Fig. 4.
    pub fn correction_bytes(&self) -> usize {
        let n_seq = self.pairs.len() + 1;
        self.blocks.iter().skip(n_seq).map(|b| b.len() * 4).sum()
    }

    /// Number of intermediate references.
    pub fn intermediate_count(&self) -> usize {
        self.blocks.len().saturating_sub(self.pairs.len() + 1)
    }

    /// Builds the references for the sequences `originals` (each `K · n · 3`
    /// f32, body frames on the phase grid), placing them by bisection.
    /// The blender is factored once on the topology and reused.
    pub fn build(
        originals: Vec<Vec<f32>>,
        n: usize,
        grid: usize,
        blender: &Blender,
        opts: &HybridOptions,
    ) -> HybridBlend {
        let count = originals.len();
        let mut blocks = originals;
        let mut pairs = Vec::new();
        let mut ws = blender.workspace();
        let mut ga = FrameGradients::default();
        let mut gb = FrameGradients::default();
        let mut buf = vec![[0.0f64; 3]; n];
        let mut truth = vec![[0.0f64; 3]; n];
        for a in 0..count.saturating_sub(1) {
            // (lo, hi, block lo, block hi, depth)
            let mut pending: Vec<(f64, f64, usize, usize, usize)> = vec![(0.0, 1.0, a, a + 1, 0)];
            let mut refs: Vec<(f64, usize)> = vec![(0.0, a), (1.0, a + 1)];
            let mut tested = Vec::new();
            let mut capped = false;
            while !pending.is_empty() {
                let qs = [0.25, 0.5, 0.75];
                let mut errs = vec![[0.0f64; 3]; pending.len()];
                let mut mids: Vec<Vec<f32>> = vec![vec![0.0; grid * n * 3]; pending.len()];
                for k in 0..grid {
                    let frame = |b: usize| &blocks[b][k * n * 3..(k + 1) * n * 3];
                    for (v, p) in buf.iter_mut().enumerate() {
                        *p = std::array::from_fn(|c| frame(a)[3 * v + c] as f64);
                    }
                    blender.decompose_into(&buf, &mut ws, &mut ga);
                    for (v, p) in buf.iter_mut().enumerate() {
                        *p = std::array::from_fn(|c| frame(a + 1)[3 * v + c] as f64);
                    }
                    blender.decompose_into(&buf, &mut ws, &mut gb);
                    for (pi, &(lo, hi, bl, bh, _)) in pending.iter().enumerate() {
                        for (qi, q) in qs.iter().enumerate() {
                            let s = lo + q * (hi - lo);
                            blender.blend(&ga, &gb, s, &mut truth, &mut ws);
                            let (fl, fh) = (frame(bl), frame(bh));
                            let mut e: f64 = 0.0;
                            for (v, t) in truth.iter().enumerate() {
                                let mut d2 = 0.0;
                                for c in 0..3 {
                                    let x = (fl[3 * v + c] as f64) * (1.0 - q)
                                        + (fh[3 * v + c] as f64) * q;
                                    d2 += (x - t[c]) * (x - t[c]);
                                }
                                e = e.max(d2);
                            }
                            errs[pi][qi] = errs[pi][qi].max(e.sqrt());
                            if qi == 1 {
                                let m = &mut mids[pi][k * n * 3..(k + 1) * n * 3];
                                for (v, t) in truth.iter().enumerate() {
                                    for c in 0..3 {
                                        m[3 * v + c] = t[c] as f32;
                                    }
                                }
                            }
                        }
                    }
                }
                let mut next = Vec::new();
                for ((pi, &(lo, hi, bl, bh, depth)), mid) in pending.iter().enumerate().zip(mids) {
                    let worst = errs[pi].iter().cloned().fold(0.0, f64::max);
                    if worst > opts.epsilon && depth < opts.max_depth {
                        let m = 0.5 * (lo + hi);
                        blocks.push(mid);
                        let bm = blocks.len() - 1;
                        refs.push((m, bm));
                        next.push((lo, m, bl, bm, depth + 1));
                        next.push((m, hi, bm, bh, depth + 1));
                    } else {
                        if worst > opts.epsilon {
                            capped = true;
                        }
                        for (q, e) in [0.25, 0.5, 0.75].iter().zip(errs[pi]) {
                            tested.push((lo + q * (hi - lo), e));
                        }
                    }
                }
                pending = next;
            }
            refs.sort_by(|x, y| x.0.total_cmp(&y.0));
            tested.sort_by(|x, y| x.0.total_cmp(&y.0));
            pairs.push(PairRefs {
                weights: refs.iter().map(|r| r.0).collect(),
                blocks: refs.iter().map(|r| r.1).collect(),
                max_error: tested.iter().map(|t| t.1).fold(0.0, f64::max),
                tested,
                capped,
            });
        }
        HybridBlend {
            n,
            grid,
            blocks,
            pairs,
        }
    }

    /// The pair, the two bracketing references and the fraction between
    /// them for the weight coordinate `u ∈ [0, N − 1]` (clamped).
    #[inline]
    pub(crate) fn bracket(&self, u: f64) -> (usize, usize, f32) {
        if self.pairs.is_empty() {
            return (0, 0, 0.0);
        }
        let u = u.clamp(0.0, self.pairs.len() as f64);
        let a = (u.floor() as usize).min(self.pairs.len() - 1);
        let s = u - a as f64;
        let p = &self.pairs[a];
        let j = p
            .weights
            .partition_point(|&w| w <= s)
            .clamp(1, p.weights.len() - 1);
        let (w0, w1) = (p.weights[j - 1], p.weights[j]);
        let t = if w1 > w0 {
            ((s - w0) / (w1 - w0)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p.blocks[j - 1], p.blocks[j], t as f32)
    }

    /// `(k0, k1, fraction)` of a phase in grid units (wrapped into `[0, K)`).
    #[inline]
    pub(crate) fn phase_samples(&self, phase: f64) -> (usize, usize, f32) {
        let k = self.grid;
        let p = phase.rem_euclid(k as f64);
        let k0 = (p.floor() as usize).min(k - 1);
        (k0, (k0 + 1) % k, (p - k0 as f64) as f32)
    }

    /// Eq. 3: the hybrid blend at weight coordinate `u` and phase `phase`
    /// (grid units), body frame, metres, written to `out` (`n` vertices).
    /// No allocation.
    pub fn eval(&self, u: f64, phase: f64, out: &mut [[f64; 3]]) {
        let (b0, b1, t) = self.bracket(u);
        self.eval_blocks(b0, b1, t, phase, out);
    }

    /// The plain linear blend of the sequences (no correction): the
    /// baseline of the paper's Table 1.
    pub fn eval_linear(&self, u: f64, phase: f64, out: &mut [[f64; 3]]) {
        if self.pairs.is_empty() {
            return self.eval_blocks(0, 0, 0.0, phase, out);
        }
        let u = u.clamp(0.0, self.pairs.len() as f64);
        let a = (u.floor() as usize).min(self.pairs.len() - 1);
        self.eval_blocks(a, a + 1, (u - a as f64) as f32, phase, out);
    }

    fn eval_blocks(&self, b0: usize, b1: usize, t: f32, phase: f64, out: &mut [[f64; 3]]) {
        let (k0, k1, f) = self.phase_samples(phase);
        let m = self.n * 3;
        let s = |b: usize, k: usize| &self.blocks[b][k * m..(k + 1) * m];
        bilerp(s(b0, k0), s(b0, k1), s(b1, k0), s(b1, k1), f, t, out);
    }
}
