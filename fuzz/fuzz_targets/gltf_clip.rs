//! Fuzz target: the glTF clip reader (a skin and one animation read as a
//! mocap clip, `mesh::io::gltf::clip`) must never panic, nor allocate beyond the
//! clip's sample limit. Sampled at 1 fps so a corrupt key time does not
//! make one input run for hours.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;
use surfmotion::mesh::io::gltf::clip::{GltfClipOptions, parse_gltf_clip};

fuzz_target!(|data: &[u8]| {
    let opts = GltfClipOptions {
        fps: Some(1.0),
        take: None,
    };
    let _ = parse_gltf_clip(data, Path::new("fuzz.glb"), &opts);
});
