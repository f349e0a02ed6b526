//! Issue 43 (session 40): `db build` chooses how far the sparse build's
//! sequence-pair scan reaches from an up-front estimate
//! (`surfmotion::similarity::scan`), says so in its report and in
//! `inspect`, and keys the cache by the choice.

use crate::common;
use std::path::Path;
use surfmotion::jobs::{SynthClip, SynthOptions, write_synthetic_database};
use surfmotion::synth::{Gait, gait_clip};

/// A generated database in `db`: the project's humanoid (coarse, 5 cm)
/// performing 20 short clips (walk, run and turn of 0.8-1.75 s at 20 fps,
/// 20 sequences: more than a reach of 16 covers).
fn twenty_clips(db: &Path) {
    let clips: Vec<SynthClip> = (0..20)
        .map(|k| {
            let g = Gait::ALL[k % 3];
            let clip = gait_clip(g, 0.8 + 0.05 * k as f64, 20.0);
            SynthClip::from_clip(&format!("{}{k:02}", g.name()), &clip).unwrap()
        })
        .collect();
    let opts = SynthOptions {
        fps: 20.0,
        name: Some("scan".into()),
        truth: false,
        plausibility: false,
        force: true,
        ..Default::default()
    };
    let character = common::humanoid_character(0.05);
    write_synthetic_database(db, &character, &clips, &opts, &mut |_, _| {}).unwrap();
}

/// `db build --similarity sparse --json` with `SURFMOTION_SPARSE=sparse`
/// (none when empty): the report's similarity cache flag and scan, and
/// what it printed.
fn build(db: &Path, sparse: &str) -> (bool, serde_json::Value, String) {
    let env: Vec<(&str, &str)> = if sparse.is_empty() {
        Vec::new()
    } else {
        vec![("SURFMOTION_SPARSE", sparse)]
    };
    let args = [
        "db".as_ref(),
        "build".as_ref(),
        db.as_os_str(),
        "--similarity".as_ref(),
        "sparse".as_ref(),
        "--json".as_ref(),
    ];
    let r = common::run_cli(&args, None, &env);
    assert_eq!(r.code, Some(0), "{sparse}: {}", r.stderr);
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    // Said up front, before the scan, as well as in the report.
    let cached = v["similarity_cached"].as_bool().unwrap();
    assert!(
        cached || r.stderr.contains("sequence-pair scan: "),
        "{sparse}: {}",
        r.stderr
    );
    (cached, v["scan"].clone(), r.stderr)
}

/// The full scan where it fits; a reach of 16 where the estimate is over
/// the budget (a budget of 1 MB here), reported with the estimates; a
/// reach given explicitly kept; and each build's cache never read as
/// another's: a database built with a chosen reach is rebuilt by a build
/// that keeps the full scan and the other way round, and `inspect` says
/// which scan the current cache holds.
#[test]
fn db_build_reports_the_scan_it_chose_and_keys_the_cache_by_it() {
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("db");
    twenty_clips(&db);
    let tight = "budget_memory=1";

    let (cached, full, said) = build(&db, "");
    assert!(!cached);
    assert!(!said.contains("sequence pairs scanned: "), "{said}");
    assert_eq!(full["reason"], "fits", "{full}");
    assert_eq!(full["chosen"]["reach"], 0, "{full}");
    assert_eq!(full["chosen"], full["full"], "{full}");
    assert_eq!(full["sequences"], 20);
    assert_eq!(full["full"]["sequence_pairs"], 210, "{full}");

    let (cached, bounded, said) = build(&db, tight);
    assert!(!cached, "the full scan's cache read for a bounded build");
    // The scan bounded: some pairs left to the far search.
    assert!(
        said.contains("(each sequence with the 16 it is most linked to); the far search"),
        "{said}"
    );
    assert_eq!(bounded["reason"], "over_budget", "{bounded}");
    assert_eq!(bounded["chosen"]["reach"], 16, "{bounded}");
    assert_eq!(bounded["budget_bytes"], 1_000_000);
    // (20 sequences: the estimate takes a reach of 16 for every pair.)
    let (scanned, far) = (
        bounded["chosen"]["sequence_pairs"].as_u64().unwrap(),
        bounded["chosen"]["far_pairs"].as_u64().unwrap(),
    );
    assert_eq!(scanned + far, 210, "{bounded}");
    assert!(
        bounded["full"]["bytes"].as_u64().unwrap() > 1_000_000,
        "{bounded}"
    );
    // Read back under the same choice.
    let (cached, again, _) = build(&db, tight);
    assert!(cached);
    assert_eq!(again, bounded);
    let inspect = common::run_cli(&["inspect".as_ref(), db.as_os_str()], None, &[]);
    assert!(
        inspect
            .stdout
            .contains("sparse-shape.bin: sparse similarity (shape); stale"),
        "{}",
        inspect.stdout
    );

    // A reach given explicitly wins over the rule, within the budget or not.
    let (cached, given, said) = build(&db, "budget_memory=1,reach=3");
    assert!(!cached);
    assert!(said.contains("with the 3 it is most linked to"), "{said}");
    assert_eq!(
        (&given["reason"], &given["chosen"]["reach"]),
        (&"given".into(), &3.into())
    );

    // Back to the default: the full scan again, rebuilt, and said so.
    let (cached, back, _) = build(&db, "");
    assert!(!cached, "a bounded build's cache read as the full scan's");
    assert_eq!(back, full);
    let inspect = common::run_cli(&["inspect".as_ref(), db.as_os_str()], None, &[]);
    assert!(
        inspect.stdout.contains("→ the full scan ("),
        "{}",
        inspect.stdout
    );
    assert!(
        inspect.stdout.contains("20 sequences"),
        "{}",
        inspect.stdout
    );
}
