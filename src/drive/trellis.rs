//! Skeletal trellis retrieval (Huang et al. 2015, Sec. 5.2.1, Eqs. 26-31,
//! Fig. 8): the path through the Surface Motion Graph whose skeletons best
//! follow a query, with few and cheap transitions.
//!
//! Row `k` of the trellis holds the database frames whose skeleton is within
//! `T_skel` of query frame `k` (Eq. 28, pre-aligned in translation and
//! heading). Edges join row `k−1` to row `k` along the graph's frame
//! adjacency plus frame repetition. Node cost `w_retr · c_skel / s_node`
//! (Eq. 30), edge cost `c(M(succ(t_i)), M(t_j)) / s_edge`: Eq. 31 charges
//! `c(M(t_i), M(t_j))`, which is 0 for a repeat and positive for playing
//! on, and so favours stop-motion; we charge the dissimilarity between the
//! frame reached and the natural successor of the frame left, which is 0
//! for playing on and for a repeat (interpolated away later, Sec. 5.2.2)
//! and the transition's dissimilarity for a jump. `s_node` and `s_edge`
//! (the median best-match skeleton cost and the median frame-to-next
//! dissimilarity) make the two dimensionless, so `w_retr = 1` weighs one
//! typical pose mismatch like one typical frame step.
//!
//! Besides repetition we allow skipping one frame (`t → t+2`, charged
//! `c(M(t+1), M(t+2))`, one step's dissimilarity), the same time warp the
//! other way: without it a query walking faster than the capture falls
//! further behind every frame until no candidate connects.
//!
//! The trellis is layered (edges only go from row `k−1` to row `k`) and its
//! costs are non-negative, so Dijkstra from the virtual source settles rows
//! in order: one relaxation sweep per row finds the same shortest path.
//!
//! `T_skel` is chosen per query: the larger of twice the median and the
//! 90th percentile of the query frames' nearest-frame costs (or given).
//! Rows keep at most `max_candidates` nodes (the nearest), so a 2,000-frame
//! query on a 2,000-frame database has at most 2,000 · `max_candidates`
//! nodes, not 4M. A query frame with no frame under `T_skel` keeps its
//! `min_candidates` nearest (reported as widened). If no graph edge joins
//! two rows, a cut (a jump to any candidate, at `cut_cost`) keeps the
//! search going and is reported.

use crate::graph::{FlatFrame, FrameAdjacency};
use crate::pose::Pose;
use crate::similarity::skeleton_index::{PoseIndex, Search, nearest_scan};
use rayon::prelude::*;
use serde::Serialize;

/// Options of the retrieval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrellisOptions {
    /// Weight of the skeleton term against transitions (Eq. 26). Default: 1.
    pub w_retr: f64,
    /// Skeleton dissimilarity threshold (metres, sum over joints); `None`
    /// chooses it from the query. Default: `None`.
    pub t_skel: Option<f64>,
    /// Largest number of candidates per query frame. Default: 128.
    pub max_candidates: usize,
    /// Candidates kept when none is under `T_skel`. Default: 8.
    pub min_candidates: usize,
    /// Allow skipping one frame (`t → t+2`), the counterpart of repetition,
    /// so that a query moving faster than the capture does not fall
    /// behind. Default: true.
    pub skip: bool,
    /// Cost of a cut (a jump along no graph edge), in the normalised units
    /// of the node and edge costs: a last resort. Default: 1000.
    pub cut_cost: f64,
}

impl Default for TrellisOptions {
    fn default() -> Self {
        TrellisOptions {
            w_retr: 1.0,
            t_skel: None,
            max_candidates: 128,
            min_candidates: 8,
            skip: true,
            cut_cost: 1000.0,
        }
    }
}

/// The retrieved path and how it was found.
#[derive(Debug, Clone, Serialize)]
pub struct Retrieval {
    /// Database frame per query frame.
    pub path: Vec<FlatFrame>,
    /// `c_skel` of each path node (metres).
    pub skeleton_cost: Vec<f64>,
    /// The threshold used.
    pub t_skel: f64,
    /// Trellis nodes.
    pub nodes: usize,
    /// Query frames with no candidate under `T_skel`.
    pub widened: Vec<usize>,
    /// Query frames entered by a cut.
    pub cuts: Vec<usize>,
    /// Total node cost (normalised).
    pub node_cost: f64,
    /// Total edge cost (normalised).
    pub edge_cost: f64,
    /// `s_node`: median best-match skeleton cost (metres).
    pub node_scale: f64,
    /// `s_edge`: median frame-to-next dissimilarity.
    pub edge_scale: f64,
    /// True skeleton distances computed to find the candidates (a scan:
    /// query frames × database frames; fewer through the index).
    pub distances: u64,
}

/// What the trellis needs from a database.
pub struct TrellisInput<'a> {
    /// Skeleton of every database frame.
    pub poses: &'a [Pose],
    /// The graph's frame adjacency.
    pub adjacency: &'a FrameAdjacency,
    /// Natural successor of a frame.
    pub successor: &'a (dyn Fn(FlatFrame) -> Option<FlatFrame> + Sync),
    /// Frame dissimilarity (the graph's measure).
    pub dissimilarity: &'a (dyn Fn(FlatFrame, FlatFrame) -> f32 + Sync),
    /// An index over `poses` ([`PoseIndex`]); `None` scans every frame
    /// (the same candidates, slower).
    pub index: Option<&'a PoseIndex>,
    /// `s_edge` computed beforehand (the median positive dissimilarity of
    /// a frame and its natural successor); `None` computes it from the
    /// links on each retrieval.
    pub edge_scale: Option<f64>,
}

/// A database character's frame links for the trellis (its natural
/// successors and its graph's dissimilarity), made once where a caller
/// needs a [`TrellisInput`] of the character (offline synthesis, the live
/// session).
pub struct DatabaseLinks<'a> {
    ch: &'a crate::db::Character,
    successor: Box<dyn Fn(FlatFrame) -> Option<FlatFrame> + Sync + 'a>,
    dissimilarity: Box<dyn Fn(FlatFrame, FlatFrame) -> f32 + Sync + 'a>,
}

impl<'a> DatabaseLinks<'a> {
    /// The links of `ch`.
    pub fn of(ch: &'a crate::db::Character) -> Self {
        DatabaseLinks {
            ch,
            successor: Box::new(move |id| ch.successor(id)),
            dissimilarity: Box::new(move |a, b| ch.dissimilarity(a, b)),
        }
    }

    /// The trellis's input: the character's skeletons, adjacency and links.
    pub fn input(&self) -> TrellisInput<'_> {
        TrellisInput {
            poses: self.ch.poses(),
            adjacency: self.ch.adjacency(),
            successor: &*self.successor,
            dissimilarity: &*self.dissimilarity,
            index: Some(self.ch.pose_index()),
            edge_scale: Some(self.ch.step_median().unwrap_or(1.0)),
        }
    }
}

/// The `kmax` database frames nearest to each query frame by `c_skel`,
/// each row sorted by (cost as f32, frame id), and how many true
/// distances were computed: through `db.index` when given (exact, the
/// same rows), else by a scan of every frame.
fn nearest_rows(
    query: &[Pose],
    db: &TrellisInput,
    kmax: usize,
) -> (Vec<Vec<(f32, FlatFrame)>>, u64) {
    let rows: Vec<(Vec<(f32, FlatFrame)>, u64)> = query
        .par_iter()
        .map_init(
            || (Search::default(), Vec::new()),
            |(search, buf), q| {
                let before = search.evaluated;
                match db.index {
                    Some(index) => index.nearest(db.poses, q, kmax, search, buf),
                    None => {
                        nearest_scan(db.poses, q, kmax, buf);
                        search.evaluated += db.poses.len() as u64;
                    }
                }
                let row = buf.iter().map(|&(c, i)| (c, FlatFrame::new(i))).collect();
                (row, search.evaluated - before)
            },
        )
        .collect();
    let distances = rows.iter().map(|r| r.1).sum();
    (rows.into_iter().map(|r| r.0).collect(), distances)
}

/// `s_edge` over `db`'s links: the median of the positive dissimilarities
/// between a frame and its natural successor (1 when there is none).
pub(crate) fn step_median(db: &TrellisInput) -> f64 {
    let ng = db.poses.len();
    let mut steps: Vec<f64> = FlatFrame::all(ng)
        .filter_map(|f| (db.successor)(f).map(|g| (db.dissimilarity)(f, g) as f64))
        .filter(|c| *c > 0.0)
        .collect();
    steps.sort_by(f64::total_cmp);
    steps.get(steps.len() / 2).copied().unwrap_or(1.0)
}

/// Finds the optimal path for `query` (Eq. 29).
pub fn retrieve(query: &[Pose], db: &TrellisInput, opts: &TrellisOptions) -> Retrieval {
    let ng = db.poses.len();
    let nq = query.len();
    if ng == 0 || nq == 0 {
        return Retrieval {
            path: Vec::new(),
            skeleton_cost: Vec::new(),
            t_skel: 0.0,
            nodes: 0,
            widened: Vec::new(),
            cuts: Vec::new(),
            node_cost: 0.0,
            edge_cost: 0.0,
            node_scale: 0.0,
            edge_scale: 0.0,
            distances: 0,
        };
    }
    let kmax = opts.max_candidates.max(1).min(ng);
    let kmin = opts.min_candidates.max(1).min(kmax);
    // Nearest frames of every query frame (sorted by cost, then id).
    let (near, distances) = nearest_rows(query, db, kmax);
    let mut best: Vec<f64> = near.iter().map(|r| r[0].0 as f64).collect();
    best.sort_by(f64::total_cmp);
    let median = best[best.len() / 2];
    let p90 = best[((best.len() as f64 * 0.9) as usize).min(best.len() - 1)];
    let t_skel = opts.t_skel.unwrap_or((2.0 * median).max(p90));
    let node_scale = median.max(1e-6);
    let edge_scale = db.edge_scale.unwrap_or_else(|| step_median(db)).max(1e-12);
    let mut widened = Vec::new();
    let rows: Vec<Vec<(f32, FlatFrame)>> = near
        .into_iter()
        .enumerate()
        .map(|(k, r)| {
            let under = r.iter().take_while(|c| (c.0 as f64) <= t_skel).count();
            if under == 0 {
                widened.push(k);
            }
            let keep = under.max(kmin).min(r.len());
            r[..keep].to_vec()
        })
        .collect();
    let nodes = rows.iter().map(Vec::len).sum();
    let node = |c: f32| opts.w_retr * c as f64 / node_scale;
    let edge = |i: FlatFrame, j: FlatFrame| -> f64 {
        match (db.successor)(i) {
            Some(s) if s == j => 0.0,
            _ if i == j => 0.0,
            Some(s) => (db.dissimilarity)(s, j) as f64 / edge_scale,
            None => (db.dissimilarity)(i, j) as f64 / edge_scale,
        }
    };
    // Relaxation row by row; back pointers per row (u32::MAX marks a cut
    // from the previous row's best node).
    let mut cost: Vec<f64> = rows[0].iter().map(|c| node(c.0)).collect();
    let mut back: Vec<Vec<(u32, bool)>> = vec![vec![(0, false); rows[0].len()]];
    let mut slot = vec![u32::MAX; ng];
    for k in 1..nq {
        let row = &rows[k];
        let (next, bp) = relax_row(
            db,
            opts,
            &rows[k - 1],
            &cost,
            row,
            &mut slot,
            &node,
            &edge,
            0.0,
        );
        cost = next;
        back.push(bp);
    }
    // Trace back from the sink (the cheapest node of the last row).
    let (mut s, _) = cost
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(b.1))
        .map(|(s, c)| (s, *c))
        .unwrap_or((0, 0.0));
    let mut path = vec![FlatFrame::default(); nq];
    let mut skel = vec![0.0; nq];
    let mut cuts = Vec::new();
    for k in (0..nq).rev() {
        path[k] = rows[k][s].1;
        skel[k] = rows[k][s].0 as f64;
        let (p, cut) = back[k][s];
        if k > 0 {
            if cut {
                cuts.push(k);
            }
            s = p as usize;
        }
    }
    cuts.reverse();
    let node_cost: f64 = skel.iter().map(|c| node(*c as f32)).sum();
    let edge_cost: f64 = (1..nq)
        .map(|k| {
            if cuts.binary_search(&k).is_ok() {
                opts.cut_cost
            } else {
                edge(path[k - 1], path[k])
            }
        })
        .sum();
    Retrieval {
        path,
        skeleton_cost: skel,
        t_skel,
        nodes,
        widened,
        cuts,
        node_cost,
        edge_cost,
        node_scale,
        edge_scale,
        distances,
    }
}

/// One row of the trellis relaxation (Huang et al. 2015, Sec. 5.2.1,
/// Eqs. 26-31), shared by [`retrieve`] and the online (fixed-lag) trellis
/// of `live`: every node of `row` is reached from the nodes of `prev`
/// (costs `cost`) by a graph edge (`edge`), a repeat, a skip of one frame
/// (`opts.skip`) or a cut from the previous row's best node
/// (`opts.cut_cost`); then its own node cost (`node`) is added. `jump`
/// (0 offline) is added to every step that is neither a repeat nor the
/// capture's own next frame, and to cuts: the online trellis's hysteresis.
/// `slot` (one entry per database frame, all `u32::MAX`) is scratch and is
/// left as it came. Returns the row's costs and back pointers (the
/// previous row's node, and whether the step is a cut).
#[allow(clippy::too_many_arguments)]
pub(crate) fn relax_row(
    db: &TrellisInput,
    opts: &TrellisOptions,
    prev: &[(f32, FlatFrame)],
    cost: &[f64],
    row: &[(f32, FlatFrame)],
    slot: &mut [u32],
    node: &dyn Fn(f32) -> f64,
    edge: &dyn Fn(FlatFrame, FlatFrame) -> f64,
    jump: f64,
) -> (Vec<f64>, Vec<(u32, bool)>) {
    let (mut next, mut bp) = (Vec::new(), Vec::new());
    let out = (&mut next, &mut bp);
    relax_row_into(db, opts, prev, cost, row, slot, (node, edge, jump), out);
    (next, bp)
}

/// [`relax_row`]'s `node`, `edge` and `jump`.
pub(crate) type RowCosts<'a> = (
    &'a dyn Fn(f32) -> f64,
    &'a dyn Fn(FlatFrame, FlatFrame) -> f64,
    f64,
);

/// [`relax_row`] into `next` and `bp` (cleared and refilled: the row's
/// costs and back pointers), `node`, `edge` and `jump` as there: no
/// allocation once both hold the row's nodes (a live session's trellis).
#[allow(clippy::too_many_arguments)]
pub(crate) fn relax_row_into(
    db: &TrellisInput,
    opts: &TrellisOptions,
    prev: &[(f32, FlatFrame)],
    cost: &[f64],
    row: &[(f32, FlatFrame)],
    slot: &mut [u32],
    (node, edge, jump): RowCosts<'_>,
    (next, bp): (&mut Vec<f64>, &mut Vec<(u32, bool)>),
) {
    for (s, c) in row.iter().enumerate() {
        slot[c.1.index()] = s as u32;
    }
    next.clear();
    next.resize(row.len(), f64::INFINITY);
    bp.clear();
    bp.resize(row.len(), (u32::MAX, false));
    for (pi, p) in prev.iter().enumerate() {
        let base = cost[pi];
        if !base.is_finite() {
            continue;
        }
        let i = p.1;
        let mut relax = |j: FlatFrame| {
            let s = slot[j.index()];
            if s != u32::MAX {
                let mut v = base + edge(i, j);
                if jump > 0.0 && !(i == j || (db.successor)(i) == Some(j)) {
                    v += jump;
                }
                if v < next[s as usize] {
                    next[s as usize] = v;
                    bp[s as usize] = (pi as u32, false);
                }
            }
        };
        relax(i);
        for (j, _) in db.adjacency.successors(i) {
            relax(j);
        }
        if opts.skip
            && let Some(j) = (db.successor)(i).and_then(|s| (db.successor)(s))
        {
            relax(j);
        }
    }
    // Cuts from the previous row's best node.
    if let Some((pi, &b)) = cost.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)) {
        for (s, v) in next.iter_mut().enumerate() {
            let mut w = b + opts.cut_cost;
            if jump > 0.0 {
                w += jump;
            }
            if w < *v {
                *v = w;
                bp[s] = (pi as u32, true);
            }
        }
    }
    for (s, c) in row.iter().enumerate() {
        next[s] += node(c.0);
        slot[c.1.index()] = u32::MAX;
    }
}
