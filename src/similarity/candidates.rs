//! The sparse similarity's candidate frames from one nearest-neighbour
//! index over all frames' cheap descriptors (issue 43): every frame's
//! `neighbours` nearest frames overall, and every `stride`-th frame's
//! `per_sequence` nearest frames in each sequence — from the same query's
//! `pool` nearest frames (session 28: at most `pool` a frame, whatever the
//! number of sequences), or from one k-d tree per sequence (`pool` 0;
//! `n / stride · sequences · per_sequence` candidates, the per-sequence
//! candidates' default to session 27). The options are the sparse
//! similarity's (`SparseOptions`, of which [`CandidateOptions`] is the
//! part read here).
//!
//! Exact: a query returns the nearest frames a scan of every frame would
//! ([`KdTree::nearest`]; squared Euclidean distances of the projected
//! descriptors, ties broken by frame number). The per-pair candidates of
//! `pair_scan` come besides; the sparse similarity (`sparse_pairs`)
//! evaluates the full measure around all of them.

use super::kdtree::KdTree;
use super::matrix::Span;
use rayon::prelude::*;

/// What makes a frame pair a candidate of the index (the fields of the
/// same names of the sparse similarity's options).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CandidateOptions {
    /// Nearest frames overall of every frame.
    pub neighbours: usize,
    /// Every `stride`-th frame takes per-sequence candidates.
    pub stride: usize,
    /// Nearest frames in each sequence of those frames.
    pub per_sequence: usize,
    /// Taken among this many nearest frames overall; 0: in every sequence
    /// (one k-d tree per sequence).
    pub pool: usize,
    /// With a pool: a sequence pair that fewer than this many of the
    /// pool's candidates link (either way) takes the per-sequence trees'
    /// candidates instead (both ways); 0: the pool's alone.
    pub cover: usize,
    /// Within a sequence, frames closer than this are not candidates.
    pub min_gap: usize,
    /// Sequence pairs each sequence reaches (issue 43, session 33): its
    /// `reach` most linked other sequences ([`reached_pairs`]); the trees'
    /// candidates (`pool` 0, or a weak pair under the cover rule) only for
    /// the pairs reached, either way. 0 (or at least the other sequences):
    /// every pair.
    pub reach: usize,
}

/// The candidates of the nearest-neighbour index ([`index_candidates`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Candidates {
    /// Per frame, its `neighbours` nearest frames overall,
    /// nearest first (ties by frame number).
    pub near: Vec<Vec<u32>>,
    /// `(frame, candidate)`: every `stride`-th frame's
    /// `per_sequence` nearest frames in each sequence —
    /// among its `pool` nearest frames overall, or in
    /// every sequence when `pool` is 0.
    pub per_sequence: Vec<(usize, u32)>,
    /// With [`CandidateOptions::reach`]: per ordered sequence pair
    /// (`i · sequences + j`, symmetric), whether it is reached
    /// ([`reached_pairs`]); `None`: every pair.
    pub reached: Option<Vec<bool>>,
}

/// The candidates of the projected descriptors `features` (`n × dims`,
/// row-major) of the frames of `spans`: a frame is never its own
/// candidate, nor a frame of its own sequence closer than
/// `min_gap`. Distances are squared Euclidean distances
/// of the descriptors, ties broken by frame number: the exact nearest
/// frames (one k-d tree over all frames; with `pool` 0, one per sequence
/// besides).
pub fn index_candidates(
    features: &[f32],
    dims: usize,
    spans: &[Span],
    opts: &CandidateOptions,
) -> Candidates {
    let n = spans.iter().map(|s| s.start + s.len).max().unwrap_or(0);
    let seq = sequence_of(spans, n);
    let index = Index {
        features,
        dims,
        seq: &seq,
        gap: opts.min_gap.max(1),
    };
    let stride = opts.stride.max(1);
    let pool = if opts.per_sequence > 0 { opts.pool } else { 0 };
    let (near, per_sequence) =
        index.nearest_overall(opts.neighbours, stride, pool, opts.per_sequence);
    let s = spans.len();
    let reached = (opts.reach > 0 && opts.reach + 1 < s).then(|| {
        reached_pairs(
            features,
            dims,
            spans,
            &seq,
            &near,
            &per_sequence,
            opts.reach,
        )
    });
    let reaches = |i: usize, j: usize| reached.as_ref().is_none_or(|r| r[i * s + j]);
    let per_sequence = if opts.pool == 0 || opts.per_sequence == 0 {
        let take = |a: usize, j: usize| reaches(seq[a] as usize, j);
        index.nearest_per_sequence(spans, stride, opts.per_sequence, &take)
    } else if opts.cover > 0 {
        let weak = weakly_linked(&per_sequence, &seq, s, opts.cover);
        // A weak pair takes the trees' candidates instead of the pool's
        // where it is reached; one not reached keeps the pool's.
        let replaced = |i: usize, j: usize| weak[i * s + j] && reaches(i, j);
        let mut kept: Vec<(usize, u32)> = per_sequence
            .into_iter()
            .filter(|&(a, b)| !replaced(seq[a] as usize, seq[b as usize] as usize))
            .collect();
        let filled = |a: usize, j: usize| replaced(seq[a] as usize, j);
        kept.extend(index.nearest_per_sequence(spans, stride, opts.per_sequence, &filled));
        kept
    } else {
        per_sequence
    };
    Candidates {
        near,
        per_sequence,
        reached,
    }
}

/// The sequence pairs reached (issue 43, session 33), per ordered pair
/// `i · sequences + j`: each sequence with itself, and with the `reach`
/// other sequences its frames are most linked to — by the candidates
/// `near` (every frame's nearest overall) and `pooled` (the pool's
/// per-sequence ones), counted either way —, ties and unlinked sequences
/// taken by the distance of the sequences' mean descriptors, then by
/// number; a pair is reached when either sequence takes the other. At most
/// `sequences · (reach + 1)` pairs, so that the candidates that are per
/// sequence pair (the per-pair scan, the cover rule's trees) grow with the
/// sequences, not with their square; every sequence reaches `reach`
/// others, also one whose frames are nobody's nearest.
pub fn reached_pairs(
    features: &[f32],
    dims: usize,
    spans: &[Span],
    seq: &[u32],
    near: &[Vec<u32>],
    pooled: &[(usize, u32)],
    reach: usize,
) -> Vec<bool> {
    let s = spans.len();
    let mut links = vec![0u64; s * s];
    let mut link = |a: usize, b: usize| {
        let (i, j) = (seq[a] as usize, seq[b] as usize);
        if i != j {
            links[i * s + j] += 1;
            links[j * s + i] += 1;
        }
    };
    for (a, bs) in near.iter().enumerate() {
        bs.iter().for_each(|&b| link(a, b as usize));
    }
    pooled.iter().for_each(|&(a, b)| link(a, b as usize));
    let mut mean = vec![0.0f64; s * dims];
    for (k, sp) in spans.iter().enumerate() {
        let m = &mut mean[k * dims..(k + 1) * dims];
        for a in sp.start..sp.start + sp.len {
            for (x, v) in m.iter_mut().zip(&features[a * dims..(a + 1) * dims]) {
                *x += *v as f64;
            }
        }
        m.iter_mut().for_each(|x| *x /= sp.len.max(1) as f64);
    }
    let apart = |i: usize, j: usize| -> f64 {
        (0..dims)
            .map(|d| (mean[i * dims + d] - mean[j * dims + d]).powi(2))
            .sum()
    };
    let mut reached = vec![false; s * s];
    for i in 0..s {
        reached[i * s + i] = true;
        let mut others: Vec<(u64, f64, usize)> = (0..s)
            .filter(|&j| j != i)
            .map(|j| (links[i * s + j], apart(i, j), j))
            .collect();
        others.sort_by(|x, y| y.0.cmp(&x.0).then(x.1.total_cmp(&y.1)).then(x.2.cmp(&y.2)));
        for &(_, _, j) in others.iter().take(reach) {
            reached[i * s + j] = true;
            reached[j * s + i] = true;
        }
    }
    reached
}

/// Per ordered sequence pair `(i, j)` (`i · sequences + j`), whether fewer
/// than `cover` of the candidates `pooled` link `i` and `j`, either way.
fn weakly_linked(
    pooled: &[(usize, u32)],
    seq: &[u32],
    sequences: usize,
    cover: usize,
) -> Vec<bool> {
    let mut links = vec![0usize; sequences * sequences];
    for &(a, b) in pooled {
        let (i, j) = (seq[a] as usize, seq[b as usize] as usize);
        links[i * sequences + j] += 1;
        if i != j {
            links[j * sequences + i] += 1;
        }
    }
    links.into_iter().map(|l| l < cover).collect()
}

/// CPU seconds of the whole process so far (every thread): the stages'
/// figure that load does not inflate as it does wall time; 0 where the
/// platform does not say.
pub(crate) fn process_cpu_seconds() -> f64 {
    crate::util::cpu::process_cpu_seconds().unwrap_or(0.0)
}

/// The sequence of every frame.
pub(super) fn sequence_of(spans: &[Span], n: usize) -> Vec<u32> {
    let mut seq = vec![0u32; n];
    for (k, s) in spans.iter().enumerate() {
        seq[s.start..s.start + s.len].fill(k as u32);
    }
    seq
}

/// Candidate pairs `(frame, candidate)`.
type Seeds = Vec<(usize, u32)>;

/// The projected descriptors and what makes a pair a candidate.
struct Index<'a> {
    features: &'a [f32],
    dims: usize,
    seq: &'a [u32],
    /// Within a sequence, frames closer than this are not candidates.
    gap: usize,
}

impl Index<'_> {
    fn feature(&self, a: usize) -> &[f32] {
        &self.features[a * self.dims..(a + 1) * self.dims]
    }

    /// Every frame's `k` nearest frames (one k-d tree over all frames);
    /// and, when `pool` is not 0, every `stride`-th frame's `per_seq`
    /// nearest frames in each sequence among its `pool` nearest (the same
    /// query, `max(k, pool)` frames), as `(frame, candidate)` pairs.
    fn nearest_overall(
        &self,
        k: usize,
        stride: usize,
        pool: usize,
        per_seq: usize,
    ) -> (Vec<Vec<u32>>, Vec<(usize, u32)>) {
        let n = self.seq.len();
        let sequences = self.seq.iter().map(|&s| s as usize + 1).max().unwrap_or(0);
        let tree = KdTree::new(self.features.to_vec(), self.dims);
        let both: Vec<(Vec<u32>, Seeds)> = (0..n)
            .into_par_iter()
            .map(|a| {
                let keep = |b: u32| {
                    b as usize != a
                        && (self.seq[b as usize] != self.seq[a]
                            || (b as usize).abs_diff(a) >= self.gap)
                };
                let pooled = pool > 0 && a % stride == 0;
                let want = if pooled { k.max(pool) } else { k };
                let found = tree.nearest(self.feature(a), want, &keep);
                let near = found.iter().take(k).map(|&(_, b)| b).collect();
                let mut per = Vec::new();
                if pooled {
                    let mut taken = vec![0usize; sequences];
                    for &(_, b) in found.iter().take(pool) {
                        let t = &mut taken[self.seq[b as usize] as usize];
                        if *t < per_seq {
                            *t += 1;
                            per.push((a, b));
                        }
                    }
                }
                (near, per)
            })
            .collect();
        let mut near = Vec::with_capacity(n);
        let mut per = Vec::new();
        for (a, p) in both {
            near.push(a);
            per.extend(p);
        }
        (near, per)
    }

    /// Every `stride`-th frame's `k` nearest frames in each sequence `j`
    /// for which `take(frame, j)` holds (one k-d tree per sequence that
    /// some frame asks), as `(frame, candidate)` pairs.
    fn nearest_per_sequence(
        &self,
        spans: &[Span],
        stride: usize,
        k: usize,
        take: &(dyn Fn(usize, usize) -> bool + Sync),
    ) -> Vec<(usize, u32)> {
        if k == 0 {
            return Vec::new();
        }
        let n = self.seq.len();
        let per_seq: Vec<Vec<(usize, u32)>> = spans
            .par_iter()
            .enumerate()
            .map(|(j, sj)| {
                let asking: Vec<usize> = (0..n).step_by(stride).filter(|&a| take(a, j)).collect();
                if asking.is_empty() {
                    return Vec::new();
                }
                let sub =
                    self.features[sj.start * self.dims..(sj.start + sj.len) * self.dims].to_vec();
                let tree = KdTree::new(sub, self.dims);
                asking
                    .into_iter()
                    .flat_map(|a| {
                        let keep = |b: u32| {
                            let b = sj.start + b as usize;
                            self.seq[b] != self.seq[a] || b.abs_diff(a) >= self.gap
                        };
                        tree.nearest(self.feature(a), k, &keep)
                            .into_iter()
                            .map(move |(_, b)| (a, (sj.start + b as usize) as u32))
                    })
                    .collect()
            })
            .collect();
        per_seq.into_iter().flatten().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::similarity::sparse::tests::spans;

    /// Squared distance of frames `a` and `b` of `f` (`dims` values each).
    fn d2(f: &[f32], dims: usize, a: usize, b: usize) -> f32 {
        let (x, y) = (&f[a * dims..(a + 1) * dims], &f[b * dims..(b + 1) * dims]);
        x.iter().zip(y).map(|(p, q)| (p - q) * (p - q)).sum()
    }

    /// The candidates of [`index_candidates`] by brute force: every frame
    /// against every other, sorted by squared distance then frame.
    fn brute_candidates(
        f: &[f32],
        dims: usize,
        spans: &[Span],
        o: &CandidateOptions,
    ) -> Candidates {
        let n = f.len() / dims;
        let seq = sequence_of(spans, n);
        let gap = o.min_gap.max(1);
        let ranked = |a: usize, only: Option<u32>| -> Vec<u32> {
            let mut all: Vec<(f32, u32)> = (0..n)
                .filter(|&b| b != a && (seq[b] != seq[a] || b.abs_diff(a) >= gap))
                .filter(|&b| only.is_none_or(|s| seq[b] == s))
                .map(|b| (d2(f, dims, a, b), b as u32))
                .collect();
            all.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            all.into_iter().map(|x| x.1).collect()
        };
        let near = (0..n)
            .map(|a| ranked(a, None).into_iter().take(o.neighbours).collect())
            .collect();
        let mut per_sequence = Vec::new();
        for a in (0..n).step_by(o.stride.max(1)) {
            if o.pool == 0 {
                for j in 0..spans.len() as u32 {
                    let r = ranked(a, Some(j));
                    per_sequence.extend(r.into_iter().take(o.per_sequence).map(|b| (a, b)));
                }
            } else {
                let mut taken = vec![0; spans.len()];
                for b in ranked(a, None).into_iter().take(o.pool) {
                    let t = &mut taken[seq[b as usize] as usize];
                    if *t < o.per_sequence {
                        *t += 1;
                        per_sequence.push((a, b));
                    }
                }
            }
        }
        if o.pool > 0 && o.cover > 0 {
            let how = (spans.len(), o.stride.max(1), o.cover);
            per_sequence = covered(&per_sequence, &seq, how, |a, j| {
                ranked(a, Some(j))
                    .into_iter()
                    .take(o.per_sequence)
                    .collect()
            });
        }
        Candidates {
            near,
            per_sequence,
            reached: None,
        }
    }

    /// The cover rule by counting: per unordered sequence pair, the links
    /// of `pooled` counted; a pair linked fewer than `cover` times loses
    /// its pooled candidates and takes every `stride`-th frame's
    /// `nearest(a, j)` in the other sequence, both ways.
    fn covered(
        pooled: &[(usize, u32)],
        seq: &[u32],
        (sequences, stride, cover): (usize, usize, usize),
        nearest: impl Fn(usize, u32) -> Vec<u32>,
    ) -> Vec<(usize, u32)> {
        let key = |i: u32, j: u32| (i.min(j), i.max(j));
        let mut links = std::collections::HashMap::new();
        for &(a, b) in pooled {
            *links.entry(key(seq[a], seq[b as usize])).or_insert(0usize) += 1;
        }
        let weak = |i: u32, j: u32| links.get(&key(i, j)).copied().unwrap_or(0) < cover;
        let mut out: Vec<(usize, u32)> = pooled
            .iter()
            .copied()
            .filter(|&(a, b)| !weak(seq[a], seq[b as usize]))
            .collect();
        for a in (0..seq.len()).step_by(stride) {
            for j in (0..sequences as u32).filter(|&j| weak(seq[a], j)) {
                out.extend(nearest(a, j).into_iter().map(|b| (a, b)));
            }
        }
        out
    }

    /// Issue 43, session 28: the index's candidates are the exact nearest
    /// frames — every frame's `neighbours` nearest overall, and the
    /// per-sequence nearest from the one index's pool (or from one tree per
    /// sequence) — as a brute-force scan finds them, on generated
    /// descriptors: random, shuffled, with duplicated frames (exact ties),
    /// one-frame sequences, one sequence only; the pool's candidates are
    /// the per-sequence trees' ones when the pool holds every frame, a
    /// subset of them otherwise, and never more than `pool` per frame.
    /// Session 29, the cover rule: a sequence pair the pool links fewer
    /// than `cover` times takes the trees' candidates, so that every
    /// sequence pair the trees link is linked — also the far motion's
    /// (frames moved away: nobody's nearest), which the pool alone loses.
    #[test]
    fn the_index_candidates_are_the_exact_nearest_frames() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        let dims = 4;
        // A wandering path (frames near their neighbours, as motion is).
        let mut f: Vec<f32> = Vec::new();
        let mut p = [0.0f32; 4];
        for _ in 0..260 {
            p.iter_mut().for_each(|v| *v += 0.3 * rnd());
            f.extend_from_slice(&p);
        }
        // Frames 200.. repeat frames 20..80 exactly (ties at every distance).
        f.copy_within(20 * dims..80 * dims, 200 * dims);
        let mut shuffled = f.clone();
        let n = f.len() / dims;
        let mut perm: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            let j = ((rnd() + 0.5) * (i + 1) as f32) as usize % (i + 1);
            perm.swap(i, j);
        }
        for (to, &from) in perm.iter().enumerate() {
            shuffled[to * dims..(to + 1) * dims]
                .copy_from_slice(&f[from * dims..(from + 1) * dims]);
        }
        // The last 60 frames moved far away: a motion whose frames are
        // nobody's nearest (as a mirrored piece is), nearest to its own.
        let mut far = f.clone();
        far[200 * dims..]
            .iter_mut()
            .step_by(dims)
            .for_each(|v| *v += 40.0);
        let cases: [(&[f32], Vec<usize>); 7] = [
            (f.as_slice(), vec![60, 100, 40, 60]),
            (shuffled.as_slice(), vec![60, 100, 40, 60]),
            (f.as_slice(), vec![1, 80, 1, 1, 120, 56, 1]),
            (f.as_slice(), vec![260]),
            (shuffled.as_slice(), vec![13, 1, 246]),
            (far.as_slice(), vec![70, 70, 60, 60]),
            (far.as_slice(), vec![1, 99, 100, 1, 59]),
        ];
        for (k, (feat, lens)) in cases.iter().enumerate() {
            let sp = spans(lens);
            for (neighbours, per_sequence, pool, stride, cover) in [
                (6, 3, 0, 4, 0),
                (6, 3, 16, 4, 0),
                (6, 3, 16, 4, 1),
                (6, 3, 16, 4, 6),
                (24, 2, 40, 3, 0),
                (24, 2, 40, 3, 2),
                (5, 1, 1, 1, 0),
                (5, 1, 1, 1, 1),
                (3, 4, 500, 2, 0),
                (3, 4, 500, 2, 3),
                (0, 3, 8, 5, 1),
                (6, 3, 16, 4, 100_000),
            ] {
                let o = CandidateOptions {
                    neighbours,
                    per_sequence,
                    pool,
                    stride,
                    cover,
                    min_gap: 10,
                    reach: 0,
                };
                let what = format!("case {k}, {neighbours}/{per_sequence}/{pool}/{stride}/{cover}");
                let got = index_candidates(feat, dims, &sp, &o);
                let want = brute_candidates(feat, dims, &sp, &o);
                assert_eq!(got.near, want.near, "{what}");
                let sorted = |mut v: Vec<(usize, u32)>| {
                    v.sort_unstable();
                    v
                };
                let per = sorted(got.per_sequence.clone());
                assert_eq!(per, sorted(want.per_sequence), "{what}");
                assert!(per.windows(2).all(|w| w[0] != w[1]), "{what}");
                if pool > 0 {
                    let trees = CandidateOptions { pool: 0, ..o };
                    let every = sorted(index_candidates(feat, dims, &sp, &trees).per_sequence);
                    assert!(per.iter().all(|c| every.binary_search(c).is_ok()), "{what}");
                    if pool >= n || cover >= n * n {
                        assert_eq!(per, every, "{what}");
                    }
                    if cover == 0 {
                        assert!(per.len() <= n.div_ceil(stride) * pool, "{what}");
                    } else {
                        // Every sequence pair the trees link, the cover
                        // rule links.
                        let linked = |v: &[(usize, u32)]| linked_pairs(v, &sp);
                        assert_eq!(linked(&per), linked(&every), "{what}");
                    }
                }
            }
        }
        // Against the pool alone: the far motion loses sequence pairs.
        let sp = spans(&[70, 70, 60, 60]);
        let o = CandidateOptions {
            neighbours: 6,
            per_sequence: 3,
            pool: 16,
            stride: 4,
            cover: 0,
            min_gap: 10,
            reach: 0,
        };
        let pooled = index_candidates(&far, dims, &sp, &o).per_sequence;
        let trees = index_candidates(&far, dims, &sp, &CandidateOptions { pool: 0, ..o });
        assert!(linked_pairs(&pooled, &sp).len() < linked_pairs(&trees.per_sequence, &sp).len());
    }

    /// The unordered sequence pairs that candidates `v` link.
    fn linked_pairs(v: &[(usize, u32)], sp: &[Span]) -> std::collections::BTreeSet<(u32, u32)> {
        let seq = sequence_of(sp, sp.iter().map(|s| s.start + s.len).sum());
        v.iter()
            .map(|&(a, b)| {
                let (i, j) = (seq[a], seq[b as usize]);
                (i.min(j), i.max(j))
            })
            .collect()
    }
}
