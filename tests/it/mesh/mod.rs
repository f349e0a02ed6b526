//! Geometry kernels and mesh I/O.

mod fbx_character;
mod glb_output;
mod io;
mod kernel_properties;
mod kernels;
mod usda_verbs;
