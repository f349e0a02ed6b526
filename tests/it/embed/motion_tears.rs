//! The two vertex defects of the skin weights fitted to motion (issue 41,
//! [`surfmotion::embed::motion_weights`]), session 22's per-segment fit:
//! on clear samba the back of the left knee (vertex 1542) took 0.105 on
//! the right hip (bone heat 0.075; that motion alone misses it by 17 cm)
//! and left its one-ring by 7-9 cm in retargets; on samba rigged on its
//! contact frame 155 (forearms on the belly) a patch at the front of the
//! waist (vertices 4164, 4264, …) was torn out by up to 3.4 m in frame 68
//! of CMU 02_02. Guarded: CMU 02_02 retargeted onto samba rigged on its
//! clear frame 0 and on its contact frame 155 keeps every vertex within
//! its one-ring (no such warning).

use crate::common;

use std::path::Path;
use surfmotion::embed::landmarks::{Landmark, Landmarks};
use surfmotion::mesh::io::obj::write_obj;
use surfmotion::mesh::io::{LoadOptions, load_sequence};

fn fixture() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json")
}

/// `db init` (with `extra` arguments), `db build`, `retarget` CMU 02_02
/// `--json`: the plausibility warnings.
fn retarget_warnings(db: &Path, mesh: &Path, landmarks: &Path, extra: &[&str]) -> Vec<String> {
    let d = common::data_dir().unwrap();
    let s = |p: &Path| p.display().to_string();
    let mut init = vec![
        "db".to_string(),
        "init".into(),
        s(db),
        "--mesh".into(),
        s(mesh),
        "--sequence".into(),
        format!("samba={}", s(&d.join("4d/samba/samba.pc2"))),
        "--landmarks".into(),
        s(landmarks),
    ];
    init.extend(extra.iter().map(|x| x.to_string()));
    common::cli_ok(&init, None);
    common::cli_ok(&["db".to_string(), "build".into(), s(db)], None);
    let out = db.with_extension("0202.pc2");
    let r = common::cli_ok(
        &[
            "retarget".to_string(),
            "--db".into(),
            s(db),
            "--mocap".into(),
            s(&d.join("mocap/cmu-amc/02/02_02.amc")),
            "-o".into(),
            s(&out),
            "--json".into(),
        ],
        None,
    );
    let v: serde_json::Value = serde_json::from_str(&r.stdout).unwrap();
    v["plausibility"]["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap().to_string())
        .collect()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_retarget_keeps_every_vertex_in_its_one_ring_from_a_clear_and_a_contact_rest() {
    let Some(d) = common::data_dir() else { return };
    let t = tempfile::tempdir().unwrap();
    let seq = load_sequence(
        d.join("4d/samba/samba.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    let n = seq.mesh().vertex_count();
    // The contact frame: 155, both forearms on the belly (`embed::contact`
    // finds 374 vertices touching); the topology that frame, the fixture's
    // point landmarks carried onto it.
    let contact = 155;
    let topo = seq.frame_mesh(contact);
    let mesh155 = t.path().join("samba155.obj");
    write_obj(&topo, None, &mesh155).unwrap();
    let text = std::fs::read_to_string(fixture()).unwrap();
    let marks: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&text).unwrap();
    let lm = Landmarks::load(&fixture(), n).unwrap();
    let moved = lm.moved(seq.frame(0), topo.positions(), topo.triangles());
    let mut carried = serde_json::Map::new();
    for (k, v) in marks {
        let l = Landmark::from_name(&k).unwrap();
        let v = if v.is_array() {
            serde_json::json!(moved.point(l, topo.positions()).unwrap())
        } else {
            v
        };
        carried.insert(k, v);
    }
    let lm155 = t.path().join("samba155.landmarks.json");
    std::fs::write(&lm155, serde_json::to_string(&carried).unwrap()).unwrap();
    let mut torn = Vec::new();
    for (name, db, mesh, lms, extra) in [
        (
            "clear frame 0",
            t.path().join("clear"),
            d.join("4d/samba/samba.obj"),
            fixture(),
            &[][..],
        ),
        (
            "contact frame 155",
            t.path().join("c155"),
            mesh155.clone(),
            lm155.clone(),
            &["--keep-rest-frame"][..],
        ),
    ] {
        let w = retarget_warnings(&db, &mesh, &lms, extra);
        eprintln!("samba rigged on its {name}, CMU 02_02: {w:?}");
        torn.extend(
            w.into_iter()
                .filter(|w| w.contains("one-ring"))
                .map(|w| format!("{name}: {w}")),
        );
    }
    // Session 22's fit: clear, "vertex 1542 leaves its one-ring by 7.4 cm";
    // contact, "vertex 4264 leaves its one-ring by 296.5 cm". Bone heat
    // alone: neither.
    assert!(torn.is_empty(), "{torn:?}");
}
