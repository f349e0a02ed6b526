//! Fuzz target: the asf reader must never panic and never allocate beyond its input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let t = String::from_utf8_lossy(data);
    let _ = surfmotion::mocap::asfamc::parse_asf(&t, Path::new("fuzz.asf"));
});
