//! `surfmotion batch` as a user runs it: whole CMU folders, a killed run
//! resumed, a corrupt clip among good ones, shards.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn fixture(n: &str) -> String {
    format!("{}/tests/fixtures/{n}", env!("CARGO_MANIFEST_DIR"))
}

/// `batch` onto the armadillo scan (the fastest target).
fn batch(d: &Path, mocap_dir: &Path, out: &Path, extra: &[&str]) -> Output {
    let scan = d.join("scans/armadillo/armadillo.obj");
    Command::new(common::bin())
        .env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("JOB_COMPLETION_INDEX")
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

pub(super) fn summary(out: &Path, name: &str) -> serde_json::Value {
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

// ---------------------------------------------------------------------
// Issue 18 (items 2, 3, 10, 16): runs without ../shared, on the demo's
// procedural humanoid and short cuts of the committed clips in mocap/.
// ---------------------------------------------------------------------

/// The demo humanoid as a scan (OBJ) and its landmarks, written once.
pub(super) fn humanoid() -> (PathBuf, PathBuf) {
    use std::sync::OnceLock;
    static H: OnceLock<(PathBuf, PathBuf, PathBuf)> = OnceLock::new();
    let h = H.get_or_init(|| {
        use surfmotion::synth::humanoid::{DEMO_GRID, humanoid_landmarks_json, humanoid_mesh};
        let tmp = common::fixture_dir("batch-humanoid");
        let scan = tmp.join("humanoid.obj");
        let seq = surfmotion::mesh::MeshSequence::single(humanoid_mesh(DEMO_GRID));
        surfmotion::mesh::io::save_sequence(&seq, &scan, None).unwrap();
        let lm = tmp.join("humanoid.landmarks.json");
        std::fs::write(&lm, humanoid_landmarks_json()).unwrap();
        (tmp, scan, lm)
    });
    (h.1.clone(), h.2.clone())
}

/// The demo's 4D character database (`surfmotion demo`), built once.
fn demo_db() -> PathBuf {
    use std::sync::OnceLock;
    static DB: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    DB.get_or_init(|| {
        let tmp = common::fixture_dir("batch-demo");
        let o = Command::new(common::bin())
            .args(["demo", "-o"])
            .arg(&tmp)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let db = tmp.join("database");
        (tmp, db)
    })
    .1
    .clone()
}

/// The first `frames` frames of the committed clip `mocap/NAME.bvh`.
fn short_clip(name: &str, frames: usize) -> String {
    let t = std::fs::read_to_string(format!("{}/mocap/{name}.bvh", env!("CARGO_MANIFEST_DIR")))
        .unwrap();
    let (head, motion) = t.split_once("MOTION\n").unwrap();
    let lines: Vec<&str> = motion.lines().collect();
    format!(
        "{head}MOTION\nFrames: {frames}\n{}\n{}\n",
        lines[1],
        lines[2..2 + frames].join("\n")
    )
}

/// Writes `short_clip("walk", frames)` to each of `rels` under `lib`.
pub(super) fn library(lib: &Path, rels: &[&str], frames: usize) {
    let clip = short_clip("walk", frames);
    for r in rels {
        let p = lib.join(r);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, &clip).unwrap();
    }
}

/// `batch --scan` onto the humanoid.
pub(super) fn hbatch(lib: &Path, out: &Path, extra: &[&str]) -> Output {
    hbatch_cmd(lib, out, extra).output().unwrap()
}

pub(super) fn hbatch_cmd(lib: &Path, out: &Path, extra: &[&str]) -> Command {
    let (scan, lm) = humanoid();
    let mut c = Command::new(common::bin());
    // Not a shard of whatever scheduler runs the tests.
    c.env_remove("SLURM_ARRAY_TASK_ID")
        .env_remove("JOB_COMPLETION_INDEX");
    c.args(["batch", "--scan"])
        .arg(&scan)
        .arg("--landmarks")
        .arg(&lm)
        .arg("--mocap-dir")
        .arg(lib)
        .arg("-o")
        .arg(out)
        .args(extra);
    c
}

pub(super) fn ok(o: &Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(o.status.success(), "{err}");
    err
}

fn outcomes(s: &serde_json::Value) -> Vec<serde_json::Value> {
    s["outcomes"].as_array().unwrap().clone()
}

fn obj_frames(dir: &Path) -> usize {
    std::fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .filter(|e| e.path().extension().is_some_and(|x| x == "obj"))
                .count()
        })
        .unwrap_or(0)
}

/// Regression (issue 18, item 2): `batch` lacked the per-clip options of
/// the verbs it batches. They are one flattened option group per job, so
/// every option of `transfer` and `retarget` that applies per clip exists
/// in `batch` too.
#[test]
fn batch_has_the_per_clip_options_of_transfer_and_retarget() {
    let help = |verb: &str| {
        let o = Command::new(common::bin())
            .args([verb, "--help"])
            .output()
            .unwrap();
        String::from_utf8_lossy(&o.stdout).to_string()
    };
    let (batch, transfer, retarget) = (help("batch"), help("transfer"), help("retarget"));
    let clip = [
        "--input-fps",
        "--asf",
        // `--assume-units` before session 7 (still accepted, hidden).
        "--input-units",
        "--up",
        "--rig-map",
    ];
    let scan = ["--group", "--marker-count", "--marker-margin", "--fps"];
    let db = [
        "--deform",
        "--no-deform",
        "--t-skel",
        "--w-retr",
        "--no-interpolate",
        "--no-blend",
        "--skeleton",
    ];
    // A flag as help prints it: `--up <AXIS>`, or `--no-blend` alone.
    let has = |help: &str, f: &str| {
        help.lines()
            .any(|l| l.trim_start().split([' ', ',']).any(|w| w == f))
    };
    for f in clip.iter().chain(&scan).chain(&db) {
        assert!(has(&batch, f), "batch lacks {f}");
    }
    for f in clip.iter().chain(&scan) {
        assert!(has(&transfer, f), "transfer lacks {f}");
    }
    for f in clip.iter().chain(&db) {
        assert!(has(&retarget, f), "retarget lacks {f}");
    }
}

/// Regression (issue 18, item 2): the options reach every clip of a batch
/// onto a scan, and are checked once before any clip.
#[test]
fn batch_scan_options_reach_every_clip() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &["a.bvh", "b.bvh"], 20);
    let run = |name: &str, extra: &[&str]| {
        let out = tmp.path().join(name);
        let o = hbatch(&lib, &out, &[&["--json"], extra].concat());
        ok(&o);
        let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(s["done"], 2, "{s}");
        (s, std::fs::read(out.join("a.glb")).unwrap())
    };
    let (plain, plain_glb) = run("plain", &[]);
    // 20 frames said to be at 60 fps last a third of a second: 10 at 30.
    let (fast, _) = run("fast", &["--input-fps", "60"]);
    for (p, f) in outcomes(&plain).iter().zip(outcomes(&fast)) {
        assert_eq!(p["frames"], 20);
        assert_eq!(f["frames"], 10);
    }
    let (_, few) = run("few", &["--marker-count", "30", "--marker-margin", "0.1"]);
    assert!(few != plain_glb, "--marker-count changed nothing");
    let (_, units) = run("units", &["--assume-units", "m", "--up", "y"]);
    assert_eq!(units, plain_glb, "the clip is in metres, y up");
    // A rig map with left and right swapped is used, not detected over.
    let map = tmp.path().join("swapped.json");
    let mut joints = serde_json::Map::new();
    for (c, n) in [
        ("pelvis", "Hips"),
        ("spine", "Spine"),
        ("chest", "Spine1"),
        ("neck", "Neck"),
        ("head", "Head"),
    ] {
        joints.insert(c.into(), n.into());
    }
    for (side, other) in [("l", "Right"), ("r", "Left")] {
        for (c, n) in [
            ("shoulder", "Arm"),
            ("elbow", "ForeArm"),
            ("wrist", "Hand"),
            ("hip", "UpLeg"),
            ("knee", "Leg"),
            ("ankle", "Foot"),
            ("toe", "ToeBase"),
        ] {
            joints.insert(format!("{side}_{c}"), format!("{other}{n}").into());
        }
    }
    let v = serde_json::json!({"convention": "swapped", "joints": joints});
    std::fs::write(&map, v.to_string()).unwrap();
    let (_, swapped) = run("swapped", &["--rig-map", map.to_str().unwrap()]);
    assert!(swapped != plain_glb, "--rig-map changed nothing");
    // Checked once, before any clip, naming the problem.
    let bad = |extra: &[&str], words: &str| {
        let o = hbatch(&lib, &tmp.path().join("bad"), extra);
        assert_eq!(o.status.code(), Some(1));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(words), "{err}");
        assert!(!err.contains("FAILED"), "{err}");
    };
    bad(&["--group", "body"], "no group named body");
    bad(&["--marker-margin", "0.9"], "--marker-margin 0.9");
    bad(&["--up", "x"], "--up 'x'");
    bad(&["--deform", "none"], "apply to --db");
    // At its default value too (session 52: a value equal to the default
    // was taken for the option left out).
    bad(&["--w-retr", "1"], "apply to --db");
    bad(&["--deform", "part"], "apply to --db");
}

/// Regression (issue 18, item 2): `retarget`'s options reach every clip of
/// a batch onto a 4D character.
#[test]
fn batch_db_options_reach_every_clip() {
    let db = demo_db();
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &["a.bvh"], 20);
    let run = |name: &str, extra: &[&str]| {
        let out = tmp.path().join(name);
        let o = Command::new(common::bin())
            .args(["batch", "--db"])
            .arg(&db)
            .arg("--mocap-dir")
            .arg(&lib)
            .arg("-o")
            .arg(&out)
            .args(extra)
            .output()
            .unwrap();
        (o, out.join("a.glb"))
    };
    let (o, plain) = run("plain", &[]);
    ok(&o);
    let (o, none) = run("none", &["--deform", "none", "--no-interpolate"]);
    ok(&o);
    assert!(
        std::fs::read(plain).unwrap() != std::fs::read(none).unwrap(),
        "--deform none changed nothing"
    );
    let (o, _) = run("group", &["--group", "body"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("apply to --scan"));
    // Regression (session 52): a scan option typed at its default value
    // (`--fps 30`) was let through, where `--fps 25` was refused; given is
    // given. Left out (the plain run above), it is no refusal.
    let (o, out) = run("fps", &["--fps", "30"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--fps") && err.contains("apply to --scan"),
        "{err}"
    );
    assert!(!out.exists(), "a refused batch wrote {}", out.display());
}

/// Regression (issue 18, item 3): a rerun after completion wrote a report
/// with `done: 0, frames: 0` and no errors, losing the first run's results.
/// Skipped outputs keep what the run that wrote them recorded.
#[test]
fn a_resumed_batch_keeps_the_report_of_earlier_outputs() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &["a.bvh", "sub/b.bvh"], 12);
    let out = tmp.path().join("out");
    ok(&hbatch(&lib, &out, &[]));
    let first = summary(&out, "batch.json");
    // A third clip appears; the rerun converts it and skips the others.
    library(&lib, &["c.bvh"], 12);
    ok(&hbatch(&lib, &out, &[]));
    let s = summary(&out, "batch.json");
    assert_eq!(s["finished"], true);
    assert_eq!(
        (s["clips"].clone(), s["done"].clone()),
        (3.into(), 1.into())
    );
    assert_eq!(s["skipped"], 2);
    assert_eq!(s["frames"], 36, "{s}");
    assert_eq!(s["frames_written"], 12);
    for o in outcomes(&s) {
        assert_eq!(o["frames"], 12, "{o}");
        assert!(o["error_cm"].as_f64().is_some(), "{o}");
        let before = outcomes(&first)
            .into_iter()
            .find(|f| f["clip"] == o["clip"]);
        if let Some(b) = before {
            assert_eq!(o["status"], "skipped");
            assert_eq!(o["earlier"], true);
            assert_eq!(o["error_cm"], b["error_cm"]);
        }
    }
    // And again: nothing converted, still every output described.
    ok(&hbatch(&lib, &out, &[]));
    let s = summary(&out, "batch.json");
    assert_eq!(
        (s["done"].clone(), s["skipped"].clone()),
        (0.into(), 3.into())
    );
    assert_eq!(s["frames"], 36, "{s}");
}

/// Regression (issue 18, item 3): a batch killed mid-run left no report.
/// The report is rewritten atomically after each clip.
#[test]
fn a_killed_batch_leaves_a_valid_report_of_what_finished() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    let names: Vec<String> = (0..8).map(|i| format!("c{i}.bvh")).collect();
    let rels: Vec<&str> = names.iter().map(String::as_str).collect();
    library(&lib, &rels, 30);
    let out = tmp.path().join("out");
    let mut child = hbatch_cmd(&lib, &out, &["--jobs", "1"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let report = out.join("batch.json");
    let t0 = std::time::Instant::now();
    let finished_clips = || -> Option<usize> {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).ok()?).ok()?;
        s["done"].as_u64().map(|d| d as usize)
    };
    while finished_clips().unwrap_or(0) < 2 && t0.elapsed().as_secs() < 120 {
        std::thread::sleep(std::time::Duration::from_millis(10));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let s = summary(&out, "batch.json");
    assert_eq!(s["finished"], false, "the run ended before the kill: {s}");
    let done = outcomes(&s);
    assert!(done.len() >= 2 && done.len() < 8, "{s}");
    for o in &done {
        assert_eq!(o["status"], "done");
        assert!(Path::new(o["output"].as_str().unwrap()).is_file(), "{o}");
    }
    // The page and the plot describe the clips of the JSON (they were
    // written only at the end of a run); written before the JSON, they may
    // be one clip ahead of it.
    let page = std::fs::read_to_string(out.join("batch.html")).expect("batch.html of a killed run");
    let svg = std::fs::read_to_string(out.join("batch.svg")).expect("batch.svg of a killed run");
    assert!(page.contains("<b>running</b>"), "{page}");
    for o in &done {
        let clip = o["clip"].as_str().unwrap();
        assert!(
            page.contains(&format!("<td>{clip}</td>")),
            "{clip} not in the page: {page}"
        );
        assert!(svg.contains(clip), "{clip} not in the plot: {svg}");
    }
    let rows = page.matches("<tr class=").count();
    assert!(
        rows == done.len() || rows == done.len() + 1,
        "{rows} rows: {page}"
    );
    // The rerun takes over the dead run's lock and completes the report.
    let err = ok(&hbatch(&lib, &out, &["--jobs", "2"]));
    assert!(err.contains("stale lock"), "{err}");
    let s = summary(&out, "batch.json");
    assert_eq!(s["finished"], true);
    assert_eq!(s["clips"], 8);
    assert_eq!(s["skipped"].as_u64().unwrap() as usize, done.len(), "{s}");
    assert_eq!(s["frames"], 8 * 30, "{s}");
    assert!(outcomes(&s).iter().all(|o| o["error_cm"].is_f64()), "{s}");
    assert!(!out.join("batch.lock").exists());
}

/// Regression (issue 18, item 10): two batches into one folder shared the
/// temporary `NAME-partial` folders and truncated each other's OBJ frames,
/// both saying done. The folder is locked: the second run is refused.
#[test]
fn a_second_batch_into_a_folder_in_use_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &["a.bvh", "b.bvh", "c.bvh"], 30);
    let out = tmp.path().join("out");
    let mut first = hbatch_cmd(&lib, &out, &["--format", "obj", "--jobs", "1"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let lock = out.join("batch.lock");
    let t0 = std::time::Instant::now();
    while !lock.exists() && t0.elapsed().as_secs() < 60 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let second = hbatch(&lib, &out, &["--format", "obj", "--jobs", "1", "--force"]);
    let shard = hbatch(&lib, &out, &["--format", "obj", "--shard", "1/2"]);
    let still_running = first.try_wait().unwrap().is_none();
    assert!(first.wait().unwrap().success());
    assert!(
        still_running,
        "the first run ended before the second started"
    );
    for o in [&second, &shard] {
        assert_eq!(o.status.code(), Some(1));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("in use by another batch"), "{err}");
        assert!(err.contains("batch.lock"), "{err}");
    }
    for c in ["a", "b", "c"] {
        assert_eq!(obj_frames(&out.join(c)), 30, "{c}");
    }
    assert!(!lock.exists());
    // A lock whose process is gone is taken over.
    let mut dead = Command::new(common::bin())
        .arg("--version")
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let pid = dead.id();
    dead.wait().unwrap();
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_else(|_| "this host".into());
    std::fs::write(
        &lock,
        serde_json::json!({"pid": pid, "host": host, "shard": null}).to_string(),
    )
    .unwrap();
    let err = ok(&hbatch(&lib, &out, &["--format", "obj"]));
    if Path::new("/proc/self").exists() {
        assert!(err.contains("removed the stale lock"), "{err}");
    }
}

/// Regression (issue 18, item 10): `x.bvh` and `x.amc` (here `x.BVH`) both
/// wrote `x.glb`. Clips that would write one output are named with their
/// extension, and the run says so.
#[test]
fn clips_writing_one_output_are_named_apart() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &["x.bvh", "x.BVH", "y.bvh"], 10);
    let out = tmp.path().join("out");
    let err = ok(&hbatch(&lib, &out, &[]));
    assert!(err.contains("named with their extension"), "{err}");
    let s = summary(&out, "batch.json");
    assert_eq!(s["done"], 3, "{s}");
    for f in ["x-bvh.glb", "x-BVH.glb", "y.glb"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    assert!(!out.join("x.glb").exists());
    // Shards agree on the names, whichever shard a clip falls in.
    let sharded = tmp.path().join("sharded");
    for i in 1..=2 {
        ok(&hbatch(&lib, &sharded, &["--shard", &format!("{i}/2")]));
    }
    for f in ["x-bvh.glb", "x-BVH.glb", "y.glb"] {
        assert!(sharded.join(f).is_file(), "{f}");
    }
}

/// Regression (issue 18, item 10): with OBJ frames, a clip `walk.bvh` beside
/// a folder `walk/` of clips was "skipped (output complete)" without being
/// converted, and `--force` deleted the folder's results.
#[test]
fn a_clip_beside_a_folder_of_its_name_keeps_both_outputs() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &["walk.bvh", "walk/a.bvh", "walk/b.bvh"], 10);
    let out = tmp.path().join("out");
    for extra in [&[][..], &["--force"][..]] {
        let o = hbatch(&lib, &out, &[&["--format", "obj"], extra].concat());
        let err = ok(&o);
        assert!(err.contains("walk.bvh -> "), "{err}");
        let s = summary(&out, "batch.json");
        assert_eq!(s["failed"], 0, "{s}");
        assert_eq!(obj_frames(&out.join("walk-bvh")), 10);
        assert_eq!(obj_frames(&out.join("walk/a")), 10);
        assert_eq!(obj_frames(&out.join("walk/b")), 10);
        assert_eq!(obj_frames(&out.join("walk")), 0);
    }
    let s = summary(&out, "batch.json");
    assert_eq!(s["done"], 3, "--force redid all three: {s}");
}

/// Regression (issue 18, item 10): `foo.bvh`'s temporary folder was
/// `foo-partial`, the output of `foo-partial.bvh`, which it deleted.
/// Temporaries have unique names of their own.
#[test]
fn obj_temporaries_never_take_another_clips_output() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &["foo.bvh", "foo-partial.bvh", "foo_partial.bvh"], 10);
    let out = tmp.path().join("out");
    for extra in [&[][..], &["--force"][..]] {
        ok(&hbatch(
            &lib,
            &out,
            &[&["--format", "obj", "--jobs", "2"], extra].concat(),
        ));
        for c in ["foo", "foo-partial", "foo_partial"] {
            assert_eq!(obj_frames(&out.join(c)), 10, "{c}");
        }
    }
    let left: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

/// Regression (issue 18, item 16): a link back up the mocap folder made the
/// batch convert one clip 41 times (once per path until the OS gave up).
#[cfg(unix)]
#[test]
fn a_symlink_loop_in_the_mocap_folder_converts_each_clip_once() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &["sub/a.bvh", "b.bvh"], 10);
    std::os::unix::fs::symlink("..", lib.join("sub/loop")).unwrap();
    std::os::unix::fs::symlink("sub/a.bvh", lib.join("also_a.bvh")).unwrap();
    std::os::unix::fs::symlink("sub", lib.join("linked")).unwrap();
    let clips = surfmotion::batch::find_clips(&lib).unwrap();
    assert_eq!(clips, [PathBuf::from("b.bvh"), PathBuf::from("sub/a.bvh")]);
    let out = tmp.path().join("out");
    ok(&hbatch(&lib, &out, &[]));
    let s = summary(&out, "batch.json");
    assert_eq!(s["clips"], 2, "{s}");
}

/// Regression (issue 18, item 16): `-o out.glb` where `out.glb` is a folder
/// filled the folder with OBJ frames. Refused, for `transfer`, `retarget`
/// and a batch's outputs.
#[test]
fn an_output_named_as_a_file_that_is_a_folder_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let clip = tmp.path().join("clip.bvh");
    std::fs::write(&clip, short_clip("walk", 10)).unwrap();
    let folder = tmp.path().join("out.glb");
    std::fs::create_dir(&folder).unwrap();
    let (scan, lm) = humanoid();
    let transfer = Command::new(common::bin())
        .args(["transfer", "--scan"])
        .arg(&scan)
        .arg("--landmarks")
        .arg(&lm)
        .arg("--mocap")
        .arg(&clip)
        .arg("-o")
        .arg(&folder)
        .output()
        .unwrap();
    let retarget = Command::new(common::bin())
        .args(["retarget", "--db"])
        .arg(demo_db())
        .arg("--mocap")
        .arg(&clip)
        .arg("-o")
        .arg(&folder)
        .output()
        .unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &["a.bvh", "b.bvh"], 10);
    let out = tmp.path().join("batch");
    std::fs::create_dir_all(out.join("a.glb")).unwrap();
    let batch = hbatch(&lib, &out, &[]);
    for (verb, o) in [
        ("transfer", transfer),
        ("retarget", retarget),
        ("batch", batch),
    ] {
        assert_eq!(o.status.code(), Some(1), "{verb}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("folder"), "{verb}: {err}");
    }
    assert_eq!(std::fs::read_dir(&folder).unwrap().count(), 0);
    // Refused before any work: b.glb was not written either.
    assert!(!out.join("b.glb").exists());
}

/// Regression (issue 18, item 16): a write killed midway left its
/// `.surfmotion-*.part` temporary (70 MB) that no rerun removed. The next
/// run into the folder removes temporaries of ours, and nothing else.
#[test]
fn temporaries_of_a_killed_write_are_removed_by_the_next_run() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &["a.bvh", "sub/b.bvh"], 10);
    let out = tmp.path().join("out");
    ok(&hbatch(&lib, &out, &[]));
    let part = out.join("sub/.surfmotion-Ab3dE9.part");
    std::fs::write(&part, vec![0u8; 1 << 20]).unwrap();
    let partial = out.join(".surfmotion-Zz9yX1-partial");
    std::fs::create_dir(&partial).unwrap();
    std::fs::write(partial.join("frame_0000.obj"), b"v 0 0 0\n").unwrap();
    let mine = out.join("sub/notes.part");
    std::fs::write(&mine, b"not ours").unwrap();
    let err = ok(&hbatch(&lib, &out, &[]));
    assert!(err.contains("removed 2 unfinished temporaries"), "{err}");
    assert!(!part.exists() && !partial.exists());
    assert!(mine.exists() && out.join("a.glb").exists() && out.join("sub/b.glb").exists());
}

/// Regression (issue 39, item 4): `batch.json` and the page held only the
/// joint-velocity error while `eval` on a clip the batch marked "done"
/// warned. Each clip's warnings (kind, count, worst frame) are in the
/// report, as many as `eval` gives on the same result, and the summary
/// counts the clips with warnings.
#[test]
fn batch_keeps_the_plausibility_warnings_eval_gives() {
    let db = demo_db();
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    std::fs::create_dir_all(&lib).unwrap();
    std::fs::write(lib.join("run.bvh"), short_clip("run", 40)).unwrap();
    // The walk with every joint turned four times as far: knees bent
    // backwards, feet through the floor, folds (eval warns of 73 turned
    // over triangles in frame 37).
    let walk = short_clip("walk", 40);
    let wild = common::scaled_angles_bvh(&walk, 4.0);
    std::fs::write(lib.join("wild.bvh"), wild).unwrap();
    let out = tmp.path().join("out");
    let o = Command::new(common::bin())
        .args(["batch", "--db"])
        .arg(&db)
        .arg("--mocap-dir")
        .arg(&lib)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    ok(&o);
    let s = summary(&out, "batch.json");
    let mut warned = 0;
    for o in outcomes(&s) {
        assert_eq!(o["status"], "done", "{o}");
        let clip = lib.join(o["clip"].as_str().unwrap());
        let result = out.join(o["output"].as_str().unwrap());
        let e = Command::new(common::bin())
            .args(["eval", "--json", "--db"])
            .arg(&db)
            .arg("--mocap")
            .arg(&clip)
            .arg("--result")
            .arg(&result)
            .output()
            .unwrap();
        assert!(e.status.success(), "{}", String::from_utf8_lossy(&e.stderr));
        let ev: serde_json::Value = serde_json::from_slice(&e.stdout).unwrap();
        let want: Vec<&str> = ev["plausibility"]["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| w.as_str().unwrap())
            .collect();
        let have = o["warnings"]
            .as_array()
            .unwrap_or_else(|| panic!("no warnings in {o}"));
        eprintln!("{}: eval {want:?}, batch {have:?}", o["clip"]);
        // The plausibility warnings only: the batch also reports its own
        // deformation's repair (kind `repair`, "stay turned over"), which
        // `eval` of the written result cannot see.
        let plausible = |kind: &str| kind != "repair";
        let have_kinds: Vec<&str> = have
            .iter()
            .map(|w| w["kind"].as_str().unwrap())
            .filter(|k| plausible(k))
            .collect();
        let want_plausible = want
            .iter()
            .filter(|m| !m.contains("stay turned over"))
            .count();
        assert_eq!(have_kinds.len(), want_plausible, "{}", o["clip"]);
        for w in have {
            assert!(w["kind"].is_string() && !w["message"].as_str().unwrap().is_empty());
            if w["kind"] == "turned_over" {
                assert!(
                    w["count"].as_u64().unwrap() > 0 && w["worst_frame"].is_u64(),
                    "{w}"
                );
            }
        }
        warned += usize::from(!have.is_empty());
    }
    assert!(warned > 0, "the wild clip was not warned about");
    assert_eq!(s["with_warnings"].as_u64(), Some(warned as u64));
    let page = std::fs::read_to_string(out.join("batch.html")).unwrap();
    assert!(page.contains("<th>warnings</th>"));
    for o in outcomes(&s) {
        for w in o["warnings"].as_array().unwrap() {
            let m = w["message"].as_str().unwrap();
            let first = m.split(' ').take(3).collect::<Vec<_>>().join(" ");
            assert!(page.contains(&first), "the page lacks {m}");
        }
    }
}

/// `clip` (a BVH of the committed clips' rig) with both knees turned 100°
/// backwards in every frame: a result that stands on bent-back legs,
/// floating over the floor (plausibility warnings).
fn knees_bent_backwards(clip: &str) -> String {
    let (head, motion) = clip.split_once("MOTION\n").unwrap();
    let (mut joints, mut index) = (Vec::new(), std::collections::HashMap::new());
    let mut k = 0;
    for line in head.lines() {
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.first() {
            Some(&"ROOT") | Some(&"JOINT") => joints.push(w[1].to_string()),
            Some(&"CHANNELS") => {
                for c in &w[2..] {
                    index.insert((joints.last().unwrap().clone(), c.to_string()), k);
                    k += 1;
                }
            }
            _ => {}
        }
    }
    let knees = ["LeftLeg", "RightLeg"].map(|j| index[&(j.to_string(), "Xrotation".to_string())]);
    let mut lines = motion.lines();
    let mut out = format!(
        "{head}MOTION\n{}\n{}\n",
        lines.next().unwrap(),
        lines.next().unwrap()
    );
    for l in lines.filter(|l| !l.trim().is_empty()) {
        let mut v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
        for &i in &knees {
            v[i] -= 100.0;
        }
        let row: Vec<String> = v.iter().map(|x| x.to_string()).collect();
        out += &(row.join(" ") + "\n");
    }
    out
}

/// Issue 39 (a): `batch --scan` recorded no plausibility warnings (its
/// clips' `warnings` were always empty) where `batch --db` records them; a
/// clip whose result `transfer` warns about now has those warnings in
/// `batch.json`, the same ones.
#[test]
fn batch_scan_records_the_warnings_transfer_gives() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    std::fs::create_dir_all(&lib).unwrap();
    let clip = lib.join("bent.bvh");
    std::fs::write(&clip, knees_bent_backwards(&short_clip("walk", 40))).unwrap();
    let out = tmp.path().join("out");
    ok(&hbatch(&lib, &out, &["--format", "pc2"]));
    let s = summary(&out, "batch.json");
    let recorded: Vec<String> = outcomes(&s)[0]["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["message"].as_str().unwrap().to_string())
        .collect();
    let (scan, lm) = humanoid();
    let o = Command::new(common::bin())
        .args(["transfer", "--scan"])
        .arg(&scan)
        .arg("--landmarks")
        .arg(&lm)
        .arg("--mocap")
        .arg(&clip)
        .arg("-o")
        .arg(tmp.path().join("one.pc2"))
        .arg("--json")
        .output()
        .unwrap();
    ok(&o);
    let t: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let given: Vec<String> = t["plausibility"]["warnings"]
        .as_array()
        .unwrap_or_else(|| panic!("no plausibility in {t}"))
        .iter()
        .map(|w| w.as_str().unwrap().to_string())
        .collect();
    assert!(!given.is_empty(), "the clip gives no warning: {t}");
    assert_eq!(recorded, given, "{s}");
    assert_eq!(s["with_warnings"], 1, "{s}");
    // The report counts the scan's factorisation once.
    assert_eq!(s["factorisations"], 1, "{s}");
}
