//! Issue 45, the whole per-frame step: once the analysis window is full, a
//! push — the pose kernel over the window, the online retrieval, the
//! timeline and placement, the blend and the part-based deformation with
//! its fold repair — makes no allocation call but faer's ordering and
//! symbolic analysis of each repair patch (counted apart: a patch's
//! sparsity differs frame to frame; `deform::unflip`'s test bounds it),
//! and but where the repair meets a larger patch than any before and its
//! kept buffers grow to it (seen as their capacity growing; a few pushes,
//! bounded below).
//!
//! The library tests' counting allocator counts per thread
//! ([`crate::deform::allocation_calls`]); the session runs inside a
//! one-thread rayon pool this test installs, so every parallel part of the
//! step (the kernel's frames and rotations, the triangles' tests, the
//! regions' solves) runs on the thread counted.

use super::{LiveFrame, OnlineOptions, Overlap, Session, SessionOptions};
use crate::db::Character;
use crate::db::build::Quiet;
use crate::deform::allocation_calls;
use crate::drive::trellis::DatabaseLinks;
use crate::drive::{DriveOptions, Prepared};
use crate::embed::Embedding;
use crate::jobs::{SynthCharacter, SynthClip, SynthOptions, write_synthetic_database};
use crate::pose::Pose;
use crate::pose::retarget::{ClipPoses, JointRotations, clip_poses};
use crate::synth::humanoid::{humanoid_landmarks, humanoid_landmarks_json, humanoid_mesh};
use crate::synth::{Gait, gait_clip};
use glam::{DQuat, DVec3};
use std::path::Path;

const FPS: f64 = 30.0;

/// The project's humanoid (meshed at 4 cm) walking for 3 s and running
/// for 2 s, written into `dir` as `synth` writes a database, and loaded.
fn database(dir: &Path) -> Character {
    let rest = humanoid_mesh(0.04);
    let rig = Embedding::new(&rest, &humanoid_landmarks(&rest), None).unwrap();
    let character = SynthCharacter {
        rest,
        rig,
        landmarks_json: humanoid_landmarks_json().into_bytes(),
    };
    let clips: Vec<SynthClip> = [(Gait::Walk, 3.0), (Gait::Run, 2.0)]
        .iter()
        .map(|&(g, s)| SynthClip::from_clip(g.name(), &gait_clip(g, s, FPS)).unwrap())
        .collect();
    let opts = SynthOptions {
        fps: FPS,
        name: Some("push".into()),
        truth: false,
        plausibility: false,
        force: true,
        ..Default::default()
    };
    write_synthetic_database(dir, &character, &clips, &opts, &mut |_, _| {}).unwrap();
    Character::load(dir, &Quiet).unwrap()
}

/// A stream: its poses and, when it has them, each frame's file joints'
/// rotations.
type Stream = (Vec<Pose>, Option<Vec<JointRotations>>);

/// The query streams: a generated walk along a circle (not in the
/// database) as generated (with its joints' rotations, which the kernel
/// turns the chest by), mirrored, turned 1.1 rad about the vertical (its
/// rotations turned too) and scaled to a 20 % shorter actor.
fn streams(q: &ClipPoses) -> Vec<(&'static str, Stream)> {
    let turn = DQuat::from_rotation_y(1.1);
    let rotations: Vec<JointRotations> = q.reference.rotations.to_vec();
    let map =
        |f: &dyn Fn(DVec3) -> DVec3| -> Vec<Pose> { q.poses.iter().map(|p| p.map(f)).collect() };
    let turned: Vec<JointRotations> = rotations
        .iter()
        .map(|w| w.map(|r| r.map(|r| turn * r)))
        .collect();
    vec![
        ("as generated", (q.poses.clone(), Some(rotations))),
        ("mirrored", (map(&|p| DVec3::new(-p.x, p.y, p.z)), None)),
        ("turned", (map(&|p| turn * p), Some(turned))),
        ("shorter", (map(&|p| p * 0.8), None)),
    ]
}

/// Per push: the allocation calls outside faer's symbolic analysis, the
/// frames output, how many of them the fold repair ran on, and whether
/// the deformation's kept buffers grew.
type Push = (usize, usize, usize, bool);

/// The most the deformation workspaces of a session of [`run`] may hold
/// (bytes): far above what the repair's largest patch needs (a few MiB),
/// checked every push so that buffers that double each other stop the
/// test before they take the machine's memory.
const HELD_AT_MOST: usize = 1 << 30;

/// Pushes `stream` through a session (`overlap`, `lag`) inside a
/// one-thread rayon pool.
fn run(
    ch: &Character,
    prepared: &Prepared,
    q: &ClipPoses,
    stream: &Stream,
    (lag, overlap): (usize, Overlap),
) -> Vec<Push> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        let links = DatabaseLinks::of(ch);
        let input = links.input();
        let opts = SessionOptions {
            online: OnlineOptions {
                lag,
                ..OnlineOptions::default()
            },
            overlap,
            ..SessionOptions::default()
        };
        let reference = q.reference.without_rotations();
        let mut s = Session::new(ch, prepared, &input, reference, opts);
        let mut counts = Vec::new();
        let (poses, rotations) = stream;
        for (i, p) in poses.iter().enumerate() {
            let w = rotations.as_ref().map(|r| &r[i]);
            let (mut out, mut repaired) = (0, 0);
            let held = s.deform_capacity();
            let before = allocation_calls();
            s.push(p, w, &mut |f: LiveFrame<'_>| {
                out += 1;
                repaired += usize::from(f.stages.repaired);
            });
            let calls = allocation_calls() - before;
            let now = s.deform_capacity();
            assert!(now <= HELD_AT_MOST, "push {i}: {now} bytes held");
            counts.push((calls, out, repaired, now > held));
        }
        counts
    })
}

/// Issue 45: after the first full analysis window (and the placement's
/// history), every push of a generated stream — as generated, mirrored,
/// turned, a shorter actor; at lag 3 and 0 — allocates nothing on the
/// thread that runs the whole step, and each outputs a frame; but a push
/// whose fold repair grew its kept buffers to a larger patch than before
/// (at most one push in ten). The window filling allocates at most two
/// calls a push on average (the counter runs: the session reserves its
/// window and sizes the kernel's buffers once, [`Session::new`]); the
/// fold repair runs on some of the frames counted (its lists are kept,
/// not made).
#[test]
fn a_full_window_push_allocates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let ch = database(&dir.path().join("db"));
    let prepared = Prepared::new(&ch, &DriveOptions::default()).unwrap();
    assert!(prepared.deformer().is_some(), "the deformation must run");
    let clip = gait_clip(Gait::Turn, 10.0, FPS);
    let map = crate::rig::detect(&clip.point_names()).map;
    let q = clip_poses(&clip, &map).unwrap();
    let opts = SessionOptions::default();
    let (mut repaired, mut counted, mut grown) = (0, 0, 0);
    for (name, stream) in streams(&q) {
        for lag in [3, 0] {
            let full = opts.analysis_window + lag + opts.history;
            let counts = run(&ch, &prepared, &q, &stream, (lag, Overlap::Off));
            let case = format!("{name}, lag {lag}");
            assert!(counts.len() > full + 60, "{case}: {} frames", counts.len());
            let filling: usize = counts[..full].iter().map(|c| c.0).sum();
            assert!(filling > 0, "{case}: the window filled without allocating");
            // While the window fills: the window's rotations (one `Arc` a
            // push) and buffers doubling as the placement's history grows
            // (session 45: ~7 calls a push, 1,277 over this fill).
            assert!(
                filling <= 2 * full,
                "{case}: {filling} allocation calls over the {full} pushes filling the window"
            );
            for (i, &(calls, out, r, grew)) in counts.iter().enumerate().skip(full) {
                assert_eq!(out, 1, "{case}: push {i} output {out} frames");
                if grew {
                    grown += 1;
                } else {
                    assert_eq!(calls, 0, "{case}: push {i} made {calls} allocation calls");
                }
                counted += 1;
                repaired += r;
            }
        }
    }
    eprintln!("{counted} pushes counted, {repaired} repaired, {grown} grew the repair's buffers");
    assert!(counted > 0);
    assert!(
        repaired > 0,
        "the fold repair ran on none of the {counted} frames"
    );
    assert!(
        grown * 10 <= counted,
        "{grown} of {counted} pushes grew the buffers"
    );
}

/// Issue 45, the two-frame overlap: with every frame held and deformed in
/// a pair (`Overlap::Always`; the two slots' repair buffers evened out
/// after every pair), the deformation's buffers grow on at most one push
/// in ten after the first full window, as with one slot, and never hold
/// more than [`HELD_AT_MOST`] (session 44: the repair's lists were grown
/// to the other slot's with amortised doubling, so two slots could double
/// each other's every pair).
#[test]
fn pairs_keep_the_repair_buffers_bounded() {
    let dir = tempfile::tempdir().unwrap();
    let ch = database(&dir.path().join("db"));
    let prepared = Prepared::new(&ch, &DriveOptions::default()).unwrap();
    let clip = gait_clip(Gait::Turn, 10.0, FPS);
    let map = crate::rig::detect(&clip.point_names()).map;
    let q = clip_poses(&clip, &map).unwrap();
    let opts = SessionOptions::default();
    let (mut out, mut repaired, mut counted, mut grown) = (0, 0, 0, 0);
    for (_, stream) in streams(&q) {
        let lag = 3;
        let full = opts.analysis_window + lag + opts.history;
        let counts = run(&ch, &prepared, &q, &stream, (lag, Overlap::Always));
        // Frames come out in pairs: one fewer or more than the pushes.
        let pushed = counts.len() - full;
        let o: usize = counts[full..].iter().map(|c| c.1).sum();
        assert!(o.abs_diff(pushed) <= 1, "{o} frames out of {pushed} pushes");
        for &(_, _, r, grew) in &counts[full..] {
            repaired += r;
            grown += usize::from(grew);
        }
        (out, counted) = (out + o, counted + pushed);
    }
    eprintln!("{counted} pushes counted, {out} frames out, {repaired} repaired, {grown} grew");
    assert!(repaired > 0, "the fold repair ran on none of the frames");
    assert!(
        grown * 10 <= counted,
        "{grown} of {counted} pushes grew the buffers"
    );
}
