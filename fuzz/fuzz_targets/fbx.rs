//! Fuzz target: the FBX reader (ufbx behind the magic-byte check) must never
//! panic or abort, and never allocate beyond its memory limit. Sampled at
//! 1 fps so a corrupt take length does not make one input run for hours.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;
use surfmotion::mocap::fbx::{FbxOptions, parse_fbx};

fuzz_target!(|data: &[u8]| {
    let opts = FbxOptions {
        fps: Some(1.0),
        take: None,
    };
    let _ = parse_fbx(data, Path::new("fuzz.fbx"), &opts);
});
