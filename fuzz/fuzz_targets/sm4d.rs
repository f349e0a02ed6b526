//! Fuzz target: the `.sm4d` compact 4D geometry reader must never panic and
//! never allocate beyond what its input can hold; a file it accepts must
//! re-encode.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(d) = surfmotion::web::codec::decode(data) {
        // Every accepted file is internally consistent.
        assert!(d.triangles.iter().flatten().all(|&v| (v as usize) < d.vertices));
        for s in &d.sequences {
            assert_eq!(s.len() % d.vertices, 0);
        }
    }
});
