//! `surfmotion batch` as a user runs it: whole CMU folders, a killed run
//! resumed, a corrupt clip among good ones, shards.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn fixture(n: &str) -> String {
    format!("{}/tests/fixtures/{n}", env!("CARGO_MANIFEST_DIR"))
}

/// `batch` onto the armadillo scan (the fastest target).
fn batch(d: &Path, mocap_dir: &Path, out: &Path, extra: &[&str]) -> Output {
    let scan = d.join("scans/armadillo/armadillo.obj");
    Command::new(common::bin())
        .args(["batch", "--scan", scan.to_str().unwrap(), "--landmarks"])
        .arg(fixture("armadillo.landmarks.json"))
        .arg("--mocap-dir")
        .arg(mocap_dir)
        .arg("-o")
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

fn summary(out: &Path, name: &str) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join(name)).unwrap()).unwrap()
}

/// A small library: two AMC clips with their skeleton, one BVH in a subfolder.
fn small_library(d: &Path, dir: &Path) {
    std::fs::create_dir_all(dir.join("bvh")).unwrap();
    for f in ["02.asf", "02_01.amc", "02_02.amc"] {
        std::fs::copy(d.join("mocap/cmu-amc/02").join(f), dir.join(f)).unwrap();
    }
    std::fs::copy(
        d.join("mocap/bandai-namco/dataset-1_walk_normal_001.bvh"),
        dir.join("bvh/walk.bvh"),
    )
    .unwrap();
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn whole_cmu_folders_convert_every_clip() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    for sub in ["cmu-amc", "cmu-bvh"] {
        let src = d.join("mocap").join(sub);
        let out = tmp.path().join(sub);
        let o = batch(&d, &src, &out, &["--jobs", "2", "--format", "pc2"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s = summary(&out, "batch.json");
        let clips = surfmotion::batch::find_clips(&src).unwrap();
        assert_eq!(s["clips"], clips.len());
        assert_eq!(s["done"], clips.len(), "{s}");
        for c in &clips {
            let p = surfmotion::batch::output_path(&out, c, surfmotion::batch::Format::Pc2);
            assert!(
                p.is_file() && p.with_extension("obj").is_file(),
                "{}",
                p.display()
            );
        }
        assert!(out.join("batch.html").is_file() && out.join("batch.svg").is_file());
        // Every clip has a joint-velocity error on the scan's own skeleton.
        for o in s["outcomes"].as_array().unwrap() {
            assert!(o["error_cm"].as_f64().unwrap() < 5.0, "{o}");
        }
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_killed_batch_resumes_to_the_same_outputs() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    small_library(&d, &lib);
    let whole = tmp.path().join("whole");
    let o = batch(&d, &lib, &whole, &["--jobs", "1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Start again elsewhere and kill it once the first output exists.
    let cut = tmp.path().join("cut");
    let scan = d.join("scans/armadillo/armadillo.obj");
    let mut child = Command::new(common::bin())
        .args(["batch", "--scan", scan.to_str().unwrap(), "--landmarks"])
        .arg(fixture("armadillo.landmarks.json"))
        .arg("--mocap-dir")
        .arg(&lib)
        .arg("-o")
        .arg(&cut)
        .args(["--jobs", "1"])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let first = cut.join("02_01.glb");
    let t0 = std::time::Instant::now();
    while !first.exists() && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let o = batch(&d, &lib, &cut, &["--jobs", "2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&cut, "batch.json");
    assert!(s["skipped"].as_u64().unwrap() >= 1, "{s}");
    for rel in ["02_01.glb", "02_02.glb", "bvh/walk.glb"] {
        let (a, b) = (
            std::fs::read(whole.join(rel)).unwrap(),
            std::fs::read(cut.join(rel)).unwrap(),
        );
        assert!(a == b, "{rel} differs after resuming");
    }
    // No temporary file is left behind.
    let mut stray: Vec<PathBuf> = Vec::new();
    for e in walk(&cut) {
        let n = e.file_name().unwrap().to_string_lossy().to_string();
        if !(n.ends_with(".glb") || n.starts_with("batch")) {
            stray.push(e);
        }
    }
    assert!(stray.is_empty(), "{stray:?}");
}

fn walk(d: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(d).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(walk(&p));
        } else {
            out.push(p);
        }
    }
    out
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_corrupt_clip_is_reported_and_the_rest_succeed() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    small_library(&d, &lib);
    let good = std::fs::read_to_string(lib.join("bvh/walk.bvh")).unwrap();
    // Cut inside the HIERARCHY block (a cut in MOTION is read leniently).
    std::fs::write(lib.join("bvh/broken.bvh"), &good[..200]).unwrap();
    let out = tmp.path().join("out");
    let o = batch(&d, &lib, &out, &["--jobs", "2"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("1 of 4 clips failed"), "{err}");
    let s = summary(&out, "batch.json");
    assert_eq!(s["done"], 3);
    let failed: Vec<&serde_json::Value> = s["outcomes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|o| o["status"] == "failed")
        .collect();
    assert_eq!(failed.len(), 1);
    assert!(failed[0]["clip"].as_str().unwrap().ends_with("broken.bvh"));
    assert!(failed[0]["reason"].as_str().unwrap().contains("broken.bvh"));
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn shards_cover_the_library_exactly_once() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    small_library(&d, &lib);
    let out = tmp.path().join("out");
    let mut seen = Vec::new();
    for i in 1..=3 {
        let o = batch(
            &d,
            &lib,
            &out,
            &["--shard", &format!("{i}/3"), "--jobs", "1"],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s = summary(&out, &format!("batch-{i}of3.json"));
        for o in s["outcomes"].as_array().unwrap() {
            seen.push(o["clip"].as_str().unwrap().to_string());
        }
    }
    seen.sort();
    let all: Vec<String> = surfmotion::batch::find_clips(&lib)
        .unwrap()
        .iter()
        .map(|p| p.display().to_string())
        .collect();
    assert_eq!(seen, all);
    let o = batch(&d, &lib, &out, &["--shard", "4/3"]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_library_onto_a_4d_character() {
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    std::fs::create_dir_all(&lib).unwrap();
    for f in ["02.asf", "02_02.amc"] {
        std::fs::copy(d.join("mocap/cmu-amc/02").join(f), lib.join(f)).unwrap();
    }
    // A dot in the clip's name must not be taken for a format.
    std::fs::copy(
        d.join("mocap/bandai-namco/dataset-1_walk_normal_001.bvh"),
        lib.join("walk.v2.bvh"),
    )
    .unwrap();
    let out = tmp.path().join("out");
    let o = Command::new(common::bin())
        .args(["batch", "--db"])
        .arg(&db)
        .arg("--mocap-dir")
        .arg(&lib)
        .arg("-o")
        .arg(&out)
        .args(["--jobs", "2", "--format", "obj", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(s["done"], 2, "{s}");
    for o in s["outcomes"].as_array().unwrap() {
        // The part-based deformation follows the clip: well under the
        // interpolation-only errors of 1-3 cm/frame (README table).
        let e = o["error_cm"].as_f64().unwrap();
        assert!(e < 0.6, "{o}");
        let dir = Path::new(o["output"].as_str().unwrap());
        let frames = std::fs::read_dir(dir).unwrap().count();
        assert_eq!(
            frames as u64,
            o["frames"].as_u64().unwrap(),
            "{}",
            dir.display()
        );
    }
    assert!(out.join("walk.v2").is_dir() && !out.join("walk_v2-partial").exists());
}

/// Regression (issue 18, item 1): `batch --scan` on the raw MakeHuman base
/// mesh (154 groups, stray pieces the preparation drops) panicked in the
/// regressor with an index past the kept vertices; `transfer` worked.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn batch_scan_prepares_a_raw_scan_like_transfer() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    std::fs::create_dir_all(&lib).unwrap();
    for f in ["02.asf", "02_01.amc"] {
        std::fs::copy(d.join("mocap/cmu-amc/02").join(f), lib.join(f)).unwrap();
    }
    let out = tmp.path().join("out");
    let o = Command::new(common::bin())
        .args(["batch", "--scan"])
        .arg(d.join("scans/makehuman/base.obj"))
        .arg("--landmarks")
        .arg(fixture("makehuman.landmarks.json"))
        .arg("--mocap-dir")
        .arg(&lib)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(!err.contains("internal error"), "{err}");
    let s = summary(&out, "batch.json");
    assert_eq!(s["failed"], 0, "{s}");
    assert!(out.join("02_01.glb").exists());
}
