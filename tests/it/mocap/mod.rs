//! Mocap input: the readers against reference implementations, other suites' skeletons, the bundled clips.

mod cartwheel;
mod fbx_units;
mod gltf_clip;
mod one_capture;
mod procedural;
mod reference;
mod suites;
