//! The error every job returns: one variant per module error (which keeps
//! the file, line or index at fault), plus usage, context and input errors.

use super::outputs;
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
    Retarget(#[from] crate::drive::DriveError),
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
    Transfer(#[from] crate::transfer::SetupError),
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
