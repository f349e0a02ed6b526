//! Lower bounds of Table III's smoothness (Huang et al. 2015, Sec. 6.1):
//! how smooth can a transition, and a key-frame path, of a given database
//! be at best?
//!
//! **Transition floor.** A transition `(m, n, L)` (Sec. 4.2) blends the
//! frames `M_i(m+k)`, `M_j(n+k)`, `k ∈ [−L, L]`; its smoothness is the
//! α′(k)-weighted average (Eq. 2's weights) of their surface Hausdorff
//! distances ([`super::smoothness`]). The floor is the least smoothness
//! over *every* frame pair `(m, n)` of every sequence pair (not only the
//! local minima of the shape matrix the graph keeps), every window
//! `L ∈ [min_window, max_window]` that fits both sequences (the graph's
//! Sec. 4.2 rules: `L < 25`, within one sequence `|m − n| ≥ min_gap`).
//! It is found exactly by bounding: the distance from every
//! `coarse_stride`-th vertex is a lower bound of the distance (a maximum
//! over fewer vertices), so is its weighted window; windows are visited in
//! increasing coarse bound, refined with `fine_stride`, and measured in
//! full only while their bound is under the best found.
//!
//! **Path floor.** The smoothness of a path is the mean of its
//! transitions' (Table III averages it over the grid's paths). On a frame
//! graph priced by smoothness, [`path_floor`] gives the least mean over
//! all paths from one key-frame to another with `k` transitions, for every
//! `k` up to a bound, by a dynamic programme over (frame, transitions so
//! far): a lower bound of every query's smoothness between those
//! key-frames (the search's 4-frame spacing of transitions is relaxed).

use super::graph::KeyGraph;
use super::smoothness::FrameSet;
use crate::db::Character;
use crate::graph::transitions::TransitionOptions;
use crate::graph::{FlatFrame, SurfaceMotionGraph};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::HashMap;

/// Options of [`transition_floor`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloorOptions {
    /// Smallest half-window `L`.
    pub min_window: usize,
    /// Largest half-window `L`.
    pub max_window: usize,
    /// Within one sequence, the smallest `|m − n|`.
    pub min_gap: usize,
    /// Vertex stride of the first bound. Default: 64.
    pub coarse_stride: usize,
    /// Vertex stride of the second bound. Default: 8.
    pub fine_stride: usize,
    /// Transitions at most this smooth are counted (metres). Default: 0.04
    /// (the goal).
    pub threshold: f64,
}

impl FloorOptions {
    /// The windows and gap of the graph's transition search (Sec. 4.2).
    pub fn of_graph(t: &TransitionOptions) -> FloorOptions {
        FloorOptions {
            min_window: t.min_window.max(1),
            max_window: t.max_window.max(t.min_window.max(1)),
            min_gap: t.min_gap,
            coarse_stride: 64,
            fine_stride: 8,
            threshold: 0.04,
        }
    }
}

/// One transition window `(m, n, L)` and its smoothness.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Window {
    /// Sequence of `m`.
    pub from: String,
    /// Centre frame in `from`.
    pub m: usize,
    /// Sequence of `n`.
    pub to: String,
    /// Centre frame in `to`.
    pub n: usize,
    /// Half-window `L`.
    pub window: usize,
    /// Weighted surface Hausdorff distance (metres).
    pub smoothness: f64,
}

/// The floor of one (unordered) sequence pair.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PairFloor {
    /// First sequence.
    pub a: String,
    /// Second sequence (the same for transitions within one).
    pub b: String,
    /// The smoothest window (`None` when no window fits).
    pub best: Option<Window>,
    /// Frame pairs `(m, n)` whose window's fine lower bound is at most the
    /// threshold (at least as many as are).
    pub under_bound: usize,
    /// Distinct transitions at most the threshold (measured in full): taken
    /// greedily in increasing fine bound, each suppressing the others
    /// within `min_gap` frames in both sequences (as the graph keeps its
    /// top N).
    pub under_distinct: usize,
    /// Windows measured in full.
    pub measured: usize,
}

/// [`transition_floor`]'s result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TransitionFloor {
    /// The smoothest window of the database.
    pub best: Option<Window>,
    /// Per sequence pair, as in [`TransitionFloor::best`].
    pub pairs: Vec<PairFloor>,
    /// The threshold of [`PairFloor::under_distinct`] (metres).
    pub threshold: f64,
    /// Frame pairs `(m, n)` with a window that fits.
    pub candidates: usize,
    /// Every frame pair with its window's coarse lower bound, as jumps
    /// `(frame left, frame entered, bound, L)` in both directions (for
    /// [`path_floor`] on [`KeyGraph::of_character_with`]).
    #[serde(skip)]
    pub bounds: Vec<(FlatFrame, FlatFrame, f64, usize)>,
}

/// The α′(k)-weighted average of `h(k)`, `k ∈ [−l, l]`, the least over
/// `l ∈ [lo, hi]` and its `l` (as [`super::smoothness::weighted`], every
/// frame present).
fn best_window(h: &[f64], lo: usize, hi: usize) -> (usize, f64) {
    let c = (h.len() - 1) / 2;
    let mut best = (lo, f64::INFINITY);
    for l in lo..=hi.min(c) {
        let (mut num, mut den) = (0.0, 0.0);
        for k in -(l as i64)..=(l as i64) {
            let alpha = (k + l as i64) as f64 / (2 * l) as f64;
            let w = alpha.min(1.0 - alpha);
            if w > 0.0 {
                num += w * h[(c as i64 + k) as usize];
                den += w;
            }
        }
        let v = if den > 0.0 { num / den } else { 0.0 };
        if v < best.1 {
            best = (l, v);
        }
    }
    best
}

/// A distance of frame pairs at one stride, cached.
struct Level<'a> {
    frames: &'a FrameSet,
    stride: usize,
    cache: HashMap<(FlatFrame, FlatFrame), f64>,
}

impl Level<'_> {
    /// The weighted window `(l, value)` of the diagonal `(a + k, b + k)`,
    /// `k ∈ [−hi, hi]`, measuring missing pairs in parallel.
    fn window(&mut self, a: FlatFrame, b: FlatFrame, lo: usize, hi: usize) -> (usize, f64) {
        // The callers keep `a ± hi` and `b ± hi` inside their sequences.
        let at = |f: FlatFrame, k: i64| FlatFrame::new((i64::from(f.get()) + k) as u32);
        let pairs: Vec<(FlatFrame, FlatFrame)> = (-(hi as i64)..=hi as i64)
            .map(|k| (at(a, k), at(b, k)))
            .map(|(x, y)| (x.min(y), x.max(y)))
            .collect();
        let missing: Vec<(FlatFrame, FlatFrame)> = pairs
            .iter()
            .copied()
            .filter(|p| !self.cache.contains_key(p))
            .collect();
        let (frames, stride) = (self.frames, self.stride);
        let got: Vec<((FlatFrame, FlatFrame), f64)> = missing
            .par_iter()
            .map(|&(x, y)| ((x, y), frames.distance(x, y, stride)))
            .collect();
        self.cache.extend(got);
        let h: Vec<f64> = pairs.iter().map(|p| self.cache[p]).collect();
        best_window(&h, lo, hi)
    }
}

/// The smoothness floor of a character's database (module docs).
pub fn transition_floor(ch: &Character, frames: &FrameSet, opts: &FloorOptions) -> TransitionFloor {
    transition_floor_with(ch, frames, opts, &mut |_, _| {})
}

/// [`transition_floor`], telling `progress(done, total)` how far it is, in
/// frame pairs of the sequence pairs (each pair's coarse distances, its
/// windows and its full measures a third each): 116 s on the README's
/// synth3 with nothing on the screen (attack s14, item 5).
pub fn transition_floor_with(
    ch: &Character,
    frames: &FrameSet,
    opts: &FloorOptions,
    progress: &mut dyn FnMut(u64, u64),
) -> TransitionFloor {
    let g = ch.graph();
    let seqs = g.sequences();
    let total: u64 = seqs
        .iter()
        .enumerate()
        .flat_map(|(i, si)| seqs.iter().skip(i).map(move |sj| (si.len * sj.len) as u64))
        .sum();
    let mut done = 0u64;
    progress(0, total);
    let mut pairs = Vec::new();
    let mut bounds = Vec::new();
    let mut candidates = 0;
    let level = |stride: usize| Level {
        frames,
        stride,
        cache: HashMap::new(),
    };
    let mut lv = Levels {
        coarse: level(opts.coarse_stride.max(1)),
        fine: level(opts.fine_stride.max(1)),
        exact: level(1),
    };
    for (i, si) in seqs.iter().enumerate() {
        for (j, sj) in seqs.iter().enumerate().skip(i) {
            let p = Pair {
                g,
                i,
                j,
                li: si.len,
                lj: sj.len,
                lo: opts.min_window.max(1),
                opts,
            };
            let size = (p.li * p.lj) as u64;
            // Coarse distances of every frame pair of the two sequences.
            lv.fill_coarse(&p);
            progress(done + size / 3, total);
            let mut cands = lv.candidates(&p, &mut bounds, &mut |at| progress(done + at, total));
            candidates += cands.len();
            progress(done + 2 * size / 3, total);
            cands.sort_by(|x, y| x.0.total_cmp(&y.0));
            let (best, mut measured) = lv.smoothest(&p, &cands);
            let (under, kept, more) = lv.distinct_under(&p, &cands);
            measured += more;
            done += size;
            progress(done, total);
            pairs.push(PairFloor {
                a: si.name.clone(),
                b: sj.name.clone(),
                best: best.map(|(e, m, n, l)| Window {
                    from: si.name.clone(),
                    m,
                    to: sj.name.clone(),
                    n,
                    window: l,
                    smoothness: e,
                }),
                under_bound: under,
                under_distinct: kept,
                measured,
            });
        }
    }
    let best = pairs
        .iter()
        .filter_map(|p| p.best.clone())
        .min_by(|a, b| a.smoothness.total_cmp(&b.smoothness));
    TransitionFloor {
        best,
        pairs,
        threshold: opts.threshold,
        candidates,
        bounds,
    }
}

/// One sequence pair `(i, j)` of [`transition_floor_with`] (`i ≤ j`), of
/// `li` and `lj` frames, windows at least `lo`.
struct Pair<'a> {
    g: &'a SurfaceMotionGraph,
    i: usize,
    j: usize,
    li: usize,
    lj: usize,
    lo: usize,
    opts: &'a FloorOptions,
}

impl Pair<'_> {
    /// The flat ids of frame `m` of sequence `i` and `n` of `j`.
    fn ids(&self, m: usize, n: usize) -> (FlatFrame, FlatFrame) {
        (self.g.flat_id(self.i, m), self.g.flat_id(self.j, n))
    }
}

/// A window that fits a pair: `(coarse bound or value, m, n, widest L)`.
type Candidate = (f64, usize, usize, usize);

/// The three levels a window is measured at (module docs): coarse, fine
/// and every vertex.
struct Levels<'a> {
    coarse: Level<'a>,
    fine: Level<'a>,
    exact: Level<'a>,
}

impl Levels<'_> {
    /// The coarse distances of every frame pair of `p` not yet cached,
    /// measured in parallel.
    fn fill_coarse(&mut self, p: &Pair) {
        let (g, i, j, opts) = (p.g, p.i, p.j, p.opts);
        let coarse = &mut self.coarse;
        let all: Vec<(FlatFrame, FlatFrame)> = (0..p.li)
            .flat_map(|r| (0..p.lj).map(move |s| (r, s)))
            .filter(|&(r, s)| i != j || s >= r + opts.min_gap)
            .map(|(r, s)| {
                let (x, y) = (g.flat_id(i, r), g.flat_id(j, s));
                (x.min(y), x.max(y))
            })
            .filter(|p| !coarse.cache.contains_key(p))
            .collect();
        let (frames, stride) = (coarse.frames, coarse.stride);
        let got: Vec<((FlatFrame, FlatFrame), f64)> = all
            .par_iter()
            .map(|&(x, y)| ((x, y), frames.distance(x, y, stride)))
            .collect();
        coarse.cache.extend(got);
    }

    /// Every window that fits `p`, with its coarse bound; each frame pair's
    /// bound also goes to `bounds` as jumps in both directions. `at` is
    /// told the progress within the pair (the second third of its size).
    fn candidates(
        &mut self,
        p: &Pair,
        bounds: &mut Vec<(FlatFrame, FlatFrame, f64, usize)>,
        at: &mut dyn FnMut(u64),
    ) -> Vec<Candidate> {
        let (li, lj, opts) = (p.li, p.lj, p.opts);
        let size = (li * lj) as u64;
        let mut cands: Vec<Candidate> = Vec::new();
        for m in 0..li {
            at(size / 3 + size * m as u64 / (3 * li as u64));
            for n in 0..lj {
                if p.i == p.j && n < m + opts.min_gap {
                    continue;
                }
                let hi = m
                    .min(n)
                    .min(li - 1 - m)
                    .min(lj - 1 - n)
                    .min(opts.max_window);
                if hi < p.lo {
                    continue;
                }
                let (a, b) = p.ids(m, n);
                let (l, v) = self.coarse.window(a, b, p.lo, hi);
                cands.push((v, m, n, hi));
                if n + 1 < lj {
                    bounds.push((a, b.next(), v, l));
                }
                if m + 1 < li {
                    bounds.push((b, a.next(), v, l));
                }
            }
        }
        cands
    }

    /// The smoothest window of a pair, `(value, m, n, L)`, from its
    /// candidates in increasing coarse bound: refined, measured in full
    /// while the bounds are under the best; and the windows measured.
    fn smoothest(&mut self, p: &Pair, cands: &[Candidate]) -> (Option<Candidate>, usize) {
        let mut best: Option<Candidate> = None;
        let mut measured = 0;
        for &(v, m, n, hi) in cands {
            let bar = best.map_or(f64::INFINITY, |b| b.0);
            if v >= bar {
                break;
            }
            let (a, b) = p.ids(m, n);
            if self.fine.window(a, b, p.lo, hi).1 >= bar {
                continue;
            }
            let (l, e) = self.exact.window(a, b, p.lo, hi);
            measured += 1;
            if e < bar {
                best = Some((e, m, n, l));
            }
        }
        (best, measured)
    }

    /// Windows under the threshold: every frame pair whose fine bound is
    /// (a superset), then distinct ones greedily in increasing fine bound,
    /// each measured in full unless a kept one within `min_gap` suppresses
    /// it. Returns the counts of both and the windows measured.
    fn distinct_under(&mut self, p: &Pair, cands: &[Candidate]) -> (usize, usize, usize) {
        let opts = p.opts;
        let mut under: Vec<Candidate> = cands
            .iter()
            .take_while(|c| c.0 <= opts.threshold)
            .map(|&(_, m, n, hi)| {
                let (a, b) = p.ids(m, n);
                let f = self.fine.window(a, b, p.lo, hi).1;
                (f, m, n, hi)
            })
            .filter(|c| c.0 <= opts.threshold)
            .collect();
        under.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut kept: Vec<(usize, usize)> = Vec::new();
        let mut measured = 0;
        for &(_, m, n, hi) in &under {
            let near = |a: usize, b: usize| a.abs_diff(b) <= opts.min_gap;
            if kept.iter().any(|&(km, kn)| near(km, m) && near(kn, n)) {
                continue;
            }
            let (a, b) = p.ids(m, n);
            let (_, e) = self.exact.window(a, b, p.lo, hi);
            measured += 1;
            if e <= opts.threshold {
                kept.push((m, n));
            }
        }
        (under.len(), kept.len(), measured)
    }
}

/// [`path_floor`]'s result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PathFloor {
    /// A path without any transition reaches the end key-frame.
    pub direct: bool,
    /// The least mean transition cost of a path with exactly `k`
    /// transitions, `k = 1, 2, …` (`None`: no such path).
    pub by_count: Vec<Option<f64>>,
    /// The least over `by_count`, with its `k`.
    pub best: Option<(usize, f64)>,
}

/// The least mean jump cost over paths of `g` from frame `from` to frame
/// `to` with `k ∈ [1, max_transitions]` jumps (module docs). With `g`
/// priced by smoothness, a lower bound of the smoothness of every path
/// between the two key-frames with at most that many transitions.
pub fn path_floor(
    g: &KeyGraph,
    from: FlatFrame,
    to: FlatFrame,
    max_transitions: usize,
) -> PathFloor {
    let n = g.step.len();
    let inf = f64::INFINITY;
    // Along a sequence: frames reachable without a jump.
    let sweep = |d: &mut Vec<f64>| {
        for f in 0..n {
            if !d[f].is_finite() {
                continue;
            }
            for e in &g.edges[g.offsets[f] as usize..g.offsets[f + 1] as usize] {
                if !e.jump && d[f] < d[e.to.index()] {
                    d[e.to.index()] = d[f];
                }
            }
        }
    };
    let mut d = vec![inf; n];
    if from.index() < n {
        d[from.index()] = 0.0;
    }
    sweep(&mut d);
    let direct = to.index() < n && d[to.index()].is_finite();
    let mut by_count = Vec::new();
    for _ in 0..max_transitions {
        let mut next = vec![inf; n];
        for (f, &df) in d.iter().enumerate() {
            if !df.is_finite() {
                continue;
            }
            for e in &g.edges[g.offsets[f] as usize..g.offsets[f + 1] as usize] {
                let c = df + e.cost;
                if e.jump && c < next[e.to.index()] {
                    next[e.to.index()] = c;
                }
            }
        }
        sweep(&mut next);
        d = next;
        let k = by_count.len() + 1;
        by_count.push(
            d.get(to.index())
                .filter(|x| x.is_finite())
                .map(|x| x / k as f64),
        );
    }
    let best = by_count
        .iter()
        .enumerate()
        .filter_map(|(k, v)| v.map(|v| (k + 1, v)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    PathFloor {
        direct,
        by_count,
        best,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn best_window_is_the_least_alpha_prime_average_over_the_windows() {
        // h(k) for k ∈ [−3, 3]. L = 1: α′ = 0, ½, 0 → h(0) = 1; L = 2:
        // ¼·1 + ½·1 + ¼·0 = 0.75 (weights sum to 1); L = 3: α′ = ⅙, ⅓, ½,
        // ⅓, ⅙ over 4, 1, 1, 0, 9 → 3 / 1.5 = 2.
        let h = [9.0, 4.0, 1.0, 1.0, 0.0, 9.0, 9.0];
        let (l, v) = best_window(&h, 1, 1);
        assert_eq!(l, 1);
        assert!((v - 1.0).abs() < 1e-12);
        let (l, v) = best_window(&h, 1, 3);
        assert_eq!(l, 2);
        assert!((v - 0.75).abs() < 1e-12);
        let (l, v) = best_window(&h, 3, 3);
        assert_eq!(l, 3);
        assert!((v - 2.0).abs() < 1e-12);
    }

    /// Two sequences of 10 frames (0-9, 10-19) with the jumps given.
    fn two(jumps: &[(u32, u32, f64)]) -> KeyGraph {
        let mut succ: Vec<Vec<(FlatFrame, f64)>> = (0..20u32)
            .map(|f| {
                if f % 10 != 9 {
                    vec![(FlatFrame::new(f + 1), 0.0)]
                } else {
                    vec![]
                }
            })
            .collect();
        for &(a, b, c) in jumps {
            succ[a as usize].push((FlatFrame::new(b), c));
        }
        let seq = (0..20).map(|f| f / 10).collect();
        KeyGraph::new(&succ, vec![[0.0; 2]; 20], seq)
    }

    #[test]
    fn path_floor_is_the_least_mean_over_paths_with_k_transitions() {
        // 0 → 15 needs the jump 3 → 12 (0.3); the loop 16 → 11 (0.1)
        // dilutes it: k = 2: (0.3 + 0.1) / 2; k = 3: 0.5 / 3.
        let g = two(&[(3, 12, 0.3), (16, 11, 0.1), (5, 18, 0.9)]);
        let f = FlatFrame::new;
        let p = path_floor(&g, f(0), f(15), 3);
        assert!(!p.direct);
        let want = [0.3, 0.2, 0.5 / 3.0];
        for (got, want) in p.by_count.iter().zip(want) {
            assert!((got.unwrap() - want).abs() < 1e-12, "{got:?} {want}");
        }
        assert_eq!(p.best.map(|b| b.0), Some(3));
        // A key-frame later in the same sequence needs no transition; one
        // before the start with no loop back cannot be reached.
        assert!(path_floor(&g, f(0), f(7), 2).direct);
        let back = path_floor(&g, f(12), f(2), 4);
        assert!(!back.direct && back.best.is_none());
    }
}
