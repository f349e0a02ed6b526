//! The compressed graph between two key-frames (Huang et al. 2015, Sec.
//! 5.1.1), built once per segment and queried for any target by both
//! searches (the walks and loops of [`super::search`], the exact-length
//! programme of [`super::lattice`]): its nodes are the key-frames and
//! every frame a transition leaves or enters; an arc is either a run of
//! plain frames to the next such frame in the same sequence, or one
//! transition. A frame path repeats a frame exactly when the compressed
//! path repeats a node, so loop-free walks and simple cycles are the same
//! in both.
//!
//! [`Segment::new`] enumerates the simple cycles and the loop-free walks
//! (each with its distinct attached loops), bounded by [`Limits`]; a hit
//! bound is kept in [`Segment::bounds_hit`]. A path found by either search
//! is a list of arcs, given back as its walk plus its repeated loops by
//! [`Segment::decompose`].

use super::error::SearchError;
use super::graph::KeyGraph;
use super::heading::wrap;
use super::options::Limits;
use super::repeats::{Cone, Tally, cone};
use crate::graph::FlatFrame;
use serde::Serialize;
use std::collections::BinaryHeap;

/// A distance and time target (0 means as short as possible).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Target {
    /// Metres.
    pub distance: f64,
    /// Frames.
    pub frames: f64,
}

#[derive(Debug, Clone, Copy)]
pub(super) struct Arc {
    pub(super) to: u32,
    pub(super) m: Tally,
    /// Frame the arc starts from and ends at.
    pub(super) from_frame: FlatFrame,
    pub(super) to_frame: FlatFrame,
    /// A transition (else a run of plain frames).
    pub(super) jump: bool,
    /// The heading's turn (radians; [`super::graph::FrameEdge::turn`]).
    pub(super) turn: f64,
}

/// An arc of the compressed graph as [`Segment::arcs_from_indexed`] gives
/// it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcView {
    /// Its index.
    pub index: u32,
    /// Head node.
    pub to: u32,
    /// Transition cost, distance, frames.
    pub m: Tally,
    /// A transition (else a run of plain frames).
    pub jump: bool,
    /// The heading's turn (radians; 0 on a run of plain frames).
    pub turn: f64,
}

/// A simple cycle of the compressed graph.
#[derive(Debug, Clone)]
pub(super) struct Cycle {
    pub(super) arcs: Vec<u32>,
    pub(super) m: Tally,
}

/// A loop-free walk with its attached loops.
#[derive(Debug, Clone)]
pub(super) struct Walk {
    pub(super) nodes: Vec<u32>,
    pub(super) arcs: Vec<u32>,
    pub(super) m: Tally,
    /// `(walk position, cycle)` of its distinct loops.
    pub(super) loops: Vec<(usize, u32)>,
    /// Their measures.
    pub(super) measures: Vec<Tally>,
    /// Their relaxation.
    pub(super) cone: Option<Cone>,
    /// The walk's heading turn (radians) and each loop's, per repetition:
    /// the path's turn is the walk's plus `n_i` times each loop's.
    pub(super) turn: f64,
    pub(super) loop_turns: Vec<f64>,
}

/// The compressed graph between two key-frames, with its cycles and the
/// bounds to the goal: built once, queried for any target.
#[derive(Debug, Clone)]
pub struct Segment {
    pub(super) from: FlatFrame,
    pub(super) to: FlatFrame,
    /// The frame of every node.
    pub(super) frames: Vec<FlatFrame>,
    pub(super) arcs: Vec<Arc>,
    pub(super) out: Vec<Vec<u32>>,
    pub(super) start: u32,
    pub(super) goal: u32,
    pub(super) relevant: Vec<bool>,
    pub(super) cycles: Vec<Cycle>,
    /// Cycles through each node.
    pub(super) through: Vec<Vec<u32>>,
    /// Cheapest cost, distance and frames from a node to the goal.
    pub(super) h: Vec<Tally>,
    /// Count the start frame in the walk's frames (first segment of a
    /// path).
    pub(super) count_start: bool,
    /// Every walk (bounded by [`Limits::walks`]).
    pub(super) walks: Vec<Walk>,
    /// Bounds hit while preparing.
    pub bounds_hit: Vec<String>,
}

/// A loop used by a path.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoopUse {
    /// The walk frame it is attached at (it starts and ends there).
    pub at: FlatFrame,
    /// One repetition's frames (after `at`, ending at `at`).
    pub frames: Vec<FlatFrame>,
    /// One repetition's cost, distance and frames.
    pub measure: Tally,
    /// Repetitions.
    pub repeats: u32,
}

/// The path found for one segment.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SegmentPath {
    /// Start key-frame.
    pub from: FlatFrame,
    /// End key-frame.
    pub to: FlatFrame,
    /// The loop-free walk's frames, `from` to `to`.
    pub walk: Vec<FlatFrame>,
    /// Its cost, distance and frames.
    pub walk_measure: Tally,
    /// Loops with their repetitions (only those repeated at least once).
    pub loops: Vec<LoopUse>,
    /// Walk plus loops.
    pub measure: Tally,
    /// The full frame path, `from` to `to`.
    pub path: Vec<FlatFrame>,
}

/// What a segment can reach (see [`Segment::reach`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Reach {
    /// Fewest frames of a walk.
    pub frames: u32,
    /// Shortest distance of a walk (metres).
    pub distance: f64,
    /// Slowest and fastest loop (metres per frame).
    pub speed: Option<(f64, f64)>,
}

/// Counts of the search.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Stats {
    /// Nodes of the compressed graph(s) and their arcs.
    pub nodes: usize,
    /// Arcs.
    pub arcs: usize,
    /// Simple cycles enumerated.
    pub cycles: usize,
    /// Walks reaching the end key-frame whose repetitions were solved.
    pub walks: usize,
    /// Walk prefixes cut by the lower bound.
    pub pruned: usize,
    /// Most loops attached to one walk.
    pub loops_per_walk: usize,
    /// Repetition problems that hit [`Limits::labels`] and were finished
    /// with a beam of [`super::options::SearchOptions::beam`] labels per
    /// frame count (not provably optimal).
    pub beamed: usize,
    /// Bounds that were hit (the result may then not be the optimum).
    pub bounds_hit: Vec<String>,
    /// Segments found by the exact-length search ([`Method::Lattice`]).
    pub exact_length: usize,
    /// Segments found by the walks-and-loops search.
    pub walks_and_loops: usize,
}

fn min_cost_paths(n: usize, rev: &[Vec<(u32, f64)>], goal: u32) -> Vec<f64> {
    #[derive(PartialEq)]
    struct Item(f64, u32);
    impl Eq for Item {}
    impl PartialOrd for Item {
        fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
            Some(self.cmp(o))
        }
    }
    impl Ord for Item {
        fn cmp(&self, o: &Self) -> std::cmp::Ordering {
            o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
        }
    }
    let mut d = vec![f64::INFINITY; n];
    let mut heap = BinaryHeap::new();
    d[goal as usize] = 0.0;
    heap.push(Item(0.0, goal));
    while let Some(Item(c, u)) = heap.pop() {
        if c > d[u as usize] {
            continue;
        }
        for &(v, w) in &rev[u as usize] {
            let nc = c + w;
            if nc < d[v as usize] {
                d[v as usize] = nc;
                heap.push(Item(nc, v));
            }
        }
    }
    d
}

/// The compressed graph between `from` and `to` (module docs): its nodes
/// (the key-frames and every transition's ends) as frame ids, each frame's
/// node index (`u32::MAX` for a plain frame), the arcs, and the arcs
/// leaving every node.
#[allow(clippy::type_complexity)]
fn compress(
    g: &KeyGraph,
    from: FlatFrame,
    to: FlatFrame,
) -> (Vec<FlatFrame>, Vec<u32>, Vec<Arc>, Vec<Vec<u32>>) {
    // Nodes: key-frames and transition ends.
    let nf = g.len();
    let mut is_node = vec![false; nf];
    is_node[from.index()] = true;
    is_node[to.index()] = true;
    for f in FlatFrame::all(nf) {
        for e in g.successors(f) {
            if e.jump {
                is_node[f.index()] = true;
                is_node[e.to.index()] = true;
            }
        }
    }
    let frames: Vec<FlatFrame> = FlatFrame::all(nf).filter(|f| is_node[f.index()]).collect();
    let mut index = vec![u32::MAX; nf];
    for (i, &f) in frames.iter().enumerate() {
        index[f.index()] = i as u32;
    }
    let mut arcs = Vec::new();
    let mut out = vec![Vec::new(); frames.len()];
    for (i, &u) in frames.iter().enumerate() {
        // The run of plain frames to the next node.
        let mut f = u;
        let mut m = Tally::default();
        while let Some(e) = g.successors(f).iter().find(|e| !e.jump) {
            f = e.to;
            m.distance += g.step_of(f);
            m.frames += 1;
            if is_node[f.index()] {
                out[i].push(arcs.len() as u32);
                arcs.push(Arc {
                    to: index[f.index()],
                    m,
                    from_frame: u,
                    to_frame: f,
                    jump: false,
                    turn: 0.0,
                });
                break;
            }
        }
        for e in g.successors(u).iter().filter(|e| e.jump) {
            out[i].push(arcs.len() as u32);
            arcs.push(Arc {
                to: index[e.to.index()],
                m: Tally {
                    cost: e.cost.max(0.0),
                    distance: g.step_of(e.to),
                    frames: 1,
                },
                from_frame: u,
                to_frame: e.to,
                jump: true,
                turn: e.turn,
            });
        }
    }
    (frames, index, arcs, out)
}

/// The nodes reachable from `seed` by `next` (of `n` nodes).
fn reachable(n: usize, seed: u32, next: &dyn Fn(u32) -> Vec<u32>) -> Vec<bool> {
    let mut seen = vec![false; n];
    let mut stack = vec![seed];
    seen[seed as usize] = true;
    while let Some(u) = stack.pop() {
        for v in next(u) {
            if !seen[v as usize] {
                seen[v as usize] = true;
                stack.push(v);
            }
        }
    }
    seen
}

/// The cheapest cost, distance and frames from every node to the goal
/// over the relevant nodes, each measure minimised on its own (lower
/// bounds); `rev` the arcs entering every node.
fn bounds_to_goal(
    rev: &[Vec<(u32, u32)>],
    arcs: &[Arc],
    relevant: &[bool],
    goal: u32,
) -> Vec<Tally> {
    let n = rev.len();
    let h_of = |w: &dyn Fn(&Tally) -> f64| {
        let r: Vec<Vec<(u32, f64)>> = rev
            .iter()
            .map(|row| {
                row.iter()
                    .filter(|(u, _)| relevant[*u as usize])
                    .map(|&(u, a)| (u, w(&arcs[a as usize].m)))
                    .collect()
            })
            .collect();
        min_cost_paths(n, &r, goal)
    };
    let hc = h_of(&|m| m.cost);
    let hd = h_of(&|m| m.distance);
    let hf = h_of(&|m| m.frames as f64);
    (0..n)
        .map(|u| Tally {
            cost: hc[u],
            distance: hd[u],
            frames: if hf[u].is_finite() {
                hf[u] as u32
            } else {
                u32::MAX / 4
            },
        })
        .collect()
}

impl Segment {
    /// Prepares the search from frame `from` to frame `to`. `count_start`
    /// counts `from` in the frames (the first segment of a path; later
    /// segments share their start with the previous one's end).
    pub fn new(
        g: &KeyGraph,
        from: FlatFrame,
        to: FlatFrame,
        count_start: bool,
        limits: &Limits,
    ) -> Result<Segment, SearchError> {
        for f in [from, to] {
            if f.index() >= g.len() {
                return Err(SearchError::Frame(f, g.len()));
            }
        }
        let (frames, index, arcs, out) = compress(g, from, to);
        let n = frames.len();
        let (start, goal) = (index[from.index()], index[to.index()]);
        // Reachable from the start and reaching the goal.
        let mut rev: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
        for (u, o) in out.iter().enumerate() {
            for &a in o {
                rev[arcs[a as usize].to as usize].push((u as u32, a));
            }
        }
        let fwd = reachable(n, start, &|u| {
            out[u as usize]
                .iter()
                .map(|&a| arcs[a as usize].to)
                .collect()
        });
        let bwd = reachable(n, goal, &|u| rev[u as usize].iter().map(|x| x.0).collect());
        if !fwd[goal as usize] {
            return Err(SearchError::NoPath { from, to });
        }
        let relevant: Vec<bool> = (0..n).map(|u| fwd[u] && bwd[u]).collect();
        let h = bounds_to_goal(&rev, &arcs, &relevant, goal);
        let mut seg = Segment {
            from,
            to,
            frames,
            arcs,
            out,
            start,
            goal,
            relevant,
            cycles: Vec::new(),
            through: vec![Vec::new(); n],
            h,
            count_start,
            walks: Vec::new(),
            bounds_hit: Vec::new(),
        };
        seg.find_cycles(limits);
        seg.find_walks(limits);
        Ok(seg)
    }
    /// Simple cycles among the relevant nodes: from each node `v`, a DFS
    /// over nodes numbered above `v` back to `v`.
    fn find_cycles(&mut self, limits: &Limits) {
        let n = self.frames.len();
        let mut on_path = vec![false; n];
        let mut steps = 0usize;
        let mut rev: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
        for (u, o) in self.out.iter().enumerate() {
            for &a in o {
                rev[self.arcs[a as usize].to as usize].push((u as u32, a));
            }
        }
        let budget = limits.cycles.saturating_mul(64);
        'outer: for v in 0..n as u32 {
            if !self.relevant[v as usize] {
                continue;
            }
            // Nodes numbered from v that reach v through such nodes.
            let mut back = vec![false; n];
            back[v as usize] = true;
            let mut todo = vec![v];
            while let Some(u) = todo.pop() {
                for &(w, _) in &rev[u as usize] {
                    if w > v && self.relevant[w as usize] && !back[w as usize] {
                        back[w as usize] = true;
                        todo.push(w);
                    }
                }
            }
            // Iterative DFS: stack of (node, next arc index).
            let mut stack: Vec<(u32, usize)> = vec![(v, 0)];
            let mut arcs: Vec<u32> = Vec::new();
            on_path[v as usize] = true;
            while let Some(&mut (u, ref mut k)) = stack.last_mut() {
                steps += 1;
                if steps > budget {
                    self.bounds_hit
                        .push(format!("cycle search stopped after {budget} steps"));
                    for &(w, _) in &stack {
                        on_path[w as usize] = false;
                    }
                    break 'outer;
                }
                if *k >= self.out[u as usize].len() {
                    on_path[u as usize] = false;
                    stack.pop();
                    arcs.pop();
                    continue;
                }
                let a = self.out[u as usize][*k];
                *k += 1;
                let w = self.arcs[a as usize].to;
                if w == v {
                    let mut c = arcs.clone();
                    c.push(a);
                    let m = c
                        .iter()
                        .fold(Tally::default(), |s, &a| s.plus(self.arcs[a as usize].m));
                    if m.frames > 0 {
                        let idx = self.cycles.len() as u32;
                        for &a in &c {
                            let from = self.arc_from(a);
                            self.through[from as usize].push(idx);
                        }
                        self.cycles.push(Cycle { arcs: c, m });
                        if self.cycles.len() >= limits.cycles {
                            self.bounds_hit
                                .push(format!("cycle enumeration stopped at {}", limits.cycles));
                            for &(w, _) in &stack {
                                on_path[w as usize] = false;
                            }
                            break 'outer;
                        }
                    }
                } else if w > v && back[w as usize] && !on_path[w as usize] {
                    on_path[w as usize] = true;
                    stack.push((w, 0));
                    arcs.push(a);
                }
            }
        }
    }

    fn arc_from(&self, a: u32) -> u32 {
        // Arcs are stored grouped by their source in `out`.
        let f = self.arcs[a as usize].from_frame;
        self.frames.binary_search(&f).unwrap_or(0) as u32
    }

    /// What the segment can reach: the shortest walk's frames and
    /// distance (each minimised on its own) and the slowest and fastest
    /// loop speed (metres per frame); `None` speeds without loops.
    pub fn reach(&self) -> Reach {
        let h = self.h[self.start as usize];
        let speeds = self
            .cycles
            .iter()
            .map(|c| c.m.distance / c.m.frames.max(1) as f64);
        let lo = speeds.clone().fold(f64::INFINITY, f64::min);
        let hi = speeds.fold(f64::NEG_INFINITY, f64::max);
        Reach {
            frames: h.frames + u32::from(self.count_start),
            distance: h.distance,
            speed: (lo <= hi).then_some((lo, hi)),
        }
    }

    /// Number of compressed nodes.
    pub fn node_count(&self) -> usize {
        self.frames.len()
    }

    /// The start key-frame's node.
    pub fn start(&self) -> u32 {
        self.start
    }

    /// The end key-frame's node.
    pub fn goal(&self) -> u32 {
        self.goal
    }

    /// Arcs of the compressed graph (indices `0..arc_count()`).
    pub(crate) fn arc_count(&self) -> usize {
        self.arcs.len()
    }

    /// Fewest frames from the start to the goal (the start frame not
    /// counted).
    pub(crate) fn least_frames(&self) -> u32 {
        self.h[self.start as usize].frames
    }

    /// Does the segment count its start frame (the first of a path)?
    pub(crate) fn counts_start(&self) -> bool {
        self.count_start
    }

    /// Is node `u` on some path from the start to the goal?
    pub(crate) fn is_relevant(&self, u: u32) -> bool {
        self.relevant[u as usize]
    }

    /// The arcs leaving node `u` towards relevant nodes, with their indices.
    pub(crate) fn arcs_from_indexed(&self, u: u32) -> impl Iterator<Item = ArcView> + '_ {
        self.out[u as usize].iter().filter_map(move |&a| {
            let arc = &self.arcs[a as usize];
            self.relevant[arc.to as usize].then_some(ArcView {
                index: a,
                to: arc.to,
                m: arc.m,
                jump: arc.jump,
                turn: arc.turn,
            })
        })
    }

    /// A path of arcs as its loop-free walk plus the loops cut out of it
    /// (each where it starts and ends; equal consecutive loops counted as
    /// repetitions).
    pub fn decompose(&self, arcs: &[u32]) -> SegmentPath {
        let mut path = vec![self.from];
        for &a in arcs {
            self.arc_frames(a, &mut path);
        }
        // Stack of (node, arc into it); loops popped when a node recurs.
        let mut stack: Vec<(u32, u32)> = vec![(self.start, u32::MAX)];
        let mut pos = vec![usize::MAX; self.frames.len()];
        pos[self.start as usize] = 0;
        let mut cut: Vec<(u32, Vec<u32>)> = Vec::new();
        for &a in arcs {
            let v = self.arcs[a as usize].to;
            let p = pos[v as usize];
            if p != usize::MAX {
                let mut cyc: Vec<u32> = stack[p + 1..].iter().map(|x| x.1).collect();
                cyc.push(a);
                for x in stack.drain(p + 1..) {
                    pos[x.0 as usize] = usize::MAX;
                }
                cut.push((v, cyc));
            } else {
                pos[v as usize] = stack.len();
                stack.push((v, a));
            }
        }
        let warcs: Vec<u32> = stack[1..].iter().map(|x| x.1).collect();
        let walk_measure = self.walk_measure(&warcs);
        let mut walk = vec![self.from];
        for &a in &warcs {
            self.arc_frames(a, &mut walk);
        }
        let mut loops: Vec<LoopUse> = Vec::new();
        for (node, cyc) in cut {
            let at = self.frames[node as usize];
            if let Some(l) = loops.last_mut() {
                let same = l.at == at && {
                    let mut fr = Vec::new();
                    for &a in &cyc {
                        self.arc_frames(a, &mut fr);
                    }
                    fr == l.frames
                };
                if same {
                    l.repeats += 1;
                    continue;
                }
            }
            let mut frames = Vec::new();
            let mut m = Tally::default();
            for &a in &cyc {
                self.arc_frames(a, &mut frames);
                m = m.plus(self.arcs[a as usize].m);
            }
            loops.push(LoopUse {
                at,
                frames,
                measure: m,
                repeats: 1,
            });
        }
        let measure = arcs.iter().fold(
            Tally {
                frames: u32::from(self.count_start),
                ..Default::default()
            },
            |s, &a| s.plus(self.arcs[a as usize].m),
        );
        SegmentPath {
            from: self.from,
            to: self.to,
            walk,
            walk_measure,
            loops,
            measure,
            path,
        }
    }

    fn walk_measure(&self, arcs: &[u32]) -> Tally {
        arcs.iter().fold(
            Tally {
                frames: u32::from(self.count_start),
                ..Default::default()
            },
            |s, &a| s.plus(self.arcs[a as usize].m),
        )
    }

    /// The distinct loops attached to a walk (node list), each with the
    /// walk position it attaches at; at most `limit` (cheapest per frame
    /// first), with a flag when some were left out.
    fn attached(&self, nodes: &[u32], limit: usize) -> (Vec<(usize, u32)>, bool) {
        let mut pos = vec![usize::MAX; self.frames.len()];
        for (k, &u) in nodes.iter().enumerate() {
            if pos[u as usize] == usize::MAX {
                pos[u as usize] = k;
            }
        }
        let mut seen: Vec<(usize, u32)> = Vec::new();
        let mut mark = std::collections::HashSet::new();
        for &u in nodes {
            for &c in &self.through[u as usize] {
                if mark.insert(c) {
                    let at = self.cycles[c as usize]
                        .arcs
                        .iter()
                        .map(|&a| pos[self.arc_from(a) as usize])
                        .min()
                        .unwrap_or(usize::MAX);
                    seen.push((at, c));
                }
            }
        }
        // Distinct measures and turns only (the cheapest of each: two
        // loops of the same frames and distance but different turns end
        // facing different ways, which a heading target tells apart).
        let turn = |c: u32| wrap(self.arcs_turn(&self.cycles[c as usize].arcs));
        seen.sort_by(|a, b| {
            let (x, y) = (&self.cycles[a.1 as usize].m, &self.cycles[b.1 as usize].m);
            x.frames
                .cmp(&y.frames)
                .then(x.distance.total_cmp(&y.distance))
                .then(turn(a.1).total_cmp(&turn(b.1)))
                .then(x.cost.total_cmp(&y.cost))
        });
        seen.dedup_by(|a, b| {
            let (x, y) = (&self.cycles[a.1 as usize].m, &self.cycles[b.1 as usize].m);
            x.frames == y.frames
                && (x.distance - y.distance).abs() < 1e-9
                && wrap(turn(a.1) - turn(b.1)).abs() < 1e-9
        });
        let capped = seen.len() > limit.max(2);
        if capped {
            let speed = |c: u32| {
                let m = &self.cycles[c as usize].m;
                m.distance / m.frames.max(1) as f64
            };
            // The slowest and the fastest first (they span the reachable
            // speeds), then the cheapest per frame.
            seen.sort_by(|a, b| speed(a.1).total_cmp(&speed(b.1)));
            let last = seen.len() - 1;
            seen.swap(1, last);
            seen[2..].sort_by(|a, b| {
                let (x, y) = (&self.cycles[a.1 as usize].m, &self.cycles[b.1 as usize].m);
                (x.cost / x.frames as f64).total_cmp(&(y.cost / y.frames as f64))
            });
            seen.truncate(limit.max(2));
        }
        (seen, capped)
    }

    /// Every walk from the start to the goal (depth-first, bounded), each
    /// with its distinct attached loops.
    fn find_walks(&mut self, limits: &Limits) {
        let (mut found, capped) = self.all_walks(limits.walks, limits.expansions);
        if found.is_empty() {
            // The enumeration stopped before it reached the goal (on a
            // large graph it can spend every expansion in one corner): the
            // walk of fewest frames, so that the search always has a path
            // when one joins the key-frames (issue 39.11).
            found.extend(self.shortest_walk());
        }
        if capped {
            self.bounds_hit
                .push(format!("walk enumeration stopped at {} walks", found.len()));
        }
        let mut capped_loops = false;
        self.walks = found
            .into_iter()
            .map(|(nodes, arcs, m)| {
                let (loops, capped) = self.attached(&nodes, limits.loops_per_walk);
                capped_loops |= capped;
                let measures: Vec<Tally> = loops
                    .iter()
                    .map(|&(_, c)| self.cycles[c as usize].m)
                    .collect();
                let cone = cone(&measures);
                let turn = self.arcs_turn(&arcs);
                let loop_turns = loops
                    .iter()
                    .map(|&(_, c)| self.arcs_turn(&self.cycles[c as usize].arcs))
                    .collect();
                Walk {
                    nodes,
                    arcs,
                    m,
                    loops,
                    measures,
                    cone,
                    turn,
                    loop_turns,
                }
            })
            .collect();
        if capped_loops {
            self.bounds_hit.push(format!(
                "a walk had more than {} distinct loops; the slowest, the fastest and the cheapest per frame were kept",
                limits.loops_per_walk
            ));
        }
    }

    /// The walk of fewest frames from the start to the goal, by the
    /// bounds `h` (each step takes an arc on a shortest path; frames are
    /// positive, so it is loop-free); `None` when the goal is not reached.
    #[allow(clippy::type_complexity)]
    fn shortest_walk(&self) -> Option<(Vec<u32>, Vec<u32>, Tally)> {
        let mut u = self.start;
        let (mut nodes, mut arcs) = (vec![u], Vec::new());
        while u != self.goal {
            let hu = self.h[u as usize].frames;
            let a = *self.out[u as usize].iter().find(|&&a| {
                let arc = &self.arcs[a as usize];
                self.relevant[arc.to as usize]
                    && arc.m.frames > 0
                    && arc.m.frames + self.h[arc.to as usize].frames == hu
            })?;
            u = self.arcs[a as usize].to;
            nodes.push(u);
            arcs.push(a);
            if nodes.len() > self.frames.len() {
                return None;
            }
        }
        let m = self.walk_measure(&arcs);
        Some((nodes, arcs, m))
    }

    /// Adds the segment's nodes, arcs and cycles to `stats`.
    pub fn count(&self, stats: &mut Stats) {
        stats.nodes += self.frames.len();
        stats.arcs += self.arcs.len();
        stats.cycles += self.cycles.len();
    }

    fn pop(
        &self,
        stack: &mut Vec<(Vec<u32>, usize)>,
        nodes: &mut Vec<u32>,
        arcs: &mut Vec<u32>,
        on: &mut [bool],
    ) {
        stack.pop();
        if let Some(u) = nodes.pop() {
            on[u as usize] = false;
        }
        arcs.pop();
    }

    /// The frames an arc adds (after its start).
    fn arc_frames(&self, a: u32, out: &mut Vec<FlatFrame>) {
        let arc = &self.arcs[a as usize];
        if arc.jump {
            out.push(arc.to_frame);
        } else {
            out.extend((arc.from_frame.get() + 1..=arc.to_frame.get()).map(FlatFrame::new));
        }
    }

    /// One repetition of a cycle's arcs starting at walk node `node`.
    fn cycle_arcs(&self, c: u32, node: u32) -> Vec<u32> {
        let cyc = &self.cycles[c as usize];
        let k = cyc
            .arcs
            .iter()
            .position(|&a| self.arc_from(a) == node)
            .unwrap_or(0);
        let len = cyc.arcs.len();
        (0..len).map(|i| cyc.arcs[(k + i) % len]).collect()
    }

    /// The path of a walk with `n[i]` repetitions of its attached loops
    /// `att[i]` (each inserted where it attaches), as [`Segment::decompose`]
    /// describes it.
    pub(super) fn expand(
        &self,
        nodes: &[u32],
        warcs: &[u32],
        att: &[(usize, u32)],
        n: &[u32],
    ) -> SegmentPath {
        let mut loops: Vec<(usize, u32, u32)> = att
            .iter()
            .zip(n)
            .filter(|&(_, &k)| k > 0)
            .map(|(&(at, c), &k)| (at, c, k))
            .collect();
        loops.sort_by_key(|l| l.0);
        let mut arcs = Vec::new();
        let mut li = 0;
        for k in 0..=warcs.len() {
            while li < loops.len() && loops[li].0 == k {
                let (at, c, reps) = loops[li];
                let cyc = self.cycle_arcs(c, nodes[at]);
                for _ in 0..reps {
                    arcs.extend_from_slice(&cyc);
                }
                li += 1;
            }
            if let Some(&a) = warcs.get(k) {
                arcs.push(a);
            }
        }
        self.decompose(&arcs)
    }

    /// The heading's turn over arcs (radians).
    fn arcs_turn(&self, arcs: &[u32]) -> f64 {
        arcs.iter().map(|&a| self.arcs[a as usize].turn).sum()
    }

    /// Every walk (up to `limit`), as node lists with their measures,
    /// cheapest transition cost first; flags a hit bound.
    #[allow(clippy::type_complexity)]
    fn all_walks(
        &self,
        limit: usize,
        expansions: usize,
    ) -> (Vec<(Vec<u32>, Vec<u32>, Tally)>, bool) {
        let mut out = Vec::new();
        let mut on = vec![false; self.frames.len()];
        let mut nodes = vec![self.start];
        let mut arcs: Vec<u32> = Vec::new();
        on[self.start as usize] = true;
        let mut stack: Vec<(Vec<u32>, usize)> = vec![(self.out[self.start as usize].clone(), 0)];
        let mut steps = 0usize;
        let mut capped = false;
        if self.start == self.goal {
            return (vec![(nodes, Vec::new(), self.walk_measure(&[]))], false);
        }
        while let Some((order, k)) = stack.last_mut() {
            if *k >= order.len() {
                self.pop(&mut stack, &mut nodes, &mut arcs, &mut on);
                continue;
            }
            let a = order[*k];
            *k += 1;
            let v = self.arcs[a as usize].to;
            if on[v as usize] || !self.relevant[v as usize] {
                continue;
            }
            steps += 1;
            if steps > expansions || out.len() >= limit {
                capped = true;
                break;
            }
            arcs.push(a);
            if v == self.goal {
                let mut ns = nodes.clone();
                ns.push(v);
                out.push((ns, arcs.clone(), self.walk_measure(&arcs)));
                arcs.pop();
                continue;
            }
            on[v as usize] = true;
            nodes.push(v);
            stack.push((self.out[v as usize].clone(), 0));
        }
        out.sort_by(|a, b| a.2.cost.total_cmp(&b.2.cost));
        (out, capped)
    }
}
