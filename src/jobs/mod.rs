//! The jobs a library user runs, one call each (issue 19): each takes an
//! options struct with documented defaults and returns a typed,
//! `Serialize` report. The CLI is these calls plus argument parsing and
//! printing; `examples/` show each in a few lines.
//!
//! In pipeline order:
//!
//! 1. [`db_init`]: write a character database's manifest from its files;
//!    [`database`]: build a character database's Surface Motion Graph
//!    (Huang et al. 2015, Sec. 4) and load it for synthesis.
//! 2. [`skeletons`]: export every frame's skeleton of a database (JSON and
//!    BVH); the one skeleton JSON schema ([`skeletons::SkeletonFile`]).
//! 3. [`synth_db`]: write a synthetic database (a rest mesh driven by
//!    clips: skinning plus secondary dynamics).
//! 4. [`retarget`]: retarget a clip through a database (Sec. 5.2).
//! 5. [`transfer`]: transfer clips onto a scan, prepared and factored once
//!    (de Aguiar et al. 2007); [`transfer_files`]: one transfer written
//!    to files (the `transfer` verb).
//! 6. [`batch`]: convert a folder of clips with any [`Converter`]
//!    (implemented by the retarget and transfer jobs; [`batch_target`]
//!    loads or factors one).
//!
//! [`web`] exports a database or a result as a static site and prepares
//! serving one.
//!
//! [`eval`] scores a result against its clip and database (the `eval`
//! verb). [`text`] and [`short_text`] are the jobs' reports as text.
//!
//! [`outputs`] is the output policy every job checks before any work
//! ([`format_options`]: writer options of one format only);
//! [`output_set::OutputSet`] holds a job's labelled outputs and inputs and
//! checks them in its order. [`db_info::verdict`] is `db info`'s.
//!
//! JSON reports are meant to be printed through `serde_json::Value`
//! (`serde_json::to_value`), whose objects keep their keys sorted, as the
//! CLI always has.

pub mod batch;
pub mod batch_target;
pub mod batch_verdict;
pub mod blend;
pub mod database;
pub mod db_info;
pub mod db_init;
pub mod demo;
mod error;
pub mod eval;
pub mod format_options;
pub mod keyframe;
pub mod live;
pub mod live_checks;
pub mod mesh;
pub mod mocap;
pub mod output_set;
pub mod outputs;
pub mod pick;
pub mod play;
mod positions;
pub mod render;
pub mod repair;
pub mod retarget;
pub mod rig;
mod rig_summary;
pub mod setup_text;
pub mod short_text;
pub mod skeletons;
pub mod spool;
pub mod synth;
pub mod synth_db;
pub mod text;
pub mod transfer;
pub mod transfer_files;
mod transfer_summary;
pub mod web;

pub use crate::batch::Converter;
pub use batch::{BatchEvent, BatchOptions, BatchReport, batch_folder};
pub use database::{build_database, load_database};
pub use db_init::{InitReport, init_database, init_database_with};
pub use error::JobError;
pub(crate) use positions::write_positions;
pub use retarget::{RetargetJob, RetargetJobOptions, RetargetRun, RetargetSummary, StreamedRun};
pub use skeletons::{SkeletonFile, SkeletonsReport, export_skeletons};
pub use synth_db::{
    SynthCharacter, SynthClip, SynthOptions, SynthReport, write_synthetic_database,
};
pub use transfer::{
    FrameProgress, ScanTransferJob, ScanTransferOptions, TransferOutcome, TransferReport,
    TransferSource, TransferSpec, TruthError, transfer_onto_scan, transfer_onto_scan_to,
};
