//! Fuzz target: the gltf reader must never panic and never allocate beyond its input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = surfmotion::mesh::io::gltf::parse_gltf(data, Path::new("fuzz.glb"));
});
