//! Mocap-driven synthesis on a synthetic samba database made from CMU
//! clips (walk 02_01, run 02_03, 01_01), queried with other clips.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::Command;
use surfmotion::db::Character;
use surfmotion::drive::query::load_mocap;
use surfmotion::drive::timeline::plays_on;
use surfmotion::drive::{DriveOptions, synthesise};
use surfmotion::similarity::VertexSet;
use surfmotion::similarity::vertex::VertexOptions;
use surfmotion::tools::eval::velocity_error;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_surfmotion")
}

fn database(d: &Path) -> PathBuf {
    common::synthetic_db(d)
}

fn run(ch: &Character, clip: &Path, opts: &DriveOptions) -> (surfmotion::drive::Output, usize) {
    let fps = ch.manifest().fps;
    let m = load_mocap(clip, &Default::default(), fps).unwrap();
    let out = synthesise(ch, &m.poses, &m.reference, fps, opts).unwrap();
    (out, m.poses.len())
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn paths_are_valid_outputs_complete_and_own_clips_come_back() {
    let Some(d) = common::data_dir() else { return };
    let db = database(&d);
    let ch = Character::load(&db, &surfmotion::db::Quiet).unwrap();
    let n = ch.n();
    for clip in ["cmu-amc/02/02_02.amc", "cmu-bvh/131_01.bvh"] {
        let (out, frames) = run(&ch, &d.join("mocap").join(clip), &DriveOptions::default());
        let r = &out.report;
        // The query's length at the database frame rate, no NaN.
        assert_eq!(r.frames, frames, "{clip}");
        assert_eq!(out.positions.len(), frames * n);
        assert!(
            out.positions.iter().flatten().all(|x| x.is_finite()),
            "{clip}"
        );
        // Every step plays on (repeat, next, skip), follows a graph edge,
        // or is a reported cut.
        let p = &r.retrieval.path;
        for k in 1..p.len() {
            let edge = ch.adjacency().successors(p[k - 1]).any(|(j, _)| j == p[k]);
            let cut = r.retrieval.cuts.contains(&k);
            assert!(
                plays_on(&ch, p[k - 1], p[k]) || edge || cut,
                "{clip} step {k}"
            );
        }
        // Output frames are placed on the query's trajectory: the extracted
        // pelvis follows the query's pelvis.
        let pelvis: Vec<f64> = (0..frames)
            .map(|f| {
                let s = ch.rig().frame_joints(&out.positions[f * n..(f + 1) * n]);
                let (a, b) = (s[0], out.query[f][0]);
                glam::DVec2::new(a.x - b.x, a.z - b.z).length()
            })
            .collect();
        let worst = pelvis.iter().cloned().fold(0.0, f64::max);
        assert!(worst < 0.15, "{clip}: pelvis {worst} m off the query's");
        eprintln!(
            "{clip}: {} frames, {} jumps, {} cuts, T_skel {:.2}",
            frames,
            r.jumps.len(),
            r.retrieval.cuts.len(),
            r.retrieval.t_skel
        );
    }
    // A clip that is in the database returns that clip's own frames.
    let (out, frames) = run(
        &ch,
        &d.join("mocap/cmu-amc/02/02_03.amc"),
        &DriveOptions::default(),
    );
    let seq = ch
        .graph()
        .sequences()
        .iter()
        .position(|s| s.name == "02_03")
        .unwrap();
    let own = out
        .report
        .retrieval
        .path
        .iter()
        .enumerate()
        .filter(|&(k, &id)| ch.graph().frame_of(id) == (seq, k))
        .count();
    assert!(
        own * 10 >= frames * 9,
        "{own} of {frames} frames are the clip's own"
    );
    // Near-zero retrieval cost: under 1 cm per joint on average (what is
    // left is the regressors reading the skeleton off a skirted mesh).
    let per_joint = out.report.retrieval.skeleton_cost.iter().sum::<f64>() / (frames * 19) as f64;
    assert!(per_joint < 0.01, "{per_joint} m per joint");
    let e = velocity_error(&out.query, &skeletons(&ch, &out.positions));
    assert!(e.mean_cm < 0.5, "{e:?}");
}

fn skeletons(ch: &Character, p: &[[f64; 3]]) -> Vec<surfmotion::pose::Pose> {
    p.chunks(ch.n()).map(|f| ch.rig().frame_joints(f)).collect()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn interpolated_frames_lie_between_their_neighbours() {
    let Some(d) = common::data_dir() else { return };
    let db = database(&d);
    let ch = Character::load(&db, &surfmotion::db::Quiet).unwrap();
    let n = ch.n();
    // A slow query: a walk at half speed forces repeats.
    let fps = ch.manifest().fps;
    let m = load_mocap(
        &d.join("mocap/cmu-amc/02/02_02.amc"),
        &Default::default(),
        fps,
    )
    .unwrap();
    let slow: Vec<_> = (0..2 * m.poses.len())
        .map(|k| {
            let (a, b) = (
                m.poses[k / 2],
                m.poses[k.div_ceil(2).min(m.poses.len() - 1)],
            );
            std::array::from_fn(|j| (a[j] + b[j]) * 0.5)
        })
        .collect();
    // Interpolation only (the deformation would move frames off the
    // captured ones on purpose).
    let opts = DriveOptions {
        deform: surfmotion::deform::DeformMode::None,
        ..Default::default()
    };
    let out = synthesise(&ch, &slow, &m.reference, fps, &opts).unwrap();
    let r = &out.report;
    let mut checked = 0;
    let mut buf = vec![[0.0; 3]; n];
    for (k, step) in r.steps.iter().enumerate() {
        if step.blend.len() != 2 || step.blend[0].0 != step.blend[1].0 {
            continue;
        }
        // Shape distances (floor-aligned RMS) between the output and the
        // two captured frames it interpolates.
        let seq = ch
            .graph()
            .sequences()
            .iter()
            .position(|s| s.name == step.blend[0].0)
            .unwrap();
        let mut set = VertexSet::new(
            n,
            VertexOptions {
                velocity_weight: 0.0,
            },
        );
        set.push_sequence(&out.positions[k * n..(k + 1) * n], false);
        for (_, f, _) in &step.blend {
            ch.frame_metres(ch.graph().flat_id(seq, *f), &mut buf);
            set.push_sequence(&buf, false);
        }
        use surfmotion::similarity::PairDistance;
        let gap = set.distance(1, 2);
        assert!(set.distance(0, 1) <= gap * 1.05 + 1e-4, "frame {k}");
        assert!(set.distance(0, 2) <= gap * 1.05 + 1e-4, "frame {k}");
        checked += 1;
    }
    assert!(checked >= 10, "only {checked} interpolated frames");
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn cli_writes_glb_report_and_evaluates() {
    let Some(d) = common::data_dir() else { return };
    let db = database(&d);
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("walk.glb");
    let report = tmp.path().join("walk.json");
    let clip = d.join("mocap/cmu-amc/02/02_02.amc");
    let o = Command::new(bin())
        .arg("retarget")
        .arg("--db")
        .arg(&db)
        .arg("--mocap")
        .arg(&clip)
        .arg("-o")
        .arg(&out)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("path:") && text.contains("02_01"), "{text}");
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let steps = r["steps"].as_array().unwrap();
    assert_eq!(steps.len(), r["frames"].as_u64().unwrap() as usize);
    assert!(steps[0]["sequence"].is_string() && steps[0]["frame"].is_u64());
    let seq =
        surfmotion::mesh::io::load_sequence(out.to_str().unwrap(), &Default::default()).unwrap();
    assert_eq!(seq.frame_count(), steps.len());
    let e = Command::new(bin())
        .arg("eval")
        .arg("--db")
        .arg(&db)
        .arg("--mocap")
        .arg(&clip)
        .arg("--result")
        .arg(&out)
        .arg("--json")
        .output()
        .unwrap();
    assert!(e.status.success(), "{}", String::from_utf8_lossy(&e.stderr));
    let v: serde_json::Value = serde_json::from_slice(&e.stdout).unwrap();
    let err = v["velocity_error_cm_per_frame"].as_f64().unwrap();
    // The paper reports about 2 cm/frame for walks with interpolation only.
    assert!(err > 0.0 && err < 4.0, "{err}");
    // eval_refuses_a_result_of_another_clip (issue 18, item 8): 02_01 has
    // more frames than 02_02's result; the pairing would be meaningless.
    let other = Command::new(bin())
        .arg("eval")
        .arg("--db")
        .arg(&db)
        .arg("--mocap")
        .arg(d.join("mocap/cmu-amc/02/02_01.amc"))
        .arg("--result")
        .arg(&out)
        .output()
        .unwrap();
    let msg = String::from_utf8_lossy(&other.stderr);
    assert_eq!(other.status.code(), Some(1), "{msg}");
    assert!(msg.contains("this clip") && msg.contains("frames"), "{msg}");
    // Bad input: a clip that does not exist is a one-line error, exit 1.
    let bad = Command::new(bin())
        .arg("retarget")
        .arg("--db")
        .arg(&db)
        .arg("--mocap")
        .arg(tmp.path().join("missing.bvh"))
        .arg("-o")
        .arg(tmp.path().join("x.pc2"))
        .output()
        .unwrap();
    assert_eq!(bad.status.code(), Some(1));
}

/// An AMC clip and its BVH conversions (in the file's units and in metres)
/// drive a character to the same poses within 1e-3 of its height, with the
/// same neutral reference (the ASF's upright rest skeleton).
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn an_amc_clip_and_its_bvh_conversions_drive_the_character_alike() {
    use surfmotion::drive::query::to_character;
    use surfmotion::embed::Embedding;
    use surfmotion::pose::retarget::ClipNeutralSource;
    use surfmotion::synth::humanoid::{DEMO_GRID, humanoid_landmarks, humanoid_mesh};
    let Some(d) = common::data_dir() else { return };
    let mesh = humanoid_mesh(DEMO_GRID);
    let rig = Embedding::new(&mesh, &humanoid_landmarks(&mesh), None).unwrap();
    let rest = rig.joints().map(glam::DVec3::from_array);
    let tmp = tempfile::tempdir().unwrap();
    for clip in ["cmu-amc/02/02_01.amc", "cmu-amc/01/01_01.amc"] {
        let amc = d.join("mocap").join(clip);
        let a = load_mocap(&amc, &Default::default(), 30.0).unwrap();
        assert_eq!(a.reference.source, ClipNeutralSource::Rest, "{clip}");
        let qa = to_character(&rest, &a.reference, &a.poses);
        for (name, metres) in [("units.bvh", false), ("metres.bvh", true)] {
            let bvh = tmp.path().join(name);
            let mut cmd = Command::new(bin());
            cmd.args(["mocap", "convert"]).arg(&amc).arg(&bvh);
            if metres {
                cmd.arg("--metres");
            }
            let o = cmd.output().unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            let b = load_mocap(&bvh, &Default::default(), 30.0).unwrap();
            assert_eq!(b.reference.source, a.reference.source, "{clip} {name}");
            let qb = to_character(&rest, &b.reference, &b.poses);
            assert_eq!(qa.len(), qb.len(), "{clip} {name}");
            let worst = qa
                .iter()
                .zip(&qb)
                .flat_map(|(p, q)| p.iter().zip(q).map(|(x, y)| x.distance(*y)))
                .fold(0.0, f64::max);
            eprintln!("{clip} vs {name}: worst joint {:.2e} m", worst);
            assert!(
                worst < 1e-3 * rig.height(),
                "{clip} vs {name}: {worst} m apart"
            );
        }
    }
}
