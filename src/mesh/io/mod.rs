//! Mesh and mesh-sequence file formats. In: OBJ, PLY, PC2, MDD, OBJ folders,
//! glTF/GLB. Out: GLB (morph-target animation), PC2 + OBJ, MDD + OBJ, OBJ,
//! OBJ folders, PLY, USD text (`.usda`, time-sampled points). Every write is atomic. [`stream::SequenceWriter`]
//! writes a sequence frame by frame (point caches and OBJ folders without
//! holding the frames).

pub mod fbx;
pub mod files;
pub mod format;
mod frame_check;
pub mod glb;
pub mod gltf;
pub mod load;
pub mod mdd;
pub mod obj;
pub mod objseq;
pub mod pc2;
pub mod ply;
pub mod save;
pub mod stream;
pub mod usd;

pub use files::{input_files, output_files, refuse_folder_as_file, refuse_overwriting};
pub use format::{MAX_ABS_COORDINATE, MeshFormat, bad_frame_ref, split_frame_ref};
pub use load::{LoadOptions, load_sequence, read_rigged};
pub use save::{SaveOptions, save_sequence, save_sequence_with};
