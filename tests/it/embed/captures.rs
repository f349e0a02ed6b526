//! Rig embedding and per-frame skeletons on the real 4D captures, with the
//! landmark fixtures in tests/fixtures (written for this project; the
//! labelled meshes were checked by rendering them with `rig embed --png`).

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;
use surfmotion::embed::Embedding;
use surfmotion::embed::frames::{SkeletonKind, bone_length_spread, poses};
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::embed::parts::{Part, neighbours, piece_counts};
use surfmotion::mesh::io::{LoadOptions, load_sequence};
use surfmotion::rig::Canonical;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

struct Case {
    name: &'static str,
    pc2: &'static str,
    landmarks: &'static str,
    facing: [f64; 3],
}

const CASES: [Case; 2] = [
    Case {
        name: "samba",
        pc2: "4d/samba/samba.pc2",
        landmarks: "samba.landmarks.json",
        facing: [1.0, 0.0, 0.0],
    },
    Case {
        name: "crane",
        pc2: "4d/crane/crane.pc2",
        landmarks: "crane.landmarks.json",
        facing: [-1.0, 0.0, 0.0],
    },
];

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn landmarks_give_contiguous_parts_exact_regressors_and_steady_bones() {
    let Some(d) = common::data_dir() else { return };
    for c in &CASES {
        let seq = load_sequence(d.join(c.pc2).to_str().unwrap(), &LoadOptions::default()).unwrap();
        let rest = seq.frame_mesh(0);
        let n = rest.vertex_count();
        let lm = Landmarks::load(&fixture(c.landmarks), n).unwrap();
        let e = Embedding::new(&rest, &lm, None).unwrap();

        // The character faces the way the data README says (judged from the feet).
        let f = glam::DVec3::from_array(e.facing());
        assert!(
            f.dot(glam::DVec3::from_array(c.facing)) > 0.9,
            "{}: facing {f}",
            c.name
        );
        // Every vertex has a part; every part is one connected region.
        assert_eq!(e.labels().len(), n);
        assert!(e.labels().iter().all(|&l| (l as usize) < Part::COUNT));
        let pieces = piece_counts(e.labels(), &neighbours(n, rest.triangles()));
        for p in Part::ALL {
            assert_eq!(pieces[p.index()], 1, "{}: part {}", c.name, p.name());
        }
        // Regions contain their labelled vertices and may overlap.
        for p in Part::ALL {
            let labelled = e
                .labels()
                .iter()
                .filter(|&&l| l as usize == p.index())
                .count();
            assert!(e.regions()[p.index()].len() >= labelled);
        }
        // Skin weights: non-negative, summing to 1.
        for (_, w) in e.skin() {
            assert!(w.iter().all(|&x| x >= 0.0));
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-9);
        }
        // Regressors reproduce the embedded joints on the rest frame.
        let j = e.frame_joints(rest.positions());
        for k in Canonical::ALL {
            let err = (j[k.index()] - glam::DVec3::from_array(e.joints()[k.index()])).length();
            assert!(err < 1e-9, "{} {}: {err}", c.name, k.name());
        }
        // Anatomy: head above neck above chest above pelvis above knees above
        // ankles; left joints on the character's left.
        let y = |k: Canonical| j[k.index()].y;
        use Canonical as C;
        assert!(y(C::Head) > y(C::Neck) && y(C::Neck) > y(C::Chest) && y(C::Chest) > y(C::Pelvis));
        assert!(y(C::Pelvis) > y(C::LKnee) && y(C::LKnee) > y(C::LAnkle));
        let left = glam::DVec3::from_array(e.left());
        for (l, r) in [
            (C::LWrist, C::RWrist),
            (C::LKnee, C::RKnee),
            (C::LShoulder, C::RShoulder),
        ] {
            assert!(
                (j[l.index()] - j[r.index()]).dot(left) > 0.0,
                "{} {l:?}",
                c.name
            );
        }

        // A rigid-skeleton sanity check on the real motion. The regressor
        // joints are a measurement of a clothed body: their long bones
        // (upper arms, forearms, thighs, shins) keep their length in the
        // median frame (within 5% on samba, 10% on crane) and vary at
        // worst by 10% (samba) and 25% (crane, whose loose jacket bunches
        // at sharply bent elbows with the arms raised).
        let measured = poses(&e, seq.all_positions(), n, SkeletonKind::Regressor);
        assert_eq!(measured.len(), 175);
        let long = [
            C::LElbow,
            C::RElbow,
            C::LWrist,
            C::RWrist,
            C::LKnee,
            C::RKnee,
            C::LAnkle,
            C::RAnkle,
        ];
        let spread = bone_length_spread(&measured);
        for b in long {
            let lens: Vec<f64> = measured
                .iter()
                .map(|p| p[b.index()].distance(p[b.parent().unwrap().index()]))
                .collect();
            let mut s = lens.clone();
            s.sort_by(f64::total_cmp);
            let med = s[s.len() / 2];
            let mut dev: Vec<f64> = lens.iter().map(|x| (x / med - 1.0).abs()).collect();
            dev.sort_by(f64::total_cmp);
            let (typical, cap) = if c.name == "samba" {
                (0.05, 0.10)
            } else {
                (0.10, 0.25)
            };
            assert!(
                dev[dev.len() / 2] < typical,
                "{} {b:?}: median deviation {}",
                c.name,
                dev[dev.len() / 2]
            );
            assert!(
                spread[b.index()] < cap,
                "{} {b:?}: {}",
                c.name,
                spread[b.index()]
            );
        }
        // The extracted (default, rigid) skeleton: every bone within 5% of
        // its median in all 175 frames, while staying on the measurement:
        // joints within 2% of the body height RMS in the median frame and
        // 6% at most (measured: samba 0.4% / 1.4%, crane 0.7% / 3.1%).
        let rigid = poses(&e, seq.all_positions(), n, SkeletonKind::Rigid);
        let spread = bone_length_spread(&rigid);
        for b in Canonical::ALL.iter().skip(1) {
            assert!(
                spread[b.index()] < 0.05,
                "{} {b:?}: rigid skeleton's bone varies by {}",
                c.name,
                spread[b.index()]
            );
        }
        let rest = e.joints().map(glam::DVec3::from_array);
        let height =
            rest[C::Head.index()].y - rest[C::LAnkle.index()].y.min(rest[C::RAnkle.index()].y);
        let mut rms: Vec<f64> = rigid
            .iter()
            .zip(&measured)
            .map(|(a, b)| {
                (a.iter()
                    .zip(b)
                    .map(|(p, q)| p.distance_squared(*q))
                    .sum::<f64>()
                    / Canonical::COUNT as f64)
                    .sqrt()
            })
            .collect();
        rms.sort_by(f64::total_cmp);
        let worst = rigid
            .iter()
            .zip(&measured)
            .flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| p.distance(*q)))
            .fold(0.0, f64::max);
        assert!(
            rms[rms.len() / 2] < 0.02 * height,
            "{}: median-frame RMS {} of height {height}",
            c.name,
            rms[rms.len() / 2]
        );
        assert!(
            worst < 0.06 * height,
            "{}: worst joint {worst} of height {height}",
            c.name
        );
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn db_skeleton_writes_json_and_a_bvh_that_reads_back() {
    let Some(d) = common::data_dir() else { return };
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("samba");
    let o = Command::new(common::bin())
        .args(["db", "init", db.to_str().unwrap(), "--mesh"])
        .arg(d.join("4d/samba/samba.obj"))
        .arg("--sequence")
        .arg(format!("dance={}", d.join("4d/samba/samba.pc2").display()))
        .arg("--landmarks")
        .arg(fixture("samba.landmarks.json"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for kind in ["rigid", "regressor", "centroid"] {
        let out = dir.path().join(kind);
        let o = Command::new(common::bin())
            .args([
                "db",
                "skeleton",
                db.to_str().unwrap(),
                "--json",
                "--kind",
                kind,
                "-o",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["sequences"][0]["frames"], 175);
        let j: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join("dance.skeleton.json")).unwrap(),
        )
        .unwrap();
        assert_eq!(j["frames"].as_array().unwrap().len(), 175);
        assert_eq!(j["joints"].as_array().unwrap().len(), Canonical::COUNT);
        // The BVH reads back with the rig detected and 175 frames; its FK
        // follows the extracted bone directions (lengths are the rest's),
        // and for the rigid skeleton it gives every joint back.
        let clip = surfmotion::rig::load_clip(&out.join("dance.bvh"), &Default::default()).unwrap();
        assert_eq!(clip.frame_count(), 175);
        let names: Vec<String> = clip.joints().iter().map(|j| j.name.clone()).collect();
        let det = surfmotion::rig::detect(&names);
        assert!(det.missing.is_empty(), "{:?}", det.missing);
        let frames = j["frames"].as_array().unwrap();
        // BVH joint of each canonical joint, found by the detected name.
        let at: Vec<usize> = Canonical::ALL
            .iter()
            .map(|c| {
                let name = &det.map.joints[c];
                names.iter().position(|n| n == name).unwrap()
            })
            .collect();
        for f in [0usize, 90, 174] {
            let all = clip.world_positions(f);
            let w: Vec<glam::DVec3> = at.iter().map(|&i| all[i]).collect();
            let p = |k: usize| {
                let a = frames[f][k].as_array().unwrap();
                glam::DVec3::new(
                    a[0].as_f64().unwrap(),
                    a[1].as_f64().unwrap(),
                    a[2].as_f64().unwrap(),
                )
            };
            assert!((w[0] - p(0)).length() < 1e-6, "root at frame {f}");
            for c in [Canonical::LKnee, Canonical::RElbow] {
                let par = c.parent().unwrap().index();
                let a = (w[c.index()] - w[par]).normalize();
                let b = (p(c.index()) - p(par)).normalize();
                assert!(a.dot(b) > 0.999, "{kind} frame {f} {c:?}: {}", a.dot(b));
            }
            if kind == "rigid" {
                for (k, wk) in w.iter().enumerate() {
                    let e = (*wk - p(k)).length();
                    assert!(e < 1e-4, "frame {f} joint {k}: {e}");
                }
            }
        }
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn rig_embed_cli_reports_errors_with_the_file() {
    let Some(d) = common::data_dir() else { return };
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.json");
    std::fs::write(&bad, r#"{"chin": 99999999, "groin": [0, 0, 0]}"#).unwrap();
    let o = Command::new(common::bin())
        .args(["rig", "embed"])
        .arg(d.join("4d/samba/samba.obj"))
        .arg("--landmarks")
        .arg(&bad)
        .args(["-o", dir.path().join("r.json").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("bad.json") && e.contains("chin"), "{e}");
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_rigged_gltf_skin_gives_the_rig_matched_by_position() {
    let Some(d) = common::data_dir() else { return };
    use surfmotion::embed::skin::from_skin;
    use surfmotion::mesh::Mesh;
    use surfmotion::mesh::io::gltf::read_gltf;
    use surfmotion::rig::RigMap;
    let g = d.join("gltf/CesiumMan/CesiumMan.glb");
    let asset = read_gltf(&g).unwrap();
    let map = RigMap::load(&fixture("cesiumman.rigmap.json")).unwrap();
    let rig = from_skin(&asset.mesh, &asset, Some(&map), &g).unwrap();
    // CesiumMan's joints have no names; its structure and geometry (it
    // faces +X in its bind space, Z up) give the hand-made map's joints,
    // so without a map it gets the same rig.
    let unmapped = from_skin(&asset.mesh, &asset, None, &g).unwrap();
    assert_eq!(unmapped.joints(), rig.joints());
    let mesh = &asset.mesh;
    assert_eq!(rig.labels().len(), mesh.vertex_count());
    // Joints are the bind pose's: the pelvis is the skin's root joint.
    let skin = asset.skin.as_ref().unwrap();
    let root = glam::Mat4::from_cols_array_2d(&skin.inverse_bind[0]).inverse();
    let pelvis = rig.joints()[Canonical::Pelvis.index()];
    assert!((pelvis[2] - root.w_axis.z as f64).abs() < 1e-6);
    // The regressors reproduce the joints on the rest frame.
    let sk = rig.frame_joints(mesh.positions());
    for c in Canonical::ALL {
        let want = glam::DVec3::from_array(rig.joints()[c.index()]);
        assert!((sk[c.index()] - want).length() < 1e-6, "{}", c.name());
    }
    // Regression (issue 39 item 10): the spine's regressor was fitted on a
    // thin band with weights from -22 to +15, exact on the rest frame and
    // drawn off the body in every posed one (`render --rig`). Every weight
    // stays within the bound.
    for (c, r) in Canonical::ALL.iter().zip(rig.regressors()) {
        let worst = r.weights.iter().fold(0.0f64, |m, w| m.max(w.abs()));
        assert!(
            worst <= surfmotion::embed::regress::MAX_WEIGHT,
            "{}: a weight of {worst}",
            c.name()
        );
    }
    // Every part labelled somewhere; the limbs are one region each (the
    // head is split by the file's UV seams, which are cuts in the mesh).
    let pieces = piece_counts(
        rig.labels(),
        &neighbours(mesh.vertex_count(), mesh.triangles()),
    );
    for p in Part::ALL {
        assert!(
            rig.labels().iter().any(|&l| l == p.index() as u8),
            "{}",
            p.name()
        );
        if p != Part::Head && p != Part::Torso {
            assert_eq!(pieces[p.index()], 1, "{}", p.name());
        }
    }
    // The same character with its vertices in another order (as another
    // tool may export it) gets the same rig, vertex by vertex.
    let n = mesh.vertex_count();
    let perm: Vec<usize> = (0..n).map(|i| (i * 7919) % n).collect();
    let mut inv = vec![0u32; n];
    for (new, &old) in perm.iter().enumerate() {
        inv[old] = new as u32;
    }
    let shuffled = Mesh::new(
        perm.iter().map(|&o| mesh.positions()[o]).collect(),
        mesh.triangles()
            .iter()
            .map(|t| t.map(|v| inv[v as usize]))
            .collect(),
    )
    .unwrap();
    let again = from_skin(&shuffled, &asset, Some(&map), &g).unwrap();
    assert_eq!(again.joints(), rig.joints());
    let same = perm
        .iter()
        .enumerate()
        .filter(|&(new, &old)| again.skin()[new].0[0] == rig.skin()[old].0[0])
        .count();
    // Vertices duplicated at seams may pick either copy: same weights anyway.
    assert!(same as f64 > 0.99 * n as f64, "{same} of {n}");
    // The rest pose in world space (Y-up here) matches too.
    let (world, _) = asset.rest_pose().unwrap();
    let upright = Mesh::new(world, mesh.triangles().to_vec()).unwrap();
    let w = from_skin(&upright, &asset, Some(&map), &g).unwrap();
    assert!(w.up()[1] > 0.99, "up {:?}", w.up());
    // A different mesh is refused with the reason.
    let arm =
        surfmotion::mesh::io::obj::read_obj(&d.join("scans/armadillo/armadillo.obj")).unwrap();
    let e = from_skin(&arm, &asset, Some(&map), &g)
        .unwrap_err()
        .to_string();
    assert!(e.contains("not this mesh"), "{e}");
}
