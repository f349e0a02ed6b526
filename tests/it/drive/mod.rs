//! Surface synthesis driven by mocap (Huang 5.2): retrieval, trellis, deformation, end to end.

mod procedural_pipeline;
mod synthesis;
