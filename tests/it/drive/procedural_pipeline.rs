//! Retarget and deform end to end on a small generated character, so a
//! fresh clone without ../shared exercises retrieval through the Surface
//! Motion Graph and the part-based deformation (issue 19, "Tests without
//! ../shared"). The character is the procedural humanoid
//! (`synth::humanoid`) at a coarse grid; its database is a walk and a run
//! synthesised from procedural clips (`synth::clips`) with skinning and
//! soft-tissue lag; the query is a walk along a circle, a motion not in
//! the database (Huang et al. 2015, Sec. 5.2).

use std::path::Path;
use std::sync::OnceLock;
use surfmotion::db::Character;
use surfmotion::db::Quiet;
use surfmotion::deform::DeformMode;
use surfmotion::drive::{DriveOptions, Output, synthesise};
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::clip_poses;
use surfmotion::synth::{Gait, gait_clip};
use surfmotion::tools::eval::velocity_error;

/// Grid spacing of the test character (metres): coarser than the demo's
/// 0.02, for speed.
use crate::common;

const GRID: f64 = 0.035;
const FPS: f64 = 30.0;

/// The database (built once per test binary) and the query poses.
struct Fixture {
    /// The database folder.
    db: std::path::PathBuf,
    ch: Character,
    query: surfmotion::pose::retarget::ClipPoses,
}

fn write_database(db: &Path) {
    common::procedural_walk_run_database(db, "procedural", GRID, FPS);
}

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let t = std::time::Instant::now();
        let db = common::fixture_dir("procedural-pipeline").join("db");
        std::fs::create_dir_all(&db).unwrap();
        write_database(&db);
        let ch = Character::load(&db, &Quiet).unwrap();
        // Longer than the database's walk (3 s), so the path must leave it.
        let clip = gait_clip(Gait::Turn, 4.0, FPS);
        let map = surfmotion::rig::detect(&clip.point_names()).map;
        let query = clip_poses(&clip, &map).unwrap();
        eprintln!(
            "fixture: {} vertices, {} database frames, {} transitions, in {:.2} s",
            ch.n(),
            ch.frame_count(),
            ch.graph().transitions().len(),
            t.elapsed().as_secs_f64()
        );
        Fixture { db, ch, query }
    })
}

fn retarget(mode: DeformMode) -> Output {
    let f = fixture();
    let opts = DriveOptions {
        deform: mode,
        ..DriveOptions::default()
    };
    let t = std::time::Instant::now();
    let out = synthesise(&f.ch, &f.query.poses, &f.query.reference, FPS, &opts).unwrap();
    eprintln!("retarget ({mode}): {:.2} s", t.elapsed().as_secs_f64());
    out
}

/// The skeleton the rig reads off each output frame.
fn output_skeletons(ch: &Character, out: &Output) -> Vec<Pose> {
    out.positions
        .chunks(ch.n())
        .map(|f| ch.rig().frame_joints(f))
        .collect()
}

/// Mean distance (metres) between the output's joints and the query's.
fn mean_joint_distance(query: &[Pose], output: &[Pose]) -> f64 {
    let mut s = 0.0;
    let mut k = 0usize;
    for (q, o) in query.iter().zip(output) {
        for (a, b) in q.iter().zip(o.iter()) {
            s += (*a - *b).length();
            k += 1;
        }
    }
    s / k as f64
}

#[test]
fn procedural_database_has_a_graph_with_transitions() {
    let f = fixture();
    // 3 s of walk and 2 s of run at 30 fps.
    assert_eq!(f.ch.frame_count(), 150);
    assert!(f.ch.n() > 500, "{} vertices", f.ch.n());
    assert!(
        !f.ch.graph().transitions().is_empty(),
        "a walk and a run of one character must have transitions"
    );
}

#[test]
fn procedural_retarget_through_the_graph_follows_the_query() {
    let f = fixture();
    let out = retarget(DeformMode::Part);
    let frames = f.query.poses.len();
    assert_eq!(frames, 120);
    assert_eq!(out.report.frames, frames);
    assert_eq!(out.positions.len(), frames * f.ch.n());
    assert_eq!(out.query.len(), frames);
    assert!(out.positions.iter().flatten().all(|c| c.is_finite()));
    // Retrieval: one database frame per query frame, mostly walking (the
    // query walks along a circle; the database walks straight or runs).
    let r = &out.report.retrieval;
    assert_eq!(r.path.len(), frames);
    assert!(r.path.iter().all(|&id| id.index() < f.ch.frame_count()));
    assert_eq!(out.report.steps.len(), frames);
    let walking = out
        .report
        .steps
        .iter()
        .filter(|s| s.sequence == "walk")
        .count();
    eprintln!(
        "walk frames: {walking} of {frames}; jumps {:?}",
        out.report.jumps
    );
    assert!(walking * 2 > frames, "{walking} of {frames} walking frames");
    // Through the graph: each step repeats a frame, follows an edge of the
    // frame graph (next frame of a sequence, or a transition), skips one
    // frame of a sequence (the trellis's counterpart of repetition,
    // `TrellisOptions::skip`), or is a cut the retrieval reports; the
    // query outlasts the walk, so there is at least one jump.
    for (k, w) in r.path.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        let edge = f.ch.adjacency().successors(a).any(|(t, _)| t == b);
        let skip = f.ch.successor(a).and_then(|s| f.ch.successor(s)) == Some(b);
        assert!(
            a == b || edge || skip || r.cuts.contains(&(k + 1)),
            "query frame {}: {a} -> {b} is neither a repeat, a graph edge, a skip nor a cut",
            k + 1
        );
    }
    // Measured: two jumps, both transitions of the graph.
    assert!(
        out.report.jumps.iter().any(|j| j.transition),
        "no transition used in {frames} frames: {:?}",
        out.report.jumps
    );
    // The paper's joint-velocity metric (Huang et al. 2015, Sec. 6.2).
    let skel = output_skeletons(&f.ch, &out);
    let err = velocity_error(&out.query, &skel);
    let dist = mean_joint_distance(&out.query, &skel);
    eprintln!(
        "part: velocity error {:.3} ± {:.3} cm/frame, mean joint distance {:.4} m",
        err.mean_cm, err.std_cm, dist
    );
    assert!(err.mean_cm.is_finite());
    assert!(
        err.mean_cm < 100.0,
        "velocity error {} cm/frame",
        err.mean_cm
    );
}

#[test]
fn procedural_part_deformation_brings_the_mesh_to_the_driving_skeleton() {
    let f = fixture();
    let part = retarget(DeformMode::Part);
    let none = retarget(DeformMode::None);
    // The same retrieval: the deformation only edits the retrieved frames.
    assert_eq!(part.report.retrieval.path, none.report.retrieval.path);
    let d_part = mean_joint_distance(&part.query, &output_skeletons(&f.ch, &part));
    let d_none = mean_joint_distance(&none.query, &output_skeletons(&f.ch, &none));
    eprintln!("mean joint distance to the query: part {d_part:.4} m, none {d_none:.4} m");
    // Measured: part 2.1 mm, none 6.8 mm.
    assert!(d_part < 0.6 * d_none, "part {d_part} vs none {d_none}");
    // The deformation edits the retrieved frames, it does not rebuild
    // them: measured at most 3.1 cm per vertex.
    let max_move = part
        .positions
        .iter()
        .zip(&none.positions)
        .map(|(a, b)| {
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .fold(0.0, f64::max);
    eprintln!("largest vertex displacement by the deformation: {max_move:.4} m");
    assert!(max_move > 0.0);
    assert!(max_move < 0.15, "{max_move} m");
}

/// Copies the files of `from` (and its sub-folders) into `to`.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let dest = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &dest);
        } else {
            std::fs::copy(e.path(), dest).unwrap();
        }
    }
}

/// The key-frame graph's floor centres read the character's frames, which
/// are in metres, Y-up once on load: they must not be converted again
/// (they were scaled by the units twice on a database not in metres).
#[test]
fn keyframe_frame_centres_read_frames_converted_once_on_load() {
    use surfmotion::keyframe::graph::{centre_of, frame_centres};
    let f = fixture();
    let dir = tempfile::tempdir().unwrap();
    let db = dir.path().join("db");
    copy_dir(&f.db, &db);
    let mut manifest = surfmotion::db::Manifest::load(&db).unwrap();
    manifest.units = "cm".into();
    manifest.up = "z".into();
    // Read as cm the body is 1.7 cm tall: not a person's size.
    manifest.human_sized = false;
    manifest.save(&db).unwrap();
    let ch = Character::load(&db, &Quiet).unwrap();
    assert_eq!(ch.metres_per_unit(), 0.01);
    assert!(ch.z_up());
    let centres = frame_centres(&ch);
    assert_eq!(centres.len(), ch.frame_count());
    for (i, c) in centres.iter().enumerate() {
        let want = centre_of(ch.frame(surfmotion::graph::FlatFrame::from_index(i)));
        assert!(
            (c[0] - want[0]).abs() < 1e-12 && (c[1] - want[1]).abs() < 1e-12,
            "frame {i}: centre {c:?}, its frame's centre {want:?}"
        );
    }
    // Not vacuous: the centres are away from the origin by more than a
    // second conversion to centimetres would leave.
    assert!(
        centres.iter().any(|c| c[0].hypot(c[1]) > 1e-3),
        "the walk's centres all sit at the origin"
    );
}

/// Regression (issue 18, item 12): a retarget streamed to its output
/// (`RetargetJob::run_to`, chunks of 64 frames handed on in order) writes
/// the bytes the held path (`run` then `write`) writes, with the same
/// report (turned-over counts, steps) and joint-velocity error; the
/// 120-frame query crosses a chunk boundary.
#[test]
fn streamed_retarget_writes_the_bytes_of_the_held_one() {
    use surfmotion::jobs::{RetargetJob, RetargetJobOptions};
    let f = fixture();
    let tmp = tempfile::tempdir().unwrap();
    let clip = tmp.path().join("turn.bvh");
    surfmotion::mocap::bvh::write_bvh(&gait_clip(Gait::Turn, 4.0, FPS), &clip).unwrap();
    let job = RetargetJob::load(&f.db, RetargetJobOptions::default(), &Quiet).unwrap();
    let held = job.run(&clip).unwrap();
    assert!(held.output.report.frames > surfmotion::drive::CHUNK_FRAMES);
    let held_error = held.velocity_error(&job.character);
    let held_report = serde_json::to_value(&held.output.report.steps).unwrap();
    let held_turned = held.output.report.turned_over;
    let first: Vec<[f64; 3]> = held.output.positions[..job.character.n()].to_vec();
    let held_files = job
        .write(held.output.positions, &tmp.path().join("held.pc2"))
        .unwrap();
    let streamed = job
        .run_to(&clip, &tmp.path().join("streamed.pc2"), 0)
        .unwrap();
    assert_eq!(held_files.len(), streamed.written.len());
    for (a, b) in held_files.iter().zip(&streamed.written) {
        let (a, b) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
        assert!(
            a == b,
            "{} bytes held, {} streamed, differ",
            a.len(),
            b.len()
        );
    }
    assert_eq!(streamed.report.turned_over, held_turned);
    assert_eq!(
        serde_json::to_value(&streamed.report.steps).unwrap(),
        held_report
    );
    assert_eq!(streamed.velocity.mean_cm, held_error.mean_cm);
    // No bytes asked for: one frame is kept, the first.
    assert_eq!(streamed.kept, first);
}

/// Counts the runs of the pose kernel (its `pose_kernel` tracing span) on
/// this thread while `f` runs.
fn kernel_runs(f: impl FnOnce()) -> usize {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
    use tracing::span::{Attributes, Id, Record};
    struct Count(Arc<AtomicUsize>, AtomicU64);
    impl tracing::Subscriber for Count {
        fn enabled(&self, _: &tracing::Metadata<'_>) -> bool {
            true
        }
        fn new_span(&self, a: &Attributes<'_>) -> Id {
            if a.metadata().name() == "pose_kernel" {
                self.0.fetch_add(1, Ordering::Relaxed);
            }
            Id::from_u64(self.1.fetch_add(1, Ordering::Relaxed) + 1)
        }
        fn record(&self, _: &Id, _: &Record<'_>) {}
        fn record_follows_from(&self, _: &Id, _: &Id) {}
        fn event(&self, _: &tracing::Event<'_>) {}
        fn enter(&self, _: &Id) {}
        fn exit(&self, _: &Id) {}
    }
    let n = Arc::new(AtomicUsize::new(0));
    tracing::subscriber::with_default(Count(n.clone(), AtomicU64::new(0)), f);
    n.load(Ordering::Relaxed)
}

/// Issue 40, "a per-clip analysed value computed once and read by
/// synthesis, placement and the plausibility checks": retargeting a clip
/// and checking the result's plausibility runs the pose kernel once per
/// clip, held or streamed, and `eval` once (before: 4 each: the query,
/// then `foot_ground_offsets` and `clip_foot_glide_cm`'s two in the checks;
/// `eval` also found the character's neutral pose twice).
#[test]
fn retarget_and_its_checks_run_the_pose_kernel_once_per_clip() {
    use surfmotion::jobs::{RetargetJob, RetargetJobOptions};
    let f = fixture();
    let tmp = tempfile::tempdir().unwrap();
    let clip = tmp.path().join("walk.bvh");
    surfmotion::mocap::bvh::write_bvh(&gait_clip(Gait::Walk, 2.0, FPS), &clip).unwrap();
    let job = RetargetJob::load(&f.db, RetargetJobOptions::default(), &Quiet).unwrap();
    let mut held = None;
    let runs = kernel_runs(|| {
        let run = job.run(&clip).unwrap();
        assert!(job.plausibility_of(&run).is_some());
        held = Some(run);
    });
    assert_eq!(runs, 1, "held run and its checks");
    let runs = kernel_runs(|| {
        let run = job
            .run_to(&clip, &tmp.path().join("s.pc2"), 1 << 30)
            .unwrap();
        assert!(job.plausibility_of_streamed(&run).is_some());
    });
    assert_eq!(runs, 1, "streamed run and its checks");
    let out = tmp.path().join("held.pc2");
    job.write(held.unwrap().output.positions, &out).unwrap();
    let mut report = None;
    let runs = kernel_runs(|| {
        report = Some(
            surfmotion::jobs::retarget::evaluate_result(
                &job.character,
                &clip,
                &out,
                &Default::default(),
            )
            .unwrap(),
        );
    });
    assert_eq!(runs, 1, "eval");
    assert!(report.unwrap().plausibility.is_some());
}

/// Issue 43: a loaded character embeds its rig from only the frames the
/// skin's motion fit reads (at most 120, taken a sequence at a time with
/// the graph's spans, not every frame of every sequence held at once); on
/// a database of two sequences whose frames the fit samples, the rig is
/// the one embedded from every frame (`db::skeletons::embed_rig`).
#[test]
fn the_rig_from_the_sampled_frames_is_the_rig_from_every_frame() {
    let f = fixture();
    let (m, topo) = surfmotion::db::Manifest::open(&f.db).unwrap();
    assert!(m.sequences.len() >= 2 && f.ch.frame_count() > 120);
    let full = surfmotion::db::skeletons::embed_rig(&f.db, &m, &topo).unwrap();
    assert_eq!(f.ch.rig(), &full);
}

/// Runs `f` and returns what it gave with the warnings logged on this
/// thread meanwhile (their text).
fn warnings_of<T>(f: impl FnOnce() -> T) -> (T, Vec<String>) {
    use std::fmt::Write as _;
    use std::sync::atomic::{AtomicU64, Ordering};
    use std::sync::{Arc, Mutex};
    use tracing::span::{Attributes, Id, Record};
    struct Text<'a>(&'a mut String);
    impl tracing::field::Visit for Text<'_> {
        fn record_debug(&mut self, _: &tracing::field::Field, v: &dyn std::fmt::Debug) {
            let _ = write!(self.0, "{v:?} ");
        }
    }
    struct Log(Arc<Mutex<Vec<String>>>, AtomicU64);
    impl tracing::Subscriber for Log {
        fn enabled(&self, m: &tracing::Metadata<'_>) -> bool {
            *m.level() <= tracing::Level::WARN
        }
        fn new_span(&self, _: &Attributes<'_>) -> Id {
            Id::from_u64(self.1.fetch_add(1, Ordering::Relaxed) + 1)
        }
        fn record(&self, _: &Id, _: &Record<'_>) {}
        fn record_follows_from(&self, _: &Id, _: &Id) {}
        fn event(&self, e: &tracing::Event<'_>) {
            let mut s = String::new();
            e.record(&mut Text(&mut s));
            self.0.lock().unwrap().push(s);
        }
        fn enter(&self, _: &Id) {}
        fn exit(&self, _: &Id) {}
    }
    let log = Arc::new(Mutex::new(Vec::new()));
    let out = tracing::subscriber::with_default(Log(log.clone(), AtomicU64::new(0)), f);
    let got = log.lock().unwrap().clone();
    (out, got)
}

/// A copy of the fixture's database without its rig cache, in a temporary
/// folder.
fn database_copy() -> (tempfile::TempDir, std::path::PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("db");
    copy_dir(&fixture().db, &db);
    let _ = std::fs::remove_file(surfmotion::db::rig_cache::rig_path(&db));
    (tmp, db)
}

/// Issue 43: a loaded character's rig (joints, parts, skin weights,
/// regressors) is cached in its database: the first load embeds and writes
/// it, the second reads it and gives the same character — the rig equal
/// to the first load's and to one embedded from every frame, the same
/// skeletons of every frame — without writing the cache again.
#[test]
fn a_second_load_reads_the_cached_rig_and_gives_the_same_character() {
    use surfmotion::db::rig_cache::{RigSource, rig_path};
    let (_tmp, db) = database_copy();
    let first = Character::load(&db, &Quiet).unwrap();
    assert_eq!(first.rig_source(), RigSource::Embedded);
    let written = std::fs::read(rig_path(&db)).unwrap();
    let stamp = std::fs::metadata(rig_path(&db))
        .unwrap()
        .modified()
        .unwrap();
    let (second, warnings) = warnings_of(|| Character::load(&db, &Quiet).unwrap());
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(second.rig_source(), RigSource::Cached);
    assert_eq!(second.rig(), first.rig());
    assert_eq!(second.rig(), fixture().ch.rig());
    let (m, topo) = surfmotion::db::Manifest::open(&db).unwrap();
    let full = surfmotion::db::skeletons::embed_rig(&db, &m, &topo).unwrap();
    assert_eq!(second.rig(), &full);
    assert_eq!(second.rig().skin(), full.skin(), "the skin weights");
    assert_eq!(second.poses(), first.poses());
    assert_eq!(std::fs::read(rig_path(&db)).unwrap(), written);
    assert_eq!(
        std::fs::metadata(rig_path(&db))
            .unwrap()
            .modified()
            .unwrap(),
        stamp,
        "the cache was written again"
    );
}

/// Issue 43: a rig cache that cannot be trusted — a digit of its rig
/// changed (same length), cut short, of another key, a consistent forgery
/// (checksum mended) whose rig has another vertex count, an empty file,
/// not a cache at all — is refused with a warning naming the file, the rig
/// embedded again (equal to the good one) and the cache written again
/// byte for byte as it was.
#[test]
fn a_changed_cut_or_foreign_rig_cache_is_embedded_again() {
    use surfmotion::db::rig_cache::{RigSource, rig_path};
    let (_tmp, db) = database_copy();
    let good_rig = Character::load(&db, &Quiet).unwrap().rig().clone();
    let path = rig_path(&db);
    let good = std::fs::read(&path).unwrap();
    let nl = good.iter().position(|&b| b == b'\n').unwrap();
    let (head, body) = (&good[..nl], &good[nl + 1..]);
    let head_text = std::str::from_utf8(head).unwrap();
    // A digit of the height changed in place.
    let mut digit = good.clone();
    let h = nl
        + 1
        + std::str::from_utf8(body)
            .unwrap()
            .find("\"height\":")
            .unwrap()
        + 9;
    let at = h + digit[h..].iter().position(|b| b.is_ascii_digit()).unwrap();
    digit[at] = if digit[at] == b'1' { b'2' } else { b'1' };
    // Another key in the header.
    let key = &head_text[head_text.find("\"key\":\"").unwrap() + 7..][..16];
    let other_key = head_text.replace(key, "0123456789abcdef");
    let mut foreign = other_key.into_bytes();
    foreign.push(b'\n');
    foreign.extend_from_slice(body);
    // A forgery with its checksum mended: the rig of one more vertex.
    let mut rig: serde_json::Value = serde_json::from_slice(body).unwrap();
    rig["vertex_count"] = (good_rig.vertex_count() + 1).into();
    let forged_body = serde_json::to_vec(&rig).unwrap();
    let forged_head = format!(
        "{{\"format\":\"surfmotion rig cache 1\",\"key\":\"{key}\",\"bytes\":{},\"xxh3\":\"{:016x}\"}}\n",
        forged_body.len(),
        xxhash_rust::xxh3::xxh3_64(&forged_body)
    );
    let forged = [forged_head.into_bytes(), forged_body].concat();
    let variants: Vec<(&str, Vec<u8>)> = vec![
        ("a digit changed", digit),
        ("cut short", good[..good.len() - 100].to_vec()),
        ("cut in its header", good[..nl / 2].to_vec()),
        ("another key", foreign),
        ("forged, another vertex count", forged),
        ("empty", Vec::new()),
        ("not a cache", b"{\"skin\": []}\nhello".to_vec()),
    ];
    for (what, bytes) in variants {
        std::fs::write(&path, &bytes).unwrap();
        let (ch, warnings) = warnings_of(|| Character::load(&db, &Quiet).unwrap());
        assert_eq!(ch.rig_source(), RigSource::Embedded, "{what}");
        assert_eq!(ch.rig(), &good_rig, "{what}");
        assert!(
            warnings
                .iter()
                .any(|w| w.contains("rig.json") && w.contains("embedding the rig again")),
            "{what}: {warnings:?}"
        );
        assert!(
            std::fs::read(&path).unwrap() == good,
            "{what}: not rewritten"
        );
        let again = Character::load(&db, &Quiet).unwrap();
        assert_eq!(again.rig_source(), RigSource::Cached, "{what}");
    }
}

/// The bytes this process has read through `read` and its kin
/// (`/proc/self/io`'s `rchar`; pages of a memory-mapped file are not
/// counted).
#[cfg(target_os = "linux")]
fn bytes_read() -> u64 {
    let io = std::fs::read_to_string("/proc/self/io").unwrap();
    io.lines()
        .find_map(|l| l.strip_prefix("rchar: "))
        .unwrap()
        .trim()
        .parse()
        .unwrap()
}

/// Issue 43 (the 10⁴-frame retarget read all 1.2 GB of its sequences on
/// every load, for the rig's skin fit): once its caches are written, a
/// load of the samba capture reads less than half its sequence file's
/// bytes in all (21 MB; the first load reads it at least once; what a
/// cached load reads is the topology, hashed into the caches' keys, and
/// the caches: 3.5 MB), and its rig and frames are the first load's.
/// Counted by the process's read bytes, so it runs alone in a process of
/// its own.
#[cfg(target_os = "linux")]
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_second_load_of_the_samba_capture_reads_no_sequence_file() {
    let Some(d) = common::data_dir() else { return };
    if !common::alone_in_process(
        module_path!(),
        "a_second_load_of_the_samba_capture_reads_no_sequence_file",
    ) {
        return;
    }
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("db");
    std::fs::create_dir_all(&db).unwrap();
    let pc2 = d.join("4d/samba/samba.pc2");
    let landmarks =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json");
    let toml = format!(
        "name = \"samba\"\ntopology = {:?}\nfps = 30.0\nunits = \"m\"\nup = \"y\"\n\n[[sequence]]\nname = \"dance\"\npath = {:?}\n\n[rig]\nlandmarks = {:?}\n",
        d.join("4d/samba/samba.obj"),
        pc2,
        landmarks
    );
    std::fs::write(db.join("character.toml"), toml).unwrap();
    let len = std::fs::metadata(&pc2).unwrap().len();
    let r0 = bytes_read();
    let first = Character::load(&db, &Quiet).unwrap();
    let r1 = bytes_read();
    assert!(
        r1 - r0 >= len,
        "the first load read {} of {len} bytes",
        r1 - r0
    );
    let second = Character::load(&db, &Quiet).unwrap();
    let read = bytes_read() - r1;
    assert!(
        read < len / 2,
        "the second load read {read} bytes; the sequence is {len}"
    );
    assert_eq!(second.rig(), first.rig());
    assert_eq!(second.poses(), first.poses());
    let last = surfmotion::graph::FlatFrame::from_index(first.frame_count() - 1);
    assert_eq!(second.frame(last), first.frame(last));
}

/// Issue 43, session 42: `retarget --report` times what runs before the
/// first frame (the load: manifest, similarity, graph, rig, frames, links,
/// the preparation's factorisations) and what runs per clip, each stage's
/// wall and CPU seconds. The stages cover the run: their CPU adds up to
/// no more than the process's at the report (each stage counted once) and
/// to at least 80 % of it (nothing large left outside them); the
/// synthesis's own stage timings fit in its stage.
#[test]
fn the_report_stages_cover_the_retarget() {
    let f = fixture();
    let tmp = tempfile::tempdir().unwrap();
    let clip = tmp.path().join("walk.bvh");
    surfmotion::mocap::bvh::write_bvh(&gait_clip(Gait::Walk, 2.0, FPS), &clip).unwrap();
    let report = tmp.path().join("r.json");
    common::run_ok(
        std::process::Command::new(common::bin())
            .arg("retarget")
            .arg("--db")
            .arg(&f.db)
            .arg("--mocap")
            .arg(&clip)
            .arg("-o")
            .arg(tmp.path().join("out.pc2"))
            .arg("--report")
            .arg(&report),
    );
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let s = &r["stages"];
    let names = |k: &str| -> Vec<String> {
        s[k].as_array()
            .unwrap_or_else(|| panic!("no stages.{k}: {s}"))
            .iter()
            .map(|x| x["stage"].as_str().unwrap().to_string())
            .collect()
    };
    let load = names("load");
    for want in [
        "manifest",
        "similarity",
        "graph",
        "rig",
        "frames",
        "links",
        "neutral pose",
        "blender",
        "deformer",
    ] {
        assert!(
            load.iter().any(|n| n == want),
            "no load stage {want}: {load:?}"
        );
    }
    let clip_stages = names("clip");
    for want in ["clip read", "clip analysed", "synthesis", "plausibility"] {
        assert!(
            clip_stages.iter().any(|n| n == want),
            "no clip stage {want}: {clip_stages:?}"
        );
    }
    let num = |v: &serde_json::Value| v.as_f64().unwrap_or_else(|| panic!("{v} in {s}"));
    let mut cpu = 0.0;
    for k in ["load", "clip"] {
        for st in s[k].as_array().unwrap() {
            assert!(num(&st["wall"]) >= 0.0 && num(&st["cpu"]) >= 0.0, "{st}");
            cpu += num(&st["cpu"]);
        }
    }
    assert!((cpu - num(&s["load_cpu"]) - num(&s["clip_cpu"])).abs() < 1e-6);
    let process = num(&s["process_cpu"]);
    assert!(
        cpu <= process + 0.02,
        "stages {cpu} s of CPU, the process {process} s"
    );
    assert!(
        cpu >= 0.8 * process,
        "stages {cpu} s of CPU of the process's {process} s: {s}"
    );
    // The synthesis's per-stage timings (wall) within its stage.
    let synthesis = s["clip"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["stage"] == "synthesis")
        .map(|x| num(&x["wall"]))
        .unwrap();
    let t = &r["timings"];
    let inside: f64 = ["retrieval", "timeline", "meshes", "deform"]
        .iter()
        .map(|k| num(&t[k]))
        .sum();
    assert!(
        inside <= synthesis + 1e-3,
        "{inside} s in a {synthesis} s synthesis: {t}"
    );
}
