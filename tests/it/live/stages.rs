//! The report's stage breakdown (`live --report`, `--json`): each stage of
//! a frame (analysis, retrieval, timeline and placement, blending,
//! deformation) timed one after the other, so the stages' means add up to
//! the mesh work's mean; the fold repair's frames counted apart. No timed
//! assertion: the figures themselves go in the README.

use crate::common;
use std::process::Command;

fn live(args: &[&str]) -> std::process::Output {
    let Some(d) = common::data_dir() else {
        unreachable!("checked by the caller")
    };
    let db = common::synthetic_db(&d);
    let clip = d.join("mocap/cmu-bvh-altered/02_01.bvh");
    Command::new(env!("CARGO_BIN_EXE_surfmotion"))
        .args(["live", "--db"])
        .arg(&db)
        .arg("--replay")
        .arg(&clip)
        .args(["--speed", "0"])
        .args(args)
        .output()
        .unwrap()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn stages_add_up_to_the_mesh_work() {
    if common::data_dir().is_none() {
        return;
    }
    let out = live(&["--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let stages = r["stages"]["stages"]
        .as_array()
        .expect("stages in the report");
    let names: Vec<&str> = stages
        .iter()
        .map(|s| s["stage"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "analysis",
            "retrieval",
            "timeline+placement",
            "blending",
            "deformation"
        ],
        "{r}"
    );
    let sum: f64 = stages.iter().map(|s| s["mean_ms"].as_f64().unwrap()).sum();
    let work = r["work_mean_ms"].as_f64().unwrap();
    eprintln!(
        "stages {sum:.3} ms against mesh work {work:.3} ms: {}",
        r["stages"]
    );
    assert!(work > 0.0, "{r}");
    // The stages tile the work: only the hand-over between the session and
    // the report's clocks lies outside them. Measured under a load average
    // of ~17 on 2 cores: 31.6 ms of stages against 34.4 ms of work (8 %
    // apart, not yet explained: a preemption in the untimed hand-over?),
    // hence the 15 % + 0.5 ms.
    assert!(
        (sum - work).abs() <= 0.15 * work + 0.5,
        "stages {sum} ms, work {work} ms"
    );
    for s in stages {
        for k in ["median_ms", "p99_ms", "max_ms", "mean_ms", "cpu_mean_ms"] {
            let v = s[k].as_f64().unwrap();
            assert!(v.is_finite() && v >= 0.0, "{k} of {s}");
        }
        assert!(
            s["p99_ms"].as_f64() <= s["max_ms"].as_f64().map(|m| m + 0.05),
            "{s}"
        );
    }
    // Every stage but retrieval does real work on 10K vertices.
    let deform = &stages[4];
    assert!(deform["mean_ms"].as_f64().unwrap() > 0.0, "{deform}");
    let frames = r["frames_out"].as_u64().unwrap();
    assert!(
        r["stages"]["repaired_frames"].as_u64().unwrap() <= frames,
        "{r}"
    );
    assert_eq!(r["output"]["frames"].as_u64(), Some(frames), "{r}");
    // The repair's work per frame: counts, so none without a repaired
    // frame, and a patch system has at least one unknown.
    let per = |k: &str| r["stages"][k].as_f64().unwrap_or(-1.0);
    let (patches, unknowns) = (
        per("patch_solves_per_frame"),
        per("patch_unknowns_per_frame"),
    );
    assert!(patches >= 0.0 && unknowns >= patches, "{r}");
    assert!(per("projections_per_frame") >= 0.0, "{r}");
    if r["stages"]["repaired_frames"].as_u64() == Some(0) {
        assert_eq!(patches, 0.0, "{r}");
    }
    // The repair's budget in force (live's default) and what it cost.
    assert_eq!(
        r["repair_budget"].as_str(),
        Some(surfmotion::deform::RepairBudget::LIVE.to_string().as_str()),
        "{r}"
    );
    let reached = r["stages"]["budget_reached_frames"].as_u64().unwrap();
    assert!(reached <= frames, "{r}");
    assert!(r["turned_over"].as_u64().is_some(), "{r}");

    // The text report shows the same breakdown.
    let out = live(&["--report"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for n in names {
        assert!(text.contains(n), "{n} missing from:\n{text}");
    }
    assert!(text.contains("fold repair on"), "{text}");
    let budget = format!(
        "fold repair budget: {};",
        surfmotion::deform::RepairBudget::LIVE
    );
    assert!(text.contains(&budget), "{text}");

    // Unbounded: said so, and never stopped at a bound.
    let out = live(&["--json", "--repair-budget", "none"]);
    assert!(out.status.success());
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(r["repair_budget"].as_str(), Some("none"), "{r}");
    assert_eq!(
        r["stages"]["budget_reached_frames"].as_u64(),
        Some(0),
        "{r}"
    );
}
