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

/// Criterion's median estimate (ns) of `group/bench` from its last run.
pub fn median_ns(group: &str, bench: &str) -> Option<f64> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("target/criterion")
        .join(group.replace('/', "_"))
        .join(bench)
        .join("new/estimates.json");
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(p).ok()?).ok()?;
    v["median"]["point_estimate"].as_f64()
}
