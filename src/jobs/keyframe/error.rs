//! What can go wrong in a key-frame job.

/// An error of a key-frame job; each variant keeps the module error (and
/// with it the file, key-frame or value at fault). Messages name the
/// options of [`super::KeyframeJobOptions`] and the job's inputs
/// (`distances`, `times`, `distance`, `time`), never a command-line flag.
#[derive(Debug, thiserror::Error)]
pub enum KeyframeJobError {
    /// The database could not be read or built.
    #[error(transparent)]
    Db(#[from] crate::db::DbError),
    /// A key-frame, a target or the search.
    #[error(transparent)]
    Keyframe(#[from] crate::keyframe::KeyframeError),
    /// A key-frame pose could not be read.
    #[error(transparent)]
    Pose(#[from] crate::keyframe::pose::PoseError),
    /// A key-frame pose that is not a body's joints in metres.
    #[error("key-frame '{key}': {msg}")]
    BadPose {
        /// As written.
        key: String,
        /// What is wrong with it.
        msg: String,
    },
    /// A grid too large to run.
    #[error("distances × times: {0}")]
    Grid(#[from] crate::keyframe::error::GridError),
    /// A target above the search's bound.
    #[error("{option} {value}: at most {max} {unit} (the search's horizon grows with the target)")]
    TooLarge {
        /// The option (`distances`, `times`).
        option: &'static str,
        /// The value, as it is printed (`1e308` in exponent form).
        value: String,
        /// The largest accepted.
        max: f64,
        /// Its unit.
        unit: &'static str,
    },
    /// The output could not be created for the path found: the error, and
    /// the search bounds the path hit (why it is that long).
    #[error("{source} (the path found has {frames} frames; search bound: {bounds})")]
    Bounded {
        /// The writer's error.
        #[source]
        source: crate::mesh::MeshError,
        /// Frames of the path.
        frames: usize,
        /// The bounds hit, `; `-separated.
        bounds: String,
    },
    /// A mesh could not be written.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// A file could not be written.
    #[error(transparent)]
    Fs(#[from] crate::util::fsutil::FsError),
    /// A report could not be serialised.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
}
