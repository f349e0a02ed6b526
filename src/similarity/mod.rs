//! Frame-to-frame dissimilarity over a whole database (Huang et al. 2015,
//! Sec. 4.1): volumetric shape histograms minimised over rotation about the
//! vertical ([`histogram`] on [`voxel`] occupancy), vertex distance with a
//! velocity term ([`vertex`]), and skeletal distance (Eq. 28,
//! [`crate::pose::measure::skeleton_distance`]); per-frame descriptors
//! ([`sets`]) compared all-pairs in parallel ([`matrix`]), or on the candidate pairs
//! of a nearest-neighbour index and of each sequence pair's best cheap
//! transitions only for large databases ([`sparse`], [`kdtree`],
//! [`pair_scan`]), the sequence pairs scanned chosen from an estimate
//! ([`scan`]); [`lookup`] reads either. Retrieval's nearest skeletons come
//! from an exact index over floor-invariant skeleton features
//! ([`skeleton_index`]).

pub mod candidates;
pub(crate) mod closure;
pub mod colour;
pub mod histogram;
pub mod kdtree;
pub mod lookup;
pub mod matrix;
pub mod pair_scan;
pub mod scan;
pub mod sets;
pub mod skeleton_index;
pub mod sparse;
#[cfg(test)]
pub(crate) mod test_rng;
pub mod tiled;
pub mod transitions;
pub mod vertex;
pub mod voxel;

pub use lookup::Similarity;
pub use matrix::{
    Dissimilarity, PairDistance, SimilarityMatrix, Span, all_pairs, mirror_upper, upper_rows,
};
pub use sets::{ColourSet, Measure, ShapeSet, SkeletonSet, VertexSet, y_up};
pub use sparse::{SparseOptions, SparseSimilarity};
