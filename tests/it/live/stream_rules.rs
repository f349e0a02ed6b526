//! The stream's own ground rules (issue 45, fidelity; options, off by
//! default): the window's end open (a foot that has left its support and
//! not landed counts with the floor under it, `Given::open_end`) and the
//! levelling and floor decided once after 64 frames and kept
//! (`live::kept`), against s24's rules (the defaults: each window decides
//! both; a foot in the air at the window's end counts with the support it
//! left), on CMU subject 03's walk over blocks, the clip as read and moved
//! about (turned and moved, turned and rescaled, cut).

use super::offline::{character, offline, run_raw, undeformed, worst_difference};
use crate::common;

use glam::{DQuat, DVec3};
use surfmotion::drive::query::{ClipQuery, load_mocap};
use surfmotion::live::{OnlineOptions, SessionOptions};
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::{ClipNeutral, ClipNeutralSource};
use surfmotion::tools::eval::velocity::velocity_error;

/// `poses` turned by `deg` about the vertical, scaled by `k` about the
/// origin and moved by `by` (metres).
fn moved(poses: &[Pose], deg: f64, k: f64, by: DVec3) -> Vec<Pose> {
    let r = DQuat::from_rotation_y(deg.to_radians());
    poses.iter().map(|p| p.map(|x| r * (k * x) + by)).collect()
}

/// The clip's variants: (name, poses, neutral pose).
fn variants(m: &ClipQuery) -> Vec<(&'static str, Vec<Pose>, Pose)> {
    let start = m.poses.len() / 3;
    let by = DVec3::new(3.0, 0.4, -2.0);
    let one = |deg: f64, k: f64, by: DVec3| {
        (
            moved(&m.poses, deg, k, by),
            moved(&[m.reference.pose], deg, k, by)[0],
        )
    };
    let (turned, turned_ref) = one(120.0, 1.0, by);
    let (scaled, scaled_ref) = one(-35.0, 1.2, DVec3::ZERO);
    vec![
        ("as read", m.poses.clone(), m.reference.pose),
        ("turned 120 and moved", turned, turned_ref),
        ("turned -35, scaled 1.2", scaled, scaled_ref),
        (
            "cut to its last two thirds",
            m.poses[start..].to_vec(),
            m.reference.pose,
        ),
    ]
}

/// The session options with both stream rules on (the ground kept after
/// 64 frames, the window's end open).
fn with_rules(base: SessionOptions) -> SessionOptions {
    SessionOptions {
        keep_ground: Some(64),
        open_end: true,
        ..base
    }
}

/// The session options with the window's end open alone.
fn open_end(base: SessionOptions) -> SessionOptions {
    SessionOptions {
        open_end: true,
        ..base
    }
}

/// Each variant of `clip` at `lag`: the output queries' joint-velocity
/// error against the offline query (cm/frame) with s24's rules and with
/// both stream rules on.
fn errors(d: &std::path::Path, clip: &str, lag: usize) -> Vec<(String, f64, f64)> {
    errors_with(d, clip, lag, with_rules)
}

/// [`errors`] with the stream's rules set by `rules` (from s24's).
fn errors_with(
    d: &std::path::Path,
    clip: &str,
    lag: usize,
    rules: fn(SessionOptions) -> SessionOptions,
) -> Vec<(String, f64, f64)> {
    let ch = character(d);
    let fps = ch.manifest().fps;
    let (opts, prepared) = undeformed(&ch);
    let m = load_mocap(&d.join("mocap").join(clip), &Default::default(), fps).unwrap();
    let s24 = SessionOptions {
        retarget: opts,
        online: OnlineOptions {
            lag,
            ..OnlineOptions::default()
        },
        keep_ground: None,
        open_end: false,
        ..SessionOptions::default()
    };
    let mut out = Vec::new();
    for (name, poses, pose) in variants(&m) {
        // The same neutral pose for the offline and the live analysis,
        // without the file's rotations (the moved poses no longer match).
        let reference = ClipNeutral {
            pose,
            source: ClipNeutralSource::Rest,
            ..m.reference.without_rotations()
        };
        let a = prepared.analyse(&ch, &reference, &poses);
        let clip_as = ClipQuery {
            poses: poses.clone(),
            reference,
            ..m.clone()
        };
        let error = |sopts: SessionOptions| {
            let (order, queries, _) = run_raw(&ch, &prepared, &clip_as, &poses, false, sopts, None);
            assert_eq!(order, (0..poses.len()).collect::<Vec<_>>(), "{clip} {name}");
            velocity_error(&a.query, &queries).mean_cm
        };
        let (old, new) = (error(s24), error(rules(s24)));
        eprintln!(
            "{clip} {name}, lag {lag}: output queries against offline {old:.3} cm/frame with s24's rules, {new:.3} with the stream's"
        );
        out.push((name.to_string(), old, new));
    }
    out
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn at_lag_0_over_blocks_the_stream_rules_bring_live_closer_to_offline() {
    let Some(d) = common::data_dir() else { return };
    // CMU 03_01 starts on a block 23 cm high and steps down off it; at
    // lag 0 the output frame is the window's end, where s24's rule held
    // the body up on the block the leading foot had left until its landing
    // was seen. Measured on the samba database: 0.522 -> 0.348 cm/frame
    // as read; at lag 3 the rules lose (0.442 -> 0.555), so only lag 0 is
    // held here.
    let clip = "cmu-amc/03/03_01.amc";
    for (name, old, new) in errors(&d, clip, 0) {
        assert!(
            new < 0.8 * old,
            "{clip} {name}, lag 0: {new:.3} >= 0.8 x {old:.3} cm/frame"
        );
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_lag_covering_a_walk_over_blocks_gives_offline_bit_for_bit_with_the_rules_on() {
    let Some(d) = common::data_dir() else { return };
    let ch = character(&d);
    let (opts, prepared) = undeformed(&ch);
    // Nothing is output before the stream ends, so neither rule applies:
    // the last analysis is the whole clip's, as offline.
    for clip in ["cmu-amc/03/03_01.amc", "cmu-amc/03/03_02.amc"] {
        let o = offline(&d, &ch, &prepared, &opts, clip, |m| {
            m.reference.without_rotations()
        });
        let covering = with_rules(o.covering);
        let (_, queries, live) = run_raw(&ch, &prepared, &o.m, &o.poses, false, covering, None);
        assert_eq!(queries, o.analysed.query, "{clip}: the queries differ");
        let worst = worst_difference(&live, &o.meshes);
        assert_eq!(worst, 0.0, "{clip}: the frames differ by {worst} m");
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn at_lag_3_over_blocks_the_open_end_steps_down_no_worse_than_s24() {
    let Some(d) = common::data_dir() else { return };
    // With a lag the output frame is inside the window: s25's open end
    // dropped the body onto the floor the frame the leading foot left
    // the block (CMU 03_01 frame 40, 8 cm below offline; 0.442 -> 0.547
    // cm/frame on samba) and a later window's landing lifted it back.
    // The causal step-down carries the body down from the block no
    // faster than the clip's pelvis falls. Measured on samba: 0.442 ->
    // 0.443 as read and turned, 0.480 -> 0.462 turned and scaled, 0.159 ->
    // 0.145 cut (s25's open end: 1.24x s24's as read).
    let clip = "cmu-amc/03/03_01.amc";
    for (name, old, new) in errors_with(&d, clip, 3, open_end) {
        assert!(
            new <= 1.05 * old,
            "{clip} {name}, lag 3: open end {new:.3} > 1.05 x s24's {old:.3} cm/frame"
        );
    }
}
