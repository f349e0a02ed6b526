//! The best cheap transitions of every sequence pair, the candidates that
//! keep the sparse similarity's transitions the dense method's (issue 43).
//!
//! The graph keeps the `top_n` best transitions of every ordered sequence
//! pair (Huang et al. 2015, Sec. 4.2, Eqs. 2–5), also between dissimilar
//! motions, whose frames are nobody's nearest frames overall. So for every
//! unordered pair of sequences `i ≤ j` (the matrix is symmetric: the
//! transitions `j → i` are those of `i → j` transposed) the transition
//! search itself ([`super::transitions::find`]: local minima, the
//! windowed cost of Eq. 3 per blended frame, suppression within a window)
//! runs on the block of cheap distances (the projected descriptors'
//! Euclidean distance, a lower bound of Eq. 1's), and the centres of its
//! best transitions become candidate pairs of the full measure.
//!
//! Work: one cheap distance (`dims` multiply-adds) for every frame pair,
//! `n² dims / 2` — at 10⁴ frames and 24 dimensions 1.2·10⁹, about a
//! thousandth of the full measure on every pair — held one block at a
//! time (`len_i × len_j` values per thread). The candidates are `top_n`
//! per sequence pair whatever the sequences' lengths: where the previous
//! scheme (every 4th frame's 12 nearest frames in each sequence) gave
//! `n × sequences × 3` candidates.

use super::matrix::{PairDistance, Span};
use super::transitions::{TransitionOptions, find, find_among};
use rayon::prelude::*;
use std::cell::RefCell;
use std::collections::HashMap;

/// The cheap distances of sequences `si` (rows) and `sj` (columns),
/// row-major (`si.len × sj.len`): the Euclidean distance of the frames'
/// rows of `features` (`n × dims`, row-major).
fn cheap_block(features: &[f32], dims: usize, si: &Span, sj: &Span) -> Vec<f32> {
    let mut out = vec![0.0f32; si.len * sj.len];
    if sj.len == 0 || dims == 0 {
        return out;
    }
    let cols = &features[sj.start * dims..(sj.start + sj.len) * dims];
    for (r, row) in out.chunks_exact_mut(sj.len).enumerate() {
        let a = &features[(si.start + r) * dims..(si.start + r + 1) * dims];
        for (o, b) in row.iter_mut().zip(cols.chunks_exact(dims)) {
            *o = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y) * (x - y))
                .sum::<f32>()
                .sqrt();
        }
    }
    out
}

/// The centres `(frame, frame)` (global rows, the first in the earlier
/// sequence) of the `opts.top_n` best transitions of every unordered
/// sequence pair by the cheap distances of `features` (`n × dims`,
/// row-major); in parallel over sequence pairs, in a fixed order. Nothing
/// when `opts.top_n` is 0.
pub fn best_per_pair(
    features: &[f32],
    dims: usize,
    spans: &[Span],
    opts: &TransitionOptions,
) -> Vec<(usize, u32)> {
    best_per_pair_with(features, dims, spans, None, opts, &|_| {})
}

/// [`best_per_pair`] telling `progress` the cheap distances of each
/// sequence pair's block as it is done (`len_i × len_j`; all of them add
/// up to [`scan_total`]), on the sequence pairs `reached` (per ordered
/// pair `i · sequences + j`, [`super::candidates::reached_pairs`]) only,
/// or on every pair (`None`).
pub fn best_per_pair_with(
    features: &[f32],
    dims: usize,
    spans: &[Span],
    reached: Option<&[bool]>,
    opts: &TransitionOptions,
    progress: &(dyn Fn(u64) + Sync),
) -> Vec<(usize, u32)> {
    let pairs = scanned_pairs(spans, reached);
    per_pair(spans, &pairs, opts.top_n, progress, |i, j| {
        let (si, sj) = (&spans[i], &spans[j]);
        let c = cheap_block(features, dims, si, sj);
        let at = |r: usize, s: usize| c[r * sj.len + s];
        let found = find(&at, si.len, sj.len, i == j, opts);
        (centres(found, i == j), 0)
    })
    .0
}

/// What [`best_per_pair_refined`] re-ranks with: the full measure, and how
/// many of each sequence pair's cheap transitions it examines.
#[derive(Clone, Copy)]
pub(crate) struct Rerank<'a> {
    /// The full measure (Eq. 1) of the frames.
    pub full: &'a dyn PairDistance,
    /// Cheap transitions examined per unordered sequence pair (their
    /// centres descended to the full measure's minima); at least `top_n`.
    pub examine: usize,
}

/// [`best_per_pair`] with the near-ties settled by the full measure
/// (issue 43, session 25): the centres of each sequence pair's
/// `rerank.examine` best cheap transitions are each moved downhill on the
/// full measure to its local minimum (8-neighbour steepest descent, at
/// most [`MAX_DESCENT`] steps), and the transition search (Eqs. 2–5:
/// minimum test, best window, suppression) runs on those minima with the
/// full measure: its `opts.top_n` best are kept. The cheap distance, a
/// lower bound of Eq. 1 on 24 principal axes, finds the valleys but not
/// which of a valley's near-equal minima Eq. 1 ranks first (session 24:
/// 71 % of the dense transitions at 3,234 frames). Also returns the full
/// measures evaluated (`examine · (steps · 5 + window)` per pair at most).
pub(crate) fn best_per_pair_refined(
    features: &[f32],
    dims: usize,
    spans: &[Span],
    reached: Option<&[bool]>,
    opts: &TransitionOptions,
    rerank: Rerank<'_>,
    progress: &(dyn Fn(u64) + Sync),
) -> (Vec<(usize, u32)>, u64) {
    let pairs = scanned_pairs(spans, reached);
    best_of_pairs(features, dims, spans, &pairs, opts, rerank, progress)
}

/// [`best_per_pair_refined`] on the unordered sequence pairs `pairs`
/// (`i ≤ j`) only. The far search (issue 43, session 34) runs it on the
/// pairs a reach does not scan ([`far_pairs`]) with a smaller `top_n`
/// and `rerank.examine`: the whole cheap block of each (a lower bound of
/// Eq. 1's, `dims` multiply-adds a frame pair), its best cheap
/// transitions descended to the full measure's minima, the best of those
/// by Eq. 3's window cost kept — the graph's per-pair rule (Sec. 4.2:
/// the best `N` of every ordered pair) for the dissimilar pairs, at a few
/// thousand full measures per pair instead of the reached pairs' ~20,000.
pub(crate) fn best_of_pairs(
    features: &[f32],
    dims: usize,
    spans: &[Span],
    pairs: &[(usize, usize)],
    opts: &TransitionOptions,
    rerank: Rerank<'_>,
    progress: &(dyn Fn(u64) + Sync),
) -> (Vec<(usize, u32)>, u64) {
    let cheap = TransitionOptions {
        top_n: rerank.examine.max(opts.top_n),
        ..*opts
    };
    per_pair(spans, pairs, opts.top_n, progress, |i, j| {
        let (si, sj) = (&spans[i], &spans[j]);
        let c = cheap_block(features, dims, si, sj);
        let at = |r: usize, s: usize| c[r * sj.len + s];
        let seeds = find(&at, si.len, sj.len, i == j, &cheap);
        let full = Memo::new(rerank.full, si, sj);
        let mut minima: Vec<(usize, usize)> = seeds
            .iter()
            .map(|&(m, n, _, _)| full.descend(m, n, i == j, opts.min_gap))
            .map(|(m, n)| if i == j && n < m { (n, m) } else { (m, n) })
            .collect();
        minima.sort_unstable();
        minima.dedup();
        let g = |r: usize, s: usize| full.get(r, s);
        let found = find_among(&g, si.len, sj.len, i == j, opts, minima.into_iter());
        (centres(found, i == j), full.evaluated())
    })
}

/// Steps of [`Memo::descend`] at most (a valley's floor is a few frames
/// from the cheap minimum; the bound keeps a long slope from costing more
/// than a band).
pub(crate) const MAX_DESCENT: usize = 32;

/// The cheap distances [`best_per_pair_with`] and
/// [`best_per_pair_refined`] compute over `spans` (every unordered
/// sequence pair's block, a sequence with itself included): what their
/// progress adds up to, `(n² + Σ lenᵢ²) / 2`; over the pairs `reached`
/// only when given.
pub fn scan_total(spans: &[Span], reached: Option<&[bool]>) -> u64 {
    if reached.is_some() {
        return cells_of(spans, &scanned_pairs(spans, reached));
    }
    let n: u64 = spans.iter().map(|s| s.len as u64).sum();
    let own: u64 = spans.iter().map(|s| (s.len as u64).pow(2)).sum();
    (n * n + own) / 2
}

/// The unordered sequence pairs `i ≤ j` scanned: every one, or those
/// `reached` (per ordered pair `i · sequences + j`).
pub fn scanned_pairs(spans: &[Span], reached: Option<&[bool]>) -> Vec<(usize, usize)> {
    let s = spans.len();
    (0..s)
        .flat_map(|i| (i..s).map(move |j| (i, j)))
        .filter(|&(i, j)| reached.is_none_or(|r| r[i * s + j]))
        .collect()
}

/// The unordered sequence pairs `i < j` not `reached` (per ordered pair
/// `i · sequences + j`): those the far search takes
/// ([`best_of_pairs`]); none without a reach.
pub fn far_pairs(spans: &[Span], reached: Option<&[bool]>) -> Vec<(usize, usize)> {
    let s = spans.len();
    let Some(r) = reached else {
        return Vec::new();
    };
    (0..s)
        .flat_map(|i| (i + 1..s).map(move |j| (i, j)))
        .filter(|&(i, j)| !r[i * s + j])
        .collect()
}

/// The cheap distances of the sequence pairs `pairs`: `Σ lenᵢ · lenⱼ`.
pub fn cells_of(spans: &[Span], pairs: &[(usize, usize)]) -> u64 {
    pairs
        .iter()
        .map(|&(i, j)| (spans[i].len * spans[j].len) as u64)
        .sum()
}

/// Runs `block(i, j)` on the unordered sequence pairs `pairs` (`i ≤ j`; in
/// parallel, results in a fixed order) when `top_n` is not 0; the centres
/// it returns and the sum of its counts.
fn per_pair(
    spans: &[Span],
    pairs: &[(usize, usize)],
    top_n: usize,
    progress: &(dyn Fn(u64) + Sync),
    block: impl Fn(usize, usize) -> (Vec<(usize, usize)>, u64) + Sync,
) -> (Vec<(usize, u32)>, u64) {
    if top_n == 0 {
        return (Vec::new(), 0);
    }
    let per: Vec<(Vec<(usize, u32)>, u64)> = pairs
        .par_iter()
        .map(|&(i, j)| {
            let (found, k) = block(i, j);
            progress((spans[i].len * spans[j].len) as u64);
            let (a0, b0) = (spans[i].start, spans[j].start);
            let global = found
                .into_iter()
                .map(|(m, n)| (a0 + m, (b0 + n) as u32))
                .collect();
            (global, k)
        })
        .collect();
    let count = per.iter().map(|p| p.1).sum();
    (per.into_iter().flat_map(|p| p.0).collect(), count)
}

/// The centres `(m, n)` of found transitions; within one sequence each
/// frame pair once (`m < n`).
fn centres(found: Vec<(usize, usize, usize, f64)>, same: bool) -> Vec<(usize, usize)> {
    found
        .into_iter()
        .filter(|&(m, n, _, _)| !same || m < n)
        .map(|(m, n, _, _)| (m, n))
        .collect()
}

/// The full measure of a sequence pair's block (frame numbers within each
/// sequence), each pair evaluated once.
pub(crate) struct Memo<'a> {
    full: &'a dyn PairDistance,
    si: &'a Span,
    sj: &'a Span,
    seen: RefCell<HashMap<(usize, usize), f32>>,
}

impl<'a> Memo<'a> {
    pub(crate) fn new(full: &'a dyn PairDistance, si: &'a Span, sj: &'a Span) -> Self {
        Memo {
            full,
            si,
            sj,
            seen: RefCell::new(HashMap::new()),
        }
    }
    /// The full measure of rows `r` and `s` (`INFINITY` outside the block).
    fn get(&self, r: usize, s: usize) -> f32 {
        if r >= self.si.len || s >= self.sj.len {
            return f32::INFINITY;
        }
        if let Some(v) = self.seen.borrow().get(&(r, s)) {
            return *v;
        }
        let v = self.full.distance(self.si.start + r, self.sj.start + s) as f32;
        self.seen.borrow_mut().insert((r, s), v);
        v
    }
    pub(crate) fn evaluated(&self) -> u64 {
        self.seen.borrow().len() as u64
    }
    /// From `(m, n)` to the smallest of the 8 neighbours while it is
    /// smaller (within one sequence, never closer than `gap` frames to the
    /// diagonal), at most [`MAX_DESCENT`] steps.
    pub(crate) fn descend(&self, m: usize, n: usize, same: bool, gap: usize) -> (usize, usize) {
        descend_on(|r, s| self.get(r, s), (m, n), same, gap)
    }
}

/// From `(m, n)` to the smallest of its 8 neighbours under `get` while it
/// is smaller (within one sequence, never closer than `gap` frames to the
/// diagonal), at most [`MAX_DESCENT`] steps; ties keep the first neighbour
/// in [`NEIGHBOURS`]' order. Shared by the pair scan and the closure.
pub(crate) fn descend_on(
    get: impl Fn(usize, usize) -> f32,
    (mut m, mut n): (usize, usize),
    same: bool,
    gap: usize,
) -> (usize, usize) {
    for _ in 0..MAX_DESCENT {
        let mut best = (get(m, n), m, n);
        for (dm, dn) in NEIGHBOURS {
            let (Some(r), Some(s)) = (m.checked_add_signed(dm), n.checked_add_signed(dn)) else {
                continue;
            };
            if same && r.abs_diff(s) < gap.max(1) {
                continue;
            }
            let v = get(r, s);
            if v < best.0 {
                best = (v, r, s);
            }
        }
        if (best.1, best.2) == (m, n) {
            break;
        }
        (m, n) = (best.1, best.2);
    }
    (m, n)
}

/// The 8 neighbours of a pair.
const NEIGHBOURS: [(isize, isize); 8] = [
    (-1, -1),
    (-1, 0),
    (-1, 1),
    (0, -1),
    (0, 1),
    (1, -1),
    (1, 0),
    (1, 1),
];

/// `seeds` and, for each, the pairs `spread` frames either way along its
/// second frame's sequence (the cheap minimum's diagonal is often a few
/// off the full measure's): each seed's `(a, b − spread)` and
/// `(a, b + spread)` where they stay in `b`'s sequence. All of `seeds`
/// alone when `spread` is 0.
pub(crate) fn spread_seeds(
    seeds: &[(usize, u32)],
    spread: usize,
    spans: &[Span],
    seq: &[u32],
) -> Vec<(usize, u32)> {
    if spread == 0 {
        return seeds.to_vec();
    }
    let mut out = Vec::with_capacity(seeds.len() * 3);
    for &(a, b) in seeds {
        out.push((a, b));
        let s = &spans[seq[b as usize] as usize];
        let b = b as usize;
        if b >= s.start + spread {
            out.push((a, (b - spread) as u32));
        }
        if b + spread < s.start + s.len {
            out.push((a, (b + spread) as u32));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn span(name: &str, start: usize, len: usize) -> Span {
        Span {
            name: name.into(),
            start,
            len,
        }
    }

    /// Two "motions" on a 1-D line far apart, each with a stretch where
    /// the other's values come close: every sequence pair gets its
    /// transitions, also the pair whose frames are nobody's nearest.
    #[test]
    fn every_sequence_pair_gets_its_best_transitions() {
        let a: Vec<f32> = (0..120).map(|t| (t as f32 * 0.2).sin()).collect();
        let mut b: Vec<f32> = (0..90).map(|t| 10.0 + (t as f32 * 0.3).cos()).collect();
        // b comes nearest to a around its frames 40..60 (still 5 away).
        for (t, v) in b.iter_mut().enumerate().take(60).skip(40) {
            *v = 6.0 + (t as f32 * 0.2).sin();
        }
        let features: Vec<f32> = a.iter().chain(&b).copied().collect();
        let spans = vec![span("a", 0, 120), span("b", 120, 90)];
        let opts = TransitionOptions {
            top_n: 2,
            ..TransitionOptions::default()
        };
        let got = best_per_pair(&features, 1, &spans, &opts);
        let across: Vec<_> = got.iter().filter(|&&(x, y)| x < 120 && y >= 120).collect();
        assert!(!across.is_empty(), "{got:?}");
        for &&(_, y) in &across {
            assert!((160..180).contains(&y), "{got:?}");
        }
        // Within each sequence (loops): first frame before the second.
        assert!(got.iter().all(|&(x, y)| x < y as usize), "{got:?}");
        assert!(
            best_per_pair(
                &features,
                1,
                &spans,
                &TransitionOptions { top_n: 0, ..opts }
            )
            .is_empty()
        );
    }

    /// A full measure: the cheap (1-D) distance plus `extra` on the pairs
    /// `inside` says (what Eq. 1 sees and the descriptor does not).
    struct Full<'a> {
        f: &'a [f32],
        extra: f32,
        inside: &'a (dyn Fn(usize, usize) -> bool + Sync),
    }
    impl PairDistance for Full<'_> {
        fn frames(&self) -> usize {
            self.f.len()
        }
        fn distance(&self, a: usize, b: usize) -> f64 {
            let bump = if (self.inside)(a, b) || (self.inside)(b, a) {
                self.extra
            } else {
                0.0
            };
            ((self.f[a] - self.f[b]).abs() + bump) as f64
        }
    }

    /// Issue 43, the near-ties: sequence `b` repeats two stretches of `a`,
    /// the first exactly by the cheap distance but not by the full measure
    /// (which adds `extra` there), the second with a little noise. The
    /// cheap ranking keeps the first; the re-ranking keeps what the dense
    /// search on the full measure keeps — at the same frames — whatever the
    /// sequences' order, sign or shift.
    #[test]
    fn the_full_measure_settles_the_near_ties() {
        let signal = |t: usize| ((t as f32) * 0.37).sin() * 3.0 + (t as f32) * 0.01;
        for (k, (flip, first_b, shift)) in [(1.0, false, 0.0), (-1.0, true, 5.0), (1.0, true, -2.0)]
            .into_iter()
            .enumerate()
        {
            let a: Vec<f32> = (0..120).map(|t| flip * signal(t) + shift).collect();
            let mut b: Vec<f32> = (0..100)
                .map(|t| flip * (20.0 + (t as f32 * 0.23).cos()) + shift)
                .collect();
            b[10..40].copy_from_slice(&a[30..60]);
            for (t, v) in b.iter_mut().enumerate().take(90).skip(60) {
                *v = a[t + 10] + 0.01 * ((t * 7 % 5) as f32 - 2.0);
            }
            let (la, lb) = (a.len(), b.len());
            let (features, spans, a0, b0) = if first_b {
                let f: Vec<f32> = b.iter().chain(&a).copied().collect();
                (f, vec![span("b", 0, lb), span("a", lb, la)], lb, 0)
            } else {
                let f: Vec<f32> = a.iter().chain(&b).copied().collect();
                (f, vec![span("a", 0, la), span("b", la, lb)], 0, la)
            };
            // The first copy, a's 30..60 on b's 10..40, as frames of `features`.
            let inside = move |x: usize, y: usize| {
                (a0 + 30..a0 + 60).contains(&x) && (b0 + 10..b0 + 40).contains(&y)
            };
            let full = Full {
                f: &features,
                extra: 0.5,
                inside: &inside,
            };
            let opts = TransitionOptions {
                top_n: 1,
                ..TransitionOptions::default()
            };
            let across = |v: Vec<(usize, u32)>| -> Vec<(usize, usize)> {
                v.into_iter()
                    .map(|(x, y)| (x, y as usize))
                    .filter(|&(x, y)| spans[0].len <= y && x < spans[0].len)
                    .map(|(x, y)| if first_b { (y, x) } else { (x, y) })
                    .collect()
            };
            // The dense search on the full measure, a's rows, b's columns.
            let g = |r: usize, s: usize| full.distance(a0 + r, b0 + s) as f32;
            let dense = find(&g, la, lb, false, &opts);
            let (m, n) = (a0 + dense[0].0, b0 + dense[0].1);
            assert!((70..100).contains(&(m - a0)), "{k}: {dense:?}");
            let cheap = across(best_per_pair(&features, 1, &spans, &opts));
            assert_eq!(cheap.len(), 1, "{k}");
            assert!(inside(cheap[0].0, cheap[0].1), "{k}: {cheap:?}");
            let rerank = Rerank {
                full: &full,
                examine: 8,
            };
            let done = std::sync::atomic::AtomicU64::new(0);
            let step = |k: u64| {
                done.fetch_add(k, std::sync::atomic::Ordering::Relaxed);
            };
            let (refined, evaluated) =
                best_per_pair_refined(&features, 1, &spans, None, &opts, rerank, &step);
            assert_eq!(across(refined), vec![(m, n)], "{k}");
            // The progress adds up to the scan's total: every block once.
            assert_eq!(done.into_inner(), scan_total(&spans, None), "{k}");
            assert_eq!(
                scan_total(&spans, None),
                ((la + lb).pow(2) + la * la + lb * lb) as u64 / 2
            );
            // Far fewer full measures than the block's pairs.
            assert!(
                evaluated > 0 && evaluated < (la * lb) as u64 / 4,
                "{k}: {evaluated}"
            );
        }
    }

    #[test]
    fn spread_stays_in_the_sequence() {
        let spans = vec![span("a", 0, 50), span("b", 50, 30)];
        let seq: Vec<u32> = (0..80).map(|f| u32::from(f >= 50)).collect();
        let out = spread_seeds(&[(10, 52), (20, 70)], 5, &spans, &seq);
        assert_eq!(out, vec![(10, 52), (10, 57), (20, 70), (20, 65), (20, 75)]);
        assert_eq!(spread_seeds(&[(1, 2)], 0, &spans, &seq), vec![(1, 2)]);
    }
}
