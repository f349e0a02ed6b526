//! The jobs layer (issue 19) on the procedural humanoid, no shared data:
//! a synthetic database written by one call, built, its skeletons exported
//! in the one schema, a clip retargeted through it, a folder batched with
//! any converter; the loaded character in metres once, with its skeleton
//! kind selectable.

use crate::common;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use surfmotion::batch::{Converted, Converter};
use surfmotion::db::{Character, CharacterOptions, Manifest, Quiet};
use surfmotion::embed::frames::SkeletonKind;
use surfmotion::jobs::skeletons::SkeletonsOptions;
use surfmotion::jobs::{
    BatchOptions, RetargetJob, RetargetSummary, SynthCharacter, SynthClip, SynthOptions,
    batch_folder, build_database, export_skeletons, write_synthetic_database,
};
use surfmotion::mesh::io::load_sequence;
use surfmotion::synth::{Gait, gait_clip};

/// A small synthetic database of the humanoid (walk 2 s, run 1.5 s).
fn humanoid_db(dir: &Path) -> surfmotion::jobs::SynthReport {
    let clips = [
        SynthClip::from_clip("walk", &gait_clip(Gait::Walk, 2.0, 30.0)).unwrap(),
        SynthClip::from_clip("run", &gait_clip(Gait::Run, 1.5, 30.0)).unwrap(),
    ];
    let ch = SynthCharacter::humanoid().unwrap();
    let mut seen = Vec::new();
    let r = write_synthetic_database(dir, &ch, &clips, &SynthOptions::default(), &mut |s, p| {
        seen.push((s.sequence.clone(), p.len()))
    })
    .unwrap();
    let n = ch.rest.vertex_count();
    assert_eq!(
        seen,
        [("walk".to_string(), 60 * n), ("run".to_string(), 45 * n)]
    );
    r
}

/// The keys of a JSON file's top-level object, in file order.
fn keys(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut k: Vec<String> = v.as_object().unwrap().keys().cloned().collect();
    // serde_json's map is sorted: the file order is checked on the text.
    let pos = |s: &str| text.find(&format!("\"{s}\"")).unwrap();
    k.sort_by_key(|s| pos(s));
    k
}

#[test]
fn synthetic_database_is_one_call_and_skeletons_share_one_schema() {
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("db");
    let r = humanoid_db(&db);
    assert_eq!(r.frames, 105);
    assert_eq!(r.sequences.len(), 2);
    let m = Manifest::load(&db).unwrap();
    assert_eq!(m.sequences.len(), 2);
    assert_eq!(m.name, "db");
    // A second write refuses to overwrite without `force`.
    let again = write_synthetic_database(
        &db,
        &SynthCharacter::humanoid().unwrap(),
        &[],
        &SynthOptions::default(),
        &mut |_, _| {},
    );
    assert!(again.unwrap_err().to_string().contains("`force`"));
    // Ground truth and extracted skeletons: one schema, sorted keys.
    assert_eq!(
        keys(&db.join("truth/walk.skeleton.json")),
        ["fps", "frames", "joints", "sequence", "source"]
    );
    let sk = export_skeletons(&db, &SkeletonsOptions::default()).unwrap();
    assert_eq!(sk.kind, SkeletonKind::Rigid);
    assert_eq!(
        keys(&db.join("skeletons/walk.skeleton.json")),
        ["fps", "frames", "joints", "kind", "sequence"]
    );
    assert!(db.join("skeletons/run.bvh").is_file());
    // The typed report serialises with the fields the CLI always printed.
    let v = serde_json::to_value(&sk.sequences[0]).unwrap();
    for k in [
        "bone_lengths",
        "fit_rms_median",
        "worst_bone",
        "json",
        "bvh",
    ] {
        assert!(v.get(k).is_some(), "{k} missing from {v}");
    }
}

#[test]
fn character_is_in_metres_once_and_its_skeleton_kind_is_selectable() {
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("db");
    humanoid_db(&db);
    // The same files read as centimetres, Z-up.
    let mut m = Manifest::load(&db).unwrap();
    m.units = "cm".into();
    m.up = "z".into();
    // Read as cm the body is 1.7 cm tall: not a person's size.
    m.human_sized = false;
    m.save(&db).unwrap();
    let (_, report) = build_database(&db, &Default::default(), &Quiet).unwrap();
    assert_eq!(report.frames, 105);
    let ch = Character::load(&db, &Quiet).unwrap();
    let walk = load_sequence(db.join("walk.pc2").to_str().unwrap(), &Default::default()).unwrap();
    let f = surfmotion::graph::FlatFrame::new(7);
    for (got, file) in ch.frame(f).iter().zip(walk.frame(f.index())) {
        let want = [file[0] * 0.01, file[2] * 0.01, -file[1] * 0.01];
        for k in 0..3 {
            assert!((got[k] - want[k]).abs() < 1e-12, "{got:?} vs {want:?}");
        }
    }
    // Frame ids: (sequence, frame) and the flat id the graph uses.
    let id = surfmotion::db::FrameId { seq: 1, frame: 4 };
    let flat = surfmotion::graph::FlatFrame::new(64);
    assert_eq!(ch.checked_flat_id(id), Some(flat));
    assert_eq!(ch.frame_at(flat), id);
    assert_eq!(
        ch.checked_flat_id(surfmotion::db::FrameId { seq: 1, frame: 45 }),
        None
    );
    let mut buf = vec![[0.0; 3]; ch.n()];
    ch.frame_metres(f, &mut buf);
    assert_eq!(buf, ch.frame(f));
    // Regressor is the default; rigid skeletons keep their bone lengths.
    assert_eq!(
        CharacterOptions::default().skeleton,
        SkeletonKind::Regressor
    );
    let rigid = Character::load_with(
        &db,
        &Quiet,
        &CharacterOptions {
            skeleton: SkeletonKind::Rigid,
        },
    )
    .unwrap();
    let differ = ch
        .poses()
        .iter()
        .zip(rigid.poses())
        .any(|(a, b)| a.iter().zip(b).any(|(p, q)| (*p - *q).length() > 1e-6));
    assert!(differ, "the skeleton kind made no difference");
}

#[test]
fn a_clip_retargets_through_a_synthetic_database_in_one_call() {
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("db");
    humanoid_db(&db);
    let clip = tmp.path().join("turn.bvh");
    surfmotion::mocap::bvh::write_bvh(&gait_clip(Gait::Turn, 2.0, 30.0), &clip).unwrap();
    let job = RetargetJob::load(&db, Default::default(), &Quiet).unwrap();
    let run = job.run(&clip).unwrap();
    assert_eq!(run.output.report.frames, 60);
    let e = run.velocity_error(&job.character);
    assert!(e.mean_cm.is_finite() && e.mean_cm < 2.0, "{}", e.mean_cm);
    let summary = RetargetSummary::new(vec![], &run.output.report, None);
    let v = serde_json::to_value(&summary).unwrap();
    let k: Vec<&String> = v.as_object().unwrap().keys().collect();
    assert_eq!(
        k,
        [
            "cuts",
            "deformation",
            "edge_cost",
            "fps",
            "frames",
            "ms_per_frame",
            "node_cost",
            "output",
            "plausibility",
            "t_skel",
            "timings",
            "transitions",
            "trellis_nodes",
            "turned_over",
            "widened"
        ]
    );
    let out = tmp.path().join("turn.pc2");
    let files = job.write(run.output.positions, &out).unwrap();
    assert_eq!(files.len(), 2);
    assert_eq!(
        load_sequence(out.to_str().unwrap(), &Default::default())
            .unwrap()
            .frame_count(),
        60
    );
    // The `eval` verb is one call: the result scored against its clip, and
    // a result of another clip (frames that do not pair) refused.
    let load = surfmotion::rig::LoadOptions::default();
    let r =
        surfmotion::jobs::retarget::evaluate_result(&job.character, &clip, &out, &load).unwrap();
    assert_eq!((r.query_frames, r.result_frames), (60, 60));
    assert!((r.velocity_error_cm_per_frame - e.mean_cm).abs() < 1e-3);
    let short = tmp.path().join("short.bvh");
    surfmotion::mocap::bvh::write_bvh(&gait_clip(Gait::Turn, 1.0, 30.0), &short).unwrap();
    let err = surfmotion::jobs::retarget::evaluate_result(&job.character, &short, &out, &load)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("turn.pc2: 60 frames, but") && err.contains("gives 30 frames"),
        "{err}"
    );
}

/// A converter that writes the clip's name: a new batch job is one impl.
struct Echo;

impl Converter for Echo {
    fn describe(&self) -> String {
        "echo".into()
    }
    fn convert(&self, clip: &Path, out: &Path) -> Result<Converted, String> {
        if clip.to_string_lossy().contains("bad") {
            return Err("refused".into());
        }
        std::fs::write(out, clip.to_string_lossy().as_bytes()).map_err(|e| e.to_string())?;
        Ok(Converted {
            frames: 3,
            error_cm: None,
            warnings: Vec::new(),
            fixed_seconds: None,
        })
    }
}

/// Collects the messages of `surfmotion::notice` events.
struct Notices(Arc<Mutex<Vec<String>>>);

impl<S: tracing::Subscriber> tracing_subscriber::Layer<S> for Notices {
    fn on_event(&self, e: &tracing::Event<'_>, _: tracing_subscriber::layer::Context<'_, S>) {
        struct M(String);
        impl tracing::field::Visit for M {
            fn record_debug(&mut self, f: &tracing::field::Field, v: &dyn std::fmt::Debug) {
                if f.name() == "message" {
                    self.0 = format!("{v:?}");
                }
            }
        }
        if e.metadata().target() == surfmotion::jobs::batch::NOTICE {
            let mut m = M(String::new());
            e.record(&mut m);
            self.0.lock().unwrap().push(m.0);
        }
    }
}

#[test]
fn batch_folder_runs_any_converter_and_raises_notices_as_tracing_events() {
    use tracing_subscriber::prelude::*;
    let tmp = tempfile::tempdir().unwrap();
    let clips = tmp.path().join("clips");
    std::fs::create_dir_all(&clips).unwrap();
    // `walk.bvh` and `walk.amc` would write one output: renamed, with a notice.
    for name in ["walk.bvh", "walk.amc", "bad.bvh"] {
        std::fs::write(clips.join(name), b"").unwrap();
    }
    let out: PathBuf = tmp.path().join("out");
    let seen = Arc::new(Mutex::new(Vec::new()));
    let subscriber = tracing_subscriber::registry().with(Notices(seen.clone()));
    let r = tracing::subscriber::with_default(subscriber, || {
        batch_folder(&clips, &out, &Echo, &BatchOptions::default(), &|_| {}).unwrap()
    });
    assert_eq!((r.summary.clips, r.summary.failed), (3, 1));
    assert!(out.join("walk-bvh.glb").is_file() && out.join("walk-amc.glb").is_file());
    assert_eq!(r.notices.len(), 1);
    assert!(
        r.notices[0].contains("named with their extension"),
        "{:?}",
        r.notices
    );
    assert_eq!(*seen.lock().unwrap(), r.notices);
    assert!(r.files.iter().any(|f| f.ends_with("batch.json")));
}

/// Runs [`transfer_onto_scan`] and checks its progress reports: one per
/// frame solved, every one with the total frame count (the `transfer`
/// verb's bar took its length from them; it was created with length 0).
fn transfer_with_progress(
    scan: &surfmotion::mesh::Mesh,
    spec: &surfmotion::jobs::TransferSpec,
) -> surfmotion::jobs::TransferOutcome {
    use surfmotion::jobs::{FrameProgress, transfer_onto_scan};
    let seen: Mutex<Vec<FrameProgress>> = Mutex::new(Vec::new());
    let out = transfer_onto_scan(scan, spec, &|p| seen.lock().unwrap().push(p)).unwrap();
    let mut seen = seen.into_inner().unwrap();
    assert_eq!(seen.len(), out.frames, "one progress report per frame");
    assert!(
        seen.iter().all(|p| p.total == out.frames),
        "every report carries the total ({} frames)",
        out.frames
    );
    seen.sort_by_key(|p| p.done);
    assert!(
        seen.iter().enumerate().all(|(i, p)| p.done == i + 1),
        "frames done count 1..={}",
        out.frames
    );
    out
}

#[test]
fn transfer_onto_scan_animates_the_procedural_humanoid_from_a_clip() {
    use surfmotion::jobs::{ScanTransferJob, ScanTransferOptions, TransferSource, TransferSpec};
    use surfmotion::synth::humanoid::{humanoid_landmarks, humanoid_landmarks_json, humanoid_mesh};
    let tmp = tempfile::tempdir().unwrap();
    let scan = humanoid_mesh(0.035);
    let lm = tmp.path().join("humanoid.landmarks.json");
    std::fs::write(&lm, humanoid_landmarks_json()).unwrap();
    let clip = tmp.path().join("walk.bvh");
    surfmotion::mocap::bvh::write_bvh(&gait_clip(Gait::Walk, 1.0, 30.0), &clip).unwrap();
    let spec = TransferSpec {
        scan_name: "humanoid".into(),
        landmarks: Some(lm),
        automatic: Default::default(),
        markers: None,
        save_markers: None,
        source: TransferSource::Mocap(clip.clone()),
        truth: None,
        options: ScanTransferOptions::default(),
    };
    let out = transfer_with_progress(&scan, &spec);
    assert_eq!(out.frames, 30);
    let n = out.prepared.mesh.vertex_count();
    assert!(n > 500, "{n} vertices");
    assert_eq!(out.positions.len(), 30 * n);
    assert!(out.positions.iter().flatten().all(|x| x.is_finite()));
    assert!(out.truth_error.is_none());
    // The clip's own head range reaches transfer's plausibility, as in
    // retarget, eval and synth (its head line: issue 17).
    let p = out.plausibility.as_ref().expect("a rigged scan is checked");
    let own = p
        .clip_head_torso_deg
        .expect("transfer passes the clip's head range");
    assert!(own.p95.is_finite(), "{own:?}");
    // The body moves: some vertex of the last frame is away from the rest
    // scan by more than a centimetre (the humanoid is in metres).
    let rest = out.prepared.mesh.positions();
    let moved = out.positions[29 * n..]
        .iter()
        .zip(rest)
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt())
        .fold(0.0, f64::max);
    assert!(moved > 0.01, "the last frame moved {moved} m at most");
    // The one-off job and the job prepared once for many clips (`batch
    // --scan`) give the same frames, and the result follows the clip.
    let job = ScanTransferJob::prepare(
        &scan,
        &humanoid_landmarks(&scan),
        "humanoid",
        ScanTransferOptions::default(),
    )
    .unwrap();
    let run = job.run(&clip).unwrap();
    assert_eq!(run.positions.len(), out.positions.len());
    let diff = run
        .positions
        .iter()
        .zip(&out.positions)
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    assert!(diff < 1e-9, "the two paths differ by {diff}");
    let e = job.velocity_error(&run).unwrap();
    assert!(e.mean_cm.is_finite() && e.mean_cm < 2.0, "{}", e.mean_cm);
    // Written by one call, with its report.
    let path = tmp.path().join("walk.pc2");
    let report = out
        .write(
            &path,
            surfmotion::mesh::io::glb::GlbOptions::DEFAULT,
            surfmotion::mesh::io::usd::UsdOptions::DEFAULT,
            false,
        )
        .unwrap();
    assert_eq!(report.frames, 30);
    assert_eq!(report.output.len(), 2);
    assert_eq!(
        load_sequence(path.to_str().unwrap(), &Default::default())
            .unwrap()
            .frame_count(),
        30
    );
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn transfer_onto_scan_reproduces_the_samba_capture_from_its_first_frame() {
    use surfmotion::jobs::{ScanTransferOptions, TransferSource, TransferSpec};
    let Some(d) = common::data_dir() else { return };
    let samba = d.join("4d/samba/samba.pc2");
    let samba = samba.to_str().unwrap().to_string();
    let seq = load_sequence(&samba, &Default::default()).unwrap();
    let scan = seq.frame_mesh(0);
    let lm = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json");
    let spec = TransferSpec {
        scan_name: format!("{samba}:0"),
        landmarks: Some(lm),
        automatic: Default::default(),
        markers: None,
        save_markers: None,
        source: TransferSource::Template {
            spec: samba.clone(),
            markers: None,
            landmarks: None,
            frame: 0,
        },
        truth: Some(samba),
        options: ScanTransferOptions {
            markers: surfmotion::transfer::MarkerOptions {
                count: 80,
                ..Default::default()
            },
            ..Default::default()
        },
    };
    let out = transfer_with_progress(&scan, &spec);
    assert_eq!(out.frames, seq.frame_count());
    // The same bound as the `transfer` verb's self-transfer test.
    let e = out.truth_error.as_ref().unwrap();
    assert!(e.mean_pct > 0.0 && e.mean_pct < 5.0, "{}", e.mean_pct);
}

/// `retarget --skeleton` selects how the database frames' skeletons are
/// read (issue 19: the kind was selectable in the library only); the
/// default is the regressor's.
#[test]
fn retarget_reads_the_skeleton_kind_given_on_the_command_line() {
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("db");
    humanoid_db(&db);
    let clip = tmp.path().join("turn.bvh");
    surfmotion::mocap::bvh::write_bvh(&gait_clip(Gait::Turn, 1.0, 30.0), &clip).unwrap();
    let run = |name: &str, extra: &[&str]| {
        let out = tmp.path().join(format!("{name}.pc2"));
        let o = std::process::Command::new(common::bin())
            .args(["retarget", "--db"])
            .arg(&db)
            .arg("--mocap")
            .arg(&clip)
            .arg("-o")
            .arg(&out)
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read(out).unwrap()
    };
    let default = run("default", &[]);
    let regressor = run("regressor", &["--skeleton", "regressor"]);
    let rigid = run("rigid", &["--skeleton", "rigid"]);
    assert_eq!(default, regressor, "the default is not the regressor's");
    assert!(rigid != regressor, "--skeleton rigid changed nothing");
}
