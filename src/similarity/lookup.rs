//! A database's similarity as `db build` made it: the dense matrix below
//! [`crate::db::build::SPARSE_FRAMES`] frames, the sparse one above
//! (issue 43), read through one interface by the graph, retrieval and the
//! key-frame search.

use super::matrix::{Dissimilarity, SimilarityMatrix, Span};
use super::sparse::SparseSimilarity;

/// Dense or sparse frame dissimilarities of a database.
#[derive(Debug, Clone, PartialEq)]
pub enum Similarity {
    /// Every pair ([`SimilarityMatrix`]).
    Dense(SimilarityMatrix),
    /// The pairs that can hold a transition ([`SparseSimilarity`]).
    Sparse(SparseSimilarity),
}

impl Similarity {
    /// The sequences, in row order.
    pub fn spans(&self) -> &[Span] {
        match self {
            Similarity::Dense(m) => &m.spans,
            Similarity::Sparse(s) => &s.spans,
        }
    }
    /// Number of frames.
    pub fn len(&self) -> usize {
        match self {
            Similarity::Dense(m) => m.len(),
            Similarity::Sparse(s) => s.len(),
        }
    }
    /// True for an empty database.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Dissimilarity of frames `a` and `b` (global rows); for a pair the
    /// sparse similarity does not store, its estimate
    /// ([`SparseSimilarity::get`]).
    pub fn get(&self, a: usize, b: usize) -> f32 {
        match self {
            Similarity::Dense(m) => m.get(a, b),
            Similarity::Sparse(s) => s.get(a, b),
        }
    }
    /// Dissimilarity of frame `r` of sequence `i` and frame `s` of
    /// sequence `j` ([`Similarity::get`]).
    pub fn between(&self, i: usize, r: usize, j: usize, s: usize) -> f32 {
        let sp = self.spans();
        self.get(sp[i].start + r, sp[j].start + s)
    }
    /// The dense matrix, if this is one.
    pub fn dense(&self) -> Option<&SimilarityMatrix> {
        match self {
            Similarity::Dense(m) => Some(m),
            Similarity::Sparse(_) => None,
        }
    }
    /// The method's name: `dense` or `sparse`.
    pub fn method(&self) -> &'static str {
        match self {
            Similarity::Dense(_) => "dense",
            Similarity::Sparse(_) => "sparse",
        }
    }
}

impl Dissimilarity for Similarity {
    fn spans(&self) -> &[Span] {
        Similarity::spans(self)
    }
    fn value(&self, a: usize, b: usize) -> f32 {
        match self {
            Similarity::Dense(m) => m.get(a, b),
            Similarity::Sparse(s) => s.value(a, b),
        }
    }
    fn cells(&self, i: usize, j: usize) -> Option<Vec<(usize, usize)>> {
        match self {
            Similarity::Dense(_) => None,
            Similarity::Sparse(s) => Some(s.block(i, j)),
        }
    }
}
