//! Issue 43 (session 31): `inspect` on every file a database's loads
//! write beside `db build`'s — the frame cache, the skeleton cache, the
//! plausibility reference, the content-hash memo and the example memo —
//! on the real samba capture: what each is, its database, its key against the one the next
//! load wants, up to date or stale; cut at many places or changed, a
//! one-line error naming the file (exit 1, never a panic) and "damaged" in
//! the database's listing; no file of the folder called "not a file db
//! build writes".

use crate::common;

use std::path::{Path, PathBuf};
use surfmotion::db::examples::examples_path;
use surfmotion::db::frames::{frames_path, poses_path};
use surfmotion::db::{Character, Quiet};
use surfmotion::drive::{DriveOptions, Prepared};
use surfmotion::embed::frames::SkeletonKind;
use surfmotion::tools::eval::plausibility::{Checker, PlausibilityOptions, reference_path};

/// A database of the samba capture (175 frames, the rig from the test
/// landmarks) in `dir/samba`, loaded once and its plausibility reference
/// measured, so that every load cache is in its cache folder.
fn loaded_samba(d: &Path, dir: &Path) -> PathBuf {
    let db = super::samba_db(d, dir);
    let ch = Character::load(&db, &Quiet).unwrap();
    Checker::for_character(&ch, PlausibilityOptions::default()).unwrap();
    Prepared::new(&ch, &DriveOptions::default()).unwrap();
    db
}

/// `inspect PATH --json`: exit code, report, stderr.
fn inspect_json(path: &Path) -> (Option<i32>, serde_json::Value, String) {
    let r = common::run_cli(
        &["inspect".as_ref(), path.as_os_str(), "--json".as_ref()],
        None,
        &[],
    );
    let v = serde_json::from_str(&r.stdout).unwrap_or(serde_json::Value::Null);
    (r.code, v, r.stderr)
}

/// The line of `inspect DB` naming `file`.
fn listed(db: &Path, file: &str) -> String {
    let r = common::run_cli(&["inspect".as_ref(), db.as_os_str()], None, &[]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    r.stdout
        .lines()
        .find(|l| l.contains(&format!(" {file}:")))
        .unwrap_or_else(|| panic!("no {file} line: {}", r.stdout))
        .to_string()
}

/// `bytes` written over `path`, then `inspect PATH` must fail in one line
/// naming the file, and the listing must call it damaged (`listing`:
/// whether the listing, which reads headers only, can see this change).
fn assert_damaged(db: &Path, path: &Path, bytes: &[u8], what: &str, listing: bool) {
    std::fs::write(path, bytes).unwrap();
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    let r = common::run_cli(&["inspect".as_ref(), path.as_os_str()], None, &[]);
    assert_eq!(r.code, Some(1), "{name} {what}: {}", r.stdout);
    assert_eq!(
        r.stderr.trim_end().lines().count(),
        1,
        "{name} {what}: {}",
        r.stderr
    );
    assert!(r.stderr.contains(&name), "{name} {what}: {}", r.stderr);
    assert!(r.stderr.contains("damaged"), "{name} {what}: {}", r.stderr);
    assert!(
        !r.stderr.contains("panicked"),
        "{name} {what}: {}",
        r.stderr
    );
    if listing {
        let line = listed(db, &name);
        assert!(line.contains("damaged"), "{name} {what}: {line}");
    }
}

/// Cut places of a file of `len` bytes whose header is `header` bytes.
fn cuts(len: usize, header: usize) -> Vec<usize> {
    let mut v = vec![
        0,
        1,
        7,
        8,
        15,
        16,
        header - 1,
        header,
        header + 1,
        len / 3,
        len / 2,
        len - 9,
        len - 8,
        len - 1,
    ];
    v.sort_unstable();
    v.dedup();
    v
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn inspect_says_what_each_load_cache_is_and_refuses_a_damaged_one() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let db = loaded_samba(&d, tmp.path());
    let frames = frames_path(&db);
    let poses = poses_path(&db, SkeletonKind::Regressor);
    let reference = reference_path(&db);
    let memo = db.join("cache/content-hashes.json");
    let examples = examples_path(&db);

    // Every file of the folder is one the tool writes.
    let all = common::run_cli(&["inspect".as_ref(), db.as_os_str()], None, &[]);
    assert_eq!(all.code, Some(0), "{}", all.stderr);
    assert!(
        !all.stdout.contains("not a file db build writes"),
        "{}",
        all.stdout
    );

    // Up to date: what, database, key = the database's, in text and JSON.
    let expect = [
        (&frames, "frame cache", Some(9971u64)),
        (&poses, "skeleton cache (regressor)", None),
        (&reference, "plausibility reference", None),
        (&memo, "content-hash memo", None),
        (&examples, "example memo", None),
    ];
    for (path, cache, vertices) in expect {
        let (code, v, err) = inspect_json(path);
        assert_eq!(code, Some(0), "{cache}: {err}");
        assert_eq!(v["kind"], "load_cache", "{v}");
        assert_eq!(v["cache"], cache, "{v}");
        assert_eq!(v["up_to_date"], true, "{cache}: {v}");
        assert!(
            v["state"].as_str().unwrap().starts_with("up to date"),
            "{v}"
        );
        assert_eq!(
            v["database"].as_str().map(PathBuf::from),
            Some(db.clone()),
            "{v}"
        );
        if cache != "content-hash memo" {
            assert_eq!(v["key"], v["wanted_key"], "{cache}: {v}");
            assert_eq!(v["frames"], 175, "{cache}: {v}");
        }
        if let Some(n) = vertices {
            assert_eq!(v["vertices"], n, "{v}");
        }
        let text = common::run_cli(&["inspect".as_ref(), path.as_os_str()], None, &[]);
        assert!(
            text.stdout.contains(&format!("({cache})"))
                && text.stdout.contains("state       up to date"),
            "{}",
            text.stdout
        );
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let line = listed(&db, &name);
        assert!(line.contains("up to date"), "{line}");
    }

    // Stale: another key in a consistent header (frames, poses) or file
    // (the reference); exit 0, "stale" in the report and the listing.
    let good_frames = std::fs::read(&frames).unwrap();
    let good_poses = std::fs::read(&poses).unwrap();
    let good_ref = std::fs::read_to_string(&reference).unwrap();
    for (path, good) in [(&frames, &good_frames), (&poses, &good_poses)] {
        let mut b = good.clone();
        b[8] ^= 0x5a;
        std::fs::write(path, &b).unwrap();
        let (code, v, err) = inspect_json(path);
        assert_eq!(code, Some(0), "{err}");
        assert!(v["state"].as_str().unwrap().starts_with("stale"), "{v}");
        assert_ne!(v["key"], v["wanted_key"], "{v}");
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        assert!(listed(&db, &name).contains("stale"));
        std::fs::write(path, good).unwrap();
    }
    let key = &good_ref[good_ref.find("\"key\":").unwrap() + 6..];
    let key = &key[..key.find(',').unwrap()];
    // The last digit moved by one (a u64 still).
    let last = key.as_bytes()[key.len() - 1] - b'0';
    let other = format!("{}{}", &key[..key.len() - 1], (last + 1) % 10);
    std::fs::write(
        &reference,
        good_ref.replacen(&format!("\"key\":{key},"), &format!("\"key\":{other},"), 1),
    )
    .unwrap();
    let (code, v, err) = inspect_json(&reference);
    assert_eq!(code, Some(0), "{err}");
    assert!(v["state"].as_str().unwrap().starts_with("stale"), "{v}");
    std::fs::write(&reference, &good_ref).unwrap();

    // A copy elsewhere: what it is by its magic, its key not judged.
    for (good, name) in [
        (&good_frames, "copy-frames.bin"),
        (&good_poses, "copy-poses.bin"),
    ] {
        let copy = tmp.path().join(name);
        std::fs::write(&copy, good).unwrap();
        let (code, v, err) = inspect_json(&copy);
        assert_eq!(code, Some(0), "{err}");
        assert_eq!(v["kind"], "load_cache", "{v}");
        assert_eq!(v["database"], serde_json::Value::Null, "{v}");
        assert_eq!(v["up_to_date"], false, "{v}");
    }

    // Cut: every kind, at the header's edges and through the body.
    for (path, good, header) in [
        (&frames, good_frames.clone(), 64),
        (&poses, good_poses.clone(), 32),
        (&reference, good_ref.clone().into_bytes(), 20),
        (&memo, std::fs::read(&memo).unwrap(), 20),
        (&examples, std::fs::read(&examples).unwrap(), 20),
    ] {
        for c in cuts(good.len(), header) {
            assert_damaged(&db, path, &good[..c], &format!("cut at {c}"), true);
        }
        std::fs::write(path, &good).unwrap();
    }

    // Changed in place (same length): a frame's lowest point lowered, a
    // coordinate or a joint made not a number, at the first, a middle and
    // the last frame; the frame checks are read by `inspect` of the file.
    let n = 9971;
    let low_vertex = |f: usize| {
        let at = |v: usize| 64 + (f * n + v) * 24 + 8;
        (0..n)
            .min_by(|&a, &b| {
                let y = |v| f64::from_le_bytes(good_frames[at(v)..at(v) + 8].try_into().unwrap());
                y(a).total_cmp(&y(b))
            })
            .map(at)
            .unwrap()
    };
    for f in [0, 87, 174] {
        let mut lowered = good_frames.clone();
        let at = low_vertex(f);
        let y = f64::from_le_bytes(lowered[at..at + 8].try_into().unwrap()) - 0.01;
        lowered[at..at + 8].copy_from_slice(&y.to_le_bytes());
        assert_damaged(&db, &frames, &lowered, &format!("frame {f} lowered"), false);
        let mut nan = good_frames.clone();
        let at = 64 + (f * n + f * 7) * 24;
        nan[at..at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
        assert_damaged(&db, &frames, &nan, &format!("frame {f} NaN"), false);
        let mut joint = good_poses.clone();
        let at = 32 + (f * 19 + 5) * 24 + 8;
        joint[at..at + 8].copy_from_slice(&f64::INFINITY.to_le_bytes());
        assert_damaged(&db, &poses, &joint, &format!("pose {f} infinite"), true);
        std::fs::write(&poses, &good_poses).unwrap();
    }
    std::fs::write(&frames, &good_frames).unwrap();
    // Not JSON any more: a brace changed.
    assert_damaged(
        &db,
        &reference,
        good_ref.replacen('{', "[", 1).as_bytes(),
        "a brace changed",
        true,
    );
    std::fs::write(&reference, &good_ref).unwrap();

    // A load mends what it reads: the frame cache cut, then loaded.
    std::fs::write(&frames, &good_frames[..good_frames.len() / 2]).unwrap();
    drop(Character::load(&db, &Quiet).unwrap());
    assert_eq!(std::fs::read(&frames).unwrap(), good_frames);
}
