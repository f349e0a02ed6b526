//! Issue 43: the database's frames memory-mapped from `cache/frames.bin`
//! (and the skeletons from `cache/poses-KIND.bin`) equal the ones loaded
//! from the sequences; a truncated or foreign cache file is refused with a
//! typed error naming it and rebuilt by the next load, never a panic.

use crate::common;

use surfmotion::db::frames::{
    FrameCacheError, FrameStore, frames_path, keys, poses_path, read_poses,
};
use surfmotion::db::{Character, Manifest, Quiet};
use surfmotion::embed::frames::{SkeletonKind, poses};
use surfmotion::mocap::units::y_up;

/// The frames and regressor skeletons of `db` as the character loaded them
/// before the frame cache: every sequence read, converted to metres, Y-up.
fn loaded(db: &std::path::Path, ch: &Character) -> (Vec<[f64; 3]>, Vec<surfmotion::pose::Pose>) {
    let m = Manifest::load(db).unwrap();
    let n = ch.n();
    let mut file_frames = Vec::new();
    for s in &m.sequences {
        file_frames.extend_from_slice(m.load_sequence(db, s).unwrap().all_positions());
    }
    let (k, z) = (ch.metres_per_unit(), ch.z_up());
    let p = poses(ch.rig(), &file_frames, n, SkeletonKind::Regressor)
        .into_iter()
        .map(|p| p.map(|j| y_up(j.to_array(), z) * k))
        .collect();
    let f = file_frames
        .iter()
        .map(|q| (y_up(*q, z) * k).to_array())
        .collect();
    (f, p)
}

fn bits(f: &[[f64; 3]]) -> Vec<u64> {
    f.iter().flatten().map(|v| v.to_bits()).collect()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn mapped_frames_equal_loaded_and_a_cut_cache_is_rebuilt() {
    let Some(d) = common::data_dir() else { return };
    let db = common::walk_run_db(&d, "db_frames_mmap");
    let ch = Character::load(&db, &Quiet).unwrap();
    assert!(ch.frame_store().is_mapped(), "{:?}", ch.frame_store());
    let n = ch.n();
    let count = ch.frame_count();
    let metres = ch.metres_per_unit();
    let (frames, skel) = loaded(&db, &ch);
    assert_eq!(frames.len(), count * n);
    // Bit for bit: the frames, each frame's lowest point, the skeletons.
    assert_eq!(bits(ch.frames()), bits(&frames));
    for id in surfmotion::graph::FlatFrame::all(count) {
        let want = &frames[id.index() * n..(id.index() + 1) * n];
        assert_eq!(bits(ch.frame(id)), bits(want), "frame {id}");
        let low = want.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
        assert_eq!(ch.lowest(id).to_bits(), low.to_bits(), "frame {id}");
    }
    assert_eq!(ch.poses(), &skel[..]);
    // Released and prefetched (scattered, one past the end ignored): the
    // same bytes read back.
    let store = ch.frame_store();
    store.release(0, count);
    let last = surfmotion::graph::FlatFrame::from_index(count - 1);
    let past = surfmotion::graph::FlatFrame::from_index(count + 5);
    let first = surfmotion::graph::FlatFrame::from_index(0);
    store.prefetch(&[last, past, first, last]);
    assert_eq!(bits(store.frame(last)), bits(&frames[(count - 1) * n..]));
    assert_eq!(bits(ch.frames()), bits(&frames));
    drop(ch);

    // A second load maps the same file (no rewrite).
    let path = frames_path(&db);
    let before = std::fs::metadata(&path).unwrap().modified().unwrap();
    let again = Character::load(&db, &Quiet).unwrap();
    assert_eq!(
        std::fs::metadata(&path).unwrap().modified().unwrap(),
        before
    );
    assert_eq!(bits(again.frames()), bits(&frames));
    drop(again);

    // Cut at several offsets: refused with the file named, then rebuilt.
    let m = Manifest::load(&db).unwrap();
    let (fkey, pkey) = keys(&db, &m, metres, SkeletonKind::Regressor).unwrap();
    let whole = std::fs::read(&path).unwrap();
    let len = whole.len();
    assert_eq!(len, 64 + count * n * 24 + count * 8);
    let cuts = [
        0,
        5,
        8,
        31,
        63,
        64,
        64 + 24 * n - 3,
        len / 2,
        len - 8,
        len - 1,
    ];
    for (k, &cut) in cuts.iter().enumerate() {
        std::fs::write(&path, &whole[..cut]).unwrap();
        let e = FrameStore::open(&path, fkey, n, count).unwrap_err();
        assert!(
            matches!(
                e,
                FrameCacheError::Length { .. } | FrameCacheError::Header { .. }
            ),
            "cut at {cut}: {e:?}"
        );
        assert!(e.to_string().contains("frames.bin"), "cut at {cut}: {e}");
        // Loading rebuilds it (three of the cuts: each load rewrites the file).
        if k % 4 == 0 || cut == len - 1 {
            let ch = Character::load(&db, &Quiet).unwrap();
            assert_eq!(
                bits(ch.frames()),
                bits(&frames),
                "rebuilt after a cut at {cut}"
            );
            assert_eq!(std::fs::read(&path).unwrap().len(), len);
        }
    }
    // Another key or size is refused too; garbage is not a frame cache.
    std::fs::write(&path, &whole).unwrap();
    assert!(FrameStore::open(&path, fkey ^ 1, n, count).is_err());
    assert!(FrameStore::open(&path, fkey, n + 1, count).is_err());
    assert!(FrameStore::open(&path, fkey, n, count).is_ok());
    std::fs::write(&path, vec![7u8; len]).unwrap();
    let e = FrameStore::open(&path, fkey, n, count).unwrap_err();
    assert!(e.to_string().contains("not a frame cache"), "{e}");

    // The skeleton cache likewise.
    let ppath = poses_path(&db, SkeletonKind::Regressor);
    let pwhole = std::fs::read(&ppath).unwrap();
    assert_eq!(read_poses(&ppath, pkey, count).unwrap(), skel);
    for cut in [0, 8, 31, 32, pwhole.len() / 2, pwhole.len() - 1] {
        std::fs::write(&ppath, &pwhole[..cut]).unwrap();
        let e = read_poses(&ppath, pkey, count).unwrap_err();
        assert!(
            e.to_string().contains("poses-regressor.bin"),
            "cut at {cut}: {e}"
        );
    }
    let ch = Character::load(&db, &Quiet).unwrap();
    assert_eq!(ch.poses(), &skel[..]);
    assert_eq!(bits(ch.frames()), bits(&frames));
    assert_eq!(std::fs::read(&ppath).unwrap(), pwhole);
}

/// Each frame's step to its successor (the dissimilarity retrieval scales
/// its edge costs by) is kept in the graph cache, so a load reads no row of
/// the similarity for it: the values equal the similarity's bit for bit,
/// one `null` ends each sequence, and a graph cache written before the
/// steps (session 44) loads the same and is completed once, to the same
/// bytes as a fresh build's.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn successor_steps_are_kept_in_the_graph_cache_and_equal_the_similarity() {
    let Some(d) = common::data_dir() else { return };
    let db = common::walk_run_db(&d, "db_steps");
    let check = |ch: &Character| {
        let count = ch.frame_count();
        let mut ends = 0;
        for a in surfmotion::graph::FlatFrame::all(count) {
            match ch.successor(a) {
                Some(b) => {
                    let want = ch.matrix().get(a.index(), b.index());
                    assert_eq!(ch.dissimilarity(a, b).to_bits(), want.to_bits(), "{a}");
                }
                None => ends += 1,
            }
        }
        ends
    };
    let ch = Character::load(&db, &Quiet).unwrap();
    let ends = check(&ch);
    let gpath = std::fs::read_dir(db.join("cache"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| {
            let n = p.file_name().unwrap().to_string_lossy().to_string();
            n.starts_with("graph-") && n.ends_with(".json")
        })
        .expect("a graph cache");
    let whole = std::fs::read(&gpath).unwrap();
    let mut v: serde_json::Value = serde_json::from_slice(&whole).unwrap();
    let steps = v["steps"].as_array().expect("steps in the graph cache");
    assert_eq!(steps.len(), ch.frame_count());
    assert_eq!(steps.iter().filter(|s| s.is_null()).count(), ends);
    assert!(ends >= 2, "{ends} sequences");
    drop(ch);
    // A cache of session 44 (no steps): the same values, the file completed.
    v.as_object_mut().unwrap().remove("steps");
    std::fs::write(&gpath, serde_json::to_vec(&v).unwrap()).unwrap();
    let ch = Character::load(&db, &Quiet).unwrap();
    assert_eq!(check(&ch), ends);
    assert_eq!(std::fs::read(&gpath).unwrap(), whole);
}
