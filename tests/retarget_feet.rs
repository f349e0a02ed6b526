//! Where the retargeting kernel stands the character's feet (issue 17,
//! "feet"; `surfmotion::rig::retarget`): on generated clips, so no
//! ../shared is needed. Each foot is put on the support it touches, not on
//! the other foot's.

use glam::DVec3;
use surfmotion::rig::Canonical;
use surfmotion::rig::retarget::{choose_reference, leg_length, retarget};
use surfmotion::skeleton::Pose;

use Canonical as C;

/// A person standing upright, 1.6 m, feet flat (ankle 8 cm up, toe joint
/// 2 cm up and 14 cm forward), facing +Z.
fn standing() -> Pose {
    let mut p = [DVec3::ZERO; Canonical::COUNT];
    let mut set = |c: C, x: f64, y: f64, z: f64| p[c.index()] = DVec3::new(x, y, z);
    set(C::Pelvis, 0.0, 1.0, 0.0);
    set(C::Spine, 0.0, 1.15, 0.0);
    set(C::Chest, 0.0, 1.35, 0.0);
    set(C::Neck, 0.0, 1.5, 0.0);
    set(C::Head, 0.0, 1.6, 0.0);
    set(C::LShoulder, 0.18, 1.45, 0.0);
    set(C::LElbow, 0.2, 1.18, 0.0);
    set(C::LWrist, 0.21, 0.93, 0.0);
    set(C::RShoulder, -0.18, 1.45, 0.0);
    set(C::RElbow, -0.2, 1.18, 0.0);
    set(C::RWrist, -0.21, 0.93, 0.0);
    set(C::LHip, 0.1, 0.95, 0.0);
    set(C::LKnee, 0.1, 0.52, 0.0);
    set(C::LAnkle, 0.1, 0.08, 0.0);
    set(C::LToe, 0.1, 0.02, 0.14);
    set(C::RHip, -0.1, 0.95, 0.0);
    set(C::RKnee, -0.1, 0.52, 0.0);
    set(C::RAnkle, -0.1, 0.08, 0.0);
    set(C::RToe, -0.1, 0.02, 0.14);
    p
}

/// The joints of one leg (hip excluded): knee, ankle, toe.
fn leg(left: bool) -> [C; 3] {
    if left {
        [C::LKnee, C::LAnkle, C::LToe]
    } else {
        [C::RKnee, C::RAnkle, C::RToe]
    }
}

/// The character's pelvis height per frame against the clip's, each from
/// its first frame, the clip's scaled by the ratio of leg lengths: the
/// largest difference between consecutive frames' changes (m).
fn worst_pelvis_step(clip: &[Pose], character: &Pose) -> (usize, f64) {
    let rf = choose_reference(Some(&clip[0]), clip).unwrap();
    let s = leg_length(character) / leg_length(&rf.pose);
    let out = retarget(character, &rf, clip);
    let p = C::Pelvis.index();
    (1..clip.len())
        .map(|t| {
            let want = (clip[t][p].y - clip[t - 1][p].y) * s;
            let got = out[t].0[p].y - out[t - 1].0[p].y;
            (t, (got - want).abs())
        })
        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a })
}

/// Stepping up onto a 20 cm block, as CMU 03_02 does: the right foot
/// already on the block, the body rises over 10 frames while the left foot
/// lifts off the floor and swings up, then lands on the block. The old
/// kernel stood the body's lowest sole point (the left foot, just off the
/// floor) on the right foot's block as soon as the left foot left the
/// floor: the character jumped up by about the block's height in one frame
/// (10-22 cm at each footfall of 03_02). Each foot now stands on the
/// support it touches, so the body rises as the clip's does.
#[test]
fn stepping_up_onto_a_block_moves_the_body_as_the_clip_moves_it() {
    let st = standing();
    let block = 0.2;
    let mut clip: Vec<Pose> = Vec::new();
    for t in 0..36 {
        let mut p = st;
        // The body rises from the floor to the block over frames 8-20.
        let rise = block * ((t as f64 - 8.0) / 12.0).clamp(0.0, 1.0);
        for c in Canonical::ALL {
            p[c.index()].y += rise;
        }
        // The right foot stands on the block throughout; the right knee
        // is bent while the body is low.
        for c in leg(false) {
            p[c.index()].y = st[c.index()].y + block;
        }
        p[C::RKnee.index()].z += 0.15 * (1.0 - rise / block);
        p[C::RKnee.index()].y = p[C::RKnee.index()].y.min(p[C::RHip.index()].y - 0.3);
        // The left foot: on the floor until frame 8, in the air (up to
        // 8 cm above the block) until frame 20, then on the block.
        let lift = if t < 8 {
            0.0
        } else if t < 20 {
            let u = (t as f64 - 8.0) / 12.0;
            block * u + 0.08 * (std::f64::consts::PI * u).sin()
        } else {
            block
        };
        for c in leg(true) {
            p[c.index()].y = st[c.index()].y + lift;
        }
        p[C::LKnee.index()].z +=
            0.1 * (std::f64::consts::PI * ((t as f64 - 8.0) / 12.0).clamp(0.0, 1.0)).sin();
        clip.push(p);
    }
    let (t, worst) = worst_pelvis_step(&clip, &standing());
    assert!(
        worst < 0.02,
        "frame {t}: the character's pelvis moved {:.1} cm more (or less) than the clip's",
        100.0 * worst
    );
}
