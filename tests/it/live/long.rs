//! A replay looped five times (`--loop 5`) with the report's own samples
//! (`--sample-every`): every frame of every loop comes out, and the resident
//! memory and the output rate stay flat from the second sample on (the
//! one-hour run, `live --replay CLIP --loop N --sample-every 60`, is an
//! evaluation command: README, *Live*).

use crate::common;
use std::process::Command;

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn five_loops_keep_memory_and_rate_flat() {
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let clip = d.join("mocap/cmu-bvh-altered/02_01.bvh");
    let out = Command::new(env!("CARGO_BIN_EXE_surfmotion"))
        .args(["live", "--db"])
        .arg(&db)
        .arg("--replay")
        .arg(&clip)
        .args([
            "--speed",
            "0",
            "--loop",
            "5",
            "--sample-every",
            "1",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let frames = r["frames_out"].as_u64().unwrap();
    // 02_01 is 86 frames at the database's 30 fps.
    assert_eq!(frames, 5 * 86, "{r}");
    assert_eq!(r["input"]["received"].as_u64(), Some(frames), "{r}");
    let samples = r["samples"].as_array().unwrap();
    assert!(samples.len() >= 4, "{r}");
    let rss: Vec<f64> = samples
        .iter()
        .filter_map(|s| s["rss_mib"].as_f64())
        .collect();
    let fps: Vec<f64> = samples[..samples.len() - 1]
        .iter()
        .map(|s| s["output_fps"].as_f64().unwrap())
        .collect();
    eprintln!(
        "{} samples: RSS {rss:?} MiB, output {fps:?} frames/s",
        samples.len()
    );
    // Memory: after the first second (the character prepared, the buffers
    // grown), within 5 % of the second sample to the end.
    if rss.len() == samples.len() {
        let base = rss[1];
        assert!(
            rss[1..].iter().all(|m| (m - base).abs() <= 0.05 * base),
            "RSS not flat: {rss:?}"
        );
    }
    // Rate: no sample (the last, partial one aside) below a third of the
    // median (the machine is shared; a leak or a growing cost would slow
    // the later loops steadily).
    let mut sorted = fps.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    assert!(
        fps[1..].iter().all(|f| *f >= median / 3.0),
        "rate not flat: {fps:?}"
    );
}
