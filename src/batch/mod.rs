//! Batch conversion of mocap libraries: every BVH/AMC clip under a folder,
//! one output per clip in a mirrored tree, in parallel across clips,
//! resumable, one bad clip never stopping the rest.
//!
//! Pipeline order: [`clips`] (find, shard, plan the outputs, refusing or
//! renaming collisions) → [`lock`] (one run per output folder, leftovers of
//! killed runs removed) → [`runner`] (parallel, resume, per-clip outcome) →
//! [`summary`] (JSON after each clip, HTML, SVG; earlier runs' records
//! kept).

pub mod clips;
pub mod lock;
pub mod runner;
pub mod summary;

pub use clips::{CollisionError, Format, Planned, Shard, find_clips, output_path, plan};
pub use lock::{FolderLock, LockError, clean_temporaries, lock_folder};
pub use runner::{
    ClipOutcome, ClipStatus, ClipWarning, Converted, Converter, Preparation, RunOptions, run,
};
pub use summary::{Earlier, Summary, report_stem, write_json, write_summary};
