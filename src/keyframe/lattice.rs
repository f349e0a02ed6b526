//! The exact-length search (an extension of Huang et al. 2015, Sec. 5.1):
//! a dynamic programme over the frame count that finds a path of exactly
//! `N` frames whose travelled distance (Eq. 10) lands on the target, with
//! the least transition cost (Eq. 8).
//!
//! The paper's search (walks plus repeated loops, [`super::search`]) can
//! only make the distances a walk plus whole repetitions of *its own*
//! loops make; short targets and targets between two loop speeds are then
//! missed by up to a metre (the paper's Table III: max distance error
//! 0.96 m). Any path is a sequence of arcs of the compressed graph, so a
//! programme over `(node, frames so far)` covers every path, nested loops
//! and loops attached to loops included:
//!
//! 1. **Exact-length extremes** (once per query): `r_min(u, m)` and
//!    `r_max(u, m)`, the least and the most distance from node `u` to the
//!    goal in exactly `m` frames, by a programme over `m`.
//! 2. **Forward labels** `(distance D, transition cost C)` per
//!    `(node, frames k)`. A label is kept only if the goal can still be
//!    reached in the remaining `N − k` frames with a distance that lands
//!    within the tolerance `T` of the target:
//!    `d_V − r_max − T ≤ D ≤ d_V − r_min + T`. That window is split into
//!    `B` bins, and each bin keeps its cheapest label; near the end the
//!    window shrinks to `2T`, so the final distance resolution is `2T/B`.
//! 3. The goal's labels at `k = N` are scored with Eq. 7 and the best is
//!    traced back.
//!
//! Two transitions are at least [`LatticeOptions::min_run`] frames apart
//! (a path that jumps out of a sequence on the frame it jumped into would
//! show that frame alone, unblended); the extremes ignore this rule, so
//! they stay valid bounds.
//!
//! The binning makes this a bounded search (like a beam), not a proof of
//! optimality: [`super::segment::Segment::solve`] keeps the paper's search
//! as the fallback when no path lands within `T`, and reports which one
//! found the result. `r_min(start, N) ≤ d_V ≤ r_max(start, N)` is necessary
//! for a path of `N` frames to travel `d_V` ([`extremes`]), not sufficient:
//! the distances of the paths of `N` frames have gaps ([`oracle`]).
//!
//! The programme runs on a [`Chain`]: one segment's compressed graph, or
//! the segments between several key-frames joined at each key-frame, so
//! that one global target is split over the segments optimally (any path
//! through the key-frames in order is a path of the chain).
//!
//! **Pruning** ([`LatticeOptions::prune`]). Step 1 also keeps
//! `c_min(u, m)`, the least transition cost from `u` to the goal in
//! exactly `m` frames ([`Extremes::least_cost`]). Every term of Eq. 7 but
//! the transition cost is non-negative, so a frame count `N` whose
//! `c_min(start, N)` plus its lower bound reaches the best total found so
//! far is not searched, and within the programme a label of cost `C` at
//! `(u, k)` with `C + c_min(u, N − k)` at that cap is kept but not
//! extended ([`solve_capped`]): any path through it costs at least the
//! best already found. `c_min` obeys `c_min(u, m) ≤ cost(a) + c_min(v, m −
//! frames(a))` along every arc `a = u → v`, so the descendants of a label
//! not extended would not have been either, and a bin whose cheapest
//! label is missing for that reason holds only labels at least as dear,
//! not extended either: the labels extended are those the unpruned
//! programme extends whose bound is below the cap, and the result is the
//! unpruned one whenever it beats the cap (else it was not taken anyway).
//! The one exception is the labels of least and most distance of a node,
//! chosen by distance, not cost: if the extreme one is missing, the next
//! one is kept in its place and may be extended. The grids of the README
//! give the same reports with and without pruning, and
//! `tests/it/keyframe/search.rs::cost_pruning_keeps_the_unpruned_result_on_random_graphs`
//! compares the two.
//!
//! **Probe** ([`LatticeOptions::probe_bins`], with a heading target). The
//! first frame count of a query is searched with no cap (no path is known
//! yet). With a probe, a cheaper programme (one bin in the coarse cells,
//! [`LatticeOptions::probe_fine`] near the goal) runs first, and its
//! path's score caps the full programme; the cheaper of the two paths is
//! returned. By the argument above the full programme returns its
//! unpruned result whenever that beats the probe's, so no query gets a
//! dearer path (Eq. 7) than without the probe; a probe path that does
//! not land within [`LatticeOptions::within`] of both targets is not used
//! as a cap (the "within" pass could then replace a landing result by a
//! dearer one). The probe's path, often cheaper than the full
//! programme's where the binning decides, also caps the frame counts
//! searched after it. Only with a heading target: on bandai9's heading
//! query it cut the search's CPU time from 1.30 to 0.81 s (README), but
//! without a heading, where the transition costs are small against the
//! cap, the cap pruned little and the probe's own time was added (a
//! 70-target bandai9 grid: 45 → 66 ms of CPU a query).
//!
//! **Following** ([`LatticeOptions::follow`]). A node that leaves a label
//! one usable arc only (a transition's head that starts no transition,
//! and every node in the [`LatticeOptions::min_run`] frames after a
//! transition, where only the run of plain frames may be taken) offers no
//! choice: the label is followed through such nodes to the next node
//! with a choice, or the goal, and binned there only (the steps are
//! recorded for the trace-back). No path is lost (a label that reaches a
//! dead end or overruns the frame count is dropped: it had no
//! continuation); what changes is only where labels are merged.
//!
//! **Classes** ([`LatticeOptions::dominance`]). The bins are split by the
//! frames since the last transition, capped at `min_run` (a label that
//! may not jump yet must not be merged with one that may). A label with
//! more frames since its last transition has every continuation of one
//! with fewer (the same arcs, and a class at least as high after each), so
//! in one distance bin (the binning's own equivalence) it dominates any
//! label of a lower class that costs no less; those are dropped.
//!
//! Neither loses a path, but labels are merged at other places, so a
//! result may differ where the binning decides (README: samba's grid
//! is unchanged, 3 of synth3's 800 queries take other transitions; on
//! bandai9 they cut the programme's CPU time by about a quarter);
//! `tests/it/keyframe/search.rs::following_one_arc_nodes_loses_no_path_against_an_exhaustive_search`
//! compares both settings with an exhaustive search on random graphs.
//!
//! **Coarse bins** ([`LatticeOptions::coarse_bins`],
//! [`LatticeOptions::coarse_from`]). A cell whose window is wider than
//! `coarse_from · 2T` (far from the goal: the remaining frames can still
//! move the final distance by several final windows) keeps
//! `coarse_bins` bins (default 4) instead of `bins` (32); the cells near
//! the goal, where the window narrows to `2T` and the final resolution is
//! set, keep all of them. Labels merged far from the goal differ by
//! distances the remaining path can still make up, so what is lost is
//! mostly the cheaper of two labels, not a landing distance. This is a
//! heuristic, not a bound: results differ where the binning decides. On
//! bandai9's 200-target grid (walk → run_happy) the query CPU time fell
//! by about 3.5× with every target met within 1 % before still met, and
//! the mean Eq. 7 total over them 0.0600 → 0.0623 (README);
//! `tests/it/keyframe/search.rs::coarse_bins_far_from_the_goal_meet_what_the_fine_search_meets`
//! compares the two on random graphs. The reachability oracle keeps the
//! fine bins everywhere.
//!
//! **Threads** (opt-in). A layer of at least
//! [`LatticeOptions::parallel_from`] labels is cut into runs of whole nodes, one per thread of the current
//! rayon pool (at most 8), each binned and extended apart; their outputs
//! are appended in node order, so the labels, their order and the result
//! are those of one thread.
//!
//! Extensions of Eq. 7 (documented departures from the paper):
//! - **Heading** ([`Heading`]): labels carry the heading's accumulated turn
//!   (the placement's rotation at every transition, [`super::place`]); a
//!   term `w_head · |turn − target|` (wrapped to ±180°) is added at the
//!   goal, and the bins are split into sectors of turn so that paths that
//!   end facing different ways survive the binning.
//! - **Within tolerance** ([`LatticeOptions::within`]): when the Eq. 7
//!   optimum misses the distance or the time by more than the tolerance
//!   but some path of a frame count within the time tolerance lands within
//!   the distance tolerance, the cheapest such path is returned instead
//!   (Eq. 7's weights can prefer a 4-frame time error to a 10 cm distance
//!   error; an animator asking for 6 m in 4 s wants both met when the
//!   graph can).

use super::heading::Heading;
use super::options::{LatticeOptions, SearchOptions, Weights};
use super::repeats::Tally;
use super::segment::{ArcView, Segment, Target};
use crate::util::budget::OverBudget;

/// The graph the programme walks: one segment's compressed graph, or
/// several joined at their key-frames (module docs). It keeps its
/// exact-length extremes (step 1) once computed, so that the queries of a
/// grid share them ([`Chain::extremes`]).
#[derive(Debug, Clone)]
pub struct Chain {
    /// Arcs leaving every node (indices global over the segments).
    adj: Vec<Vec<ArcView>>,
    relevant: Vec<bool>,
    start: u32,
    goal: u32,
    /// First global arc index of every segment.
    arc_offsets: Vec<u32>,
    /// The first segment counts its start frame.
    count_start: bool,
    /// Fewest frames (start not counted) over all segments.
    least: u32,
    /// The extremes computed so far (step 1 depends on the chain alone).
    cache: ExtremesCache,
}

/// The extremes of a chain for the longest frame count asked so far.
#[derive(Default)]
struct ExtremesCache(std::sync::Mutex<Option<std::sync::Arc<Extremes>>>);

impl Clone for ExtremesCache {
    fn clone(&self) -> Self {
        let v = self.0.lock().map(|g| g.clone()).unwrap_or_default();
        ExtremesCache(std::sync::Mutex::new(v))
    }
}

impl std::fmt::Debug for ExtremesCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let frames = self
            .0
            .lock()
            .ok()
            .and_then(|g| g.as_ref().map(|e| e.frames()));
        write!(f, "ExtremesCache({frames:?} frames)")
    }
}

impl Chain {
    /// The chain of consecutive segments (the end key-frame of each is the
    /// start of the next). `None` when a segment after the first starts
    /// where it ends (a repeated key-frame: the walks' search handles it).
    pub fn of(segs: &[Segment]) -> Option<Chain> {
        let k = segs.len();
        if k == 0 || (k > 1 && segs.iter().any(|s| s.start() == s.goal())) {
            return None;
        }
        let mut node_off = vec![0u32; k + 1];
        let mut arc_off = vec![0u32; k + 1];
        for (i, s) in segs.iter().enumerate() {
            node_off[i + 1] = node_off[i] + s.node_count() as u32;
            arc_off[i + 1] = arc_off[i] + s.arc_count() as u32;
        }
        let n = node_off[k] as usize;
        let mut adj = vec![Vec::new(); n];
        let mut relevant = vec![false; n];
        let shift = |i: usize, a: ArcView| ArcView {
            index: a.index + arc_off[i],
            to: a.to + node_off[i],
            ..a
        };
        for (i, s) in segs.iter().enumerate() {
            for u in 0..s.node_count() as u32 {
                let g = (node_off[i] + u) as usize;
                relevant[g] = s.is_relevant(u);
                if !relevant[g] {
                    continue;
                }
                adj[g].extend(s.arcs_from_indexed(u).map(|a| shift(i, a)));
                if i + 1 < k && u == s.goal() {
                    let nx = &segs[i + 1];
                    adj[g].extend(nx.arcs_from_indexed(nx.start()).map(|a| shift(i + 1, a)));
                }
            }
        }
        Some(Chain {
            adj,
            relevant,
            start: node_off[0] + segs[0].start(),
            goal: node_off[k - 1] + segs[k - 1].goal(),
            arc_offsets: arc_off[..k].to_vec(),
            count_start: segs[0].counts_start(),
            least: segs.iter().map(|s| s.least_frames()).sum(),
            cache: ExtremesCache::default(),
        })
    }

    /// The exact-length extremes for at least `0..=m` frames (step 1),
    /// computed once and shared by every query on the chain: a longer
    /// table is computed (at least doubling the last) only when a query
    /// needs more frames. The rows of `0..=m` do not depend on how far
    /// the table goes, so the result is the one [`chain_extremes`] gives.
    /// An error when the table for `m` frames exceeds the memory budget
    /// ([`crate::util::budget`]; the doubled table is only taken when it fits).
    pub fn extremes(&self, m: usize) -> Result<std::sync::Arc<Extremes>, OverBudget> {
        let mut g = match self.cache_lock() {
            Some(g) => g,
            None => return Ok(std::sync::Arc::new(chain_extremes(self, m)?)),
        };
        if let Some(e) = g.as_ref().filter(|e| e.frames() >= m) {
            return Ok(e.clone());
        }
        let have = g.as_ref().map_or(0, |e| e.frames());
        let more = m.max((2 * have).min(20_000));
        let fits = crate::util::budget::Budget::current().bytes as u128
            >= extremes_bytes(self.node_count(), more);
        let e = std::sync::Arc::new(chain_extremes(self, if fits { more } else { m })?);
        *g = Some(e.clone());
        Ok(e)
    }

    #[allow(clippy::type_complexity)]
    fn cache_lock(&self) -> Option<std::sync::MutexGuard<'_, Option<std::sync::Arc<Extremes>>>> {
        self.cache.0.lock().ok()
    }

    /// The start node.
    pub fn start_node(&self) -> u32 {
        self.start
    }

    /// True when the first segment counts its start frame.
    pub(crate) fn counts_start(&self) -> bool {
        self.count_start
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.adj.len()
    }

    /// The same chain with every arc's cost replaced by `f(arc)`, and no
    /// extremes computed yet: the ratio search of [`super::smoothest`]
    /// prices a transition `s − λ`, negative when it is smoother than `λ`.
    pub(crate) fn repriced(&self, f: impl Fn(&ArcView) -> f64) -> Chain {
        let mut c = self.clone();
        for a in c.adj.iter_mut().flatten() {
            a.m.cost = f(a);
        }
        c.cache = ExtremesCache::default();
        c
    }

    /// Every arc of the chain by its global index (`None` for an index
    /// no node leaves by).
    pub fn arcs_by_index(&self) -> Vec<Option<ArcView>> {
        let n = self
            .adj
            .iter()
            .flatten()
            .map(|a| a.index as usize + 1)
            .max();
        let mut out = vec![None; n.unwrap_or(0)];
        for a in self.adj.iter().flatten() {
            out[a.index as usize] = Some(*a);
        }
        out
    }

    /// Fewest arc frames of any path (start not counted).
    pub(crate) fn least_frames(&self) -> u32 {
        self.least
    }

    /// Global arcs cut into each segment's own arcs.
    pub fn split(&self, arcs: &[u32]) -> Vec<Vec<u32>> {
        let mut out = vec![Vec::new(); self.arc_offsets.len()];
        for &a in arcs {
            let i = self.arc_offsets.partition_point(|&o| o <= a) - 1;
            out[i].push(a - self.arc_offsets[i]);
        }
        out
    }
}

/// `r_min` and `r_max` of every node for `0..=m` frames (`m`-major).
pub struct Extremes {
    nodes: usize,
    /// `[r_min, r_max]` side by side (one cache line per look-up in the
    /// programme's inner loop): the least distance to the goal in exactly
    /// `m` frames (`+∞`: none) and the most (`−∞`: none).
    range: Vec<[f64; 2]>,
    /// The least transition cost (Eq. 8) to the goal in exactly `m`
    /// frames (`+∞`: none): the cost bound of the programme's pruning
    /// ([`LatticeOptions::prune`]).
    cost: Vec<f64>,
}

impl Extremes {
    /// The longest frame count the table covers.
    pub fn frames(&self) -> usize {
        (self.range.len() / self.nodes.max(1)).saturating_sub(1)
    }
    /// `(r_min, r_max)` of node `u` in exactly `m` frames.
    pub fn at(&self, u: u32, m: usize) -> (f64, f64) {
        let [lo, hi] = self.range[m * self.nodes + u as usize];
        (lo, hi)
    }
    /// The least transition cost (Eq. 8) of a path from node `u` to the
    /// goal in exactly `m` frames (`+∞`: none; the rule of
    /// [`LatticeOptions::min_run`] ignored, so a lower bound).
    pub fn least_cost(&self, u: u32, m: usize) -> f64 {
        self.cost[m * self.nodes + u as usize]
    }
}

/// The exact-length extremes of a segment up to `m` frames (step 1);
/// an error when they exceed the memory budget.
pub fn extremes(seg: &Segment, m: usize) -> Result<Extremes, OverBudget> {
    match Chain::of(std::slice::from_ref(seg)) {
        Some(c) => chain_extremes(&c, m),
        None => Ok(Extremes {
            nodes: 0,
            range: Vec::new(),
            cost: Vec::new(),
        }),
    }
}

/// Bytes of the extremes of `nodes` nodes for `0..=m` frames (`[r_min,
/// r_max]` and the least cost: 24 bytes a cell).
pub fn extremes_bytes(nodes: usize, m: usize) -> u128 {
    nodes as u128 * (m as u128 + 1) * 24
}

/// What to change when a chain's table for `m` frames is over `budget`
/// bytes: the table is nodes (every segment's graph, one segment between
/// each two key-frames) × frame counts (the horizon of the target, or the
/// key-frames' own path when longer). When one segment's share of the
/// nodes would fit, the number of key-frames is the cause (1000 `--via`
/// were told "lower --distance or --time" for a 3 m / 3 s target).
fn budget_hint(c: &Chain, m: usize, budget: u128) -> String {
    let segments = c.arc_offsets.len().max(1);
    if segments == 1 {
        return "; lower `Targets::distance` or `Targets::time`".into();
    }
    let keys = format!(
        "{segments} segments between {} key-frames (at least {} frames through them)",
        segments + 1,
        c.least
    );
    if extremes_bytes(c.node_count().div_ceil(segments), m) <= budget {
        format!("; it grows with the {keys}: use fewer via key-frames")
    } else {
        format!(
            "; {keys}: use fewer via key-frames, or lower `Targets::distance` or `Targets::time`"
        )
    }
}

/// The exact-length extremes of a chain up to `m` frames (step 1);
/// refused before anything is allocated when the table ([`extremes_bytes`])
/// exceeds the memory budget ([`crate::util::budget`]).
pub fn chain_extremes(c: &Chain, m: usize) -> Result<Extremes, OverBudget> {
    let n = c.node_count();
    crate::util::budget::check(
        || {
            format!(
                "the key-frame search's exact-length table ({n} nodes × {} frame counts{})",
                m as u128 + 1,
                budget_hint(c, m, crate::util::budget::Budget::current().bytes as u128)
            )
        },
        extremes_bytes(n, m),
    )?;
    let mut range = vec![[f64::INFINITY, f64::NEG_INFINITY]; n * (m + 1)];
    let mut cost = vec![f64::INFINITY; n * (m + 1)];
    let goal = c.goal as usize;
    range[goal] = [0.0, 0.0];
    cost[goal] = 0.0;
    for k in 1..=m {
        for u in 0..n {
            if !c.relevant[u] {
                continue;
            }
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            let mut least = f64::INFINITY;
            for a in &c.adj[u] {
                let l = a.m.frames as usize;
                if l == 0 || l > k {
                    continue;
                }
                let at = (k - l) * n + a.to as usize;
                let [rlo, rhi] = range[at];
                if rlo.is_finite() {
                    lo = lo.min(a.m.distance + rlo);
                    hi = hi.max(a.m.distance + rhi);
                    least = least.min(a.m.cost + cost[at]);
                }
            }
            range[k * n + u] = [lo, hi];
            cost[k * n + u] = least;
        }
    }
    Ok(Extremes {
        nodes: n,
        range,
        cost,
    })
}

/// A label of the forward programme.
#[derive(Debug, Clone, Copy)]
struct Label {
    node: u32,
    /// Index of the parent in the arena (`u32::MAX` for the start).
    parent: u32,
    /// Arc taken from the parent.
    arc: u32,
    distance: f64,
    cost: f64,
    /// Accumulated heading turn (radians).
    turn: f64,
    /// Frames since the last transition.
    since: u32,
}

impl Label {
    /// The label at the start (no parent, no transition yet).
    const START: Label = Label {
        node: 0,
        parent: u32::MAX,
        arc: u32::MAX,
        distance: 0.0,
        cost: 0.0,
        turn: 0.0,
        since: u32::MAX / 2,
    };
}

/// The path found: its arcs and measure (frames counted as the segment
/// counts them).
#[derive(Debug, Clone, PartialEq)]
pub struct Found {
    /// Arcs of the chain, in order (global indices, [`Chain::split`]).
    pub arcs: Vec<u32>,
    /// Transition cost, distance, frames (arc frames, the start frame not
    /// counted).
    pub measure: Tally,
    /// The heading's turn over the path (radians).
    pub turn: f64,
}

/// The best path of exactly `frames` arc frames from the start to the goal
/// whose distance lands within `tol` metres of `distance` (steps 2-3),
/// scored by transition cost + `w_dist |D − d|` + the heading term, or
/// `None`. `ext` must cover `frames`.
#[allow(clippy::too_many_arguments)]
pub fn solve_exact_length(
    c: &Chain,
    ext: &Extremes,
    frames: usize,
    distance: f64,
    tol: f64,
    w_dist: f64,
    heading: Option<&Heading>,
    opts: &LatticeOptions,
) -> Option<(Found, f64)> {
    solve_capped(
        c,
        ext,
        frames,
        distance,
        tol,
        w_dist,
        heading,
        opts,
        f64::INFINITY,
    )
}

/// [`solve_exact_length`], extending only the labels whose transition
/// cost plus [`Extremes::least_cost`] to the goal stays below `cap` (module
/// docs, "Pruning"): the same result whenever that result's transition
/// cost is below `cap`, else a result of at least that cost, or `None`.
///
/// 109 lines (house limit ~100), left whole: the layer loop is the
/// programme's steps 2-3 as the module docs give them (group a layer's
/// labels by node, cut it among the workers, expand, merge in order),
/// each step already its own function (`group_by_node`, `cut_layer`,
/// `Layer::expand`, `merge_part`, `trace_back`); what remains is the
/// buffers they share across layers.
#[allow(clippy::too_many_arguments)]
pub fn solve_capped(
    c: &Chain,
    ext: &Extremes,
    frames: usize,
    distance: f64,
    tol: f64,
    w_dist: f64,
    heading: Option<&Heading>,
    opts: &LatticeOptions,
    cap: f64,
) -> Option<(Found, f64)> {
    let bins = opts.bins.max(1);
    // Bins per class of frames since the last transition (below
    // `min_run`, and at least) and per sector of turn, plus the labels of
    // least and most distance (they alone may reach the extremes of the
    // window).
    let classes = opts.min_run as usize + 1;
    let sectors = heading.map_or(1, |h| h.sectors.max(1));
    let cells = bins * classes * sectors;
    let ctx = Layer {
        c,
        ext,
        frames,
        distance,
        tol,
        w_dist,
        heading,
        min_run: opts.min_run,
        cap,
        bins,
        classes,
        cells,
        dominance: opts.dominance,
        follow: opts.follow,
        coarse_bins: opts.coarse_bins.clamp(1, bins),
        coarse_from: opts.coarse_from,
    };
    let start = c.start;
    ctx.window(start, 0)?;
    let mut layers: Vec<Vec<Label>> = vec![Vec::new(); frames + 1];
    layers[0].push(Label {
        node: start,
        ..Label::START
    });
    // The trace-back of every kept label: its parent's index and the arc
    // from it (the labels themselves are not needed once expanded; 8 bytes
    // a label instead of 40 keeps a long query's memory small).
    let mut arena: Vec<(u32, u32)> = Vec::new();
    // Emptied layers' buffers, reused for later layers (fewer allocations
    // and page faults on long frame counts).
    let mut pool: Vec<Vec<Label>> = Vec::new();
    // One worker per thread (at most 8) on the larger layers, each with
    // its scratch and its part of the output.
    let workers = rayon::current_num_threads().clamp(1, 8);
    let mut scratch: Vec<Scratch> = (0..workers).map(|_| Scratch::new(cells)).collect();
    let mut parts: Vec<Part> = (0..workers).map(|_| Part::default()).collect();
    let mut best: Option<(u32, f64, Label)> = None;
    // Labels of a layer grouped by node (a stable counting sort).
    let nodes = c.node_count();
    let mut count = vec![0usize; nodes + 1];
    let mut raw: Vec<Label> = Vec::new();
    let mut cuts: Vec<usize> = Vec::new();
    for k in 0..=frames {
        let mut layer = std::mem::take(&mut layers[k]);
        group_by_node(&mut layer, nodes, &mut count, &mut raw);
        if layer.capacity() > 0 {
            pool.push(layer);
        }
        let used = if raw.len() >= opts.parallel_from.max(1) {
            workers
        } else {
            1
        };
        cut_layer(&raw, used, &mut cuts);
        if used == 1 {
            ctx.expand(&raw, k, &mut scratch[0], &mut parts[0]);
        } else {
            let raw = &raw;
            let cuts = &cuts;
            let ctx = &ctx;
            rayon::scope(|s| {
                for (p, (sc, out)) in scratch
                    .iter_mut()
                    .zip(parts.iter_mut())
                    .take(used)
                    .enumerate()
                {
                    s.spawn(move |_| ctx.expand(&raw[cuts[p]..cuts[p + 1]], k, sc, out));
                }
            });
        }
        for part in parts.iter_mut().take(used) {
            merge_part(part, &mut arena, &mut layers, &mut pool, &mut best);
        }
    }
    let (id, sc, l) = best?;
    Some((
        Found {
            arcs: trace_back(&arena, id),
            measure: Tally {
                cost: l.cost,
                distance: l.distance,
                frames: frames as u32,
            },
            turn: l.turn,
        },
        sc,
    ))
}

/// Groups the labels of `layer` by node into `raw` (a stable counting
/// sort over `nodes` nodes, `count` its scratch), emptying `layer`.
fn group_by_node(layer: &mut Vec<Label>, nodes: usize, count: &mut [usize], raw: &mut Vec<Label>) {
    count.iter_mut().for_each(|x| *x = 0);
    for l in layer.iter() {
        count[l.node as usize + 1] += 1;
    }
    for u in 0..nodes {
        count[u + 1] += count[u];
    }
    raw.clear();
    raw.resize(layer.len(), layer.first().copied().unwrap_or(Label::START));
    for l in layer.drain(..) {
        let at = &mut count[l.node as usize];
        raw[*at] = l;
        *at += 1;
    }
}

/// Cuts a layer grouped by node into `used` runs of whole nodes of about
/// equal size, as `cuts` (their bounds; the parts are merged in order, so
/// the result does not depend on the number of workers).
fn cut_layer(raw: &[Label], used: usize, cuts: &mut Vec<usize>) {
    cuts.clear();
    cuts.push(0);
    for p in 1..used {
        let mut at = (raw.len() * p / used).max(cuts[p - 1]);
        while at > 0 && at < raw.len() && raw[at].node == raw[at - 1].node {
            at += 1;
        }
        cuts.push(at);
    }
    cuts.push(raw.len());
}

/// Merges one worker's output into the programme: its trace-back entries
/// into `arena` (indices rebased), its labels into the later `layers`
/// (reusing emptied buffers from `pool`), its best label into `best`.
fn merge_part(
    part: &mut Part,
    arena: &mut Vec<(u32, u32)>,
    layers: &mut [Vec<Label>],
    pool: &mut Vec<Vec<Label>>,
    best: &mut Option<(u32, f64, Label)>,
) {
    let base = arena.len() as u32;
    arena.append(&mut part.arena);
    for x in part.local.drain(..) {
        arena[(base + x) as usize].0 += base;
    }
    for (kk, mut l) in part.pushes.drain(..) {
        l.parent += base;
        let next = &mut layers[kk as usize];
        if next.capacity() == 0
            && let Some(buf) = pool.pop()
        {
            *next = buf;
        }
        next.push(l);
    }
    if let Some((id, sc, l)) = part.best.take()
        && best.is_none_or(|(_, b, _)| sc < b)
    {
        *best = Some((id + base, sc, l));
    }
}

/// The arcs of the path ending at label `id`, from the trace-back `arena`.
fn trace_back(arena: &[(u32, u32)], id: u32) -> Vec<u32> {
    let mut arcs = Vec::new();
    let mut at = id;
    while arena[at as usize].0 != u32::MAX {
        arcs.push(arena[at as usize].1);
        at = arena[at as usize].0;
    }
    arcs.reverse();
    arcs
}

/// What one call of the programme fixes (steps 2-3).
struct Layer<'a> {
    c: &'a Chain,
    ext: &'a Extremes,
    frames: usize,
    distance: f64,
    tol: f64,
    w_dist: f64,
    heading: Option<&'a Heading>,
    min_run: u32,
    cap: f64,
    bins: usize,
    classes: usize,
    cells: usize,
    dominance: bool,
    follow: bool,
    coarse_bins: usize,
    coarse_from: f64,
}

/// A worker's bins: the slots set for the current node (reset for the
/// next), and the labels they keep.
struct Scratch {
    slot: Vec<Option<usize>>,
    touched: Vec<usize>,
    kept: Vec<usize>,
}

impl Scratch {
    fn new(cells: usize) -> Scratch {
        Scratch {
            slot: vec![None; cells + 2],
            touched: Vec::new(),
            kept: Vec::new(),
        }
    }
}

/// A worker's output for a run of nodes: the trace-back of the labels it
/// kept (parents global, indices local), the labels they extend to (layer,
/// label with a local parent index), and its best label at the goal.
#[derive(Default)]
struct Part {
    arena: Vec<(u32, u32)>,
    pushes: Vec<(u32, Label)>,
    best: Option<(u32, f64, Label)>,
    /// Arena entries whose parent is local (steps followed through).
    local: Vec<u32>,
}

impl Layer<'_> {
    /// Follows `l` (at layer `kk`) through the nodes that leave it one
    /// arc only, recording each step in `out`'s arena; false when it
    /// cannot reach the goal at the last layer.
    fn forced(&self, l: &mut Label, kk: &mut usize, out: &mut Part) -> bool {
        loop {
            let v = l.node;
            if v == self.c.goal {
                return true;
            }
            if *kk >= self.frames {
                return false;
            }
            let mut one = None;
            let mut n = 0;
            for a in &self.c.adj[v as usize] {
                if a.m.frames == 0 || (a.jump && l.since < self.min_run) {
                    continue;
                }
                n += 1;
                one = Some(a);
                if n > 1 {
                    return true;
                }
            }
            let Some(a) = one else { return false };
            let k2 = *kk + a.m.frames as usize;
            if k2 > self.frames {
                return false;
            }
            let id = out.arena.len() as u32;
            out.arena.push((l.parent, l.arc));
            out.local.push(id);
            *l = Label {
                node: a.to,
                parent: id,
                arc: a.index,
                distance: l.distance + a.m.distance,
                cost: l.cost + a.m.cost,
                turn: l.turn + a.turn,
                since: if a.jump {
                    a.m.frames
                } else {
                    l.since.saturating_add(a.m.frames)
                },
            };
            *kk = k2;
        }
    }

    /// The window of distances so far at node `u` after `k` frames.
    fn window(&self, u: u32, k: usize) -> Option<(f64, f64)> {
        let (lo, hi) = self.ext.at(u, self.frames - k);
        lo.is_finite()
            .then_some((self.distance - hi - self.tol, self.distance - lo + self.tol))
    }

    /// Bins the labels of `raw` (whole nodes of layer `k`, sorted by node)
    /// and extends the kept ones into `out`.
    fn expand(&self, raw: &[Label], k: usize, sc: &mut Scratch, out: &mut Part) {
        let Scratch {
            slot,
            touched,
            kept,
        } = sc;
        let mut i = 0;
        while i < raw.len() {
            let u = raw[i].node;
            let mut j = i;
            while j < raw.len() && raw[j].node == u {
                j += 1;
            }
            let Some((lo, hi)) = self.window(u, k) else {
                i = j;
                continue;
            };
            let labels = &raw[i..j];
            for b in touched.drain(..) {
                slot[b] = None;
            }
            self.bin(labels, lo, hi, slot, touched);
            if self.dominance {
                self.drop_dominated(labels, slot, touched);
            }
            kept.clear();
            kept.extend(touched.iter().filter_map(|&b| slot[b]));
            kept.sort_unstable();
            kept.dedup();
            for &s in kept.iter() {
                self.extend(labels[s], u, k, out);
            }
            i = j;
        }
    }

    /// Bins the labels of one node (window `[lo, hi]`): per bin the
    /// cheapest (ties: nearest the window's middle), plus the labels of
    /// least and most distance; `touched` lists the bins filled.
    fn bin(
        &self,
        labels: &[Label],
        lo: f64,
        hi: f64,
        slot: &mut [Option<usize>],
        touched: &mut Vec<usize>,
    ) {
        let (bins, classes) = (self.bins, self.classes);
        let (lo_slot, hi_slot) = (self.cells, self.cells + 1);
        // Far from the goal the window is wide, and few bins keep it
        // (module docs, "Coarse bins").
        let nb = if hi - lo > self.coarse_from * 2.0 * self.tol {
            self.coarse_bins
        } else {
            bins
        };
        let width = ((hi - lo) / nb as f64).max(1e-12);
        let mid = 0.5 * (lo + hi);
        for (r, l) in labels.iter().enumerate() {
            if slot[lo_slot].is_none_or(|o| l.distance < labels[o].distance) {
                if slot[lo_slot].is_none() {
                    touched.push(lo_slot);
                }
                slot[lo_slot] = Some(r);
            }
            if slot[hi_slot].is_none_or(|o| l.distance > labels[o].distance) {
                if slot[hi_slot].is_none() {
                    touched.push(hi_slot);
                }
                slot[hi_slot] = Some(r);
            }
            let class = l.since.min(self.min_run) as usize;
            let sector = self.heading.map_or(0, |h| h.sector(l.turn));
            let b = (sector * bins + (((l.distance - lo) / width) as usize).min(nb - 1)) * classes
                + class;
            let better = match slot[b] {
                None => true,
                Some(o) => {
                    let o = &labels[o];
                    l.cost < o.cost - 1e-12
                        || (l.cost <= o.cost + 1e-12
                            && (l.distance - mid).abs() < (o.distance - mid).abs())
                }
            };
            if better {
                if slot[b].is_none() {
                    touched.push(b);
                }
                slot[b] = Some(r);
            }
        }
    }

    /// A label with more frames since its last transition has every
    /// continuation of one with fewer: in the same bin, it dominates any
    /// such label that is not cheaper (module docs, "Classes").
    fn drop_dominated(&self, labels: &[Label], slot: &mut [Option<usize>], touched: &[usize]) {
        let classes = self.classes;
        for &b in touched.iter() {
            if b >= self.cells {
                continue;
            }
            let Some(r) = slot[b] else { continue };
            let class = b % classes;
            let c = labels[r].cost;
            let base = b - class;
            if (class + 1..classes).any(|h| slot[base + h].is_some_and(|o| labels[o].cost <= c)) {
                slot[b] = None;
            }
        }
    }

    /// Keeps label `l` of node `u` at frame count `k` (its trace-back in
    /// `out.arena`): at the last layer, scored at the goal; else extended
    /// along every arc that keeps it in its window (and under the cap).
    fn extend(&self, l: Label, u: u32, k: usize, out: &mut Part) {
        let frames = self.frames;
        let id = out.arena.len() as u32;
        out.arena.push((l.parent, l.arc));
        if k == frames {
            if u == self.c.goal {
                let sc = l.cost
                    + self.w_dist * (l.distance - self.distance).abs()
                    + self.heading.map_or(0.0, |h| h.cost(l.turn));
                if out.best.is_none_or(|(_, b, _)| sc < b) {
                    out.best = Some((id, sc, l));
                }
            }
            return;
        }
        // No path on from here can cost less than the cap.
        if l.cost + self.ext.least_cost(u, frames - k) >= self.cap {
            return;
        }
        for arc in &self.c.adj[u as usize] {
            let am = arc.m;
            let kk = k + am.frames as usize;
            if am.frames == 0 || kk > frames || (arc.jump && l.since < self.min_run) {
                continue;
            }
            let mut nl = Label {
                node: arc.to,
                parent: id,
                arc: arc.index,
                distance: l.distance + am.distance,
                cost: l.cost + am.cost,
                turn: l.turn + arc.turn,
                since: if arc.jump {
                    am.frames
                } else {
                    l.since.saturating_add(am.frames)
                },
            };
            let mut kk = kk;
            if self.follow && !self.forced(&mut nl, &mut kk, out) {
                continue;
            }
            match self.window(nl.node, kk) {
                Some((lo, hi)) if nl.distance >= lo && nl.distance <= hi => {
                    out.pushes.push((kk as u32, nl))
                }
                _ => {}
            }
        }
    }
}

/// Is `(distance, frames)` (start counted) within `within` of the targets?
fn lands(found: &Found, cs: i64, t: &Target, within: f64) -> bool {
    let f = (i64::from(found.measure.frames) + cs) as f64;
    (found.measure.distance - t.distance).abs() < within * t.distance
        && (f - t.frames).abs() < within * t.frames
}

/// The exact-length search on a chain, best first by Eq. 7 (plus the
/// heading term). Frame counts `N` are tried in increasing order of their
/// lower bound `w_dist · gap(d_V, [r_min(N), r_max(N)]) + w_time · |N − t_V|`
/// (the distance no path of `N` frames can avoid missing, plus the time
/// error), each aiming at the reachable distance nearest the target, until
/// the bound reaches the best cost; then, if that best misses either
/// target by more than [`LatticeOptions::within`], the frame counts within
/// the time tolerance are searched for a path within the distance
/// tolerance, the cheapest of which wins (module docs). Returns the path
/// and its cost; `None` for zero targets (shortest paths are the walks'
/// search) or when no path lands within the tolerance; an error when the
/// extremes for the horizon exceed the memory budget.
pub fn search(
    c: &Chain,
    t: &Target,
    heading: Option<&Heading>,
    opts: &SearchOptions,
) -> Result<Option<(Found, f64)>, OverBudget> {
    let lo = opts.lattice;
    let w = opts.weights;
    if t.distance <= 0.0 || t.frames <= 0.0 || !t.distance.is_finite() {
        return Ok(None);
    }
    let cs = i64::from(c.count_start);
    let target = (t.frames.round() as i64 - cs).max(0);
    let least = (c.least as i64).max(1);
    // Frames beyond which the time error alone exceeds the cost of
    // the nearest frame count's whole distance.
    let extra = (w.distance * t.distance / w.time.max(1e-9)).ceil() as i64;
    // ... and no longer than the horizon (a departure from Eq. 7 for
    // targets out of reach, [`super::options::Horizon`]).
    let horizon = (opts.horizon.frames(t.frames).floor() as i64 - cs).max(least);
    let top = (target.max(least) + extra + i64::from(lo.frame_slack))
        .min(lo.max_frames as i64)
        .min(horizon);
    if top < least {
        return Ok(None);
    }
    let ext = c.extremes(top as usize)?;
    let q = Query {
        c,
        ext: &ext,
        t,
        heading,
        lo,
        w: opts.weights,
        cs,
        target,
        least,
        top,
        // Cost pruning needs every term of `total` but the transition
        // cost non-negative (then `total ≥ cost + bound`).
        prune: lo.prune
            && w.distance >= 0.0
            && w.time >= 0.0
            && heading.is_none_or(|h| h.weight >= 0.0),
    };
    let mut order = q.frame_counts();
    // Every frame count in order, for the fallback below.
    let every = order.clone();
    order.truncate(8);
    let tol = lo.tolerance * t.distance + lo.tolerance_m;
    let mut best = q.best_first(&order, tol);
    if lo.within > 0.0 && best.as_ref().is_none_or(|b| !q.lands(&b.0)) {
        if let Some(inside) = q.within_tolerance() {
            best = Some(inside);
        }
    }
    if best.is_none() {
        best = q.fallback(&every, tol);
    }
    Ok(best)
}

/// One query of [`search`] on a chain: the target, the options and the
/// range of frame counts every step of the search reads.
struct Query<'a> {
    c: &'a Chain,
    ext: &'a Extremes,
    t: &'a Target,
    heading: Option<&'a Heading>,
    lo: LatticeOptions,
    w: Weights,
    /// The first segment counts its start frame (1) or not (0).
    cs: i64,
    /// The target's frame count (start not counted).
    target: i64,
    /// Fewest and most frames searched.
    least: i64,
    top: i64,
    /// Prune by cost (module docs, "Pruning").
    prune: bool,
}

impl Query<'_> {
    /// Eq. 7 plus the heading term of a path found.
    fn total(&self, f: &Found) -> f64 {
        let (w, t) = (self.w, self.t);
        f.measure.cost
            + w.distance * (f.measure.distance - t.distance).abs()
            + w.time * ((i64::from(f.measure.frames) + self.cs) as f64 - t.frames).abs()
            + self.heading.map_or(0.0, |h| h.cost(f.turn))
    }

    /// Does a path land within [`LatticeOptions::within`] of both targets?
    fn lands(&self, f: &Found) -> bool {
        lands(f, self.cs, self.t, self.lo.within)
    }

    /// The frame counts with a path, as `(bound, frames, aim)` in
    /// increasing order of their lower bound (the distance no path of that
    /// length can avoid missing, plus the time error), each aiming at the
    /// reachable distance nearest the target.
    fn frame_counts(&self) -> Vec<(f64, i64, f64)> {
        let (w, t) = (self.w, self.t);
        let mut order: Vec<(f64, i64, f64)> = (self.least..=self.top)
            .filter_map(|n| {
                let (a, b) = self.ext.at(self.c.start, n as usize);
                if !a.is_finite() {
                    return None;
                }
                let aim = t.distance.clamp(a, b);
                let time = w.time * ((n + self.cs) as f64 - t.frames).abs();
                Some((w.distance * (aim - t.distance).abs() + time, n, aim))
            })
            .collect();
        order.sort_by(|x, y| x.0.total_cmp(&y.0));
        order
    }

    /// The frame counts of `order` in turn, each pruned against the best
    /// so far (module docs, "Pruning"), each path within `tol` of its aim:
    /// the cheapest by Eq. 7.
    fn best_first(&self, order: &[(f64, i64, f64)], tol: f64) -> Option<(Found, f64)> {
        let c = self.c;
        let mut best: Option<(Found, f64)> = None;
        for &(bound, n, aim) in order {
            if best.as_ref().is_some_and(|b| bound >= b.1) {
                break;
            }
            let cap = match &best {
                Some(b) if self.prune => b.1 - bound + slack(b.1),
                _ => f64::INFINITY,
            };
            if self.ext.least_cost(c.start, n as usize) >= cap {
                continue;
            }
            if let Some((found, _)) = solve_probed(
                c,
                self.ext,
                n as usize,
                aim,
                tol,
                self.w.distance,
                self.heading,
                &self.lo,
                cap,
                &|f: &Found| self.lands(f),
            ) {
                let cost = self.total(&found);
                if best.as_ref().is_none_or(|b| cost < b.1) {
                    best = Some((found, cost));
                }
            }
        }
        best
    }

    /// The cheapest path within [`LatticeOptions::within`] of both
    /// targets, when the Eq. 7 optimum is not (module docs): the frame
    /// counts within the time tolerance whose extremes admit a distance
    /// within the distance tolerance, nearest the target first.
    fn within_tolerance(&self) -> Option<(Found, f64)> {
        let (c, t, w, within) = (self.c, self.t, self.w, self.lo.within);
        let dt = within * t.distance;
        let mut ns: Vec<i64> = (self.least..=self.top)
            .filter(|&n| ((n + self.cs) as f64 - t.frames).abs() < within * t.frames)
            .filter(|&n| {
                let (a, b) = self.ext.at(c.start, n as usize);
                a.is_finite() && a < t.distance + dt && b > t.distance - dt
            })
            .collect();
        ns.sort_by_key(|&n| (n - self.target).abs());
        let mut inside: Option<(Found, f64)> = None;
        // A frame count whose time term alone reaches the cheapest landing
        // path's cost cannot replace it (every other term of `total` is
        // non-negative when the weights and arc costs are), so it is not
        // searched: the same result without the programme.
        let nonneg = w.distance >= 0.0
            && w.time >= 0.0
            && self.heading.is_none_or(|h| h.weight >= 0.0)
            && c.adj.iter().flatten().all(|a| a.m.cost >= 0.0);
        for n in ns {
            let time = w.time * ((n + self.cs) as f64 - t.frames).abs();
            if nonneg && inside.as_ref().is_some_and(|b| time >= b.1) {
                continue;
            }
            // Nor is one whose least transition cost plus its time term
            // reaches it; the labels are pruned against it (`total ≥ cost
            // + time` for a landing path).
            let cap = match &inside {
                Some(b) if self.prune => b.1 - time + slack(b.1),
                _ => f64::INFINITY,
            };
            if self.ext.least_cost(c.start, n as usize) >= cap {
                continue;
            }
            let tol = dt * (1.0 - 1e-9);
            if let Some((found, _)) = solve_probed(
                c,
                self.ext,
                n as usize,
                t.distance,
                tol,
                w.distance,
                self.heading,
                &self.lo,
                cap,
                &|f: &Found| self.lands(f),
            ) {
                let cost = self.total(&found);
                if self.lands(&found) && inside.as_ref().is_none_or(|b| cost < b.1) {
                    inside = Some((found, cost));
                }
            }
        }
        inside
    }

    /// Nothing landed within the tolerance of its aim in the frame counts
    /// of [`Query::best_first`] (their extremes ignore `min_run`, and the
    /// distances of one length have gaps): a joined pair of key-frames then
    /// got no path at all and the walks' search, bounded on a large graph,
    /// none either ("no path" for 20 m in 10.5 s while 10 s and 11 s were
    /// answered, issue 39.11). The frame counts of `every` in the same
    /// order, each with a tolerance that keeps every path of that length
    /// (its extremes lie within it), give the best compromise instead; at
    /// most [`FALLBACK_COUNTS`] of them are searched.
    fn fallback(&self, every: &[(f64, i64, f64)], tol: f64) -> Option<(Found, f64)> {
        let c = self.c;
        let mut best: Option<(Found, f64)> = None;
        for &(bound, n, aim) in every.iter().take(FALLBACK_COUNTS) {
            if best.as_ref().is_some_and(|b| bound >= b.1) {
                break;
            }
            let (a, b) = self.ext.at(c.start, n as usize);
            let wide = (aim - a).max(b - aim).max(0.0) + tol;
            if let Some((found, _)) = solve_capped(
                c,
                self.ext,
                n as usize,
                aim,
                wide,
                self.w.distance,
                self.heading,
                &self.lo,
                f64::INFINITY,
            ) {
                let cost = self.total(&found);
                if best.as_ref().is_none_or(|b| cost < b.1) {
                    best = Some((found, cost));
                }
            }
        }
        best
    }
}

/// Frame counts the exact-length search's fallback tries, nearest bound
/// first, when no path landed near its aim ([`search`]).
pub(crate) const FALLBACK_COUNTS: usize = 64;

/// [`solve_capped`] preceded, with a heading target, when no cap bounds
/// it yet and pruning is on, by the probe (module docs, "Probe"): a programme with fewer bins
/// whose path, when `ok` accepts it, caps the full programme. Returns
/// the cheaper of the two; when `ok` does not accept the probe's path,
/// the full programme runs without a cap (the search without the probe).
#[allow(clippy::too_many_arguments)]
fn solve_probed(
    c: &Chain,
    ext: &Extremes,
    frames: usize,
    distance: f64,
    tol: f64,
    w_dist: f64,
    heading: Option<&Heading>,
    opts: &LatticeOptions,
    cap: f64,
    ok: &dyn Fn(&Found) -> bool,
) -> Option<(Found, f64)> {
    let full = |cap: f64| solve_capped(c, ext, frames, distance, tol, w_dist, heading, opts, cap);
    if !opts.prune
        || opts.probe_bins == 0
        || heading.is_none()
        || cap < f64::INFINITY
        || w_dist < 0.0
        || heading.is_some_and(|h| h.weight < 0.0)
    {
        return full(cap);
    }
    let probe_opts = LatticeOptions {
        bins: opts.probe_fine.clamp(1, opts.bins.max(1)),
        coarse_bins: opts.probe_bins,
        ..*opts
    };
    let probe = solve_capped(
        c,
        ext,
        frames,
        distance,
        tol,
        w_dist,
        heading,
        &probe_opts,
        cap,
    );
    let Some((pf, ps)) = probe else {
        return full(cap);
    };
    if !ok(&pf) {
        return full(cap);
    }
    match full(ps + slack(ps)) {
        Some((f, s)) if s <= ps => Some((f, s)),
        _ => Some((pf, ps)),
    }
}

/// The margin a cost cap leaves above a total `b` (rounding of the sums
/// of bounds must not prune a path whose total is below `b`).
fn slack(b: f64) -> f64 {
    1e-9 * (1.0 + b.abs())
}

/// What the exact-length programme says about a target `(d, t)` at a
/// tolerance (e.g. 0.01): is there a path through the chain whose
/// distance and frame count (start counted) are both strictly within the
/// tolerance of the target?
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Reachability {
    /// A path was found (a witness).
    Reachable,
    /// No frame count within the time tolerance has extremes
    /// `[r_min, r_max]` meeting the distance tolerance: certainly out of
    /// reach.
    OutOfRange,
    /// The extremes admit it but the fine programme found no path: the
    /// achievable distances of those lengths have a gap there (certain up
    /// to the programme's resolution, see [`oracle`]).
    Gap,
}

/// The reachability oracle: for every frame count `N` within the time
/// tolerance, the exact-length programme with `bins` distance bins per
/// (node, frames, class) and the final window the distance tolerance
/// (the final resolution `2 · tol · d / bins`). A witness is exact; a
/// miss by [`Reachability::OutOfRange`] is exact; a [`Reachability::Gap`]
/// is a miss at that resolution (labels merged within a bin could, in
/// principle, have extended to a distance the kept one misses). An error
/// when the extremes exceed the memory budget.
pub fn oracle(
    c: &Chain,
    t: &Target,
    within: f64,
    bins: usize,
    min_run: u32,
) -> Result<Reachability, OverBudget> {
    if t.distance <= 0.0 || t.frames <= 0.0 {
        return Ok(Reachability::OutOfRange);
    }
    let cs = i64::from(c.count_start);
    let lo_n = ((t.frames * (1.0 - within)).floor() as i64 - cs).max(0);
    let hi_n = (t.frames * (1.0 + within)).ceil() as i64 - cs;
    if hi_n < 0 {
        return Ok(Reachability::OutOfRange);
    }
    let ext = c.extremes(hi_n as usize)?;
    let dt = within * t.distance;
    // Every cell keeps all `bins` (the oracle's claims are at that
    // resolution).
    let opts = LatticeOptions {
        bins,
        min_run,
        coarse_from: f64::INFINITY,
        ..Default::default()
    };
    let mut admitted = false;
    for n in lo_n..=hi_n {
        if ((n + cs) as f64 - t.frames).abs() >= within * t.frames {
            continue;
        }
        let (a, b) = ext.at(c.start, n as usize);
        if !(a.is_finite() && a < t.distance + dt && b > t.distance - dt) {
            continue;
        }
        admitted = true;
        if let Some((f, _)) = solve_exact_length(
            c,
            &ext,
            n as usize,
            t.distance,
            dt * (1.0 - 1e-9),
            1.0,
            None,
            &opts,
        ) {
            if (f.measure.distance - t.distance).abs() < dt {
                return Ok(Reachability::Reachable);
            }
        }
    }
    Ok(if admitted {
        Reachability::Gap
    } else {
        Reachability::OutOfRange
    })
}
