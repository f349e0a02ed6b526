use std::path::PathBuf;

/// Errors of mesh construction, readers and writers.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be read or written.
    #[error(transparent)]
    Io(#[from] crate::fsutil::FsError),
    /// A syntax or value error at a line of a text file.
    #[error("{path}:{line}: {msg}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// A problem with a file as a whole, or at a byte offset of a binary file.
    #[error("{path}: {msg}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        msg: String,
    },
    /// A mesh that breaks an invariant (index out of range, non-finite value).
    #[error("{0}")]
    Topology(#[from] TopologyError),
}

impl MeshError {
    pub(crate) fn parse(path: &std::path::Path, line: usize, msg: impl Into<String>) -> Self {
        MeshError::Parse {
            path: path.to_path_buf(),
            line,
            msg: msg.into(),
        }
    }
    pub(crate) fn invalid(path: &std::path::Path, msg: impl Into<String>) -> Self {
        MeshError::Invalid {
            path: path.to_path_buf(),
            msg: msg.into(),
        }
    }
    /// Attaches a file name to a topology error.
    pub(crate) fn in_file(self, path: &std::path::Path) -> Self {
        match self {
            MeshError::Topology(t) => MeshError::invalid(path, t.to_string()),
            e => e,
        }
    }
}

/// A broken mesh invariant, with the index concerned.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TopologyError {
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {vertex}, but there are {vertices} vertices")]
    IndexOutOfRange {
        /// Triangle index.
        triangle: usize,
        /// The bad vertex index.
        vertex: u32,
        /// Vertex count.
        vertices: usize,
    },
    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinite {
        /// Vertex index (in the frame, for sequences).
        vertex: usize,
    },
    /// A frame of a sequence has another vertex count.
    #[error("frame {frame} has {got} vertices, the topology has {expected}")]
    FrameSize {
        /// Frame index.
        frame: usize,
        /// Its vertex count.
        got: usize,
        /// The topology's.
        expected: usize,
    },
    /// More vertices or triangles than `u32` indices can address.
    #[error("too many elements for u32 indices")]
    TooLarge,
}
