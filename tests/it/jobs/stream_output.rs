//! `keyframe` and `play` write their output frame by frame (attack s14,
//! item 3: every frame was held, then the whole file's bytes; 8.6 MB per
//! output second, 7.1 GB for an hour of key-frame path): the streamed
//! files are those of the whole-sequence writer, and a long session is
//! written under an address-space limit its frames would not fit.

use crate::common;

use std::path::Path;
use std::process::Command;
use surfmotion::jobs::SynthCharacter;
use surfmotion::synth::Gait;

/// The small synthetic database (CMU walk 02_01 and run 02_03 on the
/// samba character, 25 fps), built once for this binary.
fn walk_run(d: &Path) -> &'static Path {
    static DB: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    DB.get_or_init(|| common::walk_run_db(d, "stream-walk-run"))
}

/// The smoothness floor tells its progress (in frame pairs of the
/// sequence pairs) from 0 to the end, never backwards, more often than
/// once per sequence pair (`keyframe --floor` ran 116 s on synth3 with
/// nothing on the screen).
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_transition_floor_reports_its_progress_to_the_end() {
    use surfmotion::keyframe::floor::{FloorOptions, transition_floor_with};
    let Some(d) = common::data_dir() else { return };
    let ch = surfmotion::db::Character::load(walk_run(&d), &surfmotion::db::Quiet).unwrap();
    let g = ch.graph();
    let total: u64 = (0..g.sequences().len())
        .flat_map(|i| (i..g.sequences().len()).map(move |j| (i, j)))
        .map(|(i, j)| (g.sequences()[i].len * g.sequences()[j].len) as u64)
        .sum();
    let frames = surfmotion::keyframe::smoothness::FrameSet::new(&ch);
    let mut seen = Vec::new();
    let t = transition_floor_with(
        &ch,
        &frames,
        &FloorOptions::of_graph(g.options()),
        &mut |d, t| seen.push((d, t)),
    );
    assert_eq!(t.pairs.len(), 3);
    assert_eq!(seen.first(), Some(&(0, total)));
    assert_eq!(seen.last(), Some(&(total, total)));
    assert!(seen.windows(2).all(|w| w[0].0 <= w[1].0 && w[1].1 == total));
    assert!(seen.len() > 3 * 4, "{} reports", seen.len());
}

/// The key-frame path written by the CLI (streamed) is byte for byte the
/// library's held frames written whole, for a point cache and a GLB.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_streamed_keyframe_output_is_the_whole_sequence_written_at_once() {
    use surfmotion::keyframe::{KeyframeOptions, Targets, parse_key, synthesise};
    let Some(d) = common::data_dir() else { return };
    let db = walk_run(&d);
    let tmp = tempfile::tempdir().unwrap();
    let ch = surfmotion::db::Character::load(db, &surfmotion::db::Quiet).unwrap();
    let keys = [
        parse_key(&ch, "02_01:0").unwrap(),
        parse_key(&ch, "02_03:30").unwrap(),
    ];
    let targets = Targets::Global {
        distance: 6.0,
        time: 4.0,
    };
    let held = synthesise(&ch, &keys, &targets, &KeyframeOptions::default()).unwrap();
    let fps = ch.manifest().fps;
    let seq = surfmotion::mesh::MeshSequence::new(ch.topology_metres(), held.positions, Some(fps))
        .unwrap();
    // More than one chunk of frames (the blending works in chunks).
    assert!(
        seq.frame_count() > surfmotion::drive::CHUNK_FRAMES,
        "{} frames",
        seq.frame_count()
    );
    for name in ["k.pc2", "k.glb"] {
        let whole = tmp.path().join("whole").join(name);
        let streamed = tmp.path().join(format!("streamed-{name}")).join(name);
        let files = surfmotion::mesh::io::save_sequence(&seq, &whole, Some(fps)).unwrap();
        let o = Command::new(common::bin())
            .args(["keyframe", "--db"])
            .arg(db)
            .args([
                "--from",
                "02_01:0",
                "--to",
                "02_03:30",
                "--distance",
                "6",
                "--time",
                "4",
                "-o",
            ])
            .arg(&streamed)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        for f in files {
            let s = streamed.with_file_name(f.file_name().unwrap());
            assert_eq!(
                std::fs::read(&f).unwrap(),
                std::fs::read(&s).unwrap(),
                "{name}: {s:?}"
            );
        }
        // No temporary left beside the output.
        assert_eq!(
            std::fs::read_dir(streamed.parent().unwrap())
                .unwrap()
                .count(),
            if name.ends_with("pc2") { 2 } else { 1 }
        );
    }
}

/// The demo humanoid walking, running and turning, with a locomotion
/// space (as tests/parametric.rs), built once.
fn gaits() -> std::path::PathBuf {
    let db = common::fixture_dir("stream-gaits").join("db");
    common::gaits::gaits_database(
        &db,
        &SynthCharacter::humanoid().unwrap(),
        &[Gait::Walk, Gait::Run],
        "gaits",
        &[("locomotion", &["walk", "run"], &["speed"])],
    );
    db
}

fn play_under(db: &Path, limit_kb: u64, seconds: f64, out: &Path) -> std::process::Output {
    let script = out.with_file_name("control.json");
    std::fs::write(
        &script,
        r#"[{"t": 0, "space": "locomotion", "speed": 1.4}, {"t": 5, "speed": 2.5}]"#,
    )
    .unwrap();
    let sh = format!(
        "ulimit -v {limit_kb} && exec \"$0\" play --db {} --script {} --seconds {seconds} -o {}",
        db.display(),
        script.display(),
        out.display()
    );
    Command::new("sh")
        .args(["-c", &sh])
        .arg(common::bin())
        .env_remove("SURFMOTION_MEMORY_LIMIT")
        .output()
        .unwrap()
}

/// A session whose frames need more than the memory budget (half of
/// `ulimit -v`) is written, frame by frame, within the limit: it was
/// refused ("would need about ...") or, without the budget, aborted on
/// the allocation of the held frames and the file's bytes. A GLB, which
/// holds every frame, is still refused before any frame is made.
#[test]
fn a_long_play_streams_within_an_address_space_limit() {
    let db = gaits();
    let tmp = tempfile::tempdir().unwrap();
    // Build the model's cache outside the limit.
    let warm = play_under(&db, u32::MAX as u64, 1.0, &tmp.path().join("warm.pc2"));
    assert!(
        warm.status.success(),
        "{}",
        String::from_utf8_lossy(&warm.stderr)
    );
    let n = surfmotion::mesh::io::load_sequence(
        &tmp.path().join("warm.obj").to_string_lossy(),
        &Default::default(),
    )
    .unwrap()
    .mesh()
    .vertex_count() as u64;
    let fps = 30.0;
    // The limit and the session: its frames held (24 bytes a vertex)
    // need twice the budget of half the limit.
    let limit_kb = 800_000u64;
    let seconds = ((limit_kb * 1024) as f64 / (24 * n) as f64 / fps).ceil();
    let out = tmp.path().join("long.pc2");
    let o = play_under(&db, limit_kb, seconds, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let frames = (seconds * fps).round() as u64;
    assert_eq!(
        std::fs::metadata(&out).unwrap().len(),
        32 + frames * n * 12,
        "{seconds} s of {n} vertices"
    );
    let glb = tmp.path().join("long.glb");
    let o = play_under(&db, limit_kb, seconds, &glb);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("a GLB of") && err.contains("address-space limit"),
        "{err}"
    );
    assert!(!glb.exists());
}
