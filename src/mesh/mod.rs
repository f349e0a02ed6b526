//! Triangle meshes, mesh sequences and their file formats.

pub mod blend;
pub mod boundary;
pub mod components;
mod error;
pub mod frames;
pub mod harmonic;
pub mod io;
pub mod laplacian;
pub mod mass;
pub mod measure;
#[allow(clippy::module_inception)]
mod mesh;
pub mod normals;
pub mod poisson;
pub mod quality;
pub mod repair;
mod sequence;
pub mod solver;
pub mod stray;
pub mod subdivide;

pub use error::{MeshError, TopologyError};
pub use mesh::{Bounds, Group, Mesh};
pub use sequence::MeshSequence;
