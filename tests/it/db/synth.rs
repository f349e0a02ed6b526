//! Synthetic 4D databases: the samba dancer driven by CMU clips.

use crate::common;

use std::path::Path;
use std::process::Command;
use surfmotion::embed::Embedding;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::embed::parts::Part;
use surfmotion::mesh::io::obj::read_obj;
use surfmotion::pose::measure::bone_lengths;
use surfmotion::pose::retarget::clip_poses;
use surfmotion::rig::Canonical;
use surfmotion::rig::load_clip;
use surfmotion::synth::database::{Dynamics, drive};

fn samba_rig(d: &Path) -> (surfmotion::mesh::Mesh, Embedding) {
    let rest = read_obj(&d.join("4d/samba/samba.obj")).unwrap();
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json");
    let lm = Landmarks::load(&fixture, rest.vertex_count()).unwrap();
    let rig = Embedding::new(&rest, &lm, None).unwrap();
    (rest, rig)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn walk_and_run_have_the_right_frames_rigid_bones_and_measurable_dynamics() {
    let Some(d) = common::data_dir() else { return };
    let (rest, rig) = samba_rig(&d);
    let rest_lengths = bone_lengths(&rig.joints().map(glam::DVec3::from_array));
    for clip_name in ["02/02_01.amc", "02/02_03.amc"] {
        let mut clip = load_clip(
            &d.join("mocap/cmu-amc").join(clip_name),
            &Default::default(),
        )
        .unwrap();
        clip.to_metres_y_up();
        let clip = clip.resampled(30.0);
        let names = clip.point_names();
        let map = surfmotion::rig::detect(&names).map;
        let poses = clip_poses(&clip, &map).unwrap();
        let out = drive(
            &rest,
            &rig,
            &poses.poses,
            &poses.reference,
            30.0,
            Dynamics::default(),
        );
        let n = rest.vertex_count();
        let frames = clip.frame_count();
        assert_eq!(out.poses.len(), frames, "{clip_name}");
        assert_eq!(out.positions.len(), frames * n);
        assert!(
            out.positions
                .iter()
                .all(|p| p.iter().all(|x| x.is_finite()))
        );
        // The driving skeleton keeps the character's bone lengths.
        for p in &out.poses {
            let l = bone_lengths(p);
            for c in Canonical::ALL.iter().skip(1) {
                assert!((l[c.index()] - rest_lengths[c.index()]).abs() < 1e-9);
            }
        }
        // It moves: the pelvis travels (a walk and a run go somewhere).
        let travel = out.poses[frames - 1][0].distance(out.poses[0][0]);
        assert!(travel > 0.5, "{clip_name}: pelvis moved {travel} m");
        // Secondary dynamics: the skirt lags behind pure skinning, the head
        // does not move off it at all.
        let offset = |v: usize| {
            (0..frames)
                .map(|f| {
                    let (a, b) = (out.positions[f * n + v], out.skinned[f * n + v]);
                    glam::DVec3::from_array(a).distance(glam::DVec3::from_array(b))
                })
                .fold(0.0, f64::max)
        };
        let skirt: Vec<usize> = (0..n)
            .filter(|&v| {
                let y = rest.positions()[v][1];
                (0.55..0.75).contains(&y)
                    && matches!(
                        Part::ALL[rig.labels()[v] as usize],
                        Part::LThigh | Part::RThigh
                    )
            })
            .collect();
        let head: Vec<usize> = (0..n)
            .filter(|&v| Part::ALL[rig.labels()[v] as usize] == Part::Head)
            .collect();
        assert!(!skirt.is_empty() && !head.is_empty());
        let skirt_mean = skirt.iter().map(|&v| offset(v)).sum::<f64>() / skirt.len() as f64;
        let head_max = head.iter().map(|&v| offset(v)).fold(0.0, f64::max);
        eprintln!("{clip_name}: skirt mean max-offset {skirt_mean:.4} m, head {head_max:e}");
        // 5 mm until the lag was damped where it would fold (issue 42:
        // the synth3 hem crumpled by the repair): 02_01 measured 3.76 mm
        // after it.
        assert!(
            skirt_mean > 0.0025,
            "{clip_name}: skirt offset {skirt_mean}"
        );
        // The head is rigid in the dynamics; since issue 42's synth fix a
        // frame whose skinning folds a triangle is repaired in a patch
        // around the fold, which may reach the head by a fraction of a
        // millimetre (02_03: 0.13 mm).
        assert!(head_max < 1e-3, "{clip_name}: head offset {head_max}");
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn synth_cli_writes_a_database_whose_skeletons_follow_the_truth() {
    let Some(d) = common::data_dir() else { return };
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("samba_synth");
    let o = Command::new(common::bin())
        .args(["synth", "--json", "--seconds", "2", "--mesh"])
        .arg(d.join("4d/samba/samba.obj"))
        .arg("--landmarks")
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json"))
        .arg("--mocap")
        .arg(d.join("mocap/cmu-amc/02/02_01.amc"))
        .arg(d.join("mocap/cmu-bvh/01_01.bvh"))
        .arg("-o")
        .arg(&db)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["frames"], 120);
    let o = Command::new(common::bin())
        .args(["db", "info", "--json"])
        .arg(&db)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = Command::new(common::bin())
        .args(["db", "skeleton", "--json"])
        .arg(&db)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The extracted skeleton tracks the skeleton that drove the synthesis.
    for seq in ["02_01", "01_01"] {
        let read = |p: std::path::PathBuf| -> Vec<Vec<[f64; 3]>> {
            let v: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
            serde_json::from_value(v["frames"].clone()).unwrap()
        };
        let got = read(db.join("skeletons").join(format!("{seq}.skeleton.json")));
        let truth = read(db.join("truth").join(format!("{seq}.skeleton.json")));
        assert_eq!(got.len(), 60);
        assert_eq!(truth.len(), 60);
        let mut sum = 0.0;
        let mut count = 0.0;
        for (g, t) in got.iter().zip(&truth) {
            for j in 0..Canonical::COUNT {
                sum += glam::DVec3::from_array(g[j]).distance(glam::DVec3::from_array(t[j]));
                count += 1.0;
            }
        }
        let mean = sum / count;
        assert!(mean < 0.05, "{seq}: mean joint error {mean} m");
    }
}
