//! The character's neutral pose on a real database whose rest frame is
//! bent (issue 17): `rig::retarget::character_neutral` takes the database
//! frame nearest neutral, and a clip retargeted onto that character matches
//! the one retargeted onto the same capture with an upright rest frame.
//!
//! The capture is the crane performer (`4d/crane`): its frame 0 stands
//! upright (an A-pose); its frame 64 strides, the right leg 33° behind the
//! hip. The bent rig is embedded on frame 64 with
//! `tests/fixtures/crane64.landmarks.json`: the fixture's frame-0 landmarks
//! (and the ankle, toe and shoulder joints of the frame-0 rig) each moved by
//! the mean displacement of its 30 nearest vertices from frame 0 to 64.

use crate::common;

use glam::DVec3;
use surfmotion::db::Character;
use surfmotion::drive::query::load_mocap;
use surfmotion::embed::Embedding;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::{LoadOptions, load_sequence, save_sequence};
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::{NeutralSource, character_neutral, retarget_with_neutral};
use surfmotion::rig::{Canonical as C, LoadOptions as ClipOptions};
use surfmotion::tools::eval::{Checker, PlausibilityOptions};

/// The neck → head bone's angle to the pelvis → neck line (degrees).
fn head_trunk(p: &Pose) -> f64 {
    let (pe, n, h) = (p[C::Pelvis.index()], p[C::Neck.index()], p[C::Head.index()]);
    (h - n).angle_between(n - pe).to_degrees()
}

fn percentile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

/// The data folder and the crane capture (`4d/crane/crane.pc2`); `None`
/// (the test skips) without the data.
fn crane_capture() -> Option<(std::path::PathBuf, MeshSequence)> {
    let d = common::data_dir()?;
    let seq = load_sequence(
        d.join("4d/crane/crane.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    Some((d, seq))
}

/// The crane capture's rig embedded on `frame`, its rest pose and the
/// regressor skeletons of every frame (as a database loads them).
fn character(seq: &MeshSequence, frame: usize, landmarks: &str) -> (Pose, Vec<Pose>) {
    let mesh = seq.mesh().with_positions(seq.frame(frame)).unwrap();
    let lm = Landmarks::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures")
            .join(landmarks),
        mesh.vertex_count(),
    )
    .unwrap();
    let rig = Embedding::new(&mesh, &lm, None).unwrap();
    let rest = rig.frame_joints(seq.frame(frame));
    let poses = (0..seq.frame_count())
        .map(|t| rig.frame_joints(seq.frame(t)))
        .collect();
    (rest, poses)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_bent_rest_frame_takes_the_neutral_from_the_database_and_retargets_as_the_upright_one() {
    let Some((d, seq)) = crane_capture() else {
        return;
    };
    let (up_rest, up_frames) = character(&seq, 0, "crane.landmarks.json");
    let (bent_rest, bent_frames) = character(&seq, 64, "crane64.landmarks.json");
    let up = character_neutral(&up_rest, &up_frames);
    let bent = character_neutral(&bent_rest, &bent_frames);
    assert_eq!(up.source, NeutralSource::Rest);
    // The stride is not upright: the neutral is a database frame, an
    // upright one.
    let NeutralSource::Frame(i) = bent.source else {
        panic!("the bent rest frame was taken as neutral");
    };
    let leg = |p: &Pose| {
        (p[C::RAnkle.index()] - p[C::RHip.index()])
            .angle_between(DVec3::NEG_Y)
            .to_degrees()
    };
    assert!(leg(&bent_rest) > 30.0, "{}", leg(&bent_rest));
    assert!(leg(&bent.pose) < 15.0, "frame {i}: {}", leg(&bent.pose));

    let clip = load_mocap(
        &d.join("mocap/cmu-amc/02/02_02.amc"),
        &ClipOptions::default(),
        30.0,
    )
    .unwrap();
    let run = |rest: &Pose, neutral: &Pose| -> Vec<Pose> {
        retarget_with_neutral(rest, neutral, &clip.reference, &clip.poses)
            .into_iter()
            .map(|(p, _)| p)
            .collect()
    };
    let a = run(&up_rest, &up.pose);
    let b = run(&bent_rest, &bent.pose);
    // Without the neutral: the bent rest frame's attitude kept.
    let c = run(&bent_rest, &bent_rest);
    let height = up_rest[C::Head.index()].y - up_rest[C::LAnkle.index()].y;
    // Every joint relative to the pelvis, frame by frame (the two rigs are
    // embedded on different frames, so bone lengths differ by a few cm).
    let gap = |x: &[Pose], y: &[Pose]| -> Vec<f64> {
        x.iter()
            .zip(y)
            .flat_map(|(p, q)| {
                C::ALL.iter().map(move |j| {
                    let (i, r) = (j.index(), C::Pelvis.index());
                    ((p[i] - p[r]) - (q[i] - q[r])).length() / height
                })
            })
            .collect()
    };
    let (with, without) = (gap(&a, &b), gap(&a, &c));
    let (w95, o95) = (percentile(with.clone(), 0.95), percentile(without, 0.95));
    println!(
        "neutral frame {i}; joints p95 {:.1} % of the height with the neutral, {:.1} % without",
        100.0 * w95,
        100.0 * o95
    );
    assert!(w95 < 0.06, "{w95}");
    assert!(o95 > 2.0 * w95, "{o95} vs {w95}");
    // The head against the trunk, each relative to its own neutral.
    let rel = |x: &[Pose], n: &Pose| -> Vec<f64> {
        x.iter()
            .map(|p| (head_trunk(p) - head_trunk(n)).abs())
            .collect()
    };
    let (ha, hb) = (rel(&a, &up.pose), rel(&b, &bent.pose));
    for q in [0.5, 0.95] {
        let (x, y) = (percentile(ha.clone(), q), percentile(hb.clone(), q));
        println!("head-to-trunk q{q}: upright rest {x:.1}°, bent rest {y:.1}°");
        assert!((x - y).abs() < 2.0, "q{q}: {x} vs {y}");
    }
}

/// A crane database in `dir`: its rest frame `rest` of the capture (with
/// the landmarks fixture `landmarks`) and every fifth frame as a sequence.
fn crane_db(seq: &MeshSequence, dir: &std::path::Path, rest: usize, landmarks: &str) -> Character {
    let pick: Vec<usize> = (0..seq.frame_count()).step_by(5).collect();
    let frames: Vec<[f64; 3]> = pick.iter().flat_map(|&t| seq.frame(t).to_vec()).collect();
    let mesh = seq.mesh().with_positions(seq.frame(rest)).unwrap();
    save_sequence(
        &MeshSequence::single(mesh.clone()),
        &dir.join("rest.obj"),
        None,
    )
    .unwrap();
    let s = MeshSequence::new(mesh, frames, Some(30.0)).unwrap();
    save_sequence(&s, &dir.join("crane.pc2"), Some(30.0)).unwrap();
    let lm = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(landmarks);
    std::fs::write(
        dir.join("character.toml"),
        format!(
            "name = \"crane\"\ntopology = \"rest.obj\"\nfps = 30.0\nunits = \"m\"\nup = \"y\"\n\n\
             [[sequence]]\nname = \"crane\"\npath = \"crane.pc2\"\n\n[rig]\nlandmarks = {:?}\n",
            lm.to_str().unwrap()
        ),
    )
    .unwrap();
    Character::load(dir, &surfmotion::db::Quiet).unwrap()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_head_measure_of_a_bent_rest_database_starts_from_its_neutral_frame() {
    let Some((_, seq)) = crane_capture() else {
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let (du, db) = (tmp.path().join("up"), tmp.path().join("bent"));
    std::fs::create_dir_all(&du).unwrap();
    std::fs::create_dir_all(&db).unwrap();
    let up = crane_db(&seq, &du, 0, "crane.landmarks.json");
    let bent = crane_db(&seq, &db, 64, "crane64.landmarks.json");
    let cu = Checker::for_character(&up, PlausibilityOptions::default()).unwrap();
    let cb = Checker::for_character(&bent, PlausibilityOptions::default()).unwrap();
    // The bent database's neutral is one of its frames, and the head
    // measure reads zero there (it read the difference from the stride).
    let NeutralSource::Frame(i) = character_neutral(bent.rest_pose(), bent.poses()).source else {
        panic!("the stride was taken as neutral");
    };
    let at = cb
        .head
        .angle_deg(bent.frame(surfmotion::graph::FlatFrame::from_index(i)));
    assert!(at.abs() < 1e-9, "frame {i}: {at}");
    let from_rest = cb
        .head
        .raw_deg(bent.frame(surfmotion::graph::FlatFrame::from_index(i)))
        - cb.head.raw_deg(bent.topology().positions());
    assert!(from_rest.abs() > 1.0, "{from_rest}");
    // The capture's own head figures agree with the upright-rest
    // database's (the vertex sets are chosen on each rest frame, so they
    // differ a little), and far better than measured from the stride.
    let (ru, rb) = (
        cu.reference.as_ref().unwrap().head_torso_deg,
        cb.reference.as_ref().unwrap().head_torso_deg,
    );
    let rest_raw = cb.head.raw_deg(bent.topology().positions());
    let mut stride: Vec<f64> = surfmotion::graph::FlatFrame::all(bent.frame_count())
        .map(|f| (cb.head.raw_deg(bent.frame(f)) - rest_raw).abs())
        .collect();
    let stride_p95 = percentile(std::mem::take(&mut stride), 0.95);
    println!(
        "capture's head-to-torso median / p95: upright rest {:.1} / {:.1}, bent rest {:.1} / {:.1} (the stride as zero: p95 {stride_p95:.1}; neutral frame {from_rest:+.1} from it)",
        ru.median, ru.p95, rb.median, rb.p95
    );
    assert!((ru.median - rb.median).abs() < 1.0, "{ru:?} {rb:?}");
    assert!((ru.p95 - rb.p95).abs() < 2.0, "{ru:?} {rb:?}");
    assert!(
        (ru.p95 - stride_p95).abs() > 2.0 * (ru.p95 - rb.p95).abs(),
        "{stride_p95}"
    );
}
