//! Transitions by adaptive temporal filtering (Huang et al. 2015, Sec. 4.2,
//! Eqs. 2–5).
//!
//! A transition from sequence `i` to `j` is a tuple `(m, n, L)`: frames
//! `m−L..=m+L` of `i` are blended into `n−L..=n+L` of `j` with weights
//! `α(k) = (k+L)/2L`. Its distortion is approximated from the static
//! dissimilarity matrix `C` of the two sequences:
//!
//! `D(m, n, L) = Σ_{k=−L..L} α′(k) · c_{m+k, n+k}`, `α′ = min(α, 1−α)` (Eqs. 2–3).
//!
//! Every term is non-negative, so Eq. 5 taken literally always picks the
//! shortest window. We minimise the distortion per transition frame,
//! `D / (2L+1)`, over `L ∈ [min_window, max_window]` instead: a longer
//! window (a slower, smoother blend) wins whenever the frames along it stay
//! similar (among equal costs the longer window wins). Candidates `(m, n)` are the local minima of `C` (no smaller
//! 8-neighbour); within one sequence, pairs closer than `min_gap` frames are
//! not transitions. The best `top_n` per ordered sequence pair are kept,
//! each suppressing weaker candidates within its window (or `min_gap`).
//! Within one sequence the matrix is symmetric, so the best `top_n` frame
//! pairs are kept and each gives two transitions (a loop back and a skip
//! forward).

use serde::{Deserialize, Serialize};

/// Options of the transition search.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TransitionOptions {
    /// Transitions kept per ordered sequence pair. Default: 4 (the paper's N).
    pub top_n: usize,
    /// Largest half-window L. Default: 24 (the paper's L < 25).
    pub max_window: usize,
    /// Smallest half-window L. Default: 4 (the paper's Fig. 4).
    pub min_window: usize,
    /// Within a sequence, the smallest `|m − n|` of a transition (shorter
    /// jumps are not new motion); also the radius within which a kept
    /// transition suppresses weaker ones. Default: 10.
    pub min_gap: usize,
}

impl Default for TransitionOptions {
    fn default() -> Self {
        TransitionOptions {
            top_n: 4,
            max_window: 24,
            min_window: 4,
            min_gap: 10,
        }
    }
}

/// One transition between two sequences (or within one).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Transition {
    /// Source sequence.
    pub from: usize,
    /// Target sequence.
    pub to: usize,
    /// Centre frame in the source.
    pub m: usize,
    /// Centre frame in the target.
    pub n: usize,
    /// Half-window: `2L+1` frames are blended.
    pub window: usize,
    /// Distortion per blended frame, `D / (2L+1)` (the measure's unit).
    pub cost: f64,
}

/// Eq. 3 normalised: the distortion per frame of the window `(m, n, L)` of
/// `c(r, s)`.
pub(crate) fn window_cost(c: &impl Fn(usize, usize) -> f32, m: usize, n: usize, l: usize) -> f64 {
    let mut d = 0.0;
    for k in -(l as i64)..=(l as i64) {
        let alpha = (k + l as i64) as f64 / (2 * l) as f64;
        let w = alpha.min(1.0 - alpha);
        d += w * c((m as i64 + k) as usize, (n as i64 + k) as usize) as f64;
    }
    d / (2 * l + 1) as f64
}

/// The best transitions from a sequence of `rows` frames to one of `cols`
/// frames, given their dissimilarities `c(r, s)`; `same` when both are one
/// sequence. Returned as `(m, n, L, cost)` tuples, best first.
pub fn find(
    c: &impl Fn(usize, usize) -> f32,
    rows: usize,
    cols: usize,
    same: bool,
    opts: &TransitionOptions,
) -> Vec<(usize, usize, usize, f64)> {
    let lo = opts.min_window.max(1);
    let every = (lo..rows.saturating_sub(lo))
        .flat_map(|m| (lo..cols.saturating_sub(lo)).map(move |n| (m, n)));
    find_among(c, rows, cols, same, opts, every)
}

/// [`find`] with the candidates `(m, n)` taken only from `cells` (the
/// pairs a sparse similarity stores, issue 43); `c` is `f32::INFINITY` for
/// a pair not stored. A neighbour not stored counts as not smaller (the
/// sparse similarity leaves out pairs far from every candidate, which are
/// large), and a window reaching a pair not stored is not a window, so
/// the transitions found are the dense method's wherever the stored pairs
/// cover a minimum and its windows, and its unstored neighbours are not
/// smaller.
pub(crate) fn find_among(
    c: &impl Fn(usize, usize) -> f32,
    rows: usize,
    cols: usize,
    same: bool,
    opts: &TransitionOptions,
    cells: impl Iterator<Item = (usize, usize)>,
) -> Vec<(usize, usize, usize, f64)> {
    let lo = opts.min_window.max(1);
    let hi = opts.max_window.max(lo);
    let mut cands = Vec::new();
    for (m, n) in cells {
        if m < lo || n < lo || m >= rows.saturating_sub(lo) || n >= cols.saturating_sub(lo) {
            continue;
        }
        // Within one sequence C is symmetric: take each pair once
        // (m < n) and return both directions.
        if same && (n <= m || n - m < opts.min_gap.max(1)) {
            continue;
        }
        let v = c(m, n);
        let mut minimum = v.is_finite();
        'nb: for dm in -1i64..=1 {
            for dn in -1i64..=1 {
                if dm == 0 && dn == 0 {
                    continue;
                }
                let (r, s) = (m as i64 + dm, n as i64 + dn);
                if r < 0 || s < 0 || r >= rows as i64 || s >= cols as i64 {
                    continue;
                }
                // An unstored neighbour (infinite) is not smaller.
                if c(r as usize, s as usize) < v {
                    minimum = false;
                    break 'nb;
                }
            }
        }
        if !minimum {
            continue;
        }
        // Best window that fits in both sequences.
        let fit = m.min(n).min(rows - 1 - m).min(cols - 1 - n).min(hi);
        if fit < lo {
            continue;
        }
        // Longest window among equals (`min_by` keeps the first).
        let best = (lo..=fit)
            .rev()
            .map(|l| (l, window_cost(c, m, n, l)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((l, cost)) = best
            && cost.is_finite()
        {
            cands.push((m, n, l, cost));
        }
    }
    // Best first; among equal costs the longer window, then the earlier frames.
    cands.sort_by(|a, b| {
        a.3.total_cmp(&b.3)
            .then(b.2.cmp(&a.2))
            .then((a.0, a.1).cmp(&(b.0, b.1)))
    });
    let mut kept: Vec<(usize, usize, usize, f64)> = Vec::new();
    for cand in cands {
        if kept.len() >= opts.top_n {
            break;
        }
        let clash = kept.iter().any(|k| {
            let w = k.2.max(cand.2).max(opts.min_gap);
            k.0.abs_diff(cand.0) <= w && k.1.abs_diff(cand.1) <= w
        });
        if !clash {
            kept.push(cand);
        }
    }
    if same {
        // Forward skips and backward loops alike.
        let back: Vec<_> = kept.iter().map(|&(m, n, l, c)| (n, m, l, c)).collect();
        kept = kept
            .into_iter()
            .zip(back)
            .flat_map(|(a, b)| [a, b])
            .collect();
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_shared_segment_and_a_long_window() {
        // Two 1-D "motions": b repeats a's frames 30..60 at 10..40.
        let a: Vec<f64> = (0..80)
            .map(|t| (t as f64 * 0.37).sin() * 3.0 + t as f64 * 0.01)
            .collect();
        let mut b: Vec<f64> = (0..60).map(|t| 10.0 + (t as f64 * 0.23).cos()).collect();
        b[10..40].copy_from_slice(&a[30..60]);
        let c = |r: usize, s: usize| (a[r] - b[s]).abs() as f32;
        let opts = TransitionOptions::default();
        let t = find(&c, a.len(), b.len(), false, &opts);
        assert!(!t.is_empty() && t.len() <= 4);
        let (m, n, l, cost) = t[0];
        assert_eq!(m - n, 20, "{:?}", t[0]);
        assert!((30..60).contains(&m) && cost < 1e-9);
        // The whole window lies inside the shared run (its end frames have
        // weight 0).
        assert!(m - l >= 29 && m + l <= 60, "{:?}", t[0]);
        assert!(l >= 10, "a long identical run gets a long window: {l}");
        // Sorted and windows in range.
        for w in t.windows(2) {
            assert!(w[0].3 <= w[1].3);
        }
    }

    #[test]
    fn loops_skip_the_diagonal() {
        // A periodic motion of period 25 frames.
        let a: Vec<f64> = (0..100)
            .map(|t| (t as f64 * std::f64::consts::TAU / 25.0).sin())
            .collect();
        let c = |r: usize, s: usize| (a[r] - a[s]).abs() as f32 + 0.0;
        let opts = TransitionOptions::default();
        let t = find(&c, 100, 100, true, &opts);
        assert_eq!(t.len(), 8);
        for p in t.chunks(2) {
            assert_eq!((p[0].0, p[0].1), (p[1].1, p[1].0));
        }
        for (m, n, _, cost) in t {
            assert!(m.abs_diff(n) >= opts.min_gap);
            assert_eq!(m.abs_diff(n) % 25, 0, "({m}, {n})");
            assert!(cost < 1e-6);
        }
    }

    /// Issue 43: a sparse similarity leaves out pairs far from every
    /// candidate; such a neighbour of a minimum (infinite) must not hide
    /// the minimum (it did: 38 of the 116 dense transitions missed at
    /// 3,234 frames).
    #[test]
    fn an_unstored_neighbour_does_not_hide_a_minimum() {
        let a: Vec<f64> = (0..80)
            .map(|t| (t as f64 * 0.37).sin() * 3.0 + t as f64 * 0.01)
            .collect();
        let mut b: Vec<f64> = (0..60).map(|t| 10.0 + (t as f64 * 0.23).cos()).collect();
        b[10..40].copy_from_slice(&a[30..60]);
        let dense = |r: usize, s: usize| (a[r] - b[s]).abs() as f32;
        let opts = TransitionOptions::default();
        let best = find(&dense, a.len(), b.len(), false, &opts)[0];
        let (m, n) = (best.0, best.1);
        // Stored: three diagonals around the best transition's only; the
        // anti-diagonal neighbours of every cell lie two diagonals away.
        let stored = |r: usize, s: usize| (r as i64 - s as i64 - (m as i64 - n as i64)).abs() <= 1;
        let sparse = |r: usize, s: usize| {
            if stored(r, s) {
                dense(r, s)
            } else {
                f32::INFINITY
            }
        };
        let cells = (0..a.len())
            .flat_map(|r| (0..b.len()).map(move |s| (r, s)))
            .filter(|&(r, s)| stored(r, s));
        let t = find_among(&sparse, a.len(), b.len(), false, &opts, cells);
        assert_eq!(
            t.first().map(|x| (x.0, x.1, x.2)),
            Some((m, n, best.2)),
            "{t:?}"
        );
        assert_eq!(t[0].3, best.3);
    }
}
