//! Frame-to-frame dissimilarity over a whole database (Huang et al. 2015,
//! Sec. 4.1): volumetric shape histograms minimised over rotation about the
//! vertical ([`histogram`] on [`voxel`] occupancy), vertex distance with a
//! velocity term ([`vertex`]), and skeletal distance (Eq. 28,
//! [`crate::pose::measure::skeleton_distance`]); per-frame descriptors
//! ([`sets`]) compared all-pairs in parallel ([`matrix`]).

pub mod colour;
pub mod histogram;
pub mod matrix;
pub mod sets;
pub mod vertex;
pub mod voxel;

pub use matrix::{PairDistance, SimilarityMatrix, Span, all_pairs, mirror_upper, upper_rows};
pub use sets::{ColourSet, Measure, ShapeSet, SkeletonSet, VertexSet, y_up};
