//! Rig embedding: from a few landmarks on a character's rest frame to the
//! canonical joints inside it, bone-heat skin weights, contiguous body-part
//! labels with overlapping regions, and per-joint regressors that give the
//! skeleton of any frame of the character's sequences (Huang et al. 2015,
//! Sec. 3, skeleton extraction).

pub mod auto;
pub mod axes;
pub mod check;
pub mod contact;
mod embedding;
mod embedding_parts;
mod footless;
pub mod frames;
pub mod heat;
pub mod joints;
pub mod landmarks;
pub mod midplane;
pub mod motion_weights;
pub mod parts;
pub mod pose_order;
pub mod regress;
pub mod rest;
pub mod rigid;
pub mod rigidity;
pub mod scan_landmarks;
pub mod section;
pub mod skin;
mod stray;
pub(crate) mod stump;
pub mod surface;

pub use check::{EmbedCheck, check};
pub use embedding::{EmbedError, Embedding, bones, bones_of, check_body, parse_parts};
pub use embedding_parts::EmbeddingParts;
