//! Issue 43 (session 31): the part deformation's example frames chosen
//! once per database and kept in `cache/examples.json` — on the real samba
//! capture, for several example counts: the frames read back are the ones
//! chosen (and the ones a choice without the memo makes); a memo whose
//! entries were changed under the right key is what the deformation takes
//! (so it is read, not chosen again); another key, a cut file, a frame out
//! of range are chosen again and the memo rewritten; a `retarget` with the
//! memo writes the same bytes as one without.

use super::samba_db;
use crate::common;

use std::path::Path;
use surfmotion::db::examples::examples_path;
use surfmotion::db::{Character, FlatFrame, Quiet};
use surfmotion::drive::{DriveOptions, Prepared};

/// Each region's examples of a fresh load of `db` prepared with `want`
/// examples a region.
fn chosen(db: &Path, want: usize) -> Vec<Vec<FlatFrame>> {
    let ch = Character::load(db, &Quiet).unwrap();
    let mut opts = DriveOptions::default();
    opts.deform_options.examples = want;
    let p = Prepared::new(&ch, &opts).unwrap();
    p.deformer().unwrap().examples.clone()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_deformation_examples_are_chosen_once_and_read_back() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let db = samba_db(&d, tmp.path());
    let path = examples_path(&db);
    for want in [40, 12, 3] {
        let _ = std::fs::remove_file(&path);
        let fresh = chosen(&db, want);
        assert!(path.exists(), "want {want}: no memo written");
        assert!(fresh.len() > 5, "want {want}: {} regions", fresh.len());
        assert!(
            fresh.iter().all(|r| !r.is_empty() && r.len() <= want),
            "want {want}: {fresh:?}"
        );
        let good = std::fs::read(&path).unwrap();
        let stamp = std::fs::metadata(&path).unwrap().modified().unwrap();
        // Read back: the same frames, the file not written again.
        assert_eq!(chosen(&db, want), fresh, "want {want}");
        assert_eq!(std::fs::read(&path).unwrap(), good);
        assert_eq!(
            std::fs::metadata(&path).unwrap().modified().unwrap(),
            stamp,
            "want {want}: rewritten"
        );
        // Changed under the right key: read as it is (one frame moved in
        // every entry).
        let mut v: serde_json::Value = serde_json::from_slice(&good).unwrap();
        for e in v["entries"].as_array_mut().unwrap() {
            let f = e["frames"][0].as_u64().unwrap();
            e["frames"][0] = serde_json::json!((f + 1) % 175);
        }
        std::fs::write(&path, serde_json::to_vec(&v).unwrap()).unwrap();
        let read = chosen(&db, want);
        assert_ne!(read, fresh, "want {want}: the memo was not read");
        assert!(
            read.iter()
                .zip(&fresh)
                .all(|(a, b)| a[1..] == b[1..] && a[0].index() == (b[0].index() + 1) % 175),
            "want {want}"
        );
        // Another key, a frame out of range, cut: chosen again, rewritten.
        let mut other = v.clone();
        other["key"] = serde_json::json!("0123456789abcdef");
        let mut out_of_range = serde_json::from_slice::<serde_json::Value>(&good).unwrap();
        out_of_range["entries"][0]["frames"][0] = serde_json::json!(175);
        let mut variants = vec![
            (
                "another key".to_string(),
                serde_json::to_vec(&other).unwrap(),
            ),
            (
                "a frame out of range".to_string(),
                serde_json::to_vec(&out_of_range).unwrap(),
            ),
        ];
        for c in [0, 1, good.len() / 3, good.len() / 2, good.len() - 1] {
            variants.push((format!("cut at {c}"), good[..c].to_vec()));
        }
        for (what, bytes) in variants {
            std::fs::write(&path, &bytes).unwrap();
            assert_eq!(chosen(&db, want), fresh, "want {want}, {what}");
            assert_eq!(std::fs::read(&path).unwrap(), good, "want {want}, {what}");
        }
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_retarget_with_the_example_memo_writes_the_same_bytes() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let db = samba_db(&d, tmp.path());
    let path = examples_path(&db);
    let clip = d.join("mocap/cmu-amc/02/02_01.amc");
    let run = |out: &Path| {
        retarget(&db, &clip, out);
        std::fs::read(out).unwrap()
    };
    let without = run(&tmp.path().join("a.pc2"));
    assert!(path.exists(), "the retarget wrote no memo");
    let with = run(&tmp.path().join("b.pc2"));
    assert!(with == without, "the memo changed the output");
}

/// `surfmotion retarget --db DB --mocap CLIP -o OUT`, which must succeed.
fn retarget(db: &Path, clip: &Path, out: &Path) {
    let r = common::run_cli(
        &[
            "retarget".as_ref(),
            "--db".as_ref(),
            db.as_os_str(),
            "--mocap".as_ref(),
            clip.as_os_str(),
            "-o".as_ref(),
            out.as_os_str(),
        ],
        None,
        &[],
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
}

/// Every file of `dir` with its bytes and modification time.
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>, std::time::SystemTime)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            let stamp = std::fs::metadata(&p).unwrap().modified().unwrap();
            (name, std::fs::read(&p).unwrap(), stamp)
        })
        .collect();
    v.sort_by(|a, b| a.0.cmp(&b.0));
    v
}

/// Issue 43 (session 32): `db build` prepares the character as a default
/// `retarget` does — the frame and skeleton caches, the rig, the
/// deformation's example memo and the plausibility reference are written
/// by the build, so a retarget after it writes nothing into the cache
/// (every file the same bytes and time, none added), for the database as
/// `db init` writes it and for one whose caches a retarget made first and
/// whose memo was then removed (the build writes it again).
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn db_build_writes_every_cache_a_retarget_reads() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let db = samba_db(&d, tmp.path());
    let cache = surfmotion::db::cache::cache_dir(&db);
    let clip = d.join("mocap/cmu-amc/02/02_01.amc");
    let retarget = |out: &str| retarget(&db, &clip, &tmp.path().join(out));
    let build = || {
        let r = common::run_cli(
            &["db".as_ref(), "build".as_ref(), db.as_os_str()],
            None,
            &[],
        );
        assert_eq!(r.code, Some(0), "{}", r.stderr);
        assert!(
            r.stdout.contains("prepared for retargeting"),
            "{}",
            r.stdout
        );
        r
    };
    for round in ["as db init wrote it", "memo removed after a retarget"] {
        if round != "as db init wrote it" {
            retarget("first.pc2");
            std::fs::remove_file(examples_path(&db)).unwrap();
        }
        let built = build();
        // A build that compares frames makes the rig, frame and skeleton
        // caches beside the comparison (issue 43); one whose similarity is
        // current leaves them to the preparation.
        assert_eq!(
            built.stdout.contains("rig, frames and skeletons cached in"),
            round == "as db init wrote it",
            "{round}: {}",
            built.stdout
        );
        for f in [
            "examples.json",
            "frames.bin",
            "poses-regressor.bin",
            "rig.json",
            "plausibility-reference.json",
        ] {
            assert!(cache.join(f).is_file(), "{round}: db build wrote no {f}");
        }
        let before = snapshot(&cache);
        // File times of a second apart at least on coarse file systems.
        std::thread::sleep(std::time::Duration::from_millis(1100));
        retarget("after.pc2");
        let after = snapshot(&cache);
        let names = |s: &[(String, Vec<u8>, std::time::SystemTime)]| {
            s.iter().map(|f| f.0.clone()).collect::<Vec<_>>()
        };
        assert_eq!(names(&after), names(&before), "{round}: files added");
        for (a, b) in before.iter().zip(&after) {
            assert!(
                a.1 == b.1 && a.2 == b.2,
                "{round}: {} rewritten by the retarget",
                a.0
            );
        }
    }
    // Without a rig: built, nothing prepared, no memo.
    let bare = tmp.path().join("bare");
    std::fs::create_dir(&bare).unwrap();
    let manifest = std::fs::read_to_string(db.join("character.toml")).unwrap();
    // `db init` writes absolute paths: the manifest without its [rig].
    let cut = manifest.split("\n[rig]").next().unwrap();
    assert!(cut.len() < manifest.len() && cut.contains("[[sequence]]"));
    std::fs::write(bare.join("character.toml"), cut).unwrap();
    let r = common::run_cli(
        &["db".as_ref(), "build".as_ref(), bare.as_os_str()],
        None,
        &[],
    );
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert!(!r.stdout.contains("prepared"), "{}", r.stdout);
    assert!(!examples_path(&bare).exists());
}
