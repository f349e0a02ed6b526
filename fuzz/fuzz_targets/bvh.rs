//! Fuzz target: the bvh reader must never panic and never allocate beyond its input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    // As files are read: byte-order marks, UTF-16 and lone CRs decoded.
    let t = surfmotion::util::fsutil::decode_text(data.to_vec());
    let _ = surfmotion::mocap::bvh::parse_bvh(&t, Path::new("fuzz.bvh"), &Default::default());
});
