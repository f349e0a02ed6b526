//! An exact k-nearest index over a database's skeletons for the skeletal
//! dissimilarity `c_skel` ([`skeleton_distance`], Huang et al. 2015,
//! Eq. 28): retrieval's candidates without a scan of every frame (issue 43).
//!
//! `c_skel` aligns the two poses on the floor (horizontal centroids
//! together, the least-squares turn about Y) before summing the joints'
//! distances. It is not a metric a triangle-inequality tree can trust, so
//! the index searches a lower bound instead and computes the true
//! distance only for frames whose bound can still beat the current k-th.
//!
//! **The bound.** For joint `j` of pose `a` let `y_j` be its height and
//! `r_j` its horizontal distance from `a`'s horizontal centroid `c_a`. A
//! floor translation moves the centroid with the joints and a turn `R`
//! about Y keeps heights and horizontal lengths, so `(y_j, r_j)` do not
//! change under either. With `u = a_j − c_a` and `v = b_j − c_b`,
//! `(R v)_y = v_y` and `|(R v)_xz| = |v_xz|`; the reverse triangle
//! inequality in the floor plane gives `|u_xz − (R v)_xz| ≥ ||u_xz| − |v_xz||`,
//! so `|u − R v| ≥ √((u_y − v_y)² + (|u_xz| − |v_xz|)²)` for every turn `R`,
//! the fitted one included. Summed over joints:
//!
//! `LB(a, b) = Σ_j √(Δy_j² + Δr_j²) ≤ c_skel(a, b)`.
//!
//! `LB` is a norm of the difference of the 38 features (a sum of 2-D
//! Euclidean norms), so over a box of features its least value is the same
//! sum with each joint's `Δy`, `Δr` the query's distance to the box's
//! interval (0 inside). The index is a k-d tree over the features with a
//! tight box per node; a search visits nodes best-first by that box bound,
//! takes a leaf's frames one by one (their own `LB` first, the true
//! `c_skel` only when `LB` can still beat the k-th), and stops when no
//! node left can.
//!
//! **Exact.** Results are the `k` smallest by `(c_skel as f32, frame id)`,
//! the order [`nearest_scan`] uses too. A frame or node is skipped only
//! when `LB·(1 − 10⁻⁶) > worst·(1 + 10⁻⁶) + 10⁻⁹ m`, `worst` the current
//! k-th cost as f32: the margin covers the bound's and the distance's
//! rounding (~10⁻¹⁵ relative) and the f32 rounding of the cost (6·10⁻⁸
//! relative), so a skipped frame's f32 cost is strictly above the k-th's
//! and cannot tie with it. Frames with a non-finite feature sit outside
//! the tree and are always computed; a query with a non-finite feature
//! falls back to the scan.

use crate::pose::Pose;
use crate::pose::measure::{horizontal_centroid, skeleton_distance};
use crate::rig::Canonical;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Joints per pose.
const J: usize = Canonical::COUNT;
/// Features per pose: `(y_j, r_j)` per joint.
const F: usize = 2 * J;
/// Frames per leaf (16: not tuned by measurement yet).
const LEAF: usize = 16;
/// Relative pruning margin.
const REL: f64 = 1e-6;
/// Absolute pruning margin (metres).
const ABS: f64 = 1e-9;

/// The floor-invariant features of a pose: height and horizontal radius
/// from the horizontal centroid of each joint, `[y_0, r_0, y_1, r_1, …]`.
pub fn features(p: &Pose) -> [f64; F] {
    let c = horizontal_centroid(p);
    let mut f = [0.0; F];
    for (j, q) in p.iter().enumerate() {
        f[2 * j] = q.y;
        f[2 * j + 1] = (q.x - c.x).hypot(q.z - c.z);
    }
    f
}

/// `LB(a, b)` of two poses' features: never above
/// [`skeleton_distance`] of the poses (module docs).
pub fn lower_bound(a: &[f64; F], b: &[f64]) -> f64 {
    lower_bound_until(a, b, f64::INFINITY)
}

/// [`lower_bound`], the sum stopped as soon as it passes `stop` (any
/// value above `stop` is then returned: the terms are non-negative).
fn lower_bound_until(a: &[f64; F], b: &[f64], stop: f64) -> f64 {
    let mut s = 0.0;
    for j in 0..J {
        let (dy, dr) = (a[2 * j] - b[2 * j], a[2 * j + 1] - b[2 * j + 1]);
        s += (dy * dy + dr * dr).sqrt();
        if s > stop {
            break;
        }
    }
    s
}

/// A node of the tree: frames `lo..hi` of the tree order, its children
/// (`u32::MAX` for a leaf), its box at `boxes[node * 2F..]` (minima then
/// maxima).
#[derive(Debug, Clone, Copy)]
struct Node {
    lo: u32,
    hi: u32,
    left: u32,
    right: u32,
}

/// The index of one database's skeletons (module docs). Built once per
/// character ([`crate::db::Character::pose_index`]).
#[derive(Debug, Clone)]
pub struct PoseIndex {
    /// Frame count.
    n: usize,
    /// Features in tree order, `F` per frame.
    feats: Vec<f64>,
    /// Frame id of each tree position.
    ids: Vec<u32>,
    nodes: Vec<Node>,
    boxes: Vec<f64>,
    /// Frames with a non-finite feature (always computed).
    loose: Vec<u32>,
}

/// A search's scratch, kept by a caller that searches often (a thread of
/// the offline retrieval, the live session), and its count of true
/// distances computed.
#[derive(Debug, Default)]
pub struct Search {
    queue: BinaryHeap<Pending>,
    best: BinaryHeap<Found>,
    /// True distances computed since the scratch was made.
    pub evaluated: u64,
}

/// A node to visit, ordered so that the heap pops the smallest bound.
#[derive(Debug, Clone, Copy)]
struct Pending(f64, u32);

impl PartialEq for Pending {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Pending {}
impl PartialOrd for Pending {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Pending {
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}

/// A result, ordered by `(cost, id)` so that the heap's top is the worst.
#[derive(Debug, Clone, Copy)]
struct Found(f32, u32);

impl PartialEq for Found {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Found {}
impl PartialOrd for Found {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Found {
    fn cmp(&self, o: &Self) -> Ordering {
        by_cost_then_id(&(self.0, self.1), &(o.0, o.1))
    }
}

/// The order of retrieval's candidates: cost (f32, total order), then
/// frame id.
pub fn by_cost_then_id(a: &(f32, u32), b: &(f32, u32)) -> Ordering {
    a.0.total_cmp(&b.0).then(a.1.cmp(&b.1))
}

/// The `k` frames of `poses` nearest to `q` by [`skeleton_distance`]
/// (cost as f32, frame id), sorted by that order, into `out`: every frame
/// computed (the reference the index must equal, and its fallback).
pub fn nearest_scan(poses: &[Pose], q: &Pose, k: usize, out: &mut Vec<(f32, u32)>) {
    out.clear();
    out.extend(
        poses
            .iter()
            .enumerate()
            .map(|(i, p)| (skeleton_distance(q, p) as f32, i as u32)),
    );
    if k == 0 {
        out.clear();
    } else if k < out.len() {
        out.select_nth_unstable_by(k - 1, by_cost_then_id);
        out.truncate(k);
    }
    out.sort_unstable_by(by_cost_then_id);
}

/// True when a frame or node whose bound is `lb` can still beat `worst`
/// (the current k-th cost), with the rounding margins of the module docs.
fn can_beat(lb: f64, worst: f32) -> bool {
    // Not `lb ≤ w`: a NaN `worst` (the k-th is a NaN cost) keeps everything.
    let w = worst as f64 * (1.0 + REL) + ABS;
    w.is_nan() || lb * (1.0 - REL) <= w
}

impl PoseIndex {
    /// Indexes `poses` (ids are their positions).
    pub fn new(poses: &[Pose]) -> PoseIndex {
        let all: Vec<[f64; F]> = poses.iter().map(features).collect();
        let (mut order, mut loose) = (Vec::new(), Vec::new());
        for (i, f) in all.iter().enumerate() {
            if f.iter().all(|v| v.is_finite()) {
                order.push(i as u32);
            } else {
                loose.push(i as u32);
            }
        }
        let mut index = PoseIndex {
            n: poses.len(),
            feats: Vec::new(),
            ids: Vec::new(),
            nodes: Vec::new(),
            boxes: Vec::new(),
            loose,
        };
        if !order.is_empty() {
            let len = order.len();
            index.build(&all, &mut order, 0, len);
        }
        index.feats = order.iter().flat_map(|&i| all[i as usize]).collect();
        index.ids = order;
        index
    }

    /// Number of frames indexed (with the loose ones).
    pub fn len(&self) -> usize {
        self.n
    }

    /// True when there is no frame.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Bytes held by the index.
    pub fn heap_bytes(&self) -> usize {
        self.feats.len() * 8
            + self.ids.len() * 4
            + self.nodes.len() * std::mem::size_of::<Node>()
            + self.boxes.len() * 8
            + self.loose.len() * 4
    }

    /// Builds the subtree over `order[lo..hi]` (reordered in place) and
    /// returns its node.
    fn build(&mut self, all: &[[f64; F]], order: &mut [u32], lo: usize, hi: usize) -> u32 {
        let me = self.nodes.len();
        self.nodes.push(Node {
            lo: lo as u32,
            hi: hi as u32,
            left: u32::MAX,
            right: u32::MAX,
        });
        let (mut min, mut max) = ([f64::INFINITY; F], [f64::NEG_INFINITY; F]);
        for &i in &order[lo..hi] {
            for (d, v) in all[i as usize].iter().enumerate() {
                min[d] = min[d].min(*v);
                max[d] = max[d].max(*v);
            }
        }
        self.boxes.extend_from_slice(&min);
        self.boxes.extend_from_slice(&max);
        if hi - lo > LEAF {
            let d = (0..F)
                .max_by(|&a, &b| (max[a] - min[a]).total_cmp(&(max[b] - min[b])))
                .unwrap_or(0);
            let mid = (lo + hi) / 2;
            order[lo..hi].select_nth_unstable_by(mid - lo, |&x, &y| {
                all[x as usize][d].total_cmp(&all[y as usize][d])
            });
            let left = self.build(all, order, lo, mid);
            let right = self.build(all, order, mid, hi);
            self.nodes[me].left = left;
            self.nodes[me].right = right;
        }
        me as u32
    }

    /// The least `LB` from query features `q` to any frame in node `i`'s box.
    fn box_bound(&self, q: &[f64; F], i: u32) -> f64 {
        let b = &self.boxes[i as usize * 2 * F..(i as usize + 1) * 2 * F];
        let (min, max) = b.split_at(F);
        let gap = |d: usize| (min[d] - q[d]).max(q[d] - max[d]).max(0.0);
        (0..J)
            .map(|j| {
                let (dy, dr) = (gap(2 * j), gap(2 * j + 1));
                (dy * dy + dr * dr).sqrt()
            })
            .sum()
    }

    /// The `k` frames of `poses` (the poses indexed) nearest to `q`, as
    /// [`nearest_scan`] finds them (same frames, costs and order), into
    /// `out`, with `scratch` kept between calls.
    pub fn nearest(
        &self,
        poses: &[Pose],
        q: &Pose,
        k: usize,
        scratch: &mut Search,
        out: &mut Vec<(f32, u32)>,
    ) {
        let qf = features(q);
        if poses.len() != self.n || !qf.iter().all(|v| v.is_finite()) {
            scratch.evaluated += poses.len() as u64;
            return nearest_scan(poses, q, k, out);
        }
        let Search {
            queue,
            best,
            evaluated,
        } = scratch;
        queue.clear();
        best.clear();
        out.clear();
        if k == 0 {
            return;
        }
        let mut offer = |i: u32, best: &mut BinaryHeap<Found>| {
            *evaluated += 1;
            let f = Found(skeleton_distance(q, &poses[i as usize]) as f32, i);
            if best.len() < k {
                best.push(f);
            } else if best.peek().is_some_and(|w| f < *w) {
                best.pop();
                best.push(f);
            }
        };
        for &i in &self.loose {
            offer(i, best);
        }
        let worst = |best: &BinaryHeap<Found>| match best.peek() {
            Some(w) if best.len() >= k => w.0,
            _ => f32::INFINITY,
        };
        if !self.nodes.is_empty() {
            queue.push(Pending(0.0, 0));
        }
        while let Some(Pending(bound, i)) = queue.pop() {
            if best.len() >= k && !can_beat(bound, worst(best)) {
                break;
            }
            let node = self.nodes[i as usize];
            if node.left != u32::MAX {
                for c in [node.left, node.right] {
                    let b = self.box_bound(&qf, c);
                    if best.len() < k || can_beat(b, worst(best)) {
                        queue.push(Pending(b, c));
                    }
                }
                continue;
            }
            for t in node.lo as usize..node.hi as usize {
                let w = worst(best);
                // Past this the frame cannot beat the k-th (`can_beat`).
                let stop = (w as f64 * (1.0 + REL) + ABS) / (1.0 - REL);
                let lb = lower_bound_until(&qf, &self.feats[t * F..(t + 1) * F], stop);
                if best.len() < k || can_beat(lb, w) {
                    offer(self.ids[t], best);
                }
            }
        }
        out.extend(best.drain().map(|f| (f.0, f.1)));
        out.sort_unstable_by(by_cost_then_id);
    }
}

#[cfg(test)]
mod tests;
