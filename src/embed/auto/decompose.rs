//! Rigid skinning decomposition of a mesh sequence: which vertices move
//! together. In the spirit of SSDR (Le & Deng 2012, "Smooth Skinning
//! Decomposition with Rigid Bones") and Dem Bones (Le & Deng 2014,
//! "Robust and Accurate Skeletal Rigging from Mesh Sequences"), with one
//! bone per vertex (hard assignment):
//!
//! 1. every vertex's local rotation per frame (the best rigid fit of its
//!    two-ring from the rest frame to the frame, Kabsch through the polar
//!    decomposition, [`crate::mesh::frames::polar`]) is its motion
//!    signature; k-means on the signatures, every cluster then cut into
//!    its connected pieces, gives the initial parts (Le & Deng 2014,
//!    Sec. 4.1 initialise by clustering the vertices' motion);
//! 2. then alternate, as SSDR does: one rigid transform per part and frame
//!    (Kabsch of its vertices), and each vertex re-assigned to the part,
//!    among its own and its mesh neighbours' (spatial contiguity), whose
//!    transforms reproduce its positions best;
//! 3. adjacent parts whose union still moves rigidly (RMS residual below a
//!    fraction of the height) are merged, most rigid pair first;
//! 4. with [`MergeRule::Settle`] (an option, session 31) step 2 run again
//!    on the merged parts until no vertex changes part, then step 3, and
//!    again, so that the boundaries are the merged parts' own rather than
//!    those of the clusters they were merged from.
//!
//! Except with [`Seeding::Index`] (the default) all of it runs on the
//! vertices in an order of their positions ([`super::seeding`]), the
//! k-means seeded in that order: the parts do not depend on how the file
//! numbers its vertices. [`Seeding::Vote`] and [`Seeding::Consensus`]
//! (session 30) draw several k-means++ seedings and keep the parts most
//! of them agree on ([`super::consensus`]), so that no single draw
//! decides. Not yet the default: see [`DecomposeOptions::seeding`].

use crate::mesh::frames::polar;
use glam::{DMat3, DVec3};
use rayon::prelude::*;

/// One rigid part's motion: a rotation and translation per frame, taking
/// the rest frame's positions onto the frame's.
#[derive(Debug, Clone)]
pub struct PartMotion {
    /// Per frame rotation.
    pub r: Vec<DMat3>,
    /// Per frame translation.
    pub t: Vec<DVec3>,
}

/// The old name of [`PartMotion`] (before session 40: "motion" names a mesh
/// sequence's motion, `parametric::Motion`; issue 40).
#[deprecated(note = "renamed PartMotion (old name Motion)")]
pub type Motion = PartMotion; // old name

impl PartMotion {
    /// Where rest point `p` is at frame `f`.
    pub fn apply(&self, f: usize, p: DVec3) -> DVec3 {
        self.r[f] * p + self.t[f]
    }
}

/// The parts found: a label per vertex (0..count) and each part's motion.
#[derive(Debug, Clone)]
pub struct Decomposition {
    /// Part of each vertex.
    pub labels: Vec<u32>,
    /// Number of parts.
    pub count: usize,
    /// Each part's rigid motion over the frames.
    pub motions: Vec<PartMotion>,
    /// Each part's RMS residual (length units) over its vertices and frames.
    pub residual: Vec<f64>,
}

/// Settings of [`decompose`].
#[derive(Debug, Clone, Copy)]
pub struct DecomposeOptions {
    /// Clusters of the initial k-means. Default 40.
    pub clusters: usize,
    /// Alternating fit/assignment rounds. Default 8.
    pub rounds: usize,
    /// Merge adjacent parts while their union's RMS residual stays below
    /// this fraction of the height. Default 0.012.
    pub merge_below: f64,
    /// How the k-means is seeded and in which order the vertices are
    /// visited ([`Seeding`]). Default [`Seeding::Index`] (main's): no
    /// seeding independent of the numbering rigged the real captures as
    /// well yet (session 29, `autorig_eval … joints`: samba 0.69 % of the
    /// height from the landmark rig as numbered, 0.78 % renumbered; every
    /// order-free seeding tried 1.60-3.07 %; session 30's
    /// [`Seeding::Vote`] of 5 draws 1.81 %, l_knee 5.1 %, and 13.6 s of
    /// CPU for samba's `db init`).
    pub seeding: Seeding,
    /// Which pseudo-random draws the k-means++ seedings use: draw `r` of
    /// a seeding of N draws is the sequence number `salt · N + r` (0: the
    /// default's; `salt=S` in `SURFMOTION_AUTORIG`). A measurement knob:
    /// the rig's spread from draw to draw is its spread over salts.
    /// Default 0.
    pub salt: u32,
    /// What follows the greedy merges ([`MergeRule`]). Default
    /// [`MergeRule::Greedy`] (sessions 20-30's: nothing).
    pub merge: MergeRule,
}

/// [`DecomposeOptions::merge`]: what the decomposition does after its
/// greedy merges of adjacent parts whose union stays rigid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MergeRule {
    /// Nothing (sessions 20-30): the merged parts keep the boundaries of
    /// the k-means clusters they were merged from, as the re-assignment
    /// rounds on those clusters left them (`merge=greedy`). Which
    /// cluster a band at the knee fell into, so which side of the knee
    /// the boundary lies, depends on the draw (session 30: samba's
    /// joints move 1.93 % of the height on average from draw to draw).
    Greedy,
    /// The merged parts settled (`merge=settle`, session 31): the SSDR
    /// alternation (Le & Deng 2012, Sec. 3: each part's rigid transform
    /// fitted, each vertex given the part that reproduces it best, here
    /// among its own and its mesh neighbours') run again on the merged
    /// parts until no vertex changes part (at most
    /// [`SETTLE_ROUNDS`] rounds), then the merges tried again on the
    /// settled parts, and again, until a merge changes nothing (at most
    /// [`SETTLE_PASSES`] passes). A boundary then lies where the two
    /// parts' motions reproduce the surface equally well, whichever
    /// clusters the parts were merged from. Measured (session 31,
    /// `autorig_eval … spread 5 renumbered`: ten draws per capture, salts
    /// 0-4 as numbered and renumbered; greedy → settle): samba's joints
    /// move 3.15 → 1.77 % of the height on average between draws, the
    /// mean joint error 0.69-2.26 → 1.07-1.47 % (average 1.45 → 1.38),
    /// l_elbow 0.45-4.32 → 1.11-1.19 %, r_knee 0.59-4.08 → 0.22-0.85 %,
    /// parts 92.3 → 93.8 %; but the left knee lands 5.0-5.4 % low in six
    /// of ten draws (the shin cut at mid-shin: its upper half settles
    /// with the skirt's hem), and draw 0 (the default's) is 1.30 %
    /// against greedy's 0.69 %. Crane: joints move 1.80 → 1.36 %, mean
    /// 2.25 → 2.37 %, l_hip 8.3 % in most draws, 2 of 10 draws' landmarks
    /// refused by the embedding (greedy's 1 of 10: a knee on the other
    /// side of the mid-plane; none since session 32's sides,
    /// [`super::sides`], `spread 10 renumbered`: 0 of 20 either way).
    /// 1.4-1.5 → 1.9-2.1 s of CPU a rig. Not the default.
    Settle,
    /// [`MergeRule::Settle`], then each settled part that is not rigid
    /// (its RMS residual at or over the merge limit) split in two, the
    /// halves settled and the merges tried again (`merge=settle-split`,
    /// session 31; at most [`SPLIT_PASSES`] passes). A part that
    /// straddles a joint under clothing (samba's upper shin with the
    /// skirt's hem, so the knee inside one part) is cut where its two
    /// ends' motions part. The split is Dem Bones' bone insertion (Le &
    /// Deng 2014, Sec. 4.1: a new bone seeded where the reconstruction
    /// error is largest) made local: the half nearest (in mesh hops) to
    /// the part's worst-reproduced vertex against the rest, then a
    /// 2-means on the two halves' rigid motions. Measured (session 31,
    /// `autorig_eval … spread 3 renumbered`, six draws): crane exactly as
    /// [`MergeRule::Settle`] (no part split); samba's left knee 5.1 % low
    /// in three of six draws (settle's: two), joints moving 1.31 % between
    /// draws (settle 0.71 %), 2.0-4.6 s of CPU a rig. Worse than settle:
    /// kept as a measured option, not for use.
    SettleSplit,
}

impl MergeRule {
    /// The rule named `name` (`greedy`, `settle`, `settle-split`).
    pub fn parse(name: &str) -> Option<MergeRule> {
        match name {
            "greedy" => Some(MergeRule::Greedy),
            "settle" => Some(MergeRule::Settle),
            "settle-split" => Some(MergeRule::SettleSplit),
            _ => None,
        }
    }
}

/// [`MergeRule::Settle`]'s cap on the re-assignment rounds of one pass.
pub(crate) const SETTLE_ROUNDS: usize = 40;

/// [`MergeRule::Settle`]'s cap on its passes (settle, then merge).
pub(crate) const SETTLE_PASSES: usize = 4;

/// [`MergeRule::SettleSplit`]'s cap on its passes (split, settle, merge).
pub(crate) const SPLIT_PASSES: usize = 3;

/// [`DecomposeOptions::seeding`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Seeding {
    /// The vertices in their positions' order
    /// ([`super::seeding::canonical_order`]), the k-means seeded by
    /// farthest-point sampling of the rest positions
    /// ([`super::seeding::farthest_seeds`]): the same parts however the
    /// vertices are numbered (`seed=position`). Session 29's first
    /// candidate: samba's joints 3.07 % of the height from the landmark
    /// rig's (the hips 11 %; index seeding 0.69 %).
    Position,
    /// The default (sessions 20-30): the vertices in index order,
    /// k-means++ from vertex `n / 2` with a fixed pseudo-random sequence
    /// walked in index order (`seed=index` in `SURFMOTION_AUTORIG`). The
    /// rig follows the numbering: samba renumbered (reversed, shuffled,
    /// odd ids first) moves a joint by up to 2.0-5.6 % of the height,
    /// crane 1.9-7.0 %, the synthetic walk 0.6-0.8 % (session 29,
    /// `embed::auto_vertex_order` with `seed=index`).
    Index,
    /// The vertices in their positions' order, the k-means seeded by
    /// farthest-point sampling of the motion signatures from the vertex
    /// nearest the middle of the body ([`super::seeding::farthest_in`]):
    /// the most different motions first (`seed=motion`). Samba 1.60 %
    /// (session 29).
    Motion,
    /// The vertices in their positions' order, the k-means seeded by
    /// k-means++ (Arthur & Vassilvitskii 2007) drawn this many times
    /// with fixed pseudo-random sequences walked in that order, the first
    /// centre at the vertex nearest the middle of the body; the draw of
    /// least potential (sum of squared distances to the nearest seed)
    /// kept (`seed=draws-N`). With 8 draws (session 29): samba 1.82 %
    /// of the height from the landmark rig (r_knee 3.18 %, parts 88.8 %),
    /// crane 2.34 % (90.3 %); main's 0.69 % (96.3 %) and 1.94 % (91.7 %).
    Draws(u32),
    /// The vertices in their positions' order; this many whole
    /// decompositions, each from one k-means++ draw (as
    /// [`Seeding::Draws`] draws them), combined by majority
    /// ([`super::consensus`]: every vertex in the part of the draws'
    /// medoid that most draws put it in), then refined once more (the
    /// re-assignment rounds and the merges) from the vote
    /// (`seed=consensus-N`). The boundaries are the majority's, not one
    /// draw's. Costs N + 1 decompositions.
    Consensus(u32),
    /// As [`Seeding::Consensus`] but the vote taken on the draws' k-means
    /// clusters (before the re-assignment and the merges), then one
    /// decomposition from the voted clusters (`seed=vote-N`). Costs N
    /// k-means and one decomposition.
    Vote(u32),
}

impl Seeding {
    /// The seeding named `name` (`position`, `index`, `motion`,
    /// `draws-N`, `consensus-N`, `vote-N`; N in 1..=64).
    pub fn parse(name: &str) -> Option<Seeding> {
        let count = |n: &str| n.parse::<u32>().ok().filter(|&n| (1..=64).contains(&n));
        if let Some(n) = name.strip_prefix("draws-") {
            return count(n).map(Seeding::Draws);
        }
        if let Some(n) = name.strip_prefix("consensus-") {
            return count(n).map(Seeding::Consensus);
        }
        if let Some(n) = name.strip_prefix("vote-") {
            return count(n).map(Seeding::Vote);
        }
        match name {
            "position" => Some(Seeding::Position),
            "motion" => Some(Seeding::Motion),
            "index" => Some(Seeding::Index),
            _ => None,
        }
    }
}

impl Default for DecomposeOptions {
    fn default() -> Self {
        DecomposeOptions {
            clusters: 40,
            rounds: 8,
            merge_below: 0.012,
            seeding: Seeding::Index,
            salt: 0,
            merge: MergeRule::Greedy,
        }
    }
}

fn v3(p: [f64; 3]) -> DVec3 {
    DVec3::from_array(p)
}

/// Best rigid motion (Kabsch) taking rest points `idx` onto frame points:
/// `(R, t)` with `frame ≈ R · rest + t` (the identity and the centroids'
/// offset for fewer than three points).
pub fn kabsch(rest: &[[f64; 3]], frame: &[[f64; 3]], idx: &[u32]) -> (DMat3, DVec3) {
    if idx.is_empty() {
        return (DMat3::IDENTITY, DVec3::ZERO);
    }
    let k = idx.len() as f64;
    let c0 = idx.iter().map(|&v| v3(rest[v as usize])).sum::<DVec3>() / k;
    let c1 = idx.iter().map(|&v| v3(frame[v as usize])).sum::<DVec3>() / k;
    let mut h = DMat3::ZERO;
    for &v in idx {
        let (a, b) = (v3(rest[v as usize]) - c0, v3(frame[v as usize]) - c1);
        h += DMat3::from_cols(b * a.x, b * a.y, b * a.z);
    }
    if idx.len() < 3 || !h.is_finite() || h.abs_diff_eq(DMat3::ZERO, 1e-300) {
        return (DMat3::IDENTITY, c1 - c0);
    }
    let r = DMat3::from_quat(polar(h).0);
    (r, c1 - r * c0)
}

/// Fits each part's motion over the frames.
fn fit(rest: &[[f64; 3]], frames: &[&[[f64; 3]]], members: &[Vec<u32>]) -> Vec<PartMotion> {
    members
        .par_iter()
        .map(|idx| {
            let (mut r, mut t) = (Vec::new(), Vec::new());
            for f in frames {
                let (a, b) = kabsch(rest, f, idx);
                r.push(a);
                t.push(b);
            }
            PartMotion { r, t }
        })
        .collect()
}

/// Each part's best rigid motion (Kabsch) from `rest` onto `frame`, the
/// parts given by `labels` (0..`count`): how points found on the rest
/// frame are carried onto another frame (the topology's) that the
/// decomposition did not fit.
pub(crate) fn fit_onto(
    rest: &[[f64; 3]],
    frame: &[[f64; 3]],
    labels: &[u32],
    count: usize,
) -> Vec<(DMat3, DVec3)> {
    members_of(labels, count)
        .iter()
        .map(|idx| kabsch(rest, frame, idx))
        .collect()
}

/// Squared error of vertex `v` under motion `m`, summed over frames.
fn err(rest: &[[f64; 3]], frames: &[&[[f64; 3]]], m: &PartMotion, v: usize) -> f64 {
    let p = v3(rest[v]);
    frames
        .iter()
        .enumerate()
        .map(|(f, x)| (m.apply(f, p) - v3(x[v])).length_squared())
        .sum()
}

fn members_of(labels: &[u32], count: usize) -> Vec<Vec<u32>> {
    let mut m = vec![Vec::new(); count];
    for (v, &l) in labels.iter().enumerate() {
        m[l as usize].push(v as u32);
    }
    m
}

/// Relabels so that every label is one connected region: each connected
/// piece of a label becomes its own label, and pieces below `min_size`
/// vertices join the neighbouring label they touch most. Labels are then
/// renumbered 0..count.
pub(crate) fn split_connected(labels: &mut [u32], nb: &[Vec<u32>], min_size: usize) -> usize {
    let n = labels.len();
    let mut comp = vec![u32::MAX; n];
    let mut sizes: Vec<usize> = Vec::new();
    let mut stack = Vec::new();
    for s in 0..n {
        if comp[s] != u32::MAX {
            continue;
        }
        let c = sizes.len() as u32;
        comp[s] = c;
        stack.push(s as u32);
        let mut size = 0;
        while let Some(v) = stack.pop() {
            size += 1;
            for &u in &nb[v as usize] {
                if comp[u as usize] == u32::MAX && labels[u as usize] == labels[v as usize] {
                    comp[u as usize] = c;
                    stack.push(u);
                }
            }
        }
        sizes.push(size);
    }
    // Small pieces take the piece they border most, repeatedly (a piece
    // may border only other small pieces at first).
    for _ in 0..8 {
        let mut changed = false;
        for c in 0..sizes.len() {
            if sizes[c] == 0 || sizes[c] >= min_size {
                continue;
            }
            let mut count: std::collections::HashMap<u32, usize> = Default::default();
            for v in 0..n {
                if comp[v] as usize != c {
                    continue;
                }
                for &u in &nb[v] {
                    let cu = comp[u as usize];
                    if cu as usize != c {
                        *count.entry(cu).or_default() += 1;
                    }
                }
            }
            let Some((&to, _)) = count
                .iter()
                .max_by_key(|(k, c)| (**c, std::cmp::Reverse(**k)))
            else {
                continue;
            };
            for x in comp.iter_mut() {
                if *x as usize == c {
                    *x = to;
                }
            }
            sizes[to as usize] += sizes[c];
            sizes[c] = 0;
            changed = true;
        }
        if !changed {
            break;
        }
    }
    let mut renum = vec![u32::MAX; sizes.len()];
    let mut next = 0u32;
    for v in 0..n {
        let c = comp[v] as usize;
        if renum[c] == u32::MAX {
            renum[c] = next;
            next += 1;
        }
        labels[v] = renum[c];
    }
    next as usize
}

/// Motion signature of every vertex: its two-ring's rotation per frame
/// (nine numbers a frame).
fn signatures(rest: &[[f64; 3]], frames: &[&[[f64; 3]]], nb: &[Vec<u32>]) -> Vec<Vec<f64>> {
    (0..rest.len())
        .into_par_iter()
        .map(|v| {
            let mut ring: Vec<u32> = nb[v].clone();
            for &u in &nb[v] {
                ring.extend_from_slice(&nb[u as usize]);
            }
            ring.push(v as u32);
            ring.sort_unstable();
            ring.dedup();
            let step = frames.len().div_ceil(SIGNATURE_FRAMES).max(1);
            let mut s = Vec::with_capacity(9 * SIGNATURE_FRAMES);
            for f in frames.iter().step_by(step) {
                let (r, _) = kabsch(rest, f, &ring);
                s.extend_from_slice(&r.to_cols_array());
            }
            s
        })
        .collect()
}

/// Frames of the motion signatures (evenly spread).
const SIGNATURE_FRAMES: usize = 12;

fn dist2(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// k-means of the signatures from the centres `seeds` (vertex ids), or
/// without them by k-means++ seeding with the pseudo-random sequence
/// number `salt` walked in index order (deterministic, but dependent on
/// the order).
fn kmeans(sig: &[Vec<f64>], k: usize, iters: usize, seeds: Option<&[u32]>, salt: u64) -> Vec<u32> {
    let n = sig.len();
    let k = k.min(n).max(1);
    let centres = match seeds {
        Some(s) if !s.is_empty() => s.iter().map(|&v| sig[v as usize].clone()).collect(),
        _ => kmeans_pp(sig, k, salt),
    };
    lloyd(sig, centres, iters)
}

/// The state of pseudo-random sequence number `r` (0: the default's).
fn sequence(r: u64) -> u64 {
    0x9E37_79B9_7F4A_7C15 ^ r.wrapping_mul(0xD1B5_4A32_D192_ED03)
}

/// k-means++ seeds (Arthur & Vassilvitskii 2007) drawn with the
/// pseudo-random sequence number `salt`, the first at vertex `n / 2`.
fn kmeans_pp(sig: &[Vec<f64>], k: usize, salt: u64) -> Vec<Vec<f64>> {
    let ids = kmeans_pp_ids(sig, k, sig.len() / 2, sequence(salt)).0;
    ids.iter().map(|&v| sig[v as usize].clone()).collect()
}

/// The seed ids of k-means++ draw number `r` of `sig` (from vertex 0;
/// given in [`super::seeding::canonical_order`], the vertex nearest the
/// middle of the body).
fn one_draw(sig: &[Vec<f64>], k: usize, r: u64) -> Vec<u32> {
    if sig.is_empty() {
        return Vec::new();
    }
    kmeans_pp_ids(sig, k.min(sig.len()).max(1), 0, sequence(r)).0
}

/// Of `draws` k-means++ seedings of `sig` (each from vertex 0 with its
/// own fixed pseudo-random sequence, numbers `salt · draws` on), the one
/// of least potential: its seed vertex ids. Deterministic; depends on the
/// order of `sig` (given in [`super::seeding::canonical_order`]).
/// O(draws k n) distances.
fn least_potential_draw(sig: &[Vec<f64>], k: usize, draws: u32, salt: u64) -> Vec<u32> {
    if sig.is_empty() {
        return Vec::new();
    }
    let k = k.min(sig.len()).max(1);
    let first = salt * draws.max(1) as u64;
    (first..first + draws.max(1) as u64)
        .map(|r| kmeans_pp_ids(sig, k, 0, sequence(r)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(ids, _)| ids)
        .unwrap_or_default()
}

/// k-means++ seed ids of `sig` from vertex `first`, drawn with the
/// xorshift sequence from `state` (non-zero), walked in index order, and
/// the seeding's potential (sum over vertices of the squared distance to
/// the nearest seed).
fn kmeans_pp_ids(sig: &[Vec<f64>], k: usize, first: usize, state: u64) -> (Vec<u32>, f64) {
    let n = sig.len();
    let mut state = state.max(1);
    let mut rnd = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut ids = vec![first as u32];
    let mut d: Vec<f64> = sig.par_iter().map(|s| dist2(s, &sig[first])).collect();
    while ids.len() < k {
        let total: f64 = d.iter().sum();
        if total <= 0.0 {
            break;
        }
        let mut x = rnd() * total;
        let mut pick = n - 1;
        for (i, di) in d.iter().enumerate() {
            x -= di;
            if x <= 0.0 {
                pick = i;
                break;
            }
        }
        let c = &sig[pick];
        d.par_iter_mut()
            .zip(sig.par_iter())
            .for_each(|(di, s)| *di = di.min(dist2(s, c)));
        ids.push(pick as u32);
    }
    (ids, d.iter().sum())
}

/// Lloyd's iterations from `centres`: each signature to its nearest
/// centre, each centre to its members' mean, until no label changes.
fn lloyd(sig: &[Vec<f64>], mut centres: Vec<Vec<f64>>, iters: usize) -> Vec<u32> {
    let n = sig.len();
    let mut labels = vec![0u32; n];
    for _ in 0..iters {
        let new: Vec<u32> = sig
            .par_iter()
            .map(|s| {
                (0..centres.len())
                    .min_by(|&a, &b| dist2(s, &centres[a]).total_cmp(&dist2(s, &centres[b])))
                    .unwrap_or(0) as u32
            })
            .collect();
        let changed = new != labels;
        labels = new;
        let dim = sig[0].len();
        let mut sums = vec![vec![0.0; dim]; centres.len()];
        let mut counts = vec![0usize; centres.len()];
        for (s, &l) in sig.iter().zip(&labels) {
            counts[l as usize] += 1;
            for (a, b) in sums[l as usize].iter_mut().zip(s) {
                *a += b;
            }
        }
        for (c, (s, &m)) in centres.iter_mut().zip(sums.iter().zip(&counts)) {
            if m > 0 {
                *c = s.iter().map(|x| x / m as f64).collect();
            }
        }
        if !changed {
            break;
        }
    }
    labels
}

/// RMS residual of the vertices `idx` under their own best rigid motion.
fn union_rms(rest: &[[f64; 3]], frames: &[&[[f64; 3]]], idx: &[u32]) -> (f64, PartMotion) {
    let m = fit(rest, frames, &[idx.to_vec()])
        .pop()
        .unwrap_or(PartMotion {
            r: Vec::new(),
            t: Vec::new(),
        });
    let e: f64 = idx
        .par_iter()
        .map(|&v| err(rest, frames, &m, v as usize))
        .sum();
    let rms = (e / (idx.len().max(1) * frames.len().max(1)) as f64).sqrt();
    (rms, m)
}

/// Decomposes the motion of `frames` (each the rest frame's vertices, in
/// order) relative to `rest` into rigid parts; `nb` are the mesh's vertex
/// neighbours and `height` the body's size (for the merge threshold).
pub fn decompose(
    rest: &[[f64; 3]],
    frames: &[&[[f64; 3]]],
    nb: &[Vec<u32>],
    height: f64,
    opts: &DecomposeOptions,
) -> Decomposition {
    if opts.seeding == Seeding::Index || rest.is_empty() {
        return decompose_in_order(rest, frames, nb, height, opts);
    }
    use super::seeding::{canonical_order, permuted, permuted_neighbours, unpermuted};
    let order = canonical_order(rest, frames);
    let rest_c = permuted(rest, &order);
    let frames_c: Vec<Vec<[f64; 3]>> = frames.iter().map(|f| permuted(f, &order)).collect();
    let frames_c: Vec<&[[f64; 3]]> = frames_c.iter().map(Vec::as_slice).collect();
    let nb_c = permuted_neighbours(nb, &order);
    let mut dec = decompose_in_order(&rest_c, &frames_c, &nb_c, height, opts);
    dec.labels = unpermuted(&dec.labels, &order);
    dec
}

/// [`decompose`] on the vertices in their given order, the k-means seeded
/// as `opts.seeding` says.
fn decompose_in_order(
    rest: &[[f64; 3]],
    frames: &[&[[f64; 3]]],
    nb: &[Vec<u32>],
    height: f64,
    opts: &DecomposeOptions,
) -> Decomposition {
    let sig = signatures(rest, frames, nb);
    let (k, salt) = (opts.clusters, opts.salt as u64);
    let labels = match opts.seeding {
        Seeding::Consensus(m) | Seeding::Vote(m) => {
            let whole = matches!(opts.seeding, Seeding::Consensus(_));
            let draws: Vec<Vec<u32>> = (0..m as u64)
                .into_par_iter()
                .map(|r| {
                    let seeds = one_draw(&sig, k, salt * m as u64 + r);
                    let l = kmeans(&sig, k, 20, Some(&seeds), 0);
                    match whole {
                        true => refine(rest, frames, nb, height, opts, l).labels,
                        false => l,
                    }
                })
                .collect();
            drop(sig);
            super::consensus::vote(&draws, super::consensus::medoid(&draws))
        }
        _ => {
            let seeds = match opts.seeding {
                Seeding::Position => Some(super::seeding::farthest_seeds(rest, k)),
                Seeding::Motion => {
                    let first = super::seeding::farthest_seeds(rest, 1);
                    let d2 = |a: &Vec<f64>, b: &Vec<f64>| dist2(a, b);
                    Some(super::seeding::farthest_in(&sig, first[0], k, d2))
                }
                Seeding::Draws(draws) => Some(least_potential_draw(&sig, k, draws, salt)),
                _ => None,
            };
            let labels = match seeds {
                Some(s) => kmeans(&sig, k, 20, Some(&s), 0),
                None => kmeans(&sig, k, 20, None, salt),
            };
            drop(sig);
            labels
        }
    };
    refine(rest, frames, nb, height, opts, labels)
}

/// The SSDR rounds and the merges from the initial `labels` (one per
/// vertex): each connected piece of a label its own part (pieces under
/// `n / 400` vertices joined to a neighbour), then alternately each
/// part's rigid motion fitted and each vertex given the part, among its
/// own and its neighbours', that reproduces it best, then adjacent parts
/// merged while their union stays rigid ([`merge_greedy`]), then, with
/// [`MergeRule::Settle`], the merged parts re-assigned to convergence
/// and merged again. Deterministic in the labels and the vertex order.
fn refine(
    rest: &[[f64; 3]],
    frames: &[&[[f64; 3]]],
    nb: &[Vec<u32>],
    height: f64,
    opts: &DecomposeOptions,
    mut labels: Vec<u32>,
) -> Decomposition {
    let n = rest.len();
    let min_size = (n / 400).max(8);
    let mut count = split_connected(&mut labels, nb, min_size);
    let mut motions = fit(rest, frames, &members_of(&labels, count));
    reassign(
        rest,
        frames,
        nb,
        &mut labels,
        &mut count,
        &mut motions,
        opts.rounds,
        n / 1000,
    );
    let limit = opts.merge_below * height;
    merge_greedy(rest, frames, nb, &mut labels, count, limit);
    if opts.merge != MergeRule::Greedy {
        settle(rest, frames, nb, &mut labels, limit);
    }
    if opts.merge == MergeRule::SettleSplit {
        for _ in 0..SPLIT_PASSES {
            if split_loose(rest, frames, nb, &mut labels, limit) == 0 {
                break;
            }
            settle(rest, frames, nb, &mut labels, limit);
        }
    }
    let count = split_connected(&mut labels, nb, 1);
    let members = members_of(&labels, count);
    let (residual, motions): (Vec<f64>, Vec<PartMotion>) = members
        .iter()
        .map(|idx| union_rms(rest, frames, idx))
        .unzip();
    Decomposition {
        labels,
        count,
        motions,
        residual,
    }
}

/// [`MergeRule::Settle`] on `labels` (parts with gaps in their numbers
/// allowed): re-assignment to convergence, then the greedy merges under
/// `limit`, until a merge pass merges nothing (at most [`SETTLE_PASSES`]).
fn settle(
    rest: &[[f64; 3]],
    frames: &[&[[f64; 3]]],
    nb: &[Vec<u32>],
    labels: &mut Vec<u32>,
    limit: f64,
) {
    let min_size = (rest.len() / 400).max(8);
    for _ in 0..SETTLE_PASSES {
        let mut count = split_connected(labels, nb, min_size);
        let mut motions = fit(rest, frames, &members_of(labels, count));
        reassign(
            rest,
            frames,
            nb,
            labels,
            &mut count,
            &mut motions,
            SETTLE_ROUNDS,
            1,
        );
        if merge_greedy(rest, frames, nb, labels, count, limit) == 0 {
            break;
        }
    }
}

/// [`MergeRule::SettleSplit`]'s split: every part of `labels` whose RMS
/// residual under its own rigid motion is at or over `limit` (and that
/// has at least twice the least piece size) cut in two: the half of its
/// vertices nearest in mesh hops (inside the part) to its vertex worst
/// reproduced by that motion, against the rest, then five 2-means rounds
/// (each half's rigid motion fitted, each vertex of the part to the half
/// whose motion reproduces it better). New parts take labels past the
/// greatest. Returns the parts split. Deterministic in the labels and
/// the vertex order.
fn split_loose(
    rest: &[[f64; 3]],
    frames: &[&[[f64; 3]]],
    nb: &[Vec<u32>],
    labels: &mut [u32],
    limit: f64,
) -> usize {
    let min_size = (rest.len() / 400).max(8);
    let count = split_connected(labels, nb, min_size);
    let members = members_of(labels, count);
    let mut next = count as u32;
    let mut splits = 0;
    for (p, idx) in members.iter().enumerate() {
        if idx.len() < 2 * min_size {
            continue;
        }
        let (rms, m) = union_rms(rest, frames, idx);
        if rms < limit {
            continue;
        }
        // The worst-reproduced vertex (ties: the lesser id).
        let worst = idx
            .iter()
            .map(|&v| (err(rest, frames, &m, v as usize), v))
            .fold(
                (f64::NEG_INFINITY, u32::MAX),
                |a, b| if b.0 > a.0 { b } else { a },
            )
            .1;
        // Breadth-first from it inside the part: the first half reached.
        let mut side = std::collections::HashMap::with_capacity(idx.len());
        let mut queue = std::collections::VecDeque::from([worst]);
        side.insert(worst, true);
        let mut reached = 1;
        while let Some(v) = queue.pop_front() {
            for &u in &nb[v as usize] {
                if labels[u as usize] as usize == p && !side.contains_key(&u) {
                    side.insert(u, reached < idx.len() / 2);
                    reached += 1;
                    queue.push_back(u);
                }
            }
        }
        // 2-means on the halves' rigid motions.
        for _ in 0..5 {
            let (a, b): (Vec<u32>, Vec<u32>) = idx.iter().partition(|v| side.get(v) == Some(&true));
            if a.len() < 3 || b.len() < 3 {
                break;
            }
            let ms = fit(rest, frames, &[a, b]);
            for &v in idx {
                let (ea, eb) = (
                    err(rest, frames, &ms[0], v as usize),
                    err(rest, frames, &ms[1], v as usize),
                );
                side.insert(v, ea < eb);
            }
        }
        let moved: Vec<u32> = idx
            .iter()
            .copied()
            .filter(|v| side.get(v) == Some(&true))
            .collect();
        if moved.len() < min_size || idx.len() - moved.len() < min_size {
            continue;
        }
        for v in moved {
            labels[v as usize] = next;
        }
        next += 1;
        splits += 1;
    }
    splits
}

/// The SSDR alternation on `labels` (`count` parts, their `motions`):
/// each vertex given the part, among its own and its mesh neighbours',
/// whose motion reproduces it best over the frames (the current part on
/// a tie), every label then cut into its connected pieces (pieces under
/// `n / 400` vertices joined to a neighbour) and the motions fitted
/// again; at most `rounds` rounds, stopping after a round that changed
/// fewer than `stop_below` vertices. Deterministic in the labels and the
/// vertex order. O(rounds · n · frames).
#[allow(clippy::too_many_arguments)]
fn reassign(
    rest: &[[f64; 3]],
    frames: &[&[[f64; 3]]],
    nb: &[Vec<u32>],
    labels: &mut Vec<u32>,
    count: &mut usize,
    motions: &mut Vec<PartMotion>,
    rounds: usize,
    stop_below: usize,
) {
    let n = rest.len();
    let min_size = (n / 400).max(8);
    for _ in 0..rounds {
        let new: Vec<u32> = (0..n)
            .into_par_iter()
            .map(|v| {
                let mut best = (
                    err(rest, frames, &motions[labels[v] as usize], v),
                    labels[v],
                );
                for &u in &nb[v] {
                    let l = labels[u as usize];
                    if l != best.1 {
                        let e = err(rest, frames, &motions[l as usize], v);
                        if e < best.0 {
                            best = (e, l);
                        }
                    }
                }
                best.1
            })
            .collect();
        let changed = new
            .iter()
            .zip(labels.iter())
            .filter(|(a, b)| a != b)
            .count();
        *labels = new;
        *count = split_connected(labels, nb, min_size);
        *motions = fit(rest, frames, &members_of(labels, *count));
        if changed < stop_below {
            break;
        }
    }
}

/// Greedy merging of adjacent parts of `labels` (`count` parts, numbered
/// 0..count) whose union stays rigid: the adjacent pair whose union's RMS
/// residual (under its own best rigid motion) is least is merged, while
/// it is below `limit`; the merged part keeps the lesser label, so labels
/// are left with gaps. Two adjacent connected parts make a connected one:
/// no re-splitting. Returns the merges made.
fn merge_greedy(
    rest: &[[f64; 3]],
    frames: &[&[[f64; 3]]],
    nb: &[Vec<u32>],
    labels: &mut [u32],
    count: usize,
    limit: f64,
) -> usize {
    let n = rest.len();
    let mut merges = 0;
    let mut members = members_of(labels, count);
    let mut pairs = std::collections::BTreeSet::new();
    for v in 0..n {
        for &u in &nb[v] {
            let (a, b) = (labels[v], labels[u as usize]);
            if a < b {
                pairs.insert((a, b));
            }
        }
    }
    let cost = |members: &[Vec<u32>], a: u32, b: u32| {
        let mut idx = members[a as usize].clone();
        idx.extend_from_slice(&members[b as usize]);
        union_rms(rest, frames, &idx).0
    };
    let mut costs: Vec<(f64, u32, u32)> = pairs
        .into_par_iter()
        .map(|(a, b)| (cost(&members, a, b), a, b))
        .collect();
    while let Some(&(rms, a, b)) = costs.iter().min_by(|x, y| x.0.total_cmp(&y.0)) {
        if rms >= limit {
            break;
        }
        merges += 1;
        let moved = std::mem::take(&mut members[b as usize]);
        for &v in &moved {
            labels[v as usize] = a;
        }
        members[a as usize].extend(moved);
        // Pairs of b become pairs of a; pairs of a are re-costed.
        let mut touched = std::collections::BTreeSet::new();
        costs.retain(|&(_, x, y)| {
            if x == a || y == a || x == b || y == b {
                let o = if x == a || x == b { y } else { x };
                if o != a && o != b {
                    touched.insert(o);
                }
                false
            } else {
                true
            }
        });
        let fresh: Vec<(f64, u32, u32)> = touched
            .into_par_iter()
            .map(|o| (cost(&members, a.min(o), a.max(o)), a.min(o), a.max(o)))
            .collect();
        costs.extend(fresh);
    }
    merges
}
