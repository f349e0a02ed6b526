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
//! optimality: [`super::search::Segment::solve`] keeps the paper's search
//! as the fallback when no path lands within `T`, and reports which one
//! found the result. A target is *reachable* in exactly `N` frames when
//! `r_min(start, N) ≤ d_V ≤ r_max(start, N)` ([`extremes`]).

use super::repeats::Measure;
use super::search::Segment;

/// Options of the exact-length search.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct LatticeOptions {
    /// Bins per `(node, frame count)`. Default: 32.
    pub bins: usize,
    /// Tolerance on the final distance, as a fraction of the target.
    /// Default: 0.02.
    pub tolerance: f64,
    /// Plus this many metres. Default: 0.01.
    pub tolerance_m: f64,
    /// Frame counts tried on either side of the target's (each must beat
    /// the best cost by its time term). Default: 3.
    pub frame_slack: u32,
    /// Longest path considered (frames). Default: 20 000.
    pub max_frames: usize,
    /// Fewest frames between two transitions (so that each keeps a blend
    /// window; the timeline shortens windows that would overlap).
    /// Default: 4.
    pub min_run: u32,
}

impl Default for LatticeOptions {
    fn default() -> Self {
        LatticeOptions {
            bins: 32,
            tolerance: 0.02,
            tolerance_m: 0.01,
            frame_slack: 3,
            max_frames: 20_000,
            min_run: 4,
        }
    }
}

/// `r_min` and `r_max` of every node for `0..=m` frames (`m`-major).
pub struct Extremes {
    nodes: usize,
    /// Least distance to the goal in exactly `m` frames (`+∞`: none).
    pub min: Vec<f64>,
    /// Most distance (`−∞`: none).
    pub max: Vec<f64>,
}

impl Extremes {
    /// `(r_min, r_max)` of node `u` in exactly `m` frames.
    pub fn at(&self, u: u32, m: usize) -> (f64, f64) {
        let i = m * self.nodes + u as usize;
        (self.min[i], self.max[i])
    }
}

/// The exact-length extremes of a segment up to `m` frames (step 1).
pub fn extremes(seg: &Segment, m: usize) -> Extremes {
    let n = seg.node_count();
    let mut min = vec![f64::INFINITY; n * (m + 1)];
    let mut max = vec![f64::NEG_INFINITY; n * (m + 1)];
    let goal = seg.goal() as usize;
    min[goal] = 0.0;
    max[goal] = 0.0;
    for k in 1..=m {
        for u in 0..n {
            if !seg.is_relevant(u as u32) {
                continue;
            }
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for (to, am) in seg.arcs_from(u as u32) {
                let l = am.frames as usize;
                if l == 0 || l > k {
                    continue;
                }
                let j = (k - l) * n + to as usize;
                if min[j].is_finite() {
                    lo = lo.min(am.distance + min[j]);
                    hi = hi.max(am.distance + max[j]);
                }
            }
            min[k * n + u] = lo;
            max[k * n + u] = hi;
        }
    }
    Extremes { nodes: n, min, max }
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
    /// Frames since the last transition.
    since: u32,
}

/// The path found: its arcs and measure (frames counted as the segment
/// counts them).
#[derive(Debug, Clone, PartialEq)]
pub struct Found {
    /// Arcs of the compressed graph, in order.
    pub arcs: Vec<u32>,
    /// Transition cost, distance, frames.
    pub measure: Measure,
}

/// The best path of exactly `frames` arc frames from the start to the goal
/// whose distance lands within the tolerance of `distance` (steps 2-3),
/// or `None`. `ext` must cover `frames`.
pub fn solve_exact_length(
    seg: &Segment,
    ext: &Extremes,
    frames: usize,
    distance: f64,
    w_dist: f64,
    opts: &LatticeOptions,
) -> Option<(Found, f64)> {
    let tol = opts.tolerance * distance + opts.tolerance_m;
    let bins = opts.bins.max(1);
    let window = |u: u32, k: usize| -> Option<(f64, f64)> {
        let (lo, hi) = ext.at(u, frames - k);
        lo.is_finite()
            .then_some((distance - hi - tol, distance - lo + tol))
    };
    let start = seg.start();
    window(start, 0)?;
    let mut layers: Vec<Vec<Label>> = vec![Vec::new(); frames + 1];
    layers[0].push(Label {
        node: start,
        parent: u32::MAX,
        arc: u32::MAX,
        distance: 0.0,
        cost: 0.0,
        since: u32::MAX / 2,
    });
    let mut arena: Vec<Label> = Vec::new();
    // Bins per class of frames since the last transition (below
    // `min_run`, and at least), plus the labels of least and most
    // distance (they alone may reach the extremes of the window).
    let classes = opts.min_run as usize + 1;
    let mut slot: Vec<Option<usize>> = vec![None; bins * classes + 2];
    let (lo_slot, hi_slot) = (bins * classes, bins * classes + 1);
    let mut best: Option<(u32, f64)> = None;
    for k in 0..=frames {
        let mut raw = std::mem::take(&mut layers[k]);
        raw.sort_unstable_by_key(|l| l.node);
        let mut i = 0;
        while i < raw.len() {
            let u = raw[i].node;
            let mut j = i;
            while j < raw.len() && raw[j].node == u {
                j += 1;
            }
            let Some((lo, hi)) = window(u, k) else {
                i = j;
                continue;
            };
            let width = ((hi - lo) / bins as f64).max(1e-12);
            let mid = 0.5 * (lo + hi);
            slot.iter_mut().for_each(|s| *s = None);
            for (r, l) in raw[i..j].iter().enumerate() {
                if slot[lo_slot].is_none_or(|o| l.distance < raw[i + o].distance) {
                    slot[lo_slot] = Some(r);
                }
                if slot[hi_slot].is_none_or(|o| l.distance > raw[i + o].distance) {
                    slot[hi_slot] = Some(r);
                }
                let class = l.since.min(opts.min_run) as usize;
                let b = class * bins + (((l.distance - lo) / width) as usize).min(bins - 1);
                let better = match slot[b] {
                    None => true,
                    Some(o) => {
                        let o = &raw[i + o];
                        l.cost < o.cost - 1e-12
                            || (l.cost <= o.cost + 1e-12
                                && (l.distance - mid).abs() < (o.distance - mid).abs())
                    }
                };
                if better {
                    slot[b] = Some(r);
                }
            }
            slot.sort_unstable();
            let mut last = None;
            for s in slot.iter().flatten() {
                if last == Some(*s) {
                    continue;
                }
                last = Some(*s);
                let l = raw[i + s];
                let id = arena.len() as u32;
                arena.push(l);
                if k == frames {
                    if u == seg.goal() {
                        let c = l.cost + w_dist * (l.distance - distance).abs();
                        if best.is_none_or(|(_, b)| c < b) {
                            best = Some((id, c));
                        }
                    }
                    continue;
                }
                for arc in seg.arcs_from_indexed(u) {
                    let am = arc.m;
                    let kk = k + am.frames as usize;
                    if am.frames == 0 || kk > frames || (arc.jump && l.since < opts.min_run) {
                        continue;
                    }
                    let d = l.distance + am.distance;
                    match window(arc.to, kk) {
                        Some((lo, hi)) if d >= lo && d <= hi => layers[kk].push(Label {
                            node: arc.to,
                            parent: id,
                            arc: arc.index,
                            distance: d,
                            cost: l.cost + am.cost,
                            since: if arc.jump {
                                am.frames
                            } else {
                                l.since.saturating_add(am.frames)
                            },
                        }),
                        _ => {}
                    }
                }
            }
            i = j;
        }
    }
    let (id, c) = best?;
    let mut arcs = Vec::new();
    let mut at = id;
    while arena[at as usize].parent != u32::MAX {
        arcs.push(arena[at as usize].arc);
        at = arena[at as usize].parent;
    }
    arcs.reverse();
    let l = arena[id as usize];
    Some((
        Found {
            arcs,
            measure: Measure {
                cost: l.cost,
                distance: l.distance,
                frames: frames as u32,
            },
        },
        c,
    ))
}
