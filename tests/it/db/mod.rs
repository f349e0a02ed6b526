//! Character databases: the real captures' manifests, synthetic databases.

mod cache_inspect;
mod cache_trust;
mod caches;
mod captures;
mod examples;
mod frames;
mod histogram_reference;
mod scan;
mod sparse;
mod synth;

use crate::common;
use std::path::{Path, PathBuf};

/// A database of the samba capture (175 frames, the rig from the test
/// landmarks) in `dir/samba`, as `db init` writes it (`cache_trust`,
/// `cache_inspect`, `examples`).
fn samba_db(d: &Path, dir: &Path) -> PathBuf {
    let db = dir.join("samba");
    let landmarks =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json");
    let r = common::run_cli(
        &[
            "db".as_ref(),
            "init".as_ref(),
            db.as_os_str(),
            "--mesh".as_ref(),
            d.join("4d/samba/samba.obj").as_os_str(),
            "--sequence".as_ref(),
            format!("dance={}", d.join("4d/samba/samba.pc2").display()).as_ref(),
            "--landmarks".as_ref(),
            landmarks.as_os_str(),
        ],
        None,
        &[],
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    db
}
