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

use std::path::PathBuf;

fn main() {
    println!("cargo::rustc-check-cfg=cfg(no_shared_data)");
    println!("cargo::rerun-if-changed=build.rs");
    println!("cargo::rerun-if-env-changed=SURFMOTION_DATA");
    let dir = match std::env::var_os("SURFMOTION_DATA") {
        Some(p) => PathBuf::from(p),
        None => PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").unwrap_or_default())
            .join("../shared/data"),
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
