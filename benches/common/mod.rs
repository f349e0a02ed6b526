//! Shared by the benchmarks: where the real data is, and the samba capture.
#![allow(dead_code)]

use std::path::PathBuf;
use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::{LoadOptions, load_sequence};

/// `$SURFMOTION_DATA` or `../shared/data`; `None` (with a message) when absent.
pub fn data() -> Option<PathBuf> {
    let p = std::env::var_os("SURFMOTION_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    if p.exists() {
        Some(p)
    } else {
        eprintln!("benchmark skipped: no data at {}", p.display());
        None
    }
}

/// The 175-frame samba capture.
pub fn samba(d: &std::path::Path) -> MeshSequence {
    load_sequence(
        d.join("4d/samba/samba.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap()
}

/// The samba landmark fixture.
pub fn samba_landmarks() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json")
}
