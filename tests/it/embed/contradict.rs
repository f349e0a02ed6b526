//! Landmark files that contradict the body (issue 41): left and right
//! swapped (every l_/r_ pair exchanged: consistent with itself, so the
//! landmark checks pass it) and an elbow put on the knee are reported by
//! `db init`, not silently obeyed.

use crate::common;

use std::path::{Path, PathBuf};
use surfmotion::embed::check::Problem;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::embed::{Embedding, check};
use surfmotion::mesh::io::obj::read_obj;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

/// The fixture's JSON with every `l_`/`r_` key exchanged.
fn swapped(text: &str) -> String {
    let v: serde_json::Map<String, serde_json::Value> = serde_json::from_str(text).unwrap();
    let out: serde_json::Map<String, serde_json::Value> = v
        .into_iter()
        .map(|(k, x)| {
            let k = if let Some(s) = k.strip_prefix("l_") {
                format!("r_{s}")
            } else if let Some(s) = k.strip_prefix("r_") {
                format!("l_{s}")
            } else {
                k
            };
            (k, x)
        })
        .collect();
    serde_json::Value::Object(out).to_string()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn left_right_swapped_landmarks_are_reported_and_the_fixtures_are_not() {
    let Some(d) = common::data_dir() else { return };
    for (obj, lmf) in [
        ("4d/samba/samba.obj", "samba.landmarks.json"),
        ("4d/crane/crane.obj", "crane.landmarks.json"),
    ] {
        let mesh = read_obj(&d.join(obj)).unwrap();
        let n = mesh.vertex_count();
        let text = std::fs::read_to_string(fixture(lmf)).unwrap();
        let backwards = |lm: &Landmarks| {
            let e = Embedding::new(&mesh, lm, None).unwrap();
            check(&e, &mesh)
                .warnings
                .iter()
                .filter(|w| w.problem == Problem::Backwards)
                .map(|w| w.message.clone())
                .collect::<Vec<_>>()
        };
        let good = Landmarks::parse(&text, Path::new(lmf), n).unwrap();
        assert!(backwards(&good).is_empty(), "{lmf}: {:?}", backwards(&good));
        let bad = Landmarks::parse(&swapped(&text), Path::new(lmf), n).unwrap();
        let w = backwards(&bad);
        eprintln!("{lmf} swapped: {w:?}");
        assert_eq!(w.len(), 1, "{lmf}");
        assert!(w[0].contains("left and right swapped"), "{}", w[0]);
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn db_init_reports_swapped_sides_and_an_elbow_on_the_knee() {
    let Some(d) = common::data_dir() else { return };
    let t = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(fixture("samba.landmarks.json")).unwrap();
    let mut elbow: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(&text).unwrap();
    let knee = elbow["l_knee"].clone();
    elbow.insert("l_elbow".into(), knee);
    for (name, json) in [
        ("swapped", swapped(&text)),
        (
            "elbow_on_knee",
            serde_json::Value::Object(elbow).to_string(),
        ),
    ] {
        let lmf = t.path().join(format!("{name}.json"));
        std::fs::write(&lmf, json).unwrap();
        let db = t.path().join(name);
        let r = common::run_cli(
            &[
                "db",
                "init",
                db.to_str().unwrap(),
                "--mesh",
                d.join("4d/samba/samba.obj").to_str().unwrap(),
                "--sequence",
                &format!("dance={}", d.join("4d/samba/samba.pc2").display()),
                "--landmarks",
                lmf.to_str().unwrap(),
            ],
            None,
            &[],
        );
        eprintln!("{name}: exit {:?}\n{}", r.code, r.stderr);
        if name == "swapped" {
            assert_eq!(r.code, Some(0), "{}", r.stderr);
            assert!(
                r.stderr.contains("WARN rig: both feet point backwards"),
                "{}",
                r.stderr
            );
        } else {
            // Refused naming the elbow, or the rig's parts reported.
            assert!(
                (r.code == Some(1) && r.stderr.contains("l_elbow"))
                    || r.stderr.contains("WARN part l_"),
                "{}",
                r.stderr
            );
        }
    }
}
