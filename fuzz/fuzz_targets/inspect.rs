//! Fuzz target: `inspect` on any file the tool writes must never panic.
//! The first byte picks the file name (a JSON report, pose, skeleton,
//! rig, play script or site manifest; a manifest; a PNG; a similarity
//! cache), the rest is the file: the JSON classifier and each kind's
//! summary (`surfmotion::tools::inspect::json_kind` and what follows) read it as
//! `inspect` reads files the user points it at.
#![no_main]

use libfuzzer_sys::fuzz_target;
use surfmotion::tools::inspect::{InspectOptions, inspect};

const NAMES: [&str; 6] = [
    "f.json",
    "character.toml",
    "f.png",
    "similarity-shape.bin",
    "f.skeleton.json",
    "site.json",
];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, body)) = data.split_first() else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("surfmotion-fuzz-inspect-{}", std::process::id()));
    if std::fs::create_dir_all(&dir).is_err() {
        return;
    }
    let path = dir.join(NAMES[pick as usize % NAMES.len()]);
    if std::fs::write(&path, body).is_ok() {
        let _ = inspect(&path, &InspectOptions::default());
    }
    let _ = std::fs::remove_file(&path);
});
