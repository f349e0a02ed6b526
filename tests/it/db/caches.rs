//! Issue 43: a database's caches at scale. Cache keys of long files come
//! from their length, modification time and sampled blocks (not every
//! byte): a sequence rewritten or only touched still invalidates the
//! frame cache. The plausibility reference is measured from the mapped
//! frames (no copy) and cached: both equal the figures of the copy-every-
//! frame computation bit for bit.

use crate::common;

use glam::DVec3;
use std::path::{Path, PathBuf};
use surfmotion::db::frames::frames_path;
use surfmotion::db::{Character, Quiet};
use surfmotion::pose::retarget::character_neutral;
use surfmotion::tools::eval::plausibility::reference_path;
use surfmotion::tools::eval::{Checker, PlausibilityOptions, floor_height, lowest_heights};

/// The samba capture as a database whose sequence is a copy (so that the
/// test may rewrite it) in `fixture_dir(name)`.
fn samba_copy(d: &Path, name: &str) -> (PathBuf, PathBuf) {
    let dir = common::fixture_dir(name);
    let db = dir.join("db");
    let _ = std::fs::remove_dir_all(&db);
    std::fs::create_dir_all(&db).unwrap();
    let pc2 = dir.join("samba.pc2");
    std::fs::copy(d.join("4d/samba/samba.pc2"), &pc2).unwrap();
    let landmarks =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json");
    let toml = format!(
        "name = \"samba_copy\"\ntopology = {:?}\nfps = 30.0\nunits = \"m\"\nup = \"y\"\n\n[[sequence]]\nname = \"dance\"\npath = {:?}\n\n[rig]\nlandmarks = {:?}\n",
        d.join("4d/samba/samba.obj"),
        pc2,
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

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_rewritten_or_touched_sequence_invalidates_the_frame_cache() {
    let Some(d) = common::data_dir() else { return };
    let (db, pc2) = samba_copy(&d, "db_caches_touch");
    let t0 = std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_700_000_000);
    set_modified(&pc2, t0);
    let ch = Character::load(&db, &Quiet).unwrap();
    let n = ch.n();
    let before: Vec<[f64; 3]> = ch.frame(10).to_vec();
    drop(ch);
    let fpath = frames_path(&db);
    let written = modified(&fpath);

    // Unchanged: the cache is reused (not rewritten).
    let ch = Character::load(&db, &Quiet).unwrap();
    assert_eq!(
        modified(&fpath),
        written,
        "an unchanged sequence rebuilt the cache"
    );
    drop(ch);

    // Rewritten in place, the same length: frame 10's first vertex moved by
    // 1 cm along x. PC2: 32 bytes of header, then f32 triples.
    let mut bytes = std::fs::read(&pc2).unwrap();
    let at = 32 + 10 * n * 12;
    let x = f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) + 0.01;
    bytes[at..at + 4].copy_from_slice(&x.to_le_bytes());
    std::fs::write(&pc2, &bytes).unwrap();
    let ch = Character::load(&db, &Quiet).unwrap();
    assert_ne!(
        modified(&fpath),
        written,
        "a rewritten sequence kept the old cache"
    );
    assert_eq!(ch.frame(10)[0][0].to_bits(), (x as f64).to_bits());
    assert_ne!(ch.frame(10)[0], before[0]);
    assert_eq!(ch.frame(10)[1..], before[1..]);
    drop(ch);

    // Only touched (the same bytes, another time): rebuilt too.
    let written = modified(&fpath);
    std::thread::sleep(std::time::Duration::from_millis(20));
    set_modified(&pc2, t0 + std::time::Duration::from_secs(60));
    let ch = Character::load(&db, &Quiet).unwrap();
    assert_ne!(
        modified(&fpath),
        written,
        "a touched sequence kept the old cache"
    );
    assert_eq!(ch.frame(10)[0][0].to_bits(), (x as f64).to_bits());
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_plausibility_reference_equals_the_copied_frames_bit_for_bit_and_is_cached() {
    let Some(d) = common::data_dir() else { return };
    let db = common::walk_run_db(&d, "db_caches_reference");
    let ch = Character::load(&db, &Quiet).unwrap();
    assert!(ch.graph().sequences.len() >= 2);
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
        .sequences
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
