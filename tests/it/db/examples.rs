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
use surfmotion::drive::{Prepared, RetargetOptions};

/// Each region's examples of a fresh load of `db` prepared with `want`
/// examples a region.
fn chosen(db: &Path, want: usize) -> Vec<Vec<FlatFrame>> {
    let ch = Character::load(db, &Quiet).unwrap();
    let mut opts = RetargetOptions::default();
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
        std::fs::read(out).unwrap()
    };
    let without = run(&tmp.path().join("a.pc2"));
    assert!(path.exists(), "the retarget wrote no memo");
    let with = run(&tmp.path().join("b.pc2"));
    assert!(with == without, "the memo changed the output");
}
