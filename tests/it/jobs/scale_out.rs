//! Scaling `batch` out (issue 43): shards taken from a Slurm array's or a
//! Kubernetes Indexed Job's environment, `batch merge` of the shards'
//! reports equal to one unsharded run, a split that is not whole refused,
//! and `scripts/slurm-local.sh` through a real Slurm where one is installed.

use super::batch::{hbatch, hbatch_cmd, library, ok, summary};
use crate::common;
use std::path::Path;
use std::process::{Command, Output};

const CLIPS: [&str; 9] = [
    "a.bvh",
    "b.bvh",
    "c.bvh",
    "walks/w1.bvh",
    "walks/w2.bvh",
    "walks/w3.bvh",
    "runs/deep/r1.bvh",
    "runs/r2.bvh",
    "z.bvh",
];

fn merge(dirs: &[&Path], extra: &[&str]) -> Output {
    Command::new(common::bin())
        .args(["batch", "merge"])
        .args(dirs)
        .args(extra)
        .output()
        .unwrap()
}

fn fails(o: &Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).to_string();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// What a report says of each clip, outputs relative to `dir`.
fn view(dir: &Path) -> Vec<serde_json::Value> {
    let s = summary(dir, "batch.json");
    s["outcomes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|o| {
            let out = Path::new(o["output"].as_str().unwrap());
            let rel = out.strip_prefix(dir).unwrap().display().to_string();
            serde_json::json!([
                o["clip"],
                rel,
                o["status"],
                o["frames"],
                o["error_cm"],
                o["warnings"]
            ])
        })
        .collect()
}

fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if matches!(p.extension().and_then(|x| x.to_str()), Some("pc2" | "obj")) {
                let rel = p.strip_prefix(dir).unwrap().display().to_string();
                out.push((rel, std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

/// Three tasks of a Slurm array `--array=5-9:2` (ids 5, 7, 9) shard the
/// library from their environment alone, into one folder; `batch merge`
/// makes the report one run writes, and the outputs are those of one run
/// byte for byte.
#[test]
fn a_slurm_array_merged_equals_one_run() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &CLIPS, 8);
    let whole = tmp.path().join("whole");
    ok(&hbatch(&lib, &whole, &["--format", "pc2", "--jobs", "1"]));
    let sharded = tmp.path().join("sharded");
    let mut per_shard = Vec::new();
    for (k, id) in ["5", "7", "9"].iter().enumerate() {
        let o = hbatch_cmd(&lib, &sharded, &["--format", "pc2", "--jobs", "1"])
            .env("SLURM_ARRAY_TASK_ID", id)
            .env("SLURM_ARRAY_TASK_MIN", "5")
            .env("SLURM_ARRAY_TASK_MAX", "9")
            .env("SLURM_ARRAY_TASK_STEP", "2")
            .env("SLURM_ARRAY_TASK_COUNT", "3")
            .output()
            .unwrap();
        let err = ok(&o);
        let i = k + 1;
        assert!(
            err.contains(&format!("shard {i}/3 from the Slurm array")),
            "{err}"
        );
        let s = summary(&sharded, &format!("batch-{i}of3.json"));
        assert_eq!(s["library_clips"], CLIPS.len());
        per_shard.push(s["clips"].as_u64().unwrap());
    }
    // The hash split leaves no shard of these nine empty.
    assert!(per_shard.iter().all(|&n| n > 0), "{per_shard:?}");
    let err = ok(&merge(&[&sharded], &[]));
    assert!(err.is_empty(), "{err}");
    assert_eq!(view(&sharded), view(&whole));
    assert_eq!(view(&whole).len(), CLIPS.len());
    let (a, b) = (files(&whole), files(&sharded));
    assert_eq!(a.len(), 2 * CLIPS.len());
    assert!(a == b, "outputs differ");
    let m = summary(&sharded, "batch.json");
    assert_eq!(m["merged_from"].as_array().unwrap().len(), 3);
    assert_eq!(m["shard"], serde_json::Value::Null);
    let page = std::fs::read_to_string(sharded.join("batch.html")).unwrap();
    assert!(page.contains("Merged from 3 shard reports"), "{page}");
    // Merging again replaces the merged report; the whole run's own
    // report is never replaced.
    ok(&merge(&[&sharded], &[]));
    let e = fails(&merge(&[&sharded], &["-o", whole.to_str().unwrap()]));
    assert!(e.contains("report of an unsharded run"), "{e}");
}

/// A Kubernetes Indexed Job (JOB_COMPLETION_INDEX and --shard-count), one
/// folder per pod: merged with -o; a missing, doubled or unfinished shard
/// is refused with the reason.
#[test]
fn an_indexed_job_merges_and_an_incomplete_split_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &CLIPS[..5], 6);
    let pods: Vec<_> = (0..2).map(|i| tmp.path().join(format!("pod{i}"))).collect();
    for (i, out) in pods.iter().enumerate() {
        let o = hbatch_cmd(&lib, out, &["--shard-count", "2", "--format", "pc2"])
            .env("JOB_COMPLETION_INDEX", i.to_string())
            .output()
            .unwrap();
        let err = ok(&o);
        assert!(err.contains("Kubernetes Indexed Job"), "{err}");
    }
    let merged = tmp.path().join("merged");
    let (p0, p1) = (pods[0].as_path(), pods[1].as_path());
    let e = fails(&merge(&[p0, p1], &[]));
    assert!(e.contains("give -o"), "{e}");
    let o = merge(&[p0, p1], &["-o", merged.to_str().unwrap(), "--json"]);
    ok(&o);
    let s: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (s["clips"].as_u64(), s["done"].as_u64()),
        (Some(5), Some(5))
    );
    // A shard missing.
    let e = fails(&merge(&[p0], &[]));
    assert!(e.contains("missing shard 2/2"), "{e}");
    // One shard twice (its report copied into the other folder).
    std::fs::copy(p0.join("batch-1of2.json"), p1.join("batch-1of2.json")).unwrap();
    let e = fails(&merge(&[p0, p1], &["-o", merged.to_str().unwrap()]));
    assert!(e.contains("shard 1/2 twice"), "{e}");
    std::fs::remove_file(p1.join("batch-1of2.json")).unwrap();
    // A shard killed before its end.
    let r = p1.join("batch-2of2.json");
    let text = std::fs::read_to_string(&r).unwrap();
    std::fs::write(
        &r,
        text.replace("\"finished\": true", "\"finished\": false"),
    )
    .unwrap();
    let e = fails(&merge(&[p0, p1], &["-o", merged.to_str().unwrap()]));
    assert!(e.contains("shard 2/2 has not finished"), "{e}");
    // A shard of another split.
    std::fs::write(&r, &text).unwrap();
    std::fs::copy(&r, p1.join("batch-3of3.json")).unwrap();
    let e = fails(&merge(&[p0, p1], &["-o", merged.to_str().unwrap()]));
    assert!(e.contains("records shard 2/2"), "{e}");
}

/// Scheduler settings that contradict each other are one-line errors
/// before anything is read; `--shard` wins over the environment.
#[test]
fn scheduler_conflicts_are_one_line_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &CLIPS[..3], 4);
    let out = tmp.path().join("out");
    let run = |extra: &[&str], env: &[(&str, &str)]| {
        let mut c = hbatch_cmd(&lib, &out, extra);
        for (k, v) in env {
            c.env(k, v);
        }
        c.output().unwrap()
    };
    type Case<'a> = (&'a [&'a str], &'a [(&'a str, &'a str)], &'a str);
    let cases: [Case; 5] = [
        (&[], &[("JOB_COMPLETION_INDEX", "1")], "not --shard-count"),
        (&["--shard-count", "3"], &[], "needs a shard index"),
        (
            &["--shard", "1/2", "--shard-count", "3"],
            &[],
            "different splits",
        ),
        (
            &[],
            &[
                ("SLURM_ARRAY_TASK_ID", "1"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
                ("JOB_COMPLETION_INDEX", "0"),
            ],
            "the Slurm array says shard 2/2",
        ),
        (
            &["--shard-count", "3"],
            &[
                ("SLURM_ARRAY_TASK_ID", "0"),
                ("SLURM_ARRAY_TASK_COUNT", "2"),
            ],
            "disagrees with the Slurm array",
        ),
    ];
    for (extra, env, want) in cases {
        let e = fails(&run(extra, env));
        assert!(e.contains(want), "{extra:?} {env:?}: {e}");
        assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    }
    assert!(!out.exists(), "nothing written");
    // --shard wins over the array, and says so.
    let err = ok(&run(
        &["--shard", "1/1"],
        &[
            ("SLURM_ARRAY_TASK_ID", "1"),
            ("SLURM_ARRAY_TASK_COUNT", "2"),
        ],
    ));
    assert!(err.contains("wins over SLURM_ARRAY_TASK_ID=1"), "{err}");
    assert_eq!(summary(&out, "batch-1of1.json")["clips"], 3);
}

/// `scripts/slurm-local.sh` brings up Slurm, runs a 4-task array and checks
/// the merged report against one run. Runs where `sbatch` is installed and
/// the tests run as root (`.ci/run` installs Slurm when it is root); says
/// why it did not run otherwise.
#[test]
fn the_slurm_script_runs_a_real_array() {
    let has_sbatch = Command::new("sh")
        .args(["-c", "command -v sbatch"])
        .output()
        .is_ok_and(|o| o.status.success());
    let root = Command::new("id")
        .arg("-u")
        .output()
        .is_ok_and(|o| o.stdout.trim_ascii() == b"0");
    if !(has_sbatch && root) {
        eprintln!("the_slurm_script_runs_a_real_array: not run (needs sbatch and root)");
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let lib = tmp.path().join("lib");
    library(&lib, &CLIPS, 6);
    // The procedural humanoid of the batch tests as the target (no data).
    let (mesh, lm) = super::batch::humanoid();
    let o = Command::new("bash")
        .arg(format!(
            "{}/scripts/slurm-local.sh",
            env!("CARGO_MANIFEST_DIR")
        ))
        .arg(tmp.path().join("slurm"))
        .env("LIB", &lib)
        .env(
            "TARGET",
            format!("--scan {} --landmarks {}", mesh.display(), lm.display()),
        )
        .env("BIN", common::bin())
        // Beside a Slurm of the script's default ports, if one runs.
        .env("PORT", "16917")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{text}");
    assert!(
        text.contains(&format!("OK: {} clips", CLIPS.len())),
        "{text}"
    );
}
