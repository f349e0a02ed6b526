//! Batch conversion of mocap libraries: every BVH/AMC clip under a folder,
//! one output per clip in a mirrored tree, in parallel across clips,
//! resumable, one bad clip never stopping the rest.
//!
//! Pipeline order: [`clips`] (find, shard, plan the outputs, refusing or
//! renaming collisions) → [`lock`] (one run per output folder, leftovers of
//! killed runs removed) → [`runner`] (parallel, resume, per-clip outcome) →
//! [`summary`] (JSON after each clip, HTML, SVG; earlier runs' records
//! kept). A sharded batch takes its shard from the scheduler
//! ([`schedule`]: Slurm arrays, Kubernetes Indexed Jobs) and [`merge`]
//! combines the shards' reports.

pub mod clips;
pub mod lock;
pub mod merge;
pub mod runner;
pub mod schedule;
pub mod summary;

pub use clips::{
    CollisionError, Format, Planned, Shard, clip_hash, find_clips, output_path, plan, shard_of,
};
pub use lock::{FolderLock, LockError, clean_temporaries, lock_folder};
pub use merge::{MergeError, ShardReport, find_reports, merge, read_report};
pub use runner::{
    ClipOutcome, ClipStatus, ClipWarning, Converted, Converter, Preparation, RunOptions, run,
};
#[allow(deprecated)]
pub use summary::Summary;
pub use summary::{BatchSummary, Earlier, report_stem, write_json, write_summary};
