//! Fuzz target: landmark and part-label JSON must never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let t = String::from_utf8_lossy(data);
    let _ = surfmotion::embed::landmarks::Landmarks::parse(&t, Path::new("f.json"), 1000);
    let tris = [[0u32, 1, 2], [0, 2, 3]];
    let _ = surfmotion::embed::parse_parts(&t, Path::new("p.json"), &tris, 4);
});
