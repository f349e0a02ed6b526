//! Batch conversion of mocap libraries: every BVH/AMC clip under a folder,
//! one output per clip in a mirrored tree, in parallel across clips,
//! resumable, one bad clip never stopping the rest.
//!
//! Pipeline order: [`clips`] (find, shard, output paths) → [`runner`]
//! (parallel, resume, per-clip outcome) → [`summary`] (JSON, HTML, SVG).

pub mod clips;
pub mod runner;
pub mod summary;

pub use clips::{Format, Shard, find_clips, output_path};
pub use runner::{ClipOutcome, ClipStatus, Converted, RunOptions, run};
pub use summary::{Summary, write_summary};
