//! Online transitions between motion spaces (Casas et al. 2013, Sec. 3.2,
//! Eqs. 4-5).
//!
//! **Similarity (Eq. 5).** For every pair of spaces, the shape-and-motion
//! similarity `s = 1 − d / max d` of every pair of *reference* frames is
//! precomputed, where the references are a space's sequences and its
//! bisection references ([`super::hybrid`]), on their phase grids, and
//! `d = (1/N_v)(‖X_i − X_j‖² + ‖V_i − V_j‖²)` on body frames (Sec. 3.2.1;
//! `V` the vertex displacement over 0.1 s, and the vertices strided to at
//! most 500). At run time the similarity between parametric states is the
//! weighted sum `w_s S w_tᵀ` of the reference similarities (Eq. 5, a lower
//! bound for convex weights), with `w` the hat weights of the two nearest
//! references: four table reads.
//!
//! **Path (Eq. 4).** A trellis forward in the source space from the current
//! state (the frames the source would play next, at most `depth`) and
//! backward in the target space from the target state; a path plays the
//! source to some frame, jumps to a target frame and plays the target to
//! the target state. Its cost is `E_S + λ · E_L`: the dissimilarity
//! `1 − s` at the jump plus `λ` (5, as the paper) times the latency in
//! seconds (frames of the path / fps). When no target frame is asked
//! (a request names only the space), every target phase is an end state.
//! Shortest path by Dijkstra over the trellis, with buffers reused across
//! decisions.

use serde::{Deserialize, Serialize};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Seconds over which the velocity term of the measure is taken.
pub(crate) const VELOCITY_SECONDS: f64 = 0.1;
/// Vertices of the similarity measure per frame (at most).
pub(crate) const SIMILARITY_VERTICES: usize = 500;

/// Options of the transition search.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TransitionOptions {
    /// Weight of latency against dissimilarity, per second. Default: 5
    /// (the paper's λ).
    pub lambda: f64,
    /// Trellis depth in frames (the paper's `l_max`). Default: 30.
    pub depth: usize,
    /// Frames over which a transition cross-fades. Default: 6.
    pub blend_frames: usize,
}

impl Default for TransitionOptions {
    fn default() -> Self {
        TransitionOptions {
            lambda: 5.0,
            depth: 30,
            blend_frames: 6,
        }
    }
}

/// The reference frames of a space for the similarity: weight coordinates
/// (sorted) and, per reference, `K` feature vectors.
#[derive(Debug, Clone, PartialEq)]
pub struct RefFeatures {
    /// Weight coordinate of each reference, increasing.
    pub u: Vec<f64>,
    /// Per reference, per phase sample: positions then velocities (f32).
    pub feats: Vec<Vec<Vec<f32>>>,
}

/// Precomputed similarities of the references of a source and a target
/// space (Eq. 5's `S`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimilarityTable {
    /// Source phase samples.
    pub ks: usize,
    /// Target phase samples.
    pub kt: usize,
    /// Source reference weight coordinates.
    pub us: Vec<f64>,
    /// Target reference weight coordinates.
    pub ut: Vec<f64>,
    /// `s` in `[0, 1]`, index `((p · |ut| + q) · ks + i) · kt + j`.
    #[serde(skip)]
    pub sim: Vec<f32>,
}

/// The two hat weights of `u` over sorted reference coordinates.
#[inline]
pub(crate) fn hat(refs: &[f64], u: f64) -> (usize, usize, f64) {
    if refs.len() < 2 {
        return (0, 0, 0.0);
    }
    let u = u.clamp(refs[0], refs[refs.len() - 1]);
    let j = refs.partition_point(|&r| r <= u).clamp(1, refs.len() - 1);
    let (a, b) = (refs[j - 1], refs[j]);
    let t = if b > a { (u - a) / (b - a) } else { 0.0 };
    (j - 1, j, t)
}

fn dist(a: &[f32], b: &[f32]) -> f64 {
    let s: f32 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    3.0 * s as f64 / a.len().max(1) as f64
}

impl SimilarityTable {
    /// Computes the table between the references of two spaces.
    pub fn new(src: &RefFeatures, tgt: &RefFeatures) -> SimilarityTable {
        let ks = src.feats.first().map_or(0, |f| f.len());
        let kt = tgt.feats.first().map_or(0, |f| f.len());
        let mut d = Vec::with_capacity(src.u.len() * tgt.u.len() * ks * kt);
        for fp in &src.feats {
            for fq in &tgt.feats {
                for a in fp {
                    for b in fq {
                        d.push(dist(a, b));
                    }
                }
            }
        }
        let max = d.iter().cloned().fold(0.0, f64::max).max(1e-12);
        SimilarityTable {
            ks,
            kt,
            us: src.u.clone(),
            ut: tgt.u.clone(),
            sim: d.iter().map(|x| (1.0 - x / max) as f32).collect(),
        }
    }

    /// Eq. 5: the similarity between the source at (phase sample `i`,
    /// weight `u_s`) and the target at (phase sample `j`, weight `u_t`).
    #[inline]
    pub fn similarity(
        &self,
        i: usize,
        us: (usize, usize, f64),
        j: usize,
        ut: (usize, usize, f64),
    ) -> f64 {
        let nq = self.ut.len();
        let at = |p: usize, q: usize| self.sim[((p * nq + q) * self.ks + i) * self.kt + j] as f64;
        let (p0, p1, a) = us;
        let (q0, q1, b) = ut;
        (1.0 - a) * ((1.0 - b) * at(p0, q0) + b * at(p0, q1))
            + a * ((1.0 - b) * at(p1, q0) + b * at(p1, q1))
    }
}

/// The chosen transition.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Plan {
    /// Source frames played before the jump (0: at the next frame).
    pub wait: usize,
    /// Source phase sample at the jump.
    pub source_sample: usize,
    /// Target phase (grid units) entered at the jump.
    pub entry: usize,
    /// Target frames played after the jump to reach the target state.
    pub after: usize,
    /// Similarity at the jump (Eq. 5).
    pub similarity: f64,
    /// `E_S + λ E_L` (Eq. 4).
    pub cost: f64,
}

/// The target end state of a search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TargetState {
    /// Any phase of the target space.
    AnyPhase,
    /// Reach this phase sample: the backward trellis holds the target
    /// samples that many frames before it (`backward[m]` is the sample
    /// `m` frames before; `backward[0]` the target itself).
    Phase,
}

/// Dijkstra over the transition trellis, with buffers kept across calls.
#[derive(Debug, Default)]
pub struct TransitionPlanner {
    dist: Vec<f64>,
    prev: Vec<usize>,
    heap: BinaryHeap<Reverse<(u64, usize)>>,
}

/// Order-preserving bits of a non-negative cost.
fn key(c: f64) -> u64 {
    c.max(0.0).to_bits()
}

impl TransitionPlanner {
    /// A planner with room for trellises of `depth` and `k` target samples.
    pub fn with_capacity(depth: usize, k: usize) -> TransitionPlanner {
        let n = depth + 2 + k.max(depth + 1) + 1;
        TransitionPlanner {
            dist: Vec::with_capacity(n),
            prev: Vec::with_capacity(n),
            heap: BinaryHeap::with_capacity(n * 4),
        }
    }

    /// Finds the best path (Eq. 4). `source[i]` is the source phase sample
    /// after `i` frames (`i = 0..=depth`); `backward` (for
    /// [`TargetState::Phase`]) the target phase samples `m` frames before
    /// the target state, `m = 0..=depth`. Source weights `us`, target `ut`
    /// as hat weights over the table's references.
    #[allow(clippy::too_many_arguments)]
    pub fn plan(
        &mut self,
        table: &SimilarityTable,
        source: &[usize],
        us: f64,
        ut: f64,
        target: TargetState,
        backward: &[usize],
        fps: f64,
        opts: &TransitionOptions,
    ) -> Option<Plan> {
        let hs = hat(&table.us, us);
        let ht = hat(&table.ut, ut);
        let l = source.len();
        let tn = match target {
            TargetState::AnyPhase => table.kt,
            TargetState::Phase => backward.len(),
        };
        if l == 0 || tn == 0 {
            return None;
        }
        // Nodes: source 0..l, target l..l+tn, sink l+tn.
        let sink = l + tn;
        self.dist.clear();
        self.dist.resize(sink + 1, f64::INFINITY);
        self.prev.clear();
        self.prev.resize(sink + 1, usize::MAX);
        self.heap.clear();
        let step = opts.lambda / fps;
        self.dist[0] = 0.0;
        self.heap.push(Reverse((0, 0)));
        while let Some(Reverse((_, v))) = self.heap.pop() {
            if v == sink {
                break;
            }
            let dv = self.dist[v];
            let relax = |w: usize,
                         c: f64,
                         dist: &mut Vec<f64>,
                         prev: &mut Vec<usize>,
                         heap: &mut BinaryHeap<Reverse<(u64, usize)>>| {
                if dv + c < dist[w] {
                    dist[w] = dv + c;
                    prev[w] = v;
                    heap.push(Reverse((key(dv + c), w)));
                }
            };
            if v < l {
                if v + 1 < l {
                    relax(v + 1, step, &mut self.dist, &mut self.prev, &mut self.heap);
                }
                #[allow(clippy::needless_range_loop)] // m indexes target nodes too
                for m in 0..tn {
                    let j = match target {
                        TargetState::AnyPhase => m,
                        TargetState::Phase => backward[m],
                    };
                    let s = table.similarity(source[v], hs, j, ht);
                    relax(
                        l + m,
                        (1.0 - s).max(0.0),
                        &mut self.dist,
                        &mut self.prev,
                        &mut self.heap,
                    );
                }
            } else {
                let m = v - l;
                match target {
                    TargetState::AnyPhase => {
                        relax(sink, 0.0, &mut self.dist, &mut self.prev, &mut self.heap)
                    }
                    TargetState::Phase if m == 0 => {
                        relax(sink, 0.0, &mut self.dist, &mut self.prev, &mut self.heap)
                    }
                    TargetState::Phase => relax(
                        l + m - 1,
                        step,
                        &mut self.dist,
                        &mut self.prev,
                        &mut self.heap,
                    ),
                }
            }
        }
        if !self.dist[sink].is_finite() {
            return None;
        }
        // Walk back: the target node entered from a source node.
        let mut v = self.prev[sink];
        while self.prev[v] >= l {
            v = self.prev[v];
        }
        let entered = v - l;
        let wait = self.prev[v];
        let (entry, after) = match target {
            TargetState::AnyPhase => (entered, 0),
            TargetState::Phase => (backward[entered], entered),
        };
        let similarity = table.similarity(source[wait], hs, entry, ht);
        Some(Plan {
            wait,
            source_sample: source[wait],
            entry,
            after,
            similarity,
            cost: self.dist[sink],
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One reference each, 4 × 4 samples: the best jump is from source
    /// sample 2 to target sample 1; reaching it costs two frames of
    /// latency, which a small λ pays and a huge λ does not.
    #[test]
    fn dijkstra_trades_similarity_for_latency() {
        let mut sim = vec![0.2f32; 16];
        sim[2 * 4 + 1] = 1.0;
        sim[0] = 0.5;
        let t = SimilarityTable {
            ks: 4,
            kt: 4,
            us: vec![0.0],
            ut: vec![0.0],
            sim,
        };
        let mut p = TransitionPlanner::with_capacity(3, 4);
        let src = [0, 1, 2, 3];
        let o = TransitionOptions {
            lambda: 0.3,
            depth: 3,
            blend_frames: 0,
        };
        let plan = p
            .plan(&t, &src, 0.0, 0.0, TargetState::AnyPhase, &[], 10.0, &o)
            .unwrap();
        assert_eq!((plan.wait, plan.entry), (2, 1));
        assert!(
            (plan.cost - (0.0 + 2.0 * 0.03)).abs() < 1e-6,
            "{}",
            plan.cost
        );
        let o = TransitionOptions { lambda: 100.0, ..o };
        let plan = p
            .plan(&t, &src, 0.0, 0.0, TargetState::AnyPhase, &[], 10.0, &o)
            .unwrap();
        assert_eq!((plan.wait, plan.entry), (0, 0));
        // A target phase: entering sample 1 then playing 2 frames to 3.
        let o = TransitionOptions { lambda: 0.3, ..o };
        let plan = p
            .plan(
                &t,
                &src,
                0.0,
                0.0,
                TargetState::Phase,
                &[3, 2, 1, 0],
                10.0,
                &o,
            )
            .unwrap();
        assert_eq!((plan.wait, plan.entry, plan.after), (2, 1, 2));
    }
}
