//! The character's feet on the clip's footfalls (issue 44,
//! `Footfalls::Targets`, `SURFMOTION_PLACEMENT=…,feet`) on generated
//! variants of one motion (no data needed): a walk along a circle onto a
//! character whose thighs are longer and shins shorter than the clip's
//! (so the limbs' directions put its feet off the scaled travel), the
//! clip mirrored, turned and rescaled to centimetres, and with its root
//! moved inside the body. Planted feet slide less than without, the legs
//! keep their bones and their knees bend the way they did, and a clip
//! with no footfall is unchanged.

use crate::common;

use super::anchor::{placed_turned, root_moved};
use super::stride::slide;
use super::two_files::{mirrored, turned};
use glam::{DQuat, DVec3};
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::{
    Anchor, ClipPoses, Footfalls, Placement, TravelScale, clip_poses,
};
use surfmotion::rig::{Canonical, detect_clip};

use Canonical as C;

/// The legs' joints (hip, knee, ankle, toe), left then right.
const LEGS: [[C; 4]; 2] = [
    [C::LHip, C::LKnee, C::LAnkle, C::LToe],
    [C::RHip, C::RKnee, C::RAnkle, C::RToe],
];

/// `p` with each thigh `thigh` times as long and each shin `shin` times
/// (the foot carried along).
fn proportioned(p: &Pose, thigh: f64, shin: f64) -> Pose {
    let mut o = *p;
    for [h, k, a, t] in LEGS.map(|l| l.map(|c| c.index())) {
        o[k] = p[h] + thigh * (p[k] - p[h]);
        o[a] = o[k] + shin * (p[a] - p[k]);
        o[t] = o[a] + (p[t] - p[a]);
    }
    o
}

fn with_feet(scale: TravelScale) -> Placement {
    Placement {
        anchor: Anchor::Root,
        scale,
        footfalls: Footfalls::Targets,
    }
}

/// The part of leg `l`'s hip → knee across its hip → ankle line (the
/// way the knee bends) and the knee's bend (radians).
fn knee(p: &Pose, l: usize) -> (DVec3, f64) {
    let [h, k, a, _] = LEGS[l].map(|c| c.index());
    let u = (p[a] - p[h]).normalize();
    let v = p[k] - p[h];
    let bend = (p[k] - p[h]).angle_between(p[a] - p[k]);
    (v - v.dot(u) * u, bend)
}

/// The generated walk and its variants: planted feet slide less with the
/// footfalls than without (by more than half), every leg keeps its bone
/// lengths, and no knee bends the other way than without (wherever the
/// knee is bent over 2°), nor does it straighten past straight.
#[test]
fn generated_variants_slide_less_on_their_footfalls() {
    let (rest, _) = common::walk_character();
    let character = proportioned(&rest, 1.12, 0.9);
    let walk = surfmotion::synth::gait_clip(surfmotion::synth::Gait::Turn, 4.0, 30.0);
    let map = detect_clip(&walk).unwrap().map;
    let plain = clip_poses(&walk, &map).unwrap();
    let q = DQuat::from_rotation_y(30f64.to_radians());
    let variants: Vec<(&str, ClipPoses)> = vec![
        ("plain", plain.clone()),
        ("mirrored", mirrored(plain.clone())),
        (
            "turned and rescaled to centimetres",
            turned(plain.clone(), q, 100.0),
        ),
        (
            "root moved up and back",
            root_moved(plain.clone(), 0.11, 0.05),
        ),
    ];
    let bones = |p: &Pose, l: usize| {
        let [h, k, a, _] = LEGS[l].map(|c| c.index());
        (p[h].distance(p[k]), p[k].distance(p[a]))
    };
    for (name, cp) in &variants {
        let free = placed_turned(&character, cp, Placement::default());
        let free_pos: Vec<Pose> = free.iter().map(|r| r.0).collect();
        let before = slide(&free_pos, &cp.poses);
        for scale in [TravelScale::Legs, TravelScale::Stance] {
            let got: Vec<Pose> = placed_turned(&character, cp, with_feet(scale))
                .into_iter()
                .map(|r| r.0)
                .collect();
            let after = slide(&got, &cp.poses);
            eprintln!(
                "generated turn, {name}, {scale:?}: feet slide {:.3} → {:.3} cm/frame",
                100.0 * before,
                100.0 * after
            );
            assert!(after < 0.5 * before, "{name} {scale:?}: {before} → {after}");
            let mut flips = 0;
            for (i, (p, f)) in got.iter().zip(&free_pos).enumerate() {
                for l in 0..2 {
                    let (b0, b1) = (bones(p, l), bones(&character, l));
                    assert!(
                        (b0.0 - b1.0).abs() < 1e-9 && (b0.1 - b1.1).abs() < 1e-9,
                        "{name} {scale:?} frame {i} leg {l}: {b0:?} against {b1:?}"
                    );
                    let ((dir, bend), (dir0, bend0)) = (knee(p, l), knee(f, l));
                    assert!(bend.is_finite() && bend >= 0.0);
                    if bend0 > 2f64.to_radians() && bend > 2f64.to_radians() && dir.dot(dir0) <= 0.0
                    {
                        flips += 1;
                    }
                }
            }
            assert_eq!(flips, 0, "{name} {scale:?}: knees bent the other way");
        }
    }
}

/// A clip with no footfall (the walk carried sideways 5 % of its leg a
/// frame, so no foot is ever still: a glide, a swim) gives the same
/// result with the footfalls as without, bit for bit.
#[test]
fn a_clip_with_no_footfall_is_unchanged() {
    let (rest, _) = common::walk_character();
    let character = proportioned(&rest, 1.12, 0.9);
    let walk = surfmotion::synth::gait_clip(surfmotion::synth::Gait::Walk, 2.0, 30.0);
    let map = detect_clip(&walk).unwrap().map;
    let mut glide = clip_poses(&walk, &map).unwrap();
    let leg = surfmotion::pose::retarget::leg_length(&glide.reference.pose);
    // Across the walk, so the walk's own motion never cancels it.
    let (a, b) = (glide.poses[0], glide.poses[glide.poses.len() - 1]);
    let travel = b[C::Pelvis.index()] - a[C::Pelvis.index()];
    let across = DVec3::new(travel.x, 0.0, travel.z)
        .normalize()
        .cross(DVec3::Y);
    for (i, p) in glide.poses.iter_mut().enumerate() {
        let d = across * (0.05 * leg * i as f64);
        for x in p.iter_mut() {
            *x += d;
        }
    }
    for scale in [TravelScale::Legs, TravelScale::Stance] {
        let free = placed_turned(
            &character,
            &glide,
            Placement {
                scale,
                ..Placement::default()
            },
        );
        let feet = placed_turned(&character, &glide, with_feet(scale));
        assert_eq!(free.len(), feet.len());
        for (i, (a, b)) in free.iter().zip(&feet).enumerate() {
            assert!(a.0 == b.0 && a.1 == b.1, "{scale:?} frame {i}");
        }
    }
}
