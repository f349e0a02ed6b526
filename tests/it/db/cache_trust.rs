//! Issue 43 (session 30): the caches a user can trust, on the real samba
//! capture. `SURFMOTION_SPARSE` is judged on every `db build`, also when
//! the cache is current; `inspect` says what `cache/rig.json` is (which
//! rig, its key, up to date or stale against the database and the code)
//! and refuses a damaged one in one line naming it; the skeleton cache's
//! key carries the code's fingerprint, so a cache another build wrote is
//! rebuilt, not read.

use super::samba_db;
use crate::common;

use std::path::Path;
use surfmotion::db::frames::{keys, keys_of_code, poses_path};
use surfmotion::db::rig_cache::rig_path;
use surfmotion::db::{Character, Manifest, Quiet};
use surfmotion::embed::frames::SkeletonKind;

/// Each cache file's name and modification time.
fn stamps(db: &Path) -> Vec<(String, std::time::SystemTime)> {
    let mut v: Vec<_> = std::fs::read_dir(db.join("cache"))
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let t = e.metadata().unwrap().modified().unwrap();
            (e.file_name().to_string_lossy().into_owned(), t)
        })
        .collect();
    v.sort();
    v
}

/// `db build` with a `SURFMOTION_SPARSE` that cannot be read, on a
/// current cache (dense, then sparse): the warning a fresh build prints,
/// naming the variable and the value, exit 0 as before, and no cache file
/// written again.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_bad_sparse_variable_is_warned_about_on_a_current_cache() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let db = samba_db(&d, tmp.path());
    let dbs = db.to_str().unwrap();
    for method in ["dense", "sparse"] {
        let args = ["db", "build", dbs, "--similarity", method];
        let fresh = common::run_cli(&args, None, &[]);
        assert_eq!(fresh.code, Some(0), "{}", fresh.stderr);
        let before = stamps(&db);
        for bad in ["cover=abc", "covr=32", "bogus", "cover=-1", "pool=1e3"] {
            let r = common::run_cli(&args, None, &[("SURFMOTION_SPARSE", bad)]);
            assert_eq!(r.code, Some(0), "{method} {bad}: {}", r.stderr);
            let warned: Vec<&str> = r
                .stderr
                .lines()
                .filter(|l| l.contains("SURFMOTION_SPARSE"))
                .collect();
            assert_eq!(warned.len(), 1, "{method} {bad}: {}", r.stderr);
            let name = bad.split('=').next().unwrap();
            assert!(
                warned[0].contains(name) && warned[0].contains("default sparse options are used"),
                "{method} {bad}: {}",
                warned[0]
            );
            assert!(!r.stderr.contains("panicked"), "{}", r.stderr);
            assert!(
                r.stdout.contains("similarity: cached") && r.stdout.contains("(cached)"),
                "{method} {bad}: {}",
                r.stdout
            );
            assert_eq!(stamps(&db), before, "{method} {bad}: a cache was written");
        }
        // A good value is silent.
        let r = common::run_cli(&args, None, &[("SURFMOTION_SPARSE", "cover=16")]);
        assert!(!r.stderr.contains("SURFMOTION_SPARSE"), "{}", r.stderr);
    }
}

/// The `inspect --json` report of `path` and the exit code.
fn inspect_json(path: &Path) -> (Option<i32>, serde_json::Value, String) {
    let r = common::run_cli(
        &["inspect".as_ref(), path.as_os_str(), "--json".as_ref()],
        None,
        &[],
    );
    let v = serde_json::from_str(&r.stdout).unwrap_or(serde_json::Value::Null);
    (r.code, v, r.stderr)
}

/// The rig cache's line of `inspect DB`.
fn listed(db: &Path) -> String {
    let r = common::run_cli(&["inspect".as_ref(), db.as_os_str()], None, &[]);
    r.stdout
        .lines()
        .find(|l| l.contains("rig.json"))
        .unwrap_or_else(|| panic!("no rig.json line: {}", r.stdout))
        .to_string()
}

/// `inspect` of a loaded samba database's `cache/rig.json`, text and JSON,
/// and of the database: the rig cache, its rig's landmarks, its key (the
/// database's), up to date; stale by its header's key, with the cause
/// (other code, other inputs) told apart; a copy elsewhere checked against
/// its own bytes; cut at ten places or a digit changed: exit 1 with one
/// line naming the file, never a panic, and "damaged" in the listing.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn inspect_says_what_the_rig_cache_is_and_refuses_a_damaged_one() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let db = samba_db(&d, tmp.path());
    drop(Character::load(&db, &Quiet).unwrap());
    let path = rig_path(&db);
    let good = std::fs::read(&path).unwrap();

    let (code, v, err) = inspect_json(&path);
    assert_eq!(code, Some(0), "{err}");
    assert_eq!(v["kind"], "rig_cache", "{v}");
    assert_eq!(v["up_to_date"], true, "{v}");
    assert_eq!(v["state"], "up to date");
    assert_eq!(v["head"]["key"], v["wanted_key"]);
    assert_eq!(v["head"]["source"], v["this_source"]);
    assert_eq!(v["vertices"], 9971);
    assert!(
        v["rig"][0]
            .as_str()
            .unwrap()
            .contains("samba.landmarks.json"),
        "{v}"
    );
    let text = common::run_cli(&["inspect".as_ref(), path.as_os_str()], None, &[]);
    assert!(text.stdout.contains("(rig cache)"), "{}", text.stdout);
    assert!(
        text.stdout.contains("state       up to date"),
        "{}",
        text.stdout
    );
    let line = listed(&db);
    assert!(
        line.contains("rig cache") && line.ends_with("up to date"),
        "{line}"
    );

    // A copy elsewhere: what it is, its key not judged.
    let copy = tmp.path().join("elsewhere.json");
    std::fs::write(&copy, &good).unwrap();
    let (code, v, _) = inspect_json(&copy);
    assert_eq!(
        (code, &v["database"]),
        (Some(0), &serde_json::Value::Null),
        "{v}"
    );
    assert_eq!(v["up_to_date"], false);

    // Another key (a consistent header): stale, the cause from the code's
    // fingerprint in the header.
    let nl = good.iter().position(|&b| b == b'\n').unwrap();
    let head = std::str::from_utf8(&good[..nl]).unwrap();
    let key = &head[head.find("\"key\":\"").unwrap() + 7..][..16];
    let source = &head[head.find("\"source\":\"").unwrap() + 10..][..16];
    for (other_source, cause) in [
        (source.to_string(), "rig inputs changed"),
        ("0123456789abcdef".to_string(), "other embedding code"),
    ] {
        let h = head
            .replace(key, "fedcba9876543210")
            .replace(source, &other_source);
        std::fs::write(&path, [h.as_bytes(), &good[nl..]].concat()).unwrap();
        let (code, v, err) = inspect_json(&path);
        assert_eq!(code, Some(0), "{err}");
        let state = v["state"].as_str().unwrap();
        assert!(
            state.starts_with("stale") && state.contains(cause),
            "{state}"
        );
        assert!(listed(&db).contains(cause));
    }

    // Cut or changed: one line naming the file, exit 1; damaged in the list.
    let mut digit = good.clone();
    let at = nl + 1 + good[nl + 1..].iter().position(u8::is_ascii_digit).unwrap();
    digit[at] = if digit[at] == b'1' { b'2' } else { b'1' };
    let cuts = [
        0,
        1,
        10,
        nl / 2,
        nl,
        nl + 1,
        nl + 2,
        good.len() / 2,
        good.len() - 2,
        good.len() - 1,
    ];
    let variants = cuts
        .iter()
        .map(|&c| (format!("cut at {c}"), good[..c].to_vec()))
        .chain([("a digit changed".to_string(), digit)]);
    for (what, bytes) in variants {
        std::fs::write(&path, &bytes).unwrap();
        let r = common::run_cli(&["inspect".as_ref(), path.as_os_str()], None, &[]);
        assert_eq!(r.code, Some(1), "{what}: {}", r.stdout);
        assert_eq!(
            r.stderr.trim_end().lines().count(),
            1,
            "{what}: {}",
            r.stderr
        );
        assert!(r.stderr.contains("rig.json"), "{what}: {}", r.stderr);
        assert!(!r.stderr.contains("panicked"), "{what}: {}", r.stderr);
        let line = listed(&db);
        assert!(line.contains("damaged"), "{what}: {line}");
    }
    // A load mends it.
    drop(Character::load(&db, &Quiet).unwrap());
    assert_eq!(std::fs::read(&path).unwrap(), good);
}

/// The skeleton cache written by another build (another code fingerprint
/// in its key) is rebuilt, not read: its skeletons tampered with, a load
/// gives the true ones and writes the file again; the same tampered file
/// under this build's key is read (the tampering is visible), and another
/// `[rig] rest` frame changes the key too.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_skeleton_cache_of_other_code_is_rebuilt_not_read() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let db = samba_db(&d, tmp.path());
    let ch = Character::load(&db, &Quiet).unwrap();
    let truth = ch.poses().to_vec();
    let metres = ch.metres_per_unit();
    drop(ch);
    let m = Manifest::load(&db).unwrap();
    let kind = SkeletonKind::Regressor;
    let (_, key) = keys(&db, &m, metres, kind).unwrap();
    let (_, other) = keys_of_code(&db, &m, metres, kind, "another build").unwrap();
    assert_ne!(key, other, "the code's fingerprint is not in the key");
    let path = poses_path(&db, kind);
    let good = std::fs::read(&path).unwrap();
    assert_eq!(&good[8..16], &key.to_le_bytes());
    // Every coordinate moved by 1 m.
    let mut tampered = good.clone();
    for c in tampered[32..].chunks_exact_mut(8) {
        let v = f64::from_le_bytes(c.try_into().unwrap()) + 1.0;
        c.copy_from_slice(&v.to_le_bytes());
    }
    // Under this build's key it is read: the tampering shows.
    std::fs::write(&path, &tampered).unwrap();
    let read = Character::load(&db, &Quiet).unwrap();
    assert_ne!(read.poses(), &truth[..], "the tampered cache was not read");
    drop(read);
    // Under another build's key it is rebuilt.
    tampered[8..16].copy_from_slice(&other.to_le_bytes());
    std::fs::write(&path, &tampered).unwrap();
    let rebuilt = Character::load(&db, &Quiet).unwrap();
    assert_eq!(rebuilt.poses(), &truth[..]);
    assert_eq!(std::fs::read(&path).unwrap(), good);
    drop(rebuilt);
    // Another rest frame: another rig, another key.
    let text = std::fs::read_to_string(db.join("character.toml")).unwrap();
    let rest = text.replace("[rig]\n", "[rig]\nrest = \"dance:40\"\n");
    assert_ne!(rest, text);
    std::fs::write(db.join("character.toml"), rest).unwrap();
    let m = Manifest::load(&db).unwrap();
    assert_ne!(keys(&db, &m, metres, kind).unwrap().1, key);
}
