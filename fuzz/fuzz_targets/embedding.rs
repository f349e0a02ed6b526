//! Fuzz target: a rig embedding file (`rig embed -o`, `DIR/skeletons/rig.json`)
//! must never panic; one it accepts has every index in range.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let t = String::from_utf8_lossy(data);
    if let Ok(e) = surfmotion::embed::Embedding::parse(&t, Path::new("rig.json"), 4) {
        assert_eq!(e.labels().len(), 4);
    }
});
