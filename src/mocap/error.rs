use std::path::PathBuf;

/// Errors of the mocap readers and writers. Every variant names the file and,
/// where there is one, the 1-based line the problem is on.
#[derive(Debug, thiserror::Error)]
pub enum MocapError {
    /// The file could not be read or written.
    #[error(transparent)]
    Io(#[from] crate::fsutil::FsError),
    /// A syntax or value error at a line of a text file.
    #[error("{path}:{line}: {msg}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// A problem with the file as a whole (no frames, missing ASF, ...).
    #[error("{path}: {msg}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        msg: String,
    },
}

impl MocapError {
    pub(crate) fn parse(path: &std::path::Path, line: usize, msg: impl Into<String>) -> Self {
        MocapError::Parse {
            path: path.to_path_buf(),
            line,
            msg: msg.into(),
        }
    }
    pub(crate) fn invalid(path: &std::path::Path, msg: impl Into<String>) -> Self {
        MocapError::Invalid {
            path: path.to_path_buf(),
            msg: msg.into(),
        }
    }
}
