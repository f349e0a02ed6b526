//! Fuzz target: the ply reader must never panic and never allocate beyond its input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = surfmotion::mesh::io::ply::parse_ply(data, Path::new("fuzz.ply"));
});
