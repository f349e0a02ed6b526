//! Build script: tells the tests whether the shared data folder is there.
//!
//! Tests on real data (`$SURFMOTION_DATA`, else `../shared/data` beside the
//! package) carry
//! `#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]`.
//! This script sets `no_shared_data` when the folder (its `README.md`) is
//! absent and `CI` is not `true`, so a plain `cargo test` lists those tests as
//! ignored, with the reason, in its summary; under `CI=true` they run and fail
//! on the missing data (`tests/it/common/mod.rs::data_dir`).
//!
//! What is watched, and why:
//! - present: the folder's `README.md`, so removing the data reruns this
//!   script (an existing file costs nothing on later builds);
//! - absent: nothing on disk. Cargo treats a watched path that does not exist
//!   as changed on every build, which would rebuild the whole crate each time.
//!   When the data appears after such a build, `tests/it/hygiene/data_gate.rs` fails and
//!   says to `touch build.rs` (or set `SURFMOTION_DATA`).
//!
//! It also sets `SURFMOTION_RIG_SOURCE`, a fingerprint of the sources a
//! database's rig is embedded by ([`RIG_SOURCES`]): the rig cache of a
//! loaded character (`src/db/rig_cache.rs`) carries it in its key, so a
//! change to the embedding's code embeds the rig again instead of reading
//! the rig of the old code. `SURFMOTION_SKELETON_SOURCE` likewise for the
//! skeleton cache (`cache/poses-KIND.bin`, keyed in `src/db/frames.rs`):
//! the rig's sources and the cache's own reader and writer
//! ([`SKELETON_SOURCES`]), so a changed reader or skeleton code rebuilds it.

use std::path::{Path, PathBuf};

/// The files and folders whose bytes the rig cache's key covers: the
/// embedding and everything it calls (meshes and their solvers, poses,
/// clips and units, the rig readers, file helpers), the database code that
/// runs it, and the locked versions of the numerical crates.
const RIG_SOURCES: &[&str] = &[
    "src/embed",
    "src/rig",
    "src/mesh",
    "src/pose",
    "src/mocap",
    "src/util",
    "src/db/skeletons.rs",
    "src/db/manifest.rs",
    "src/db/rig_cache.rs",
    "Cargo.lock",
];

/// The files and folders whose bytes the skeleton cache's key covers: the
/// rig's ([`RIG_SOURCES`]: the per-frame joints and the rigid fit are in
/// `src/embed`) and the cache's reader and writer.
const SKELETON_SOURCES: &[&str] = &["src/db/frames.rs"];

/// The files whose bytes the example memo's key covers besides the
/// skeleton's ([`SKELETON_SOURCES`]): the choice and the memo.
const EXAMPLES_SOURCES: &[&str] = &["src/deform/regions.rs", "src/db/examples.rs"];

/// Every file under `p` (or `p` itself), in no particular order.
fn files_under(p: &Path, out: &mut Vec<PathBuf>) {
    if p.is_dir() {
        for e in std::fs::read_dir(p).into_iter().flatten().flatten() {
            files_under(&e.path(), out);
        }
    } else if p.is_file() {
        out.push(p.to_path_buf());
    }
}

/// FNV-1a (64 bit) of the relative paths and bytes of the files under
/// `sources`, in path order; each is watched, so an edit reruns this script.
fn source_fingerprint(root: &Path, sources: &[&str]) -> u64 {
    let mut files = Vec::new();
    for s in sources {
        println!("cargo::rerun-if-changed={s}");
        files_under(&root.join(s), &mut files);
    }
    files.sort();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |bytes: &[u8]| {
        for &b in bytes {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    for f in files {
        let rel = f.strip_prefix(root).unwrap_or(&f);
        feed(rel.to_string_lossy().as_bytes());
        feed(&[0]);
        let bytes = std::fs::read(&f).unwrap_or_default();
        feed(&(bytes.len() as u64).to_le_bytes());
        feed(&bytes);
    }
    h
}

fn main() {
    println!("cargo::rustc-check-cfg=cfg(no_shared_data)");
    println!("cargo::rerun-if-changed=build.rs");
    let root = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default());
    println!(
        "cargo::rustc-env=SURFMOTION_RIG_SOURCE={:016x}",
        source_fingerprint(&root, RIG_SOURCES)
    );
    let skeleton: Vec<&str> = RIG_SOURCES
        .iter()
        .chain(SKELETON_SOURCES)
        .copied()
        .collect();
    println!(
        "cargo::rustc-env=SURFMOTION_SKELETON_SOURCE={:016x}",
        source_fingerprint(&root, &skeleton)
    );
    // The deformation's example choice kept in `cache/examples.json`.
    let examples: Vec<&str> = skeleton.iter().chain(EXAMPLES_SOURCES).copied().collect();
    println!(
        "cargo::rustc-env=SURFMOTION_EXAMPLES_SOURCE={:016x}",
        source_fingerprint(&root, &examples)
    );
    println!("cargo::rerun-if-env-changed=SURFMOTION_DATA");
    let dir = match std::env::var_os("SURFMOTION_DATA") {
        Some(p) => PathBuf::from(p),
        None => root.join("../shared/data"),
    };
    let marker = dir.join("README.md");
    if marker.is_file() {
        println!("cargo::rerun-if-changed={}", marker.display());
        return;
    }
    // CI only matters while the data is absent; watching it always would
    // rebuild the crate whenever a run with CI=true follows one without.
    println!("cargo::rerun-if-env-changed=CI");
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        return;
    }
    println!("cargo::rustc-cfg=no_shared_data");
}
