//! Triangle meshes, mesh sequences and their file formats.

mod error;
pub mod io;
#[allow(clippy::module_inception)]
mod mesh;
mod sequence;

pub use error::{MeshError, TopologyError};
pub use mesh::{Bounds, Group, Mesh};
pub use sequence::MeshSequence;
