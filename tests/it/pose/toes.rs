//! A foot pitched down onto its ball through the retargeting kernel
//! (`pose::retarget::retarget_toes`). A real foot standing on its ball
//! bends its toes flat at the ball: its lowest point is the ball, not a
//! rigid toe tip below it. With toes that bend ([`Toes::Bending`], what
//! `transfer` drives: its markers on the toes turn with the toe joint)
//! the body stands where the clip's stands and the toes turn up about
//! the ball; with rigid toes ([`Toes::Rigid`], the part-based
//! deformation's foot part) the rigid tip dips below the ball and the
//! body is lifted to stand it on the floor (the self-transfer of the
//! samba stood 1-2 cm high while the dancer was on her ball).

use glam::{DQuat, DVec3};
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::{Toes, choose_reference, retarget_toes};
use surfmotion::rig::Canonical as C;

/// The procedural humanoid's embedded rest skeleton.
fn character() -> Pose {
    use surfmotion::embed::Embedding;
    use surfmotion::synth::humanoid::{DEMO_GRID, humanoid_landmarks, humanoid_mesh};
    let mesh = humanoid_mesh(DEMO_GRID);
    let rig = Embedding::new(&mesh, &humanoid_landmarks(&mesh), None).unwrap();
    rig.joints().map(DVec3::from_array)
}

/// The knee of a leg from hip `h` to ankle `a` with thigh `l1` and shin
/// `l2`, bent forward (+z, the humanoid's facing).
fn knee(h: DVec3, a: DVec3, l1: f64, l2: f64) -> DVec3 {
    let d = a - h;
    let len = d.length().min(l1 + l2 - 1e-9);
    let u = d / d.length();
    let along = (l1 * l1 - l2 * l2 + len * len) / (2.0 * len);
    let off = (l1 * l1 - along * along).max(0.0).sqrt();
    let side = (DVec3::Z - u * u.z).normalize_or(DVec3::Z);
    h + u * along + side * off
}

/// The left foot of `rest` turned about its toe joint (the ball) by
/// `angle` (positive: heel up), the knee re-solved, hip unmoved.
fn on_the_ball(rest: &Pose, angle: f64) -> Pose {
    let mut p = *rest;
    let [h, k, a, t] = [C::LHip, C::LKnee, C::LAnkle, C::LToe].map(|c| c.index());
    let foot = rest[t] - rest[a];
    let axis = foot.cross(DVec3::Y).normalize();
    let q = DQuat::from_axis_angle(axis, -angle);
    p[a] = rest[t] - q * foot;
    let (l1, l2) = (rest[h].distance(rest[k]), rest[k].distance(rest[a]));
    // The hip lowers with the body's weight on the ball; here it stays
    // and the leg bends or, past its reach, the ankle is pulled along.
    let d = p[a] - p[h];
    if d.length() > l1 + l2 {
        p[a] = p[h] + d.normalize() * (l1 + l2 - 1e-6);
    }
    p[k] = knee(p[h], p[a], l1, l2);
    p[t] = p[a] + q * foot;
    p
}

/// A clip of the character's own skeleton: 30 frames standing, 10 rising
/// onto the left ball to `angle`, 15 held there, the right foot flat.
fn clip(rest: &Pose, angle: f64) -> Vec<Pose> {
    (0..55)
        .map(|i| {
            let f = ((i as f64 - 30.0) / 10.0).clamp(0.0, 1.0);
            on_the_ball(rest, angle * f)
        })
        .collect()
}

/// The quarter toe tip of the left foot (a quarter of the rest foot's
/// horizontal length beyond the toe joint), carried by the toe joint's
/// rotation.
fn toe_tip(rest: &Pose, p: &Pose, g: &[DQuat; C::COUNT]) -> DVec3 {
    let f = rest[C::LToe.index()] - rest[C::LAnkle.index()];
    p[C::LToe.index()] + g[C::LToe.index()] * DVec3::new(0.25 * f.x, 0.0, 0.25 * f.z)
}

#[test]
fn a_foot_on_its_ball_bends_its_toes_and_the_body_stands_as_the_clip() {
    let rest = character();
    let height = rest.iter().map(|p| p.y).fold(f64::MIN, f64::max)
        - rest.iter().map(|p| p.y).fold(f64::MAX, f64::min);
    let floor = rest.iter().map(|p| p.y).fold(f64::MAX, f64::min);
    for deg in [12.0, 25.0, 40.0] {
        let frames = clip(&rest, f64::to_radians(deg));
        let reference = choose_reference(Some(&rest), &frames).unwrap();
        let bent = retarget_toes(&rest, &rest, &reference, &frames, Toes::Bending);
        let rigid = retarget_toes(&rest, &rest, &reference, &frames, Toes::Rigid);
        let mut rigid_lift: f64 = 0.0;
        for (i, m) in frames.iter().enumerate() {
            let (p, g) = &bent[i];
            // The body where the clip's is (its own skeleton: scale 1).
            let lift = p[C::Pelvis.index()].y - m[C::Pelvis.index()].y;
            assert!(
                lift.abs() < 1e-3 * height,
                "{deg}° frame {i}: the body stands {:.2} cm off the clip's",
                100.0 * lift
            );
            // The ball on the floor, the toes on or above it and never
            // past level.
            let tip = toe_tip(&rest, p, g);
            let ball = p[C::LToe.index()];
            assert!(
                tip.y >= floor - 1e-6,
                "{deg}° frame {i}: toe tip {} below the floor {floor}",
                tip.y
            );
            assert!(
                tip.y <= ball.y.max(floor) + 1e-6 || i < 30,
                "{deg}° frame {i}: toes turned past level"
            );
            if i >= 40 {
                // Held on the ball: the toes turned up from the foot.
                let foot = g[C::LAnkle.index()];
                let toes = g[C::LToe.index()];
                assert!(
                    foot.angle_between(toes) > f64::to_radians(deg) * 0.5,
                    "{deg}° frame {i}: the toes do not bend ({:.1}°)",
                    foot.angle_between(toes).to_degrees()
                );
            }
            // The right foot flat on the floor, its toes with it.
            assert!(g[C::RToe.index()].angle_between(g[C::RAnkle.index()]) < 1e-9);
            rigid_lift = rigid_lift.max(rigid[i].0[C::Pelvis.index()].y - m[C::Pelvis.index()].y);
        }
        // Rigid toes (the tip carried by the ankle): lifted off the clip's.
        assert!(
            rigid_lift > 2e-3 * height,
            "{deg}°: rigid toes lift the body {:.2} cm",
            100.0 * rigid_lift
        );
    }
}

#[test]
fn toes_in_the_air_stay_with_the_foot() {
    let rest = character();
    // The left leg swung back about the hip by up to 40°, its foot
    // pointing down with it: no ground stops its toes.
    let hip = rest[C::LHip.index()];
    let frames: Vec<Pose> = (0..40)
        .map(|i| {
            let f = ((i as f64 - 20.0) / 10.0).clamp(0.0, 1.0);
            let q = DQuat::from_rotation_x(f64::to_radians(40.0) * f);
            let mut p = rest;
            for c in [C::LKnee, C::LAnkle, C::LToe] {
                p[c.index()] = hip + q * (rest[c.index()] - hip);
            }
            p
        })
        .collect();
    let reference = choose_reference(Some(&rest), &frames).unwrap();
    let out = retarget_toes(&rest, &rest, &reference, &frames, Toes::Bending);
    for (p, g) in &out[32..] {
        assert!(p[C::LToe.index()].y > rest[C::LToe.index()].y + 0.1);
        assert!(g[C::LToe.index()].angle_between(g[C::LAnkle.index()]) < 1e-9);
    }
}
