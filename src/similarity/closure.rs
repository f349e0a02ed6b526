//! The sparse similarity's transitions made the dense method's where the
//! stored pairs cannot vouch for them (issue 43, session 39).
//!
//! The transition search on stored pairs ([`super::transitions::find_among`])
//! treats a pair not stored as not smaller and a window reaching one as no
//! window. So at the edge of the stored runs — a valley of a re-timed copy
//! runs slanted across the diagonals, out of the five diagonals stored
//! around a candidate — a pair can pass for a local minimum whose smaller
//! neighbour is simply not stored, and its transition can take one of the
//! `N` places of its sequence pair (Huang et al. 2015, Sec. 4.2) from the
//! dense method's transition at the valley's true floor a few frames away.
//!
//! The closure runs the transition search on each sequence pair's stored
//! pairs and **certifies** every transition it keeps: the centre's 8
//! neighbours and its whole diagonal (the longest window that fits) are
//! stored, so the minimum test and the window cost (Eqs. 2–5) are the dense
//! method's exactly. Each transition that is not certified is descended on
//! the full measure (8-neighbour steepest descent) to a true local
//! minimum, which becomes a candidate: its runs are stored and the search
//! runs again (a few rounds, [`super::SparseOptions::closure`]). The
//! last round's new runs are not checked again: on noisy generated motions
//! (`db::sparse::the_default_sparse_build_keeps_the_dense_candidates`)
//! 192 of 2,108 graph transitions are still not the dense method's
//! candidates after 3 rounds (198 without the closure).

use super::matrix::{PairDistance, Span};
use super::pair_scan::Memo;
use super::transitions::{TransitionOptions, find_among};
use rayon::prelude::*;

/// The stored pairs a closure round reads: the stored value of a global
/// frame pair, and the stored pairs of a sequence pair's block (frames
/// within each sequence).
pub(crate) trait StoredPairs: Sync {
    /// The stored dissimilarity of frames `a` and `b`, if stored.
    fn stored(&self, a: usize, b: usize) -> Option<f32>;
    /// The stored pairs of sequences `i` (rows) and `j` (columns).
    fn block(&self, i: usize, j: usize) -> Vec<(usize, usize)>;
}

/// The full measure with the stored values read first (the same bits: a
/// stored value is the full measure's, rounded to `f32` as it was stored),
/// so a round evaluates only the pairs not stored yet.
pub(crate) struct Known<'a> {
    /// The stored pairs.
    pub stored: &'a dyn StoredPairs,
    /// The full measure.
    pub full: &'a dyn PairDistance,
}

impl PairDistance for Known<'_> {
    fn frames(&self) -> usize {
        self.full.frames()
    }
    fn distance(&self, a: usize, b: usize) -> f64 {
        match self.stored.stored(a, b) {
            Some(v) => v as f64,
            None => self.full.distance(a, b),
        }
    }
}

/// One closure round: on every unordered sequence pair `i ≤ j` with a
/// stored pair, the transitions the search keeps (`opts.top_n`) that the
/// stored pairs do not certify, each descended on the full measure to a
/// local minimum; returned as global centres `(a, b)` (`a` in sequence
/// `i`), with the full measures the descents evaluated.
pub(crate) fn uncertified_minima(
    stored: &dyn StoredPairs,
    full: &dyn PairDistance,
    spans: &[Span],
    opts: &TransitionOptions,
) -> (Vec<(usize, u32)>, u64) {
    let s = spans.len();
    let pairs: Vec<(usize, usize)> = (0..s).flat_map(|i| (i..s).map(move |j| (i, j))).collect();
    let per: Vec<(Vec<(usize, u32)>, u64)> = pairs
        .par_iter()
        .map(|&(i, j)| pair_minima(stored, full, spans, (i, j), opts))
        .collect();
    let evaluated = per.iter().map(|p| p.1).sum();
    (per.into_iter().flat_map(|p| p.0).collect(), evaluated)
}

/// [`uncertified_minima`] of the block of sequences `i` (rows) and `j`.
fn pair_minima(
    stored: &dyn StoredPairs,
    full: &dyn PairDistance,
    spans: &[Span],
    (i, j): (usize, usize),
    opts: &TransitionOptions,
) -> (Vec<(usize, u32)>, u64) {
    let (si, sj, same) = (&spans[i], &spans[j], i == j);
    let cells = stored.block(i, j);
    if cells.is_empty() {
        return (Vec::new(), 0);
    }
    let c = |r: usize, s: usize| {
        if r >= si.len || s >= sj.len {
            return f32::INFINITY;
        }
        stored
            .stored(si.start + r, sj.start + s)
            .unwrap_or(f32::INFINITY)
    };
    let found = find_among(&c, si.len, sj.len, same, opts, cells.into_iter());
    let known = Known { stored, full };
    let memo = Memo::new(&known, si, sj);
    let mut out = Vec::new();
    for &(m, n, _, _) in &found {
        if same && n < m {
            continue; // the transposed copy of a kept pair
        }
        if certified(&c, m, n, si.len, sj.len, opts.max_window) {
            continue;
        }
        let (r, s) = memo.descend(m, n, same, opts.min_gap);
        out.push((si.start + r, (sj.start + s) as u32));
    }
    out.sort_unstable();
    out.dedup();
    (out, memo.evaluated())
}

/// True when the transition search's result at `(m, n)` reads stored pairs
/// only: its 8 neighbours (inside the block) and its diagonal as far as the
/// longest window that fits (`max_window`).
fn certified(
    c: &impl Fn(usize, usize) -> f32,
    m: usize,
    n: usize,
    rows: usize,
    cols: usize,
    max_window: usize,
) -> bool {
    for dm in -1i64..=1 {
        for dn in -1i64..=1 {
            let (r, s) = (m as i64 + dm, n as i64 + dn);
            if r < 0 || s < 0 || r >= rows as i64 || s >= cols as i64 {
                continue;
            }
            if !c(r as usize, s as usize).is_finite() {
                return false;
            }
        }
    }
    let fit = m.min(n).min(rows - 1 - m).min(cols - 1 - n).min(max_window);
    (1..=fit).all(|k| c(m - k, n - k).is_finite() && c(m + k, n + k).is_finite())
}
