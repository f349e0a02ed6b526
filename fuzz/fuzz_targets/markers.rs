//! Fuzz target: Confluent marker files must never panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let t = String::from_utf8_lossy(data);
    let _ = surfmotion::transfer::MarkerFile::parse(&t, Path::new("m.json"), 1000);
});
