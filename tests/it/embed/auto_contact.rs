//! The automatic rig of a capture that starts in contact, through `db
//! init` itself (issue 41): samba re-ordered so that a frame with the hands
//! on the hips (120-174) or the forearms on the belly (155) comes first,
//! its topology that frame, written as OBJ + PC2 and given to `db init`
//! without landmarks, plain, mirrored, turned Z-up and scaled to cm.
//!
//! Started at frame 130, `db init` once exited 1 with "landmark l_knee: 9%
//! … above the groin": the automatic landmarks, found on the rest frame
//! chosen clear of contact, were written as points carried to the
//! topology (the contact frame) and carried back by the topology's
//! nearest triangles, which near the hands are the hips'.
//! `embed::auto_knees` missed it: it embeds on the topology, not on the
//! rest frame `db init` chooses. The landmarks are now fixed to the rest
//! frame's surface (`Mark::Surface`). Here every start must set up (exit
//! 0; main's binary exits 1 on s130 with the same command), on a rest
//! frame without contact, with its landmarks fixed to that frame.
//!
//! The rig `db init` embeds is also compared with the clear order's
//! (samba as captured, through the same `db init`, its joints carried to
//! the start frame). Issue 41 asks joints within 1 % of the height, parts
//! on >= 95 % of the vertices. Until session 25 not reached (joints mean
//! %, knees l / r %, parts %: s130 2.59, 8.52 / 0.64, 86.0; s155 1.64,
//! 0.20 / 4.63, 88.3; s165 Z-up 1.71, 5.27 / 3.98, 88.0 …): the contact
//! orders chose another rest frame (original 29, 64, 35 …; the clear order
//! kept 0) and the frames sampled for the decomposition followed the
//! order. With the rules by pose of session 26 (the rest frame the most
//! standing of the clear ones, `RestOptions::automatic`; the frames by
//! their poses, `FrameSample::PoseQuantiles`; options of `db init` through
//! `SURFMOTION_AUTORIG`, not its default) every start chooses the clear
//! order's rest frame, and is held to the issue's figures.

use crate::common;

/// The rules by pose (`RestOptions::automatic`,
/// `FrameSample::PoseQuantiles`): options, not `db init`'s default (as
/// the default they failed `embed::auto_knees` on crane).
const BY_POSE: &str = "rest=standing,frames=quantiles";

use glam::DVec3;
use std::path::Path;
use surfmotion::db::Manifest;
use surfmotion::db::skeletons::embed_rig;
use surfmotion::embed::Embedding;
use surfmotion::embed::auto::options::AUTORIG_ENV;
use surfmotion::embed::landmarks::{Anchor, Landmark, Landmarks, Mark};
use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::obj::write_obj;
use surfmotion::mesh::io::pc2::write_pc2;
use surfmotion::mesh::io::{LoadOptions, load_sequence};
use surfmotion::rig::Canonical;

/// A start: the frame put first, the map of every position, the triangles
/// reversed (a mirror).
struct Start {
    name: &'static str,
    first: usize,
    map: fn([f64; 3]) -> [f64; 3],
    mirror: bool,
}

fn same(p: [f64; 3]) -> [f64; 3] {
    p
}
fn mirror(p: [f64; 3]) -> [f64; 3] {
    [-p[0], p[1], p[2]]
}
fn z_up(p: [f64; 3]) -> [f64; 3] {
    [p[0], -p[2], p[1]]
}
fn cm(p: [f64; 3]) -> [f64; 3] {
    p.map(|x| x * 100.0)
}

/// `seq` re-ordered to start at `s.first`, mapped, written as
/// `DIR/NAME.obj` (that frame) and `DIR/NAME.pc2`; `db init DIR/NAME_db`
/// run on them without landmarks.
fn init(seq: &MeshSequence, s: &Start, dir: &Path) -> (common::CliRun, std::path::PathBuf) {
    let nf = seq.frame_count();
    let frame = |f: usize| -> Vec<[f64; 3]> { seq.frame(f).iter().map(|p| (s.map)(*p)).collect() };
    let mut tris = seq.mesh().triangles().to_vec();
    if s.mirror {
        tris.iter_mut().for_each(|t| t.swap(1, 2));
    }
    let mesh = surfmotion::mesh::Mesh::new(frame(s.first), tris).unwrap();
    let mut all = Vec::with_capacity(nf * mesh.vertex_count());
    for k in 0..nf {
        all.extend(frame((s.first + k) % nf));
    }
    let (obj, pc2) = (
        dir.join(format!("{}.obj", s.name)),
        dir.join(format!("{}.pc2", s.name)),
    );
    write_obj(&mesh, None, &obj).unwrap();
    write_pc2(mesh.vertex_count(), &all, &pc2).unwrap();
    let db = dir.join(format!("{}_db", s.name));
    let p = |p: &Path| p.display().to_string();
    let run = common::run_cli(
        &[
            "db".to_string(),
            "init".into(),
            p(&db),
            "--mesh".into(),
            p(&obj),
            "--sequence".into(),
            format!("dance={}", p(&pc2)),
        ],
        None,
        &[(AUTORIG_ENV, BY_POSE)],
    );
    (run, db)
}

/// The rig `db build` embeds for the database `db`.
fn rig_of(db: &Path) -> (Manifest, Embedding) {
    let m = Manifest::load(db).unwrap();
    let topo = m.load_topology(db).unwrap();
    let rig = embed_rig(db, &m, &topo).unwrap();
    (m, rig)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn samba_started_in_contact_sets_up_as_from_its_clear_start() {
    let Some(d) = common::data_dir() else { return };
    let seq = load_sequence(
        d.join("4d/samba/samba.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    let t = tempfile::tempdir().unwrap();
    let clear = Start {
        name: "clear",
        first: 0,
        map: same,
        mirror: false,
    };
    let (run, db) = init(&seq, &clear, t.path());
    assert_eq!(run.code, Some(0), "clear order: {}", run.stderr);
    let (clear_m, truth) = rig_of(&db);
    let h = truth.height();
    let nf = seq.frame_count();
    // The rest frame as a frame of the capture's own order (the topology:
    // the start frame).
    let original = |rest: &Option<String>, first: usize| -> Option<usize> {
        let Some(r) = rest else { return Some(first) };
        let f: usize = r.rsplit_once(':')?.1.parse().ok()?;
        Some((first + f) % nf)
    };
    let clear_rest = original(&clear_m.rig.rest, 0);
    type Map = fn([f64; 3]) -> [f64; 3];
    let starts: [(&str, usize, Map, bool); 6] = [
        ("s130", 130, same, false),
        ("s155", 155, same, false),
        ("s120", 120, same, false),
        ("s140_mirrored", 140, mirror, true),
        ("s165_zup", 165, z_up, false),
        ("s145_cm", 145, cm, false),
    ];
    let mut failures = Vec::new();
    for (name, first, map, flip) in starts {
        let s = Start {
            name,
            first,
            map,
            mirror: flip,
        };
        let (run, db) = init(&seq, &s, t.path());
        if run.code != Some(0) {
            failures.push(format!(
                "{name}: db init exit {:?}: {}",
                run.code, run.stderr
            ));
            continue;
        }
        let (m, rig) = rig_of(&db);
        let setup: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(db.join("setup.json")).unwrap()).unwrap();
        assert!(
            m.rig.rest.is_some() && setup["rest_contacts"].as_array().is_some_and(Vec::is_empty),
            "{name}: the rest frame must be another, clear: {:?} {}",
            m.rig.rest,
            setup["why"]
        );
        // The clear order's rig carried to this start's first frame, mapped.
        let want = truth
            .frame_joints(seq.frame(first))
            .map(|p| map(p.to_array()));
        let scale =
            (DVec3::from_array(map([1.0, 0.0, 0.0])) - DVec3::from_array(map([0.0; 3]))).length();
        let mean = super::auto::mean_percent(rig.joints(), &want, h * scale, flip);
        let (l, r) = (Canonical::LKnee, Canonical::RKnee);
        let knees =
            [(l, if flip { r } else { l }), (r, if flip { l } else { r })].map(|(k, twin)| {
                100.0
                    * DVec3::from_array(rig.joints()[k.index()])
                        .distance(DVec3::from_array(want[twin.index()]))
                    / (h * scale)
            });
        // Mirrored, the labels' sides swap: parts compared unmirrored only.
        let agree = if flip {
            None
        } else {
            let same = rig
                .labels()
                .iter()
                .zip(truth.labels())
                .filter(|(a, b)| a == b);
            Some(100.0 * same.count() as f64 / truth.labels().len() as f64)
        };
        let rest = original(&m.rig.rest, first);
        eprintln!(
            "{name}: rest {:?} (frame {rest:?} of the capture; the clear order's {clear_rest:?}); joints {mean:.2} % of the height from the clear order's, knees {:.2} / {:.2} %, parts {agree:?} %",
            m.rig.rest, knees[0], knees[1]
        );
        if rest != clear_rest {
            failures.push(format!(
                "{name}: rest frame {rest:?} of the capture, the clear order's {clear_rest:?}"
            ));
        }
        // The setup report names the frames in contact (the start frame,
        // the topology, first) and keeps the automatic rig's summary;
        // `db info` shows the rig's setup from it.
        assert_eq!(
            setup["contact_frames"][0], "topology",
            "{name}: the start frame has a contact: {}",
            setup["contact_frames"]
        );
        assert!(
            setup["automatic"][0]
                .as_str()
                .is_some_and(|s| s.starts_with("automatic rig: confidence")),
            "{name}: {}",
            setup["automatic"]
        );
        let info = common::run_cli(
            &[
                "db".to_string(),
                "info".into(),
                db.display().to_string(),
                "--json".into(),
            ],
            None,
            &[],
        );
        let notes =
            serde_json::from_str::<serde_json::Value>(&info.stdout).unwrap()["notes"].to_string();
        assert!(
            notes.contains("rig set up by `db init` on the rest frame dance:")
                && notes.contains("automatic rig: confidence"),
            "{name}: db info: {notes}"
        );
        let lm = std::fs::read_to_string(db.join("auto.landmarks.json")).unwrap();
        assert!(
            lm.contains("\"triangle\""),
            "{name}: the landmarks are fixed to the rest frame's surface: {lm}"
        );
        // Issue 41's figures: 1 % (joints), 3 % (knees), 95 % (parts).
        if mean > 1.0 || knees.iter().any(|&k| k > 3.0) || agree.is_some_and(|a| a < 95.0) {
            failures.push(format!(
                "{name}: joints {mean:.2} % (bound 1), knees {:.2} / {:.2} % (bound 3), parts {agree:?} % (bound 95)",
                knees[0], knees[1]
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A surface mark lands where it was found on its frame, follows its
/// triangle on another (turned, moved), is left alone by `moved`, and
/// reads back from its JSON; bad ones are refused naming the key.
#[test]
fn a_surface_mark_is_where_it_was_found_on_every_frame() {
    let a = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [5.0, 5.0, 5.0],
    ];
    let tris = [[0u32, 1, 2]];
    let q = [0.2, 0.3, -0.4];
    let m = Anchor::nearest(q, &a, &tris).unwrap();
    let back = m.point(&a);
    assert!((0..3).all(|k| (back[k] - q[k]).abs() < 1e-12), "{back:?}");
    // Turned 90° about z and moved: the point turns and moves with it.
    let b: Vec<[f64; 3]> = a.iter().map(|p| [-p[1] + 2.0, p[0], p[2] + 1.0]).collect();
    let on_b = m.point(&b);
    let want = [-q[1] + 2.0, q[0], q[2] + 1.0];
    assert!(
        (0..3).all(|k| (on_b[k] - want[k]).abs() < 1e-12),
        "{on_b:?}"
    );
    let mut lm = Landmarks::default();
    lm.marks.insert(Landmark::Chin, Mark::Surface(m));
    lm.marks.insert(Landmark::Groin, Mark::Point(q));
    let moved = lm.moved(&a, &b, &tris);
    assert_eq!(moved.marks[&Landmark::Chin], Mark::Surface(m));
    let g = moved.point(Landmark::Groin, &b).unwrap();
    assert!((0..3).all(|k| (g[k] - want[k]).abs() < 1e-12), "{g:?}");
    // JSON both ways.
    let text = format!(
        r#"{{"chin": {}, "groin": 0, "l_wrist": 1, "r_wrist": 2, "l_elbow": 1,
            "r_elbow": 2, "l_knee": 0, "r_knee": 3}}"#,
        m.to_json()
    );
    let p = std::path::Path::new("s.json");
    let read = Landmarks::parse(&text, p, 4).unwrap();
    assert_eq!(read.marks[&Landmark::Chin], Mark::Surface(m));
    let bad = text.replace("\"triangle\":[0,1,2]", "\"triangle\":[0,1,9]");
    assert_ne!(bad, text);
    let e = Landmarks::parse(&bad, p, 4).unwrap_err().to_string();
    assert!(e.contains("chin") && e.contains("out of range"), "{e}");
    let bad = text.replace("\"offset\"", "\"offst\"");
    let e = Landmarks::parse(&bad, p, 4).unwrap_err().to_string();
    assert!(e.contains("chin") && e.contains("offst"), "{e}");
}
