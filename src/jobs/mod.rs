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
//!    (de Aguiar et al. 2007).
//! 6. [`batch`]: convert a folder of clips with any [`Converter`]
//!    (implemented by the retarget and transfer jobs).
//!
//! [`outputs`] is the output policy every job checks before any work.
//!
//! JSON reports are meant to be printed through `serde_json::Value`
//! (`serde_json::to_value`), whose objects keep their keys sorted, as the
//! CLI always has.

pub mod batch;
pub mod blend;
pub mod database;
pub mod db_init;
pub mod demo;
pub mod keyframe;
pub mod live;
pub mod mesh;
pub mod mocap;
pub mod outputs;
pub mod pick;
pub mod play;
pub mod render;
pub mod retarget;
pub mod rig;
pub mod skeletons;
pub mod synth;
pub mod synth_db;
pub mod text;
pub mod transfer;

pub use crate::batch::Converter;
pub use batch::{BatchEvent, BatchOptions, BatchReport, batch_folder};
pub use database::{build_database, load_database};
pub use db_init::{InitReport, init_database, init_database_with};
pub use retarget::{RetargetJob, RetargetJobOptions, RetargetRun, RetargetSummary, StreamedRun};
pub use skeletons::{SkeletonFile, SkeletonsReport, export_skeletons};
pub use synth_db::{
    SynthCharacter, SynthClip, SynthOptions, SynthReport, write_synthetic_database,
};
pub use transfer::{
    FrameProgress, ScanTransferJob, ScanTransferOptions, TransferOutcome, TransferReport,
    TransferSource, TransferSpec, TruthError, transfer_onto_scan, transfer_onto_scan_to,
};

use std::path::PathBuf;

/// What can go wrong in a job; each variant keeps the module error (and
/// with it the file, line or index at fault).
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// A database could not be read or built.
    #[error(transparent)]
    Db(#[from] crate::db::DbError),
    /// A mesh could not be read or written.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// Positions do not fit a mesh's topology.
    #[error(transparent)]
    Topology(#[from] crate::mesh::TopologyError),
    /// A clip could not be read.
    #[error(transparent)]
    Query(#[from] crate::drive::query::QueryError),
    /// A clip's canonical poses could not be made.
    #[error(transparent)]
    Rig(#[from] crate::rig::RigError),
    /// A mocap file could not be written.
    #[error(transparent)]
    Mocap(#[from] crate::mocap::MocapError),
    /// A mocap clip could not be built from poses.
    #[error(transparent)]
    Clip(#[from] crate::mocap::ClipError),
    /// Synthesis failed (a solver could not be factored).
    #[error(transparent)]
    Retarget(#[from] crate::drive::RetargetError),
    /// The rig could not be embedded.
    #[error(transparent)]
    Embed(#[from] crate::embed::EmbedError),
    /// The capture could not be rigged automatically.
    #[error(transparent)]
    AutoRig(#[from] crate::embed::auto::options::AutoError),
    /// A scan could not be prepared.
    #[error(transparent)]
    Scan(#[from] crate::transfer::ScanError),
    /// A transfer could not be set up.
    #[error(transparent)]
    Transfer(#[from] crate::transfer::JobError),
    /// A file could not be read or written.
    #[error(transparent)]
    Fs(#[from] crate::util::fsutil::FsError),
    /// The job would not fit in memory (checked before allocating).
    #[error(transparent)]
    Budget(#[from] crate::util::budget::OverBudget),
    /// A report could not be serialised.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// A marker file could not be read or written.
    #[error(transparent)]
    Markers(#[from] crate::transfer::MarkerError),
    /// A landmark file could not be read.
    #[error(transparent)]
    Landmarks(#[from] crate::embed::landmarks::LandmarkError),
    /// An output refused before any work.
    #[error(transparent)]
    Output(#[from] outputs::OutputError),
    /// A solver could not be factored.
    #[error(transparent)]
    Solve(#[from] crate::mesh::solver::SolveError),
    /// A contact sheet not drawn.
    #[error(transparent)]
    Preview(#[from] crate::tools::render::preview::PreviewError),
    /// A manifest not written.
    #[error(transparent)]
    Init(#[from] crate::db::init::InitError),
    /// Options that do not make a job (what to give instead).
    #[error("{0}")]
    Usage(String),
    /// An error with what the job was doing when it happened (the inputs
    /// involved).
    #[error("{what}")]
    Context {
        /// What was being done, naming its inputs.
        what: String,
        /// The error.
        #[source]
        source: Box<JobError>,
    },
    /// An input the job refuses, with the file it came from.
    #[error("{path}: {msg}")]
    Input {
        /// The file at fault.
        path: PathBuf,
        /// What is wrong with it.
        msg: String,
    },
}

/// Writes `positions` (frame-major, `mesh`'s vertices) as a sequence at
/// `fps` to `out` (by extension, GLB options `glb`); returns the files
/// written. The one path from a job's positions to a file (retarget,
/// transfer, scan transfer).
pub(crate) fn write_positions(
    mesh: crate::mesh::Mesh,
    positions: Vec<[f64; 3]>,
    fps: f64,
    glb: crate::mesh::io::glb::GlbOptions,
    out: &std::path::Path,
) -> Result<Vec<std::path::PathBuf>, JobError> {
    let seq = crate::mesh::MeshSequence::new(mesh, positions, Some(fps))?;
    Ok(crate::mesh::io::save_sequence_with(
        &seq,
        out,
        &crate::mesh::io::SaveOptions {
            fps: Some(fps),
            glb,
        },
    )?)
}
