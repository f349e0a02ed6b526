//! The Surface Motion Graph (Huang et al. 2015, Secs. 4.2–4.3): transitions
//! found by adaptive temporal filtering of the similarity matrix
//! ([`transitions`]), and the graph of sequences and transitions with its
//! frame-level adjacency ([`smg`]), over database frames named by
//! [`FlatFrame`] (flat) or [`FrameId`] (sequence and frame) ([`frame`]).

pub mod compare;
pub mod frame;
pub mod parts;
pub mod plot;
pub(crate) mod smg;
/// The transition search (Eqs. 2–5) lives with the similarity it reads
/// (`similarity/transitions.rs`: the sparse similarity searches per sequence
/// pair with it, and the graph imports the similarity, not the reverse).
pub use crate::similarity::transitions;

pub use frame::{FlatFrame, FrameId};
pub use parts::{GraphParts, SequenceEdge};
pub use smg::{FrameAdjacency, GraphEdits, SurfaceMotionGraph};
pub use transitions::{Transition, TransitionOptions};
