//! Fuzz target: the pc2 reader must never panic and never allocate beyond its input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let _ = surfmotion::mesh::io::pc2::parse_pc2(data, Path::new("fuzz.pc2"));
});
