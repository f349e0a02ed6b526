//! The errors of the parametric layer.

/// Errors of the parametric layer.
#[derive(Debug, thiserror::Error)]
pub enum ParamError {
    /// A `[[space]]` entry of the manifest cannot be built.
    #[error("{path}: space '{space}': {msg}")]
    Space {
        /// The manifest.
        path: std::path::PathBuf,
        /// The space's name.
        space: String,
        /// What is wrong.
        msg: String,
    },
    /// The database failed to load.
    #[error(transparent)]
    Db(#[from] crate::db::DbError),
    /// The blender could not be factored on the topology.
    #[error("the topology cannot be factored for blending: {0}")]
    Solve(#[from] crate::mesh::solver::SolveError),
    /// Writing the cache failed.
    #[error(transparent)]
    Io(#[from] crate::util::fsutil::FsError),
}
