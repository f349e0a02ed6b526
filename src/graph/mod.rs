//! The Surface Motion Graph (Huang et al. 2015, Secs. 4.2–4.3): transitions
//! found by adaptive temporal filtering of the similarity matrix
//! ([`transitions`]), and the graph of sequences and transitions with its
//! frame-level adjacency ([`smg`]).

pub mod compare;
pub mod plot;
pub mod smg;
pub mod transitions;

pub use smg::{FrameAdjacency, FrameId, GraphEdits, SequenceEdge, SurfaceMotionGraph};
pub use transitions::{Transition, TransitionOptions};
