//! glTF 2.0 reader (`.gltf` with external or data-URI buffers, `.glb`):
//! triangle primitives of every mesh node merged into one [`Mesh`] (node
//! transforms applied, except to skinned meshes, which stay in bind space),
//! vertex colours and normals, the first skin (joints, parents, inverse bind
//! matrices, per-vertex joints and weights), morph targets (POSITION and
//! NORMAL displacements, through the node transform like the base), and a
//! morph-weights animation sampled at its key times as a mesh sequence.
//! Quantised attributes (`KHR_mesh_quantization`: integer and normalized
//! integer component types, dequantised by the node transform) are read;
//! the `gltf` crate's validation, which refuses that required extension,
//! runs with it taken out of `extensionsRequired`.
//!
//! Accessors are read by our own bounds-checked code rather than
//! `gltf::Reader`, so a malformed file gives an error, never a panic.

mod animation;
mod asset;
mod buffers;
pub mod clip;
mod geometry;
mod read;
mod skin;
mod validate;

pub use asset::{GltfAsset, KeyWeights, NodeAnimation, NodeChannel, NodeGraph, Skin, TrsPath};
pub use read::{parse_gltf, read_gltf};
