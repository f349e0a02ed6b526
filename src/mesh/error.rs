use crate::util::fsutil::{FileError, FsError};
use std::path::{Path, PathBuf};

/// Errors of mesh construction, readers and writers: the shared file-error
/// shape ([`FileError`]: the file could not be read, an error at a line of a
/// text file, a problem with a file as a whole or at a byte offset of a
/// binary file), or a mesh that breaks an invariant.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A file could not be read or written, or holds something wrong.
    #[error(transparent)]
    File(#[from] FileError),
    /// A mesh that breaks an invariant (index out of range, non-finite value).
    #[error("{0}")]
    Topology(#[from] TopologyError),
    /// A glTF buffer URI the reader does not follow: absolute, with a
    /// scheme other than `data:`, or climbing more than one folder above
    /// the glTF's (the rule: `mesh::io::gltf`, README "Mesh formats").
    #[error("{}: buffer {buffer}: URI '{uri}' {why}", gltf.display())]
    BufferUri {
        /// The glTF file.
        gltf: PathBuf,
        /// The buffer's index.
        buffer: usize,
        /// The URI as written in the file.
        uri: String,
        /// Why it is not followed.
        why: String,
    },
}

impl From<FsError> for MeshError {
    fn from(e: FsError) -> Self {
        MeshError::File(FileError::Io(e))
    }
}

impl MeshError {
    pub(crate) fn parse(path: &Path, line: usize, msg: impl Into<String>) -> Self {
        MeshError::File(FileError::parse(path, line, msg))
    }
    pub(crate) fn invalid(path: &Path, msg: impl Into<String>) -> Self {
        MeshError::File(FileError::invalid(path, msg))
    }
    /// Attaches a file name to a topology error.
    pub(crate) fn in_file(self, path: &Path) -> Self {
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
