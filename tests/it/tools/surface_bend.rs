//! The knees' example-based correction (`deform::bend_examples`, issue 42,
//! session 38) on the real samba capture: learnt from half of its frames,
//! it brings the other half's knees nearer to the capture.

use crate::common;

use glam::DVec3;
use surfmotion::db::Character;
use surfmotion::deform::bend_examples::{BendExamples, knee_angle};
use surfmotion::deform::{DeformMode, DeformOptions, Deformer};
use surfmotion::graph::FlatFrame;
use surfmotion::pose::{Pose, pose_rotations};
use surfmotion::rig::Canonical;

/// Frame `f` of `ch` (metres) and its joints by the rig's regressors.
fn frame(ch: &Character, f: usize) -> (Vec<[f64; 3]>, Pose) {
    let mut x = vec![[0.0; 3]; ch.n()];
    ch.frame_metres(FlatFrame::from_index(f), &mut x);
    let p = ch.rig().frame_joints(&x);
    (x, p)
}

/// `x` (joints `from`) skinned linearly to the joints `to`.
fn skinned(ch: &Character, x: &[[f64; 3]], from: &Pose, to: &Pose) -> Vec<[f64; 3]> {
    let g = pose_rotations(from, to);
    let mut out = vec![[0.0; 3]; x.len()];
    surfmotion::deform::lbs::skin_into(x, ch.rig(), from, to, &g, &mut out);
    out
}

/// Mean distance over `zone` between `a` and `b`.
fn mean_gap(zone: &[u32], a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let sum: f64 = zone
        .iter()
        .map(|&v| (DVec3::from_array(a[v as usize]) - DVec3::from_array(b[v as usize])).length())
        .sum();
    sum / zone.len().max(1) as f64
}

/// Learnt from the even frames of the samba capture, the correction is
/// tested on pairs of odd frames whose knees bend at least 10° apart
/// (both ways round: a straighter source to a more bent target and back):
/// the source skinned to the target's joints lands nearer the captured
/// target in the knees' zones with the correction than without, on most
/// pairs and on the mean; a target bent as the source leaves the source
/// as it is; the captured knee angles span more than 20°.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn held_out_frames_bend_nearer_the_capture() {
    let Some(d) = common::data_dir() else { return };
    let ch = Character::load(&crate::deform::samba_capture_db(&d), &surfmotion::db::Quiet).unwrap();
    let b = BendExamples::from_frames(&ch, 0.2, 1.0, &|f| f % 2 == 0).unwrap();
    let ranges = b.ranges();
    assert_eq!(ranges.len(), 2, "both knees learnt");
    for (lo, hi) in &ranges {
        eprintln!(
            "knee angles captured (even frames): {:.1}°-{:.1}°",
            lo.to_degrees(),
            hi.to_degrees()
        );
        assert!(hi - lo > 20f64.to_radians(), "{lo} {hi}");
    }
    let zone = b.zone();
    assert!(zone.len() > 100, "{} zone vertices", zone.len());
    let joints = [
        [Canonical::LHip, Canonical::LKnee, Canonical::LAnkle],
        [Canonical::RHip, Canonical::RKnee, Canonical::RAnkle],
    ]
    .map(|s| s.map(Canonical::index));
    let odd: Vec<(Vec<[f64; 3]>, Pose)> = (1..ch.frame_count())
        .step_by(2)
        .map(|f| frame(&ch, f))
        .collect();
    let (mut pairs, mut nearer, mut before, mut after) = (0, 0, 0.0, 0.0);
    let mut bent = vec![[0.0; 3]; ch.n()];
    for (i, (xa, pa)) in odd.iter().enumerate() {
        b.bend(xa, pa, pa, ch.rest_pose(), ch.rig(), &mut bent);
        assert_eq!(&bent, xa, "a target bent as the source moved it");
        for (xb, pb) in odd.iter().skip(i + 1).step_by(3) {
            let apart = joints
                .iter()
                .map(|&j| (knee_angle(pa, j) - knee_angle(pb, j)).abs())
                .fold(0.0, f64::max);
            if apart < 10f64.to_radians() {
                continue;
            }
            for (xs, ps, xt, pt) in [(xa, pa, xb, pb), (xb, pb, xa, pa)] {
                b.bend(xs, ps, pt, ch.rest_pose(), ch.rig(), &mut bent);
                let plain = mean_gap(&zone, &skinned(&ch, xs, ps, pt), xt);
                let with = mean_gap(&zone, &skinned(&ch, &bent, ps, pt), xt);
                pairs += 1;
                nearer += usize::from(with < plain);
                before += plain;
                after += with;
            }
        }
    }
    let (before, after) = (before / pairs as f64, after / pairs as f64);
    eprintln!(
        "{pairs} held-out pairs: knees' zones {:.2} → {:.2} cm from the capture, nearer on {nearer}",
        100.0 * before,
        100.0 * after
    );
    assert!(pairs >= 50, "{pairs} pairs");
    assert!(after < before, "{before} → {after}");
    assert!(2 * nearer > pairs, "nearer on {nearer} of {pairs}");
}

/// The deformation with the correction on: a frame deformed to its own
/// joints is the deformation without it, bit for bit (nothing to
/// correct); deformed to another frame's joints it differs and stays
/// finite.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_deformer_bends_only_when_the_knees_differ() {
    let Some(d) = common::data_dir() else { return };
    let ch = Character::load(&crate::deform::samba_capture_db(&d), &surfmotion::db::Quiet).unwrap();
    let plain = Deformer::new(&ch, DeformMode::Part, &DeformOptions::default()).unwrap();
    let opts = DeformOptions {
        bend_examples: 1.0,
        ..Default::default()
    };
    let bend = Deformer::new(&ch, DeformMode::Part, &opts).unwrap();
    let (mut wp, mut wb) = (plain.workspace(), bend.workspace());
    let n = ch.n();
    let (mut a, mut c) = (vec![[0.0; 3]; n], vec![[0.0; 3]; n]);
    let (x0, p0) = frame(&ch, 40);
    plain.deform(&ch, &x0, &p0, &p0, &mut a, &mut wp);
    bend.deform(&ch, &x0, &p0, &p0, &mut c, &mut wb);
    assert_eq!(a, c, "deformed to its own joints");
    let (_, p1) = frame(&ch, 120);
    plain.deform(&ch, &x0, &p0, &p1, &mut a, &mut wp);
    bend.deform(&ch, &x0, &p0, &p1, &mut c, &mut wb);
    assert!(c.iter().flatten().all(|x| x.is_finite()));
    let moved = a.iter().zip(&c).filter(|(p, q)| p != q).count();
    eprintln!("frame 40 to frame 120's joints: {moved} of {n} vertices differ");
    assert!(moved > 0, "the correction changed nothing");
}
