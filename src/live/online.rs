//! Online retrieval: the skeletal trellis of [`crate::drive::trellis`]
//! (Huang et al. 2015, Sec. 5.2.1, Eqs. 26-31) run as the query arrives,
//! a fixed-lag Viterbi decoder.
//!
//! Each arriving query frame adds a row of candidates (its nearest database
//! frames, as offline). While more than `lag` rows are undecided, the
//! shortest path from the last committed node through every undecided row
//! is found by the offline relaxation (same node and edge costs, same
//! repeat, skip and cut rules) and its first node is committed: the frame
//! `lag` frames back is decided with `lag` frames of future. The threshold
//! `T_skel` and the node scale `s_node` are the offline rules (twice the
//! median, the 90th percentile of the best-match costs) over the frames
//! seen so far (the last [`SCALE_WINDOW`] of them, so a stream of any
//! length keeps its memory flat); the edge scale `s_edge` depends on the
//! database only.
//!
//! With `lag` at least the query's length nothing is committed before the
//! stream ends, and [`OnlineTrellis::finish`] solves the whole trellis with
//! the final scales: the offline path, bit for bit (the integration test
//! `live::online` checks it). With `lag` 0 each frame is decided greedily
//! from the last one (node cost plus transition cost), and a jump (a step
//! that neither plays on nor repeats) is charged `hysteresis` more, so the
//! output does not flicker between near-equal candidates (the parametric
//! controller's rule: leave the current motion only for a clearly better
//! one).

use crate::drive::trellis::{RowCosts, TrellisInput, TrellisOptions, relax_row_into, step_median};
use crate::graph::FlatFrame;
use crate::pose::Pose;
use crate::similarity::skeleton_index::{Search, nearest_scan};
use serde::Serialize;

/// Frames whose best-match costs set the scales (`T_skel`, `s_node`): the
/// last 18,000 (10 minutes at 30 fps). A clip shorter than this has the
/// offline scales; a longer stream's memory stays flat.
pub(crate) const SCALE_WINDOW: usize = 18_000;

/// Options of the online retrieval (besides the trellis's own).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OnlineOptions {
    /// Frames of future seen before a frame is decided. Default: 3.
    pub lag: usize,
    /// Extra cost (normalised units) of a jump when `lag` is 0. Default: 1.
    pub hysteresis: f64,
}

impl Default for OnlineOptions {
    fn default() -> Self {
        OnlineOptions {
            lag: 3,
            hysteresis: 1.0,
        }
    }
}

/// One decided query frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Committed {
    /// Query frame (from 0, in arrival order).
    pub index: usize,
    /// Database frame retrieved.
    pub id: FlatFrame,
    /// `c_skel` of the node (metres).
    pub skeleton_cost: f64,
    /// Entered by a cut.
    pub cut: bool,
}

/// What one step of the decoder decided.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Advance {
    /// Frames decided, in order (none until `lag` frames of future are in;
    /// at most one per arriving frame; all the rest at the end).
    pub committed: Vec<Committed>,
    /// The current best continuation of the last committed frame through
    /// the undecided rows (database frames; may still change).
    pub lookahead: Vec<FlatFrame>,
}

/// Counts of the decoder so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct OnlineStats {
    /// Frames received.
    pub frames: usize,
    /// Frames decided.
    pub committed: usize,
    /// Decided frames entered by a cut.
    pub cuts: usize,
    /// Decided frames with no candidate under `T_skel` when decided.
    pub widened: usize,
    /// Decided frames that left the previous frame's motion (neither a
    /// repeat nor its natural successor nor a skip).
    pub jumps: usize,
    /// The threshold now (metres).
    pub t_skel: f64,
    /// `s_node` now (metres).
    pub node_scale: f64,
    /// `s_edge` (the database's).
    pub edge_scale: f64,
}

/// The fixed-lag trellis over a database.
pub struct OnlineTrellis<'a> {
    db: &'a TrellisInput<'a>,
    trellis: TrellisOptions,
    opts: OnlineOptions,
    kmax: usize,
    kmin: usize,
    edge_scale: f64,
    /// Best-match cost of the last [`SCALE_WINDOW`] frames, sorted (the
    /// scales' sample), and in arrival order.
    bests: Vec<f64>,
    recent: std::collections::VecDeque<f64>,
    /// Nearest frames (sorted by cost, at most `kmax`) of every undecided
    /// query frame, oldest first.
    rows: std::collections::VecDeque<Vec<(f32, FlatFrame)>>,
    /// The last committed node.
    anchor: Option<FlatFrame>,
    committed: usize,
    stats: OnlineStats,
    /// Row slot of each database frame (scratch; `u32::MAX` = none).
    slot: Vec<u32>,
    /// The nearest `kmax` database frames to the last frame searched.
    all: Vec<(f32, FlatFrame)>,
    /// The index's search scratch and its results (frame ids as `u32`).
    search: Search,
    found: Vec<(f32, u32)>,
    /// Rows' buffers already decided, for reuse.
    spare: Vec<Vec<(f32, FlatFrame)>>,
    /// The solver's buffers, reused by every decision (issue 45).
    solver: SolveBuffers,
}

/// The buffers of [`OnlineTrellis`]'s decisions, reused from one to the
/// next (each cleared before use): no allocation once they hold the
/// undecided rows.
#[derive(Debug, Default)]
struct SolveBuffers {
    /// Per undecided row, the nodes kept, and whether none was under
    /// `T_skel` (the row widened to `kmin`).
    keep: Vec<usize>,
    widened: Vec<bool>,
    /// The costs of the row relaxed from, and of the row relaxed.
    cost: Vec<f64>,
    next: Vec<f64>,
    /// Per row, the back pointers (the rows' buffers past `rows` unused).
    back: Vec<Vec<(u32, bool)>>,
    /// Per row, the chosen node's slot and whether it was entered by a cut.
    slots: Vec<usize>,
    cuts: Vec<bool>,
}

/// Decided rows' buffers kept for new rows ([`OnlineTrellis::decide`]).
const SPARE_ROWS: usize = 4;

impl<'a> OnlineTrellis<'a> {
    /// A decoder over `db` with the trellis options `trellis` (as offline)
    /// and the online options `opts`.
    pub fn new(db: &'a TrellisInput<'a>, trellis: TrellisOptions, opts: OnlineOptions) -> Self {
        let ng = db.poses.len();
        let kmax = trellis.max_candidates.max(1).min(ng.max(1));
        let kmin = trellis.min_candidates.max(1).min(kmax);
        let edge_scale = db.edge_scale.unwrap_or_else(|| step_median(db)).max(1e-12);
        OnlineTrellis {
            db,
            trellis,
            opts,
            kmax,
            kmin,
            edge_scale,
            // The scales' sample grows to its window and no further:
            // reserved once (no allocation as frames arrive; pages are
            // touched as it fills).
            bests: Vec::with_capacity(SCALE_WINDOW),
            recent: std::collections::VecDeque::with_capacity(SCALE_WINDOW),
            // At most `lag + 1` undecided rows; their buffers made once
            // and passed from decided rows to new ones (see `decide`).
            rows: std::collections::VecDeque::with_capacity(opts.lag + 1),
            anchor: None,
            committed: 0,
            stats: OnlineStats {
                edge_scale,
                ..OnlineStats::default()
            },
            slot: vec![u32::MAX; ng],
            all: Vec::with_capacity(kmax),
            search: Search::default(),
            found: Vec::with_capacity(if db.index.is_some() { kmax } else { ng }),
            spare: (0..(opts.lag + 1).min(SPARE_ROWS))
                .map(|_| Vec::with_capacity(kmax))
                .collect(),
            solver: SolveBuffers::default(),
        }
    }

    /// The counts so far.
    pub fn stats(&self) -> OnlineStats {
        self.stats
    }

    /// Frames received but not decided.
    pub(crate) fn pending(&self) -> usize {
        self.rows.len()
    }

    /// Takes the next query frame (the analysed pose on the database's
    /// floor, [`crate::drive::Analysed::on_floor`]); decides the frame
    /// `lag` back once it can.
    pub fn push(&mut self, q: &Pose) -> Advance {
        let mut out = Advance::default();
        self.push_into(q, &mut out);
        out
    }

    /// [`OnlineTrellis::push`] into `out` (cleared and refilled): no
    /// allocation once its buffers hold a step's frames (issue 45: the
    /// live session keeps one).
    pub fn push_into(&mut self, q: &Pose, out: &mut Advance) {
        out.committed.clear();
        out.lookahead.clear();
        if self.db.poses.is_empty() {
            return;
        }
        let best = self.nearest(q);
        if self.recent.len() == SCALE_WINDOW
            && let Some(old) = self.recent.pop_front()
        {
            self.forget_best(old);
        }
        self.recent.push_back(best);
        self.insert_best(best);
        // The oldest row's buffer is reused once decided (see `decide`).
        let mut row = self.spare.pop().unwrap_or_default();
        row.clear();
        row.extend_from_slice(&self.all);
        self.rows.push_back(row);
        self.stats.frames += 1;
        if self.rows.len() > self.opts.lag {
            self.decide(1, out);
        }
    }

    /// Replaces the undecided frame `k` (0 = the oldest undecided) by `q`,
    /// its newer analysis: its candidates and its best-match cost in the
    /// scales' sample are `q`'s, as if `q` had been pushed. Decided frames
    /// stay decided; an index past the undecided ones is ignored.
    pub(crate) fn revise(&mut self, k: usize, q: &Pose) {
        if self.db.poses.is_empty() || k >= self.rows.len() {
            return;
        }
        let best = self.nearest(q);
        // The frame's place in arrival order: the undecided frames are the
        // newest `rows.len()` of `recent` (when the sample still holds it).
        let back = self.rows.len() - k;
        if let Some(at) = self.recent.len().checked_sub(back) {
            let old = std::mem::replace(&mut self.recent[at], best);
            self.forget_best(old);
            self.insert_best(best);
        }
        let row = &mut self.rows[k];
        row.clear();
        row.extend_from_slice(&self.all);
    }

    /// Fills `all` with the nearest `kmax` database frames to `q`, sorted
    /// by cost then id; returns the best cost.
    fn nearest(&mut self, q: &Pose) -> f64 {
        let (poses, kmax) = (self.db.poses, self.kmax);
        match self.db.index {
            Some(index) => index.nearest(poses, q, kmax, &mut self.search, &mut self.found),
            None => nearest_scan(poses, q, kmax, &mut self.found),
        }
        self.all.clear();
        self.all
            .extend(self.found.iter().map(|&(c, i)| (c, FlatFrame::new(i))));
        self.all[0].0 as f64
    }

    /// Takes `old` out of the scales' sorted sample.
    fn forget_best(&mut self, old: f64) {
        let at = self.bests.partition_point(|x| x.total_cmp(&old).is_lt());
        self.bests.remove(at);
    }

    /// Puts `best` into the scales' sorted sample.
    fn insert_best(&mut self, best: f64) {
        let at = self.bests.partition_point(|x| x.total_cmp(&best).is_lt());
        self.bests.insert(at, best);
    }

    /// Decides every frame still undecided (the stream ended).
    pub fn finish(&mut self) -> Advance {
        let mut out = Advance::default();
        self.finish_into(&mut out);
        out
    }

    /// [`OnlineTrellis::finish`] into `out` (cleared and refilled).
    pub fn finish_into(&mut self, out: &mut Advance) {
        out.committed.clear();
        out.lookahead.clear();
        let n = self.rows.len();
        self.decide(n, out);
    }

    /// The current `(T_skel, s_node)`.
    fn scales(&self) -> (f64, f64) {
        let b = &self.bests;
        if b.is_empty() {
            return (0.0, 1e-6);
        }
        let median = b[b.len() / 2];
        let p90 = b[((b.len() as f64 * 0.9) as usize).min(b.len() - 1)];
        let t_skel = self.trellis.t_skel.unwrap_or((2.0 * median).max(p90));
        (t_skel, median.max(1e-6))
    }

    /// Solves the undecided rows from the anchor and commits the first
    /// `count` of them, appended to `out` (cleared by the caller).
    fn decide(&mut self, count: usize, out: &mut Advance) {
        if self.rows.is_empty() || count == 0 {
            return;
        }
        let (t_skel, node_scale) = self.scales();
        self.stats.t_skel = t_skel;
        self.stats.node_scale = node_scale;
        let mut b = std::mem::take(&mut self.solver);
        b.keep.clear();
        b.widened.clear();
        for r in &self.rows {
            let under = r.iter().take_while(|c| (c.0 as f64) <= t_skel).count();
            b.widened.push(under == 0);
            b.keep.push(under.max(self.kmin).min(r.len()));
        }
        let mut slot = std::mem::take(&mut self.slot);
        self.solve(node_scale, &mut slot, &mut b);
        let (slots, cuts, widened) = (&b.slots, &b.cuts, &b.widened);
        let rows = |k: usize| &self.rows[k][..b.keep[k]];
        let count = count.min(self.rows.len());
        for k in 0..count {
            let (c, id) = rows(k)[slots[k]];
            let (cut, widened) = (cuts[k], widened[k]);
            if let Some(a) = self.anchor
                && !self.continues(a, id)
            {
                self.stats.jumps += 1;
            }
            self.anchor = Some(id);
            self.stats.committed += 1;
            self.stats.cuts += usize::from(cut);
            self.stats.widened += usize::from(widened);
            out.committed.push(Committed {
                index: self.committed,
                id,
                skeleton_cost: c as f64,
                cut,
            });
            self.committed += 1;
        }
        out.lookahead
            .extend((count..self.rows.len()).map(|k| rows(k)[slots[k]].1));
        self.slot = slot;
        self.solver = b;
        for r in self.rows.drain(..count) {
            if self.spare.len() < SPARE_ROWS {
                self.spare.push(r);
            }
        }
    }

    /// True when `b` repeats `a`, is its natural successor or skips one.
    fn continues(&self, a: FlatFrame, b: FlatFrame) -> bool {
        let s = self.db.successor;
        a == b || s(a) == Some(b) || s(a).and_then(s) == Some(b)
    }

    /// The shortest path through the undecided rows (each row's first
    /// `b.keep` nodes) from the anchor (or from the first row when nothing
    /// is decided yet), into `b`: the slot of the chosen node per row, and
    /// whether it was entered by a cut. The relaxation is
    /// [`crate::drive::trellis::retrieve`]'s, operation for operation.
    fn solve(&self, node_scale: f64, slot: &mut [u32], b: &mut SolveBuffers) {
        let db = self.db;
        let opts = self.trellis;
        let edge_scale = self.edge_scale;
        let hysteresis = if self.opts.lag == 0 {
            self.opts.hysteresis
        } else {
            0.0
        };
        let node = |c: f32| opts.w_retr * c as f64 / node_scale;
        let edge = |i: FlatFrame, j: FlatFrame| -> f64 {
            match (db.successor)(i) {
                Some(s) if s == j => 0.0,
                _ if i == j => 0.0,
                Some(s) => (db.dissimilarity)(s, j) as f64 / edge_scale,
                None => (db.dissimilarity)(i, j) as f64 / edge_scale,
            }
        };
        let SolveBuffers {
            keep,
            cost,
            next,
            back,
            slots,
            cuts,
            ..
        } = b;
        let rows = |k: usize| &self.rows[k][..keep[k]];
        let n = self.rows.len();
        let anchor_row = self.anchor.map(|a| [(0.0f32, a)]);
        // The first row relaxed from: the anchor (cost 0) or the first
        // undecided row (its node costs).
        cost.clear();
        let first = match &anchor_row {
            Some(_) => {
                cost.push(0.0);
                0
            }
            None => {
                cost.extend(rows(0).iter().map(|c| node(c.0)));
                1
            }
        };
        for k in 0..n {
            if back.len() == k {
                back.push(Vec::new());
            }
            if k < first {
                back[k].clear();
                back[k].resize(rows(0).len(), (0, false));
                continue;
            }
            let row = rows(k);
            // Row 0 is relaxed from only when there is an anchor.
            let prev: &[(f32, FlatFrame)] = if k == 0 {
                anchor_row.as_ref().map_or(&[][..], |a| &a[..])
            } else {
                rows(k - 1)
            };
            let how: RowCosts<'_> = (&node, &edge, hysteresis);
            relax_row_into(db, &opts, prev, cost, row, slot, how, (next, &mut back[k]));
            std::mem::swap(cost, next);
        }
        let mut s = cost
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .map(|(s, _)| s)
            .unwrap_or(0);
        slots.clear();
        slots.resize(n, 0);
        cuts.clear();
        cuts.resize(n, false);
        for k in (0..n).rev() {
            slots[k] = s;
            let (p, cut) = back[k][s];
            if k > 0 || first == 0 {
                cuts[k] = cut;
                s = p as usize;
            }
        }
    }
}
