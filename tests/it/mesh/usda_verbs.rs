//! `.usda` from the verbs that write a sequence by extension (issue 44):
//! `batch --format usda` names each clip's output `CLIP.usda`, skips it
//! when complete, and the files are USD text layers with one time sample
//! per frame (without normals under `--usd-no-normals`).

use crate::common;
use std::path::Path;

fn fixture(n: &str) -> String {
    format!("{}/tests/fixtures/{n}", env!("CARGO_MANIFEST_DIR"))
}

/// The frame count of a `.usda` file: its `points.timeSamples` entries.
fn usda_frames(p: &Path) -> usize {
    let text = std::fs::read_to_string(p).unwrap();
    assert!(text.starts_with("#usda 1.0"), "{}", p.display());
    let samples = text
        .split("point3f[] points.timeSamples = {")
        .nth(1)
        .unwrap_or_else(|| panic!("{}: no points.timeSamples", p.display()));
    let block = samples.split("\n    }").next().unwrap();
    block
        .lines()
        .filter(|l| l.trim_end().ends_with("],"))
        .count()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn batch_format_usda_writes_one_usda_per_clip_and_skips_complete_ones() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let src = tmp.path().join("clips");
    std::fs::create_dir_all(src.join("sub")).unwrap();
    std::fs::copy(
        d.join("mocap/bandai-namco/dataset-1_run_normal_001.bvh"),
        src.join("sub/run.bvh"),
    )
    .unwrap();
    let out = tmp.path().join("out");
    let run_into = |out: &Path, extra: &[&str]| {
        common::run_ok(
            std::process::Command::new(common::bin())
                .args(["batch", "--scan"])
                .arg(d.join("scans/armadillo/armadillo.obj"))
                .arg("--landmarks")
                .arg(fixture("armadillo.landmarks.json"))
                .arg("--mocap-dir")
                .arg(&src)
                .arg("-o")
                .arg(out)
                .args(["--format", "usda", "--json"])
                .args(extra),
        )
    };
    let run = |extra: &[&str]| run_into(&out, extra);
    run(&[]);
    let want = out.join("sub/run.usda");
    assert_eq!(
        want,
        surfmotion::batch::output_path(
            &out,
            Path::new("sub/run.bvh"),
            surfmotion::batch::Format::Usda
        )
    );
    let frames = usda_frames(&want);
    assert!(frames > 1, "{frames} frames");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("batch.json")).unwrap()).unwrap();
    assert_eq!(s["done"], 1, "{s}");
    assert_eq!(s["outcomes"][0]["frames"], frames, "{s}");
    // A second run finds the output complete and skips it.
    let before = std::fs::metadata(&want).unwrap().modified().unwrap();
    run(&[]);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("batch.json")).unwrap()).unwrap();
    assert_eq!(s["skipped"], 1, "{s}");
    assert_eq!(
        std::fs::metadata(&want).unwrap().modified().unwrap(),
        before
    );
    // `--usd-no-normals` reaches the batch's writer: the same points, no
    // normals (the default file has one normal sample per frame).
    let bare = tmp.path().join("bare");
    run_into(&bare, &["--usd-no-normals"]);
    let (with, without) = (
        std::fs::read_to_string(&want).unwrap(),
        std::fs::read_to_string(bare.join("sub/run.usda")).unwrap(),
    );
    let points = |t: &str| {
        t.split("point3f[] points.timeSamples")
            .nth(1)
            .unwrap()
            .split("\n    }")
            .next()
            .unwrap()
            .to_string()
    };
    assert_eq!(points(&with), points(&without));
    assert!(with.contains("normal3f[] normals.timeSamples"));
    assert!(
        !without.contains("normal3f"),
        "normals written with --usd-no-normals"
    );
    assert_eq!(usda_frames(&bare.join("sub/run.usda")), frames);
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn mesh_convert_writes_usda_and_refuses_fbx_output() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("samba.usda");
    common::run_ok(
        std::process::Command::new(common::bin())
            .args(["mesh", "convert"])
            .arg(d.join("4d/samba/samba.pc2"))
            .arg(&out),
    );
    assert_eq!(usda_frames(&out), 175);
    // FBX is read (a rigged character), never written: refused up front.
    let o = std::process::Command::new(common::bin())
        .args(["mesh", "convert"])
        .arg(d.join("4d/samba/samba.obj"))
        .arg(tmp.path().join("samba.fbx"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("samba.fbx") && e.contains("not supported"),
        "{e}"
    );
    assert_eq!(e.trim().lines().count(), 1, "{e}");
}
