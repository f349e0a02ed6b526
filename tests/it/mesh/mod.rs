//! Geometry kernels and mesh I/O.

mod glb_output;
mod io;
mod kernel_properties;
mod kernels;
