//! Fuzz target: the obj reader must never panic and never allocate beyond its input.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    // As files are read: byte-order marks, UTF-16 and lone CRs decoded.
    let t = surfmotion::util::fsutil::decode_text(data.to_vec());
    let _ = surfmotion::mesh::io::obj::parse_obj(&t, Path::new("fuzz.obj"));
});
