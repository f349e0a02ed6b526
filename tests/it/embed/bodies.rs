//! The rig embedding on generated bodies of many shapes (the procedural
//! humanoid's shape parameters) and on the real fixtures: the pelvis on the
//! body's mid-plane, the hips symmetric about it, twin bones of one length,
//! every joint inside the body, every part one non-empty region, and the
//! self-check silent; degenerate landmark sets refused with the landmark
//! named, broken embeddings warned about.
//!
//! Regression for issue 17: on a body whose crotch lies above the
//! horizontal section 3.5 % of the height over the groin landmark, that
//! section is the two thighs apart, and the pelvis and both hips were put
//! at the centre of one thigh (5-6 % of the height to the side).

use crate::common;

use glam::DVec3;
use std::path::{Path, PathBuf};
use surfmotion::embed::check::{Problem, check};
use surfmotion::embed::landmarks::{Landmark, LandmarkError, Landmarks, Mark};
use surfmotion::embed::parts::{Part, neighbours, piece_counts};
use surfmotion::embed::surface::is_inside;
use surfmotion::embed::{EmbedError, Embedding};
use surfmotion::mesh::Mesh;
use surfmotion::rig::Canonical;
use surfmotion::synth::humanoid::{
    DEMO_GRID, HumanoidShape, humanoid_landmarks_json_with, humanoid_landmarks_with,
    humanoid_mesh_with,
};

fn variants() -> Vec<(&'static str, HumanoidShape)> {
    let d = HumanoidShape::default();
    vec![
        ("default", d),
        (
            "hips x0.7",
            HumanoidShape {
                hip_width: 0.7,
                ..d
            },
        ),
        (
            "hips x1.4",
            HumanoidShape {
                hip_width: 1.4,
                ..d
            },
        ),
        (
            "T-pose",
            HumanoidShape {
                arm_angle: 0.0,
                ..d
            },
        ),
        (
            "A-pose 60",
            HumanoidShape {
                arm_angle: 60.0,
                ..d
            },
        ),
        (
            "legs apart",
            HumanoidShape {
                leg_spread: 8.0,
                ..d
            },
        ),
        (
            "legs together",
            HumanoidShape {
                leg_spread: -4.0,
                ..d
            },
        ),
        (
            "shoulders x1.2",
            HumanoidShape {
                shoulder_width: 1.2,
                ..d
            },
        ),
        (
            "shifted and turned",
            HumanoidShape {
                yaw: 35.0,
                offset: [0.6, 0.2, -0.4],
                ..d
            },
        ),
        (
            "high crotch",
            HumanoidShape {
                crotch_lift: 0.15,
                ..d
            },
        ),
        (
            "woman-like: 1.66 m, wide hips, T-pose, high crotch, placed",
            HumanoidShape {
                height: 1.66,
                hip_width: 1.25,
                arm_angle: 0.0,
                crotch_lift: 0.15,
                yaw: -20.0,
                offset: [-0.3, 0.0, 0.5],
                ..d
            },
        ),
    ]
}

/// Embeds shape `s` and returns the mesh and the embedding.
fn embed(s: &HumanoidShape) -> (Mesh, Embedding) {
    let m = humanoid_mesh_with(DEMO_GRID * s.height / 1.75, s);
    let lm = humanoid_landmarks_with(&m, s);
    let e = Embedding::new(&m, &lm, None).unwrap();
    (m, e)
}

#[test]
fn generated_bodies_embed_on_their_mid_plane_and_pass_the_self_check() {
    use Canonical as C;
    let mut failures = Vec::new();
    for (name, s) in variants() {
        let (m, e) = embed(&s);
        let h = e.height();
        assert!((h - s.height).abs() < 0.03 * s.height, "{name}: height {h}");
        let (o, n) = s.mid_plane();
        let j = |c: C| DVec3::from_array(e.joints()[c.index()]);
        let dist = |c: C| (j(c) - o).dot(n);
        let pelvis = dist(C::Pelvis).abs() / h;
        let (dl, dr) = (dist(C::LHip), -dist(C::RHip));
        let hips = (dl - dr).abs() / h;
        let mut worst_bone: (f64, &str) = (0.0, "");
        for (l, r) in [
            (C::LShoulder, C::RShoulder),
            (C::LElbow, C::RElbow),
            (C::LWrist, C::RWrist),
            (C::LHip, C::RHip),
            (C::LKnee, C::RKnee),
            (C::LAnkle, C::RAnkle),
            (C::LToe, C::RToe),
        ] {
            let a = j(l).distance(j(l.parent().unwrap()));
            let b = j(r).distance(j(r.parent().unwrap()));
            let ratio = (a - b).abs() / a.max(b);
            if ratio > worst_bone.0 {
                worst_bone = (ratio, l.name());
            }
        }
        let outside: Vec<&str> = Canonical::ALL
            .iter()
            .filter(|c| !is_inside(m.positions(), m.triangles(), j(**c)))
            .map(|c| c.name())
            .collect();
        // Limb joints across the body where the body's own skeleton has
        // them (the landmarks are points on it).
        let truth: std::collections::BTreeMap<String, [f64; 3]> =
            serde_json::from_str(&humanoid_landmarks_json_with(&s)).unwrap();
        let mut worst_across: (f64, &str) = (0.0, "");
        for c in [
            C::LKnee,
            C::RKnee,
            C::LAnkle,
            C::RAnkle,
            C::LElbow,
            C::RElbow,
            C::LWrist,
            C::RWrist,
        ] {
            let t = (DVec3::from_array(truth[c.name()]) - o).dot(n);
            let err = (dist(c) - t).abs() / h;
            if err > worst_across.0 {
                worst_across = (err, c.name());
            }
        }
        let pieces = piece_counts(e.labels(), &neighbours(m.vertex_count(), m.triangles()));
        let c = check(&e, &m);
        eprintln!(
            "{name}: {} vertices, height {h:.3}; pelvis {:.3}% of the height from the true mid-plane, hips {:.3} / {:.3} m from it ({:.3}%), worst twin bones {:.2}% ({}), worst limb joint across {:.2}% ({}), outside {outside:?}, pieces {pieces:?}, self-check {} warnings; notes {:?}",
            m.vertex_count(),
            100.0 * pelvis,
            dl,
            dr,
            100.0 * hips,
            100.0 * worst_bone.0,
            worst_bone.1,
            100.0 * worst_across.0,
            worst_across.1,
            c.warnings.len(),
            e.notes()
        );
        for w in &c.warnings {
            eprintln!("    warning: {}", w.message);
        }
        let ok = pelvis < 0.01
            && hips < 0.01
            && worst_bone.0 < 0.05
            && worst_across.0 < 0.015
            && outside.is_empty()
            && pieces.iter().all(|&k| k == 1)
            && c.passed();
        if !ok {
            failures.push(name);
        }
    }
    assert!(failures.is_empty(), "failed: {failures:?}");
}

fn expect_landmark_error(r: Result<Embedding, EmbedError>) -> LandmarkError {
    match r {
        Err(EmbedError::Landmarks(e)) => e,
        Err(e) => panic!("expected a landmark error, got {e}"),
        Ok(_) => panic!("expected a landmark error, got an embedding"),
    }
}

#[test]
fn degenerate_landmark_sets_are_refused_naming_the_landmark() {
    let s = HumanoidShape::default();
    let m = humanoid_mesh_with(DEMO_GRID, &s);
    let good = humanoid_landmarks_with(&m, &s);

    // One landmark moved well off the body (half a metre in front).
    let mut off = good.clone();
    let w = off.point(Landmark::LWrist, m.positions()).unwrap();
    off.marks
        .insert(Landmark::LWrist, Mark::Point([w[0], w[1], w[2] + 0.5]));
    let e = expect_landmark_error(Embedding::new(&m, &off, None));
    assert!(
        matches!(e, LandmarkError::OffSurface { key: "l_wrist", .. }),
        "{e}"
    );
    assert!(e.to_string().contains("l_wrist"), "{e}");

    // All landmarks at one point.
    let mut one = good.clone();
    for v in one.marks.values_mut() {
        *v = Mark::Point([0.0, 1.0, 0.0]);
    }
    let e = expect_landmark_error(Embedding::new(&m, &one, None));
    assert!(matches!(e, LandmarkError::Span { .. }), "{e}");

    // Landmarks in metres on the same body in millimetres.
    let mm = Mesh::new(
        m.positions()
            .iter()
            .map(|p| p.map(|x| x * 1000.0))
            .collect(),
        m.triangles().to_vec(),
    )
    .unwrap();
    let e = expect_landmark_error(Embedding::new(&mm, &good, None));
    assert!(matches!(e, LandmarkError::Span { .. }), "{e}");
    assert!(e.to_string().contains("units"), "{e}");

    // Both knees marked at one place.
    let mut knees = good.clone();
    let k = knees.marks[&Landmark::LKnee];
    knees.marks.insert(Landmark::RKnee, k);
    let e = expect_landmark_error(Embedding::new(&m, &knees, None));
    assert!(
        matches!(
            e,
            LandmarkError::Coincide {
                a: "l_knee",
                b: "r_knee",
                ..
            }
        ),
        "{e}"
    );
    // The good set embeds.
    assert!(Embedding::new(&m, &good, None).is_ok());
}

/// An embedding is built or edited only through its checked parts
/// (issue 40): every broken invariant is refused with the reason, an
/// untouched round trip is the same embedding, and a file that breaks one
/// is refused naming the file.
#[test]
fn an_edited_embedding_is_checked_again() {
    let (m, e) = embed(&HumanoidShape::default());
    let n = m.vertex_count();
    assert_eq!(e.clone().edited(|_| {}).unwrap(), e);
    type Edit<'a> = Box<dyn Fn(&mut surfmotion::embed::EmbeddingParts) + 'a>;
    let breaks: [(&str, Edit); 7] = [
        (
            "inconsistent sizes",
            Box::new(move |p| p.labels.truncate(n - 1)),
        ),
        (
            "inconsistent sizes",
            Box::new(move |p| p.skin.push(p.skin[0])),
        ),
        (
            "inconsistent sizes",
            Box::new(move |p| {
                p.regressors.pop();
            }),
        ),
        ("positive length", Box::new(move |p| p.height = 0.0)),
        (
            "part",
            Box::new(move |p| p.labels[n / 2] = Part::COUNT as u8),
        ),
        (
            "regressor",
            Box::new(move |p| p.regressors[3].vertices[0] = n as u32),
        ),
        (
            "skin",
            Box::new(move |p| p.skin[7].0[1] = Canonical::COUNT as u8),
        ),
    ];
    let dir = common::fixture_dir("embedding_parts");
    for (k, (why, edit)) in breaks.iter().enumerate() {
        let err = e.clone().edited(|p| edit(p)).unwrap_err();
        assert!(err.contains(why), "break {k}: {err}");
        // The same break in a file: refused on reading, naming the file.
        let mut v = serde_json::to_value(&e).unwrap();
        let mut p = e.clone().into_parts();
        edit(&mut p);
        for (key, val) in [
            ("labels", serde_json::to_value(&p.labels).unwrap()),
            ("skin", serde_json::to_value(&p.skin).unwrap()),
            ("regressors", serde_json::to_value(&p.regressors).unwrap()),
            ("height", serde_json::to_value(p.height).unwrap()),
        ] {
            v[key] = val;
        }
        let path = dir.join(format!("broken_{k}.json"));
        std::fs::write(&path, v.to_string()).unwrap();
        let err = Embedding::load(&path, n).unwrap_err().to_string();
        assert!(
            err.contains("broken_") && err.contains(why),
            "break {k}: {err}"
        );
    }
}

#[test]
fn the_self_check_warns_about_a_broken_embedding() {
    use Canonical as C;
    let s = HumanoidShape::default();
    let (m, e) = embed(&s);
    assert!(check(&e, &m).passed(), "{:?}", check(&e, &m).warnings);
    let h = e.height();
    let left = DVec3::from_array(e.left());

    // The failure: pelvis and hips moved to one side by the
    // thigh's offset (5.1 % of the height), spine and knees in place.
    let bad = e
        .clone()
        .edited(|b| {
            for c in [C::Pelvis, C::LHip, C::RHip] {
                let p = DVec3::from_array(b.joints[c.index()]) + left * 0.09;
                b.joints[c.index()] = p.to_array();
            }
        })
        .unwrap();
    let r = check(&bad, &m);
    let off = r
        .warnings
        .iter()
        .find(|w| w.problem == Problem::OffMidPlane && w.joint == "pelvis")
        .expect("the pelvis off the mid-plane is reported");
    assert!((off.distance - 0.09).abs() < 0.01 * h, "{off:?}");
    assert!((off.percent_of_height - 100.0 * off.distance / h).abs() < 1e-9);
    assert!(
        r.warnings
            .iter()
            .any(|w| w.problem == Problem::Asymmetric && w.joint == "l_hip"),
        "{:?}",
        r.warnings
    );

    // A wrist moved out of the arm: outside the body, and its bones unequal.
    let wr = DVec3::from_array(e.joints()[C::LWrist.index()]) + DVec3::Z * 0.2;
    let bad = e
        .clone()
        .edited(|b| b.joints[C::LWrist.index()] = wr.to_array())
        .unwrap();
    let r = check(&bad, &m);
    let out = r
        .warnings
        .iter()
        .find(|w| w.problem == Problem::Outside && w.joint == "l_wrist")
        .expect("the wrist outside is reported");
    assert!(out.distance > 0.1 && out.distance < 0.2, "{out:?}");
    assert!(
        r.warnings
            .iter()
            .any(|w| w.problem == Problem::BoneLengths && w.joint == "l_wrist")
    );

    // A part emptied: its vertices given to the torso.
    let head = Part::ALL.iter().position(|p| p.name() == "head").unwrap() as u8;
    let bad = e
        .clone()
        .edited(|b| {
            for l in &mut b.labels {
                if *l == head {
                    *l = 0;
                }
            }
        })
        .unwrap();
    let r = check(&bad, &m);
    assert!(
        r.warnings
            .iter()
            .any(|w| w.problem == Problem::EmptyPart && w.joint == "head"),
        "{:?}",
        r.warnings
    );
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_real_fixtures_have_the_pelvis_on_the_mid_plane() {
    let Some(d) = common::data_dir() else { return };
    // Read as `rig embed` reads them.
    let read = |p: &str| {
        surfmotion::mesh::io::load_sequence(
            d.join(p).to_str().unwrap(),
            &surfmotion::mesh::io::LoadOptions::default(),
        )
        .unwrap()
        .frame_mesh(0)
    };
    let cases: Vec<(&str, Mesh, bool)> = vec![
        ("samba", read("4d/samba/samba.obj"), true),
        ("crane", read("4d/crane/crane.obj"), true),
        ("smpl", read("scans/smpl-template/human_man.obj"), true),
        (
            "makehuman",
            // As `rig embed --group body` takes it: the group, repaired.
            surfmotion::mesh::repair::repair(
                &surfmotion::mesh::io::obj::read_obj(&d.join("scans/makehuman/base.obj"))
                    .unwrap()
                    .select_groups(&["body".into()])
                    .unwrap(),
                &Default::default(),
            )
            .0,
            true,
        ),
        // Not human-shaped (a crouching armadillo with a tail): reported,
        // not held to human symmetry.
        ("armadillo", read("scans/armadillo/armadillo.obj"), false),
    ];
    for (name, m, human) in cases {
        let lm = Landmarks::load(
            &fixture(&format!("{name}.landmarks.json")),
            m.vertex_count(),
        )
        .unwrap();
        let e = Embedding::new(&m, &lm, None).unwrap();
        let c = check(&e, &m);
        eprintln!(
            "{name}: height {:.3}, pelvis {:.3}% of the height from the mid-plane, hips {:.3}% asymmetric, self-check {}",
            c.height,
            c.pelvis_offset_percent,
            c.hip_asymmetry_percent,
            if c.passed() { "passed" } else { "warned" }
        );
        for w in &c.warnings {
            eprintln!("    warning: {}", w.message);
        }
        // Every part is one non-empty region on every fixture.
        assert!(
            c.parts.iter().all(|p| p.vertices > 0 && p.pieces == 1),
            "{name}: {:?}",
            c.parts
        );
        if human {
            assert!(c.pelvis_offset_percent.abs() < 1.0, "{name}");
            assert!(c.hip_asymmetry_percent < 1.0, "{name}");
        }
    }
}

/// Writes each variant's mesh and landmarks to `$EMBED_BODIES_OUT` (for
/// `rig embed --png`); run with `--ignored`.
#[test]
#[ignore]
fn write_the_variants() {
    let Some(dir) = std::env::var_os("EMBED_BODIES_OUT") else {
        return;
    };
    let dir = PathBuf::from(dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (k, (_, s)) in variants().into_iter().enumerate() {
        let m = humanoid_mesh_with(DEMO_GRID * s.height / 1.75, &s);
        surfmotion::mesh::io::obj::write_obj(&m, None, &dir.join(format!("v{k}.obj"))).unwrap();
        std::fs::write(
            dir.join(format!("v{k}.landmarks.json")),
            humanoid_landmarks_json_with(&s),
        )
        .unwrap();
    }
}
