//! The error of `inspect`.

use crate::mesh::MeshError;
use crate::mocap::MocapError;
use std::path::PathBuf;

/// Error of [`inspect`].
#[derive(Debug, thiserror::Error)]
pub enum InspectError {
    /// A mocap reader failed.
    #[error(transparent)]
    Mocap(#[from] MocapError),
    /// A mesh reader failed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A bad landmark or marker file.
    #[error("{0}")]
    Json(String),
    /// Not a format we read.
    #[error(
        "{0}: unknown file type (mocap: .bvh .amc .asf .fbx; meshes: .obj .ply .pc2 .mdd .gltf .glb or a folder of .obj; a database folder or its cache; the JSON files, manifests, caches, Graphviz graphs, pictures and web sites the tool writes)"
    )]
    Unknown(PathBuf),
    /// A mesh path that is not UTF-8: mesh paths are read as text
    /// (`SEQ.pc2:FRAME`), and a lossy copy named another file ("No such
    /// file or directory" for a file that is there).
    #[error("{}: a mesh file name that is not UTF-8 is not supported; rename it", .0.display())]
    NotUtf8(PathBuf),
}
