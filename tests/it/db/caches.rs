//! Issue 43: a database's caches at scale. Cache keys of long files come
//! from their length and the hash of all their bytes, remembered in
//! `cache/content-hashes.json` by path, length and times: a sequence
//! rewritten in place (even with its length and modification time put
//! back) invalidates the frame cache; one only touched, or a copy of the
//! database made without its files' times (`cp -r`), keeps every cache.
//! The plausibility reference is measured from the mapped frames (no copy)
//! and cached: both equal the figures of the copy-every-frame computation
//! bit for bit.

use crate::common;

use glam::DVec3;
use std::path::{Path, PathBuf};
use surfmotion::db::cache::{cache_dir, memo_path};
use surfmotion::db::content::SETTLE_SECONDS;
use surfmotion::db::frames::frames_path;
use surfmotion::db::{Character, Quiet};
use surfmotion::pose::retarget::character_neutral;
use surfmotion::tools::eval::plausibility::reference_path;
use surfmotion::tools::eval::{Checker, PlausibilityOptions, floor_height, lowest_heights};

/// The samba capture as a database whose sequence is a copy inside its
/// folder (so that the test may rewrite it, and copy the folder) in
/// `fixture_dir(name)`.
fn samba_copy(d: &Path, name: &str) -> (PathBuf, PathBuf) {
    let dir = common::fixture_dir(name);
    let db = dir.join("db");
    let _ = std::fs::remove_dir_all(&db);
    std::fs::create_dir_all(&db).unwrap();
    let pc2 = db.join("samba.pc2");
    std::fs::copy(d.join("4d/samba/samba.pc2"), &pc2).unwrap();
    let landmarks =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json");
    let toml = format!(
        "name = \"samba_copy\"\ntopology = {:?}\nfps = 30.0\nunits = \"m\"\nup = \"y\"\n\n[[sequence]]\nname = \"dance\"\npath = \"samba.pc2\"\n\n[rig]\nlandmarks = {:?}\n",
        d.join("4d/samba/samba.obj"),
        landmarks
    );
    std::fs::write(db.join("character.toml"), toml).unwrap();
    (db, pc2)
}

fn modified(p: &Path) -> std::time::SystemTime {
    std::fs::metadata(p).unwrap().modified().unwrap()
}

fn set_modified(p: &Path, t: std::time::SystemTime) {
    std::fs::File::options()
        .write(true)
        .open(p)
        .unwrap()
        .set_modified(t)
        .unwrap();
}

/// Each cache file of `db` (but the content-hash memo) with its time.
fn cache_times(db: &Path) -> Vec<(String, std::time::SystemTime)> {
    let mut v: Vec<_> = std::fs::read_dir(cache_dir(db))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| *p != memo_path(db))
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                modified(&p),
            )
        })
        .collect();
    v.sort();
    v
}

/// Waits until a file changed now is old enough to be remembered.
fn settle() {
    std::thread::sleep(std::time::Duration::from_millis(
        SETTLE_SECONDS * 1000 + 300,
    ));
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_rewritten_sequence_invalidates_the_frame_cache_a_touched_or_copied_one_does_not() {
    let Some(d) = common::data_dir() else { return };
    let (db, pc2) = samba_copy(&d, "db_caches_touch");
    let t0 = std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_700_000_000);
    set_modified(&pc2, t0);
    settle();
    let ch = Character::load(&db, &Quiet).unwrap();
    let n = ch.n();
    let before: Vec<[f64; 3]> = ch.frame(surfmotion::graph::FlatFrame::new(10)).to_vec();
    drop(ch);
    let fpath = frames_path(&db);
    assert!(
        memo_path(&db).is_file(),
        "the content hash was not remembered"
    );
    let built = cache_times(&db);
    assert!(built.len() >= 4, "{built:?}");

    // Unchanged: the caches are reused (not rewritten).
    drop(Character::load(&db, &Quiet).unwrap());
    assert_eq!(
        cache_times(&db),
        built,
        "an unchanged sequence rebuilt a cache"
    );

    // Only touched (the same bytes, another time): every cache kept.
    set_modified(&pc2, t0 + std::time::Duration::from_secs(60));
    drop(Character::load(&db, &Quiet).unwrap());
    assert_eq!(
        cache_times(&db),
        built,
        "a touched sequence rebuilt a cache"
    );

    // The memo cut (a torn write): not trusted, the file hashed again, the
    // caches still kept (the same bytes, the same key).
    settle();
    std::fs::write(memo_path(&db), "{\"version\": 1, \"files\": [{\"pa").unwrap();
    drop(Character::load(&db, &Quiet).unwrap());
    assert_eq!(cache_times(&db), built, "a cut memo rebuilt a cache");
    let memo = std::fs::read_to_string(memo_path(&db)).unwrap();
    assert!(
        memo.contains("samba.pc2"),
        "the memo was not written again: {memo}"
    );

    // A copy of the whole folder without its files' times (`cp -r`): the
    // copy's caches are used, none rebuilt.
    let copy = db.with_file_name("db_copy");
    let _ = std::fs::remove_dir_all(&copy);
    std::fs::create_dir_all(cache_dir(&copy)).unwrap();
    for sub in [PathBuf::new(), PathBuf::from("cache")] {
        for e in std::fs::read_dir(db.join(&sub)).unwrap() {
            let p = e.unwrap().path();
            if p.is_file() {
                std::fs::copy(&p, copy.join(&sub).join(p.file_name().unwrap())).unwrap();
            }
        }
    }
    std::thread::sleep(std::time::Duration::from_millis(20));
    let copied = cache_times(&copy);
    assert_ne!(modified(&copy.join("samba.pc2")), modified(&pc2));
    let ch = Character::load(&copy, &Quiet).unwrap();
    assert_eq!(cache_times(&copy), copied, "a copy rebuilt a cache");
    assert_eq!(ch.frame(surfmotion::graph::FlatFrame::new(10)), &before[..]);
    drop(ch);

    // Rewritten in place, the same length, the modification time put back:
    // frame 10's first vertex moved by 1 cm along x (a block the previous
    // keys' samples did not read). PC2: 32 bytes of header, then f32
    // triples.
    settle();
    drop(Character::load(&db, &Quiet).unwrap());
    let written = modified(&fpath);
    let mut bytes = std::fs::read(&pc2).unwrap();
    let at = 32 + 10 * n * 12;
    let x = f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) + 0.01;
    bytes[at..at + 4].copy_from_slice(&x.to_le_bytes());
    let stamp = modified(&pc2);
    std::fs::write(&pc2, &bytes).unwrap();
    set_modified(&pc2, stamp);
    let ch = Character::load(&db, &Quiet).unwrap();
    assert_ne!(
        modified(&fpath),
        written,
        "a rewritten sequence kept the old cache"
    );
    assert_eq!(
        ch.frame(surfmotion::graph::FlatFrame::new(10))[0][0].to_bits(),
        (x as f64).to_bits()
    );
    assert_ne!(
        ch.frame(surfmotion::graph::FlatFrame::new(10))[0],
        before[0]
    );
    assert_eq!(
        ch.frame(surfmotion::graph::FlatFrame::new(10))[1..],
        before[1..]
    );
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_plausibility_reference_equals_the_copied_frames_bit_for_bit_and_is_cached() {
    let Some(d) = common::data_dir() else { return };
    let db = common::walk_run_db(&d, "db_caches_reference");
    let ch = Character::load(&db, &Quiet).unwrap();
    assert!(ch.graph().sequences().len() >= 2);
    let neutral = character_neutral(ch.rest_pose(), ch.poses());
    let opts = PlausibilityOptions::default();
    let path = reference_path(&db);
    let _ = std::fs::remove_file(&path);
    let measured = Checker::for_character_with(&ch, &neutral, opts).unwrap();
    assert!(path.is_file(), "the reference was not cached");
    let stamp = modified(&path);
    let cached = Checker::for_character_with(&ch, &neutral, opts).unwrap();
    assert_eq!(
        modified(&path),
        stamp,
        "a current reference was measured again"
    );

    // The computation before issue 43's change: every sequence copied out
    // of the frames, the floor from their lowest points, then the checks.
    let n = ch.n();
    let copies: Vec<Vec<[f64; 3]>> = ch
        .graph()
        .sequences()
        .iter()
        .map(|q| ch.frames()[q.start * n..(q.start + q.len) * n].to_vec())
        .collect();
    let lowest: Vec<f64> = copies
        .iter()
        .flat_map(|f| lowest_heights(f, n, DVec3::Y))
        .collect();
    let mut old = measured.clone();
    old.reference = None;
    old.floor = floor_height(&lowest);
    let refs: Vec<&[[f64; 3]]> = copies.iter().map(|c| &c[..]).collect();
    old.set_reference(
        &format!(
            "database '{}' ({} frames)",
            ch.manifest().name,
            lowest.len()
        ),
        &refs,
        n,
    );
    let bits = |c: &Checker| serde_json::to_string(&c.reference).unwrap();
    for (what, c) in [("measured", &measured), ("cached", &cached)] {
        assert_eq!(c.floor.to_bits(), old.floor.to_bits(), "{what} floor");
        assert_eq!(c.reference, old.reference, "{what} reference");
        assert_eq!(bits(c), bits(&old), "{what} reference");
    }
    assert!(old.reference.as_ref().unwrap().frames > 0);

    // A cache of another key (here: garbage) is measured again, not trusted.
    std::fs::write(&path, "{\"key\": 1, \"floor\": 9.0}").unwrap();
    let again = Checker::for_character_with(&ch, &neutral, opts).unwrap();
    assert_eq!(again.floor.to_bits(), old.floor.to_bits());
    assert_eq!(again.reference, old.reference);
}
