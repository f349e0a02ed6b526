//! The all-frames × all-frames dissimilarity matrix, computed in parallel.
//!
//! Only the upper triangle and the diagonal are evaluated (`n (n + 1) / 2`
//! pairs) and mirrored.
//! Rows are processed in blocks of [`ROW_BLOCK`] frames so that each column
//! frame's descriptor is read once per block and reused from cache for the
//! block's rows; rayon steals blocks, which balances the shrinking rows.
//! Memory: the per-frame descriptors (not pairs of them) plus the `n²` f32
//! matrix itself (400 MB at 10,000 frames).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Rows per parallel task.
pub(crate) const ROW_BLOCK: usize = 8;

/// Frames with a pairwise dissimilarity.
pub trait PairDistance: Sync {
    /// Number of frames.
    fn frames(&self) -> usize;
    /// Dissimilarity of frames `a` and `b` (≥ 0, 0 for `a == b`).
    fn distance(&self, a: usize, b: usize) -> f64;
}

/// A named run of consecutive frames in the matrix.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Span {
    /// Sequence name.
    pub name: String,
    /// First frame's row.
    pub start: usize,
    /// Number of frames.
    pub len: usize,
}

/// A symmetric dissimilarity matrix over all frames of a database, f32,
/// row-major, with the sequences' spans.
#[derive(Debug, Clone, PartialEq)]
pub struct SimilarityMatrix {
    /// The sequences, in row order.
    pub spans: Vec<Span>,
    n: usize,
    data: Vec<f32>,
}

impl SimilarityMatrix {
    /// Wraps `data` (`n × n`, row-major). `None` if the sizes disagree.
    pub fn new(spans: Vec<Span>, data: Vec<f32>) -> Option<SimilarityMatrix> {
        let n: usize = spans.iter().map(|s| s.len).sum();
        let mut at = 0;
        for s in &spans {
            if s.start != at {
                return None;
            }
            at += s.len;
        }
        (data.len() == n * n).then_some(SimilarityMatrix { spans, n, data })
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.n
    }
    /// True for an empty database.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }
    /// Dissimilarity of frames `a` and `b` (global rows).
    pub fn get(&self, a: usize, b: usize) -> f32 {
        self.data[a * self.n + b]
    }
    /// Row `a`.
    pub fn row(&self, a: usize) -> &[f32] {
        &self.data[a * self.n..(a + 1) * self.n]
    }
    /// All values, row-major.
    pub fn data(&self) -> &[f32] {
        &self.data
    }
    /// Dissimilarity of frame `r` of sequence `i` and frame `s` of sequence `j`.
    pub fn between(&self, i: usize, r: usize, j: usize, s: usize) -> f32 {
        self.get(self.spans[i].start + r, self.spans[j].start + s)
    }
}

/// What the transition search and the graph read from a similarity,
/// dense ([`SimilarityMatrix`]) or sparse
/// ([`super::sparse::SparseSimilarity`]).
pub trait Dissimilarity: Sync {
    /// The sequences, in row order.
    fn spans(&self) -> &[Span];
    /// The stored dissimilarity of frames `a` and `b` (global rows),
    /// `f32::INFINITY` when the pair is not stored.
    fn value(&self, a: usize, b: usize) -> f32;
    /// The stored pairs of sequences `i` (rows) and `j` (columns) as frame
    /// numbers within each, rows then columns ascending; `None` when every
    /// pair is stored.
    fn cells(&self, _i: usize, _j: usize) -> Option<Vec<(usize, usize)>> {
        None
    }
    /// Number of frames.
    fn frame_count(&self) -> usize {
        self.spans().iter().map(|s| s.len).sum()
    }
}

impl Dissimilarity for SimilarityMatrix {
    fn spans(&self) -> &[Span] {
        &self.spans
    }
    fn value(&self, a: usize, b: usize) -> f32 {
        self.get(a, b)
    }
}

/// Evaluates every pair of `set` in parallel; `progress` is called with the
/// number of rows finished by each block.
pub fn all_pairs(set: &dyn PairDistance, progress: &(dyn Fn(u64) + Sync)) -> Vec<f32> {
    let n = set.frames();
    let mut data = vec![0.0f32; n * n];
    upper_rows(set, 0, &mut data, &|rows, _| progress(rows));
    mirror_upper(&mut data, n);
    data
}

/// Evaluates the upper triangle (diagonal included) of the rows `first..`
/// that `rows` holds (`rows.len() / n` whole rows of `n = set.frames()`
/// values, row-major; `first` a multiple of [`ROW_BLOCK`]), in parallel
/// blocks of [`ROW_BLOCK`] rows; values left of the diagonal are not
/// touched. `progress` hears the rows of each finished block. The values
/// are those [`all_pairs`] computes, whichever rows a call covers, so a
/// matrix may be computed a slice of rows at a time (`db build` resuming
/// after a kill).
pub fn upper_rows(
    set: &dyn PairDistance,
    first: usize,
    rows: &mut [f32],
    progress: &(dyn Fn(u64, u64) + Sync),
) {
    let n = set.frames();
    rows.par_chunks_mut((ROW_BLOCK * n).max(1))
        .enumerate()
        .for_each(|(blk, rows)| {
            let a0 = first + blk * ROW_BLOCK;
            let na = rows.len() / n.max(1);
            for b in a0..n {
                for i in 0..na {
                    let a = a0 + i;
                    if a <= b {
                        rows[i * n + b] = set.distance(a, b) as f32;
                    }
                }
            }
            let pairs: usize = (a0..a0 + na).map(|a| n - a).sum();
            progress(na as u64, pairs as u64);
        });
}

/// Copies the upper triangle of the `n × n` row-major `data` onto the lower.
pub fn mirror_upper(data: &mut [f32], n: usize) {
    for a in 0..n {
        for b in a + 1..n {
            data[b * n + a] = data[a * n + b];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    struct Line(Vec<f64>);
    impl PairDistance for Line {
        fn frames(&self) -> usize {
            self.0.len()
        }
        fn distance(&self, a: usize, b: usize) -> f64 {
            (self.0[a] - self.0[b]).abs()
        }
    }

    #[test]
    fn all_pairs_fills_a_symmetric_matrix() {
        let set = Line((0..29).map(|i| (i as f64 * 0.7).sin()).collect());
        let rows = AtomicU64::new(0);
        let d = all_pairs(&set, &|k| {
            rows.fetch_add(k, Ordering::Relaxed);
        });
        assert_eq!(rows.into_inner(), 29);
        let m = SimilarityMatrix::new(
            vec![
                Span {
                    name: "a".into(),
                    start: 0,
                    len: 20,
                },
                Span {
                    name: "b".into(),
                    start: 20,
                    len: 9,
                },
            ],
            d,
        )
        .unwrap();
        for a in 0..29 {
            assert_eq!(m.get(a, a), 0.0);
            for b in 0..29 {
                assert_eq!(m.get(a, b), m.get(b, a));
                assert_eq!(m.get(a, b), set.distance(a, b) as f32);
            }
        }
        assert_eq!(m.between(1, 2, 0, 3), m.get(22, 3));
    }

    #[test]
    fn rows_computed_in_slices_equal_all_pairs() {
        let set = Line((0..45).map(|i| (i as f64 * 0.3).cos()).collect());
        let n = 45;
        let whole = all_pairs(&set, &|_| {});
        let mut data = vec![0.0f32; n * n];
        for first in (0..n).step_by(2 * ROW_BLOCK) {
            let end = (first + 2 * ROW_BLOCK).min(n);
            upper_rows(&set, first, &mut data[first * n..end * n], &|_, _| {});
        }
        mirror_upper(&mut data, n);
        assert_eq!(data, whole);
    }
}
