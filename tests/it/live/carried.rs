//! The live analysis's decisions carried over (issue 45, fidelity): a
//! stream pushed raw with a lag covering the clip gives the offline meshes
//! bit for bit (the last analysis is of the whole clip and every frame is
//! still undecided), and at lag 3 the queries the session outputs follow
//! the offline query's motion within a bound the per-window re-decision
//! (a 32-frame window re-deciding the frames already output, settled by
//! 20 % a frame) did not meet.

use super::offline::{character, offline, run_raw, undeformed, worst_difference};
use crate::common;

use surfmotion::drive::query::{ClipQuery, load_mocap};
use surfmotion::drive::{DriveOptions, Prepared};
use surfmotion::live::ground::{OfflineGround, Swap};
use surfmotion::live::{OnlineOptions, SessionOptions};
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::{ClipNeutral, ClipNeutralSource};
use surfmotion::tools::eval::velocity::velocity_error;

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_lag_covering_the_clip_pushed_raw_gives_the_offline_meshes_exactly() {
    let Some(d) = common::data_dir() else { return };
    let ch = character(&d);
    let opts = DriveOptions::default();
    let prepared = Prepared::new(&ch, &opts).unwrap();
    for clip in ["cmu-amc/02/02_02.amc", "cmu-bvh/131_01.bvh"] {
        // Offline on the same frames, without file rotations (the stream
        // is pushed without them).
        let o = offline(&d, &ch, &prepared, &opts, clip, |m| {
            m.reference.without_rotations()
        });
        let n = o.poses.len();
        let (order, queries, live) =
            run_raw(&ch, &prepared, &o.m, &o.poses, false, o.covering, None);
        assert_eq!(order, (0..n).collect::<Vec<_>>(), "{clip}");
        assert_eq!(
            queries, o.analysed.query,
            "{clip}: the queries differ from offline"
        );
        assert_eq!(live.len(), o.meshes.len(), "{clip}");
        let worst = worst_difference(&live, &o.meshes);
        assert_eq!(worst, 0.0, "{clip}: raw-pushed meshes differ by {worst} m");
        eprintln!("{clip}: {n} frames pushed raw at lag {n}: queries and meshes = offline");
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn at_lag_3_the_output_queries_follow_the_offline_motion() {
    let Some(d) = common::data_dir() else { return };
    let ch = character(&d);
    let fps = ch.manifest().fps;
    // The queries do not depend on the deformation: none, to keep it quick.
    let (opts, prepared) = undeformed(&ch);
    // (clip, bound in cm/frame). Measured (the output queries against the
    // offline query, joint-velocity error, lag 3): with the per-window
    // re-decision (32-frame window, settle 0.2) 131_02 0.339, 02_02 0.119;
    // carried (128 frames of context, the undecided frames re-analysed,
    // settle 0.05) 0.206 and 0.097.
    for (clip, bound) in [("cmu-bvh/131_02.bvh", 0.26), ("cmu-amc/02/02_02.amc", 0.11)] {
        let m = load_mocap(&d.join("mocap").join(clip), &Default::default(), fps).unwrap();
        let a = prepared.analyse(&ch, &m.reference, &m.poses);
        let sopts = SessionOptions {
            retarget: opts,
            ..SessionOptions::default()
        };
        let (order, queries, _) = run_raw(&ch, &prepared, &m, &m.poses, true, sopts, None);
        assert_eq!(order, (0..m.poses.len()).collect::<Vec<_>>(), "{clip}");
        let v = velocity_error(&a.query, &queries);
        eprintln!(
            "{clip}: lag 3, the output queries' velocity error against offline's {:.3} cm/frame (bound {bound})",
            v.mean_cm
        );
        assert!(
            v.mean_cm <= bound,
            "{clip}: {:.3} cm/frame > {bound}",
            v.mean_cm
        );
    }
}

/// Mean absolute difference (cm per frame) between two query sequences'
/// frame-to-frame vertical pelvis motion.
fn pelvis_bounce_error(a: &[Pose], b: &[Pose]) -> f64 {
    let p = surfmotion::rig::Canonical::Pelvis.index();
    let n = a.len().min(b.len());
    let sum: f64 = (1..n)
        .map(|k| ((a[k][p].y - a[k - 1][p].y) - (b[k][p].y - b[k - 1][p].y)).abs())
        .sum();
    100.0 * sum / (n.max(2) - 1) as f64
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_running_floor_keeps_the_pelvis_bounce_closer_to_offline() {
    let Some(d) = common::data_dir() else { return };
    let ch = character(&d);
    let fps = ch.manifest().fps;
    let (opts, prepared) = undeformed(&ch);
    {
        let clip = "cmu-bvh/131_02.bvh";
        let m = load_mocap(&d.join("mocap").join(clip), &Default::default(), fps).unwrap();
        let a = prepared.analyse(&ch, &m.reference, &m.poses);
        let bounce = |floor_step: Option<f64>| {
            let sopts = SessionOptions {
                retarget: opts,
                floor_step,
                ..SessionOptions::default()
            };
            let (_, queries, _) = run_raw(&ch, &prepared, &m, &m.poses, true, sopts, None);
            pelvis_bounce_error(&a.query, &queries)
        };
        let (window, running) = (bounce(None), bounce(Some(0.0005)));
        eprintln!(
            "{clip}: lag 3, pelvis bounce error against offline {window:.4} cm/frame on each window's floor, {running:.4} on the running floor"
        );
        assert!(running < window, "{clip}: {running} >= {window}");
    }
}

/// `poses` turned by `deg` about the vertical and moved by `by` (metres).
fn turned(poses: &[Pose], deg: f64, by: glam::DVec3) -> Vec<Pose> {
    let r = glam::DQuat::from_rotation_y(deg.to_radians());
    poses.iter().map(|p| p.map(|x| r * x + by)).collect()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn over_blocks_the_offline_ground_swapped_in_brings_live_closer_to_offline() {
    let Some(d) = common::data_dir() else { return };
    let ch = character(&d);
    let fps = ch.manifest().fps;
    let (opts, prepared) = undeformed(&ch);
    let sopts = SessionOptions {
        retarget: opts,
        online: OnlineOptions {
            lag: 10,
            ..OnlineOptions::default()
        },
        ..SessionOptions::default()
    };
    let all = Swap {
        tilt: true,
        floor: true,
        support: true,
    };
    // CMU subject 03 walks over blocks 11-25 cm high, and each window
    // decides the levelling, the floor and the supports over what has
    // arrived (live::decompose: samba, lag 10, 03_01 0.431 → 0.245 and
    // 03_02 0.464 → 0.254 cm/frame with the offline ones). The output
    // queries' joint-velocity error against offline's must drop when the
    // offline decisions are swapped in, whatever way the clip faces and
    // wherever the stream starts — except where live is already within
    // 0.1 cm/frame of offline: 03_01's last two thirds do not start on the
    // block the whole clip starts on (lag 10: 0.075 cm/frame, 0.084 with
    // the offline ground; 0.431 as read), and there the offline ground
    // need not help, only keep it as close.
    for clip in ["cmu-amc/03/03_01.amc", "cmu-amc/03/03_02.amc"] {
        let m = load_mocap(&d.join("mocap").join(clip), &Default::default(), fps).unwrap();
        // The clip as read, turned 120° and moved 3 m away, and its last
        // two thirds (the stream starting mid-walk): without the file's
        // rotations, which the turned poses no longer match.
        let start = m.poses.len() / 3;
        let (turn, by) = (120.0, glam::DVec3::new(3.0, 0.0, -2.0));
        let variants: [(&str, Vec<Pose>, Pose); 3] = [
            ("as read", m.poses.clone(), m.reference.pose),
            (
                "turned",
                turned(&m.poses, turn, by),
                turned(&[m.reference.pose], turn, by)[0],
            ),
            ("cut", m.poses[start..].to_vec(), m.reference.pose),
        ];
        for (name, poses, pose) in variants {
            // The same neutral pose for the offline and the live analysis.
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
            let error = |swap: Option<Swap>| {
                let g = swap.map(|s| OfflineGround::of(&clip_as.reference, &poses, s));
                let (order, queries, _) =
                    run_raw(&ch, &prepared, &clip_as, &poses, false, sopts, g);
                assert_eq!(order, (0..poses.len()).collect::<Vec<_>>(), "{clip} {name}");
                velocity_error(&a.query, &queries).mean_cm
            };
            let (live, swapped) = (error(None), error(Some(all)));
            eprintln!(
                "{clip} {name}: lag 10, the output queries' velocity error against offline's {live:.3} cm/frame, {swapped:.3} with the offline ground"
            );
            let close = 0.1;
            assert!(
                swapped < live || swapped.max(live) < close,
                "{clip} {name}: {swapped:.3} >= {live:.3}"
            );
        }
    }
}
