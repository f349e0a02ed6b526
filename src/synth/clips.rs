//! Procedural mocap: a humanoid skeleton (metres, Y-up, facing +Z, arms
//! down) and gait clips generated from a few sinusoids, so the demo and the
//! tests have motion without any downloaded data. Joint names follow the
//! MotionBuilder/cgspeed convention, so the rig map detects them.
//!
//! A gait is a phase `φ = 2π f t` (f: strides per second). Hip flexion
//! `A_h sin φ` (left) and `A_h sin(φ + π)` (right); the knee flexes during
//! swing, `A_k max(0, sin(φ + π/2 ∓ ...))`; arms swing against the legs;
//! the pelvis bobs at 2f and turns slightly about the vertical; the root
//! moves forward at the gait's speed, along a circle for `Turn`.

use crate::mocap::{Channel, Clip, Joint, JointId, PointConvention, Units, UpAxis};
use glam::{DQuat, DVec3};
use std::f64::consts::{PI, TAU};

/// Which procedural motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Gait {
    /// Walk straight ahead at 1.4 m/s.
    Walk,
    /// Run straight ahead at 3.2 m/s.
    Run,
    /// Walk along a circle of 2 m radius.
    Turn,
}

impl Gait {
    /// All gaits.
    pub const ALL: [Gait; 3] = [Gait::Walk, Gait::Run, Gait::Turn];

    /// File stem (`walk`, `run`, `turn`).
    pub fn name(self) -> &'static str {
        match self {
            Gait::Walk => "walk",
            Gait::Run => "run",
            Gait::Turn => "turn",
        }
    }
}

/// (name, parent, offset from parent in metres, end-site offset for leaves).
type Bone = (&'static str, Option<usize>, [f64; 3], Option<[f64; 3]>);

/// The procedural skeleton, parents first: 19 joints, 1.75 m tall.
pub fn skeleton() -> Vec<Bone> {
    vec![
        ("Hips", None, [0.0, 0.95, 0.0], None),
        ("Spine", Some(0), [0.0, 0.10, 0.0], None),
        ("Spine1", Some(1), [0.0, 0.22, 0.0], None),
        ("Neck", Some(2), [0.0, 0.21, 0.0], None),
        ("Head", Some(3), [0.0, 0.10, 0.02], Some([0.0, 0.17, 0.0])),
        ("LeftArm", Some(2), [0.18, 0.17, 0.0], None),
        ("LeftForeArm", Some(5), [0.0, -0.29, 0.0], None),
        (
            "LeftHand",
            Some(6),
            [0.0, -0.26, 0.0],
            Some([0.0, -0.09, 0.0]),
        ),
        ("RightArm", Some(2), [-0.18, 0.17, 0.0], None),
        ("RightForeArm", Some(8), [0.0, -0.29, 0.0], None),
        (
            "RightHand",
            Some(9),
            [0.0, -0.26, 0.0],
            Some([0.0, -0.09, 0.0]),
        ),
        ("LeftUpLeg", Some(0), [0.09, -0.04, 0.0], None),
        ("LeftLeg", Some(11), [0.0, -0.42, 0.0], None),
        ("LeftFoot", Some(12), [0.0, -0.42, 0.0], None),
        (
            "LeftToeBase",
            Some(13),
            [0.0, -0.06, 0.12],
            Some([0.0, 0.0, 0.06]),
        ),
        ("RightUpLeg", Some(0), [-0.09, -0.04, 0.0], None),
        ("RightLeg", Some(15), [0.0, -0.42, 0.0], None),
        ("RightFoot", Some(16), [0.0, -0.42, 0.0], None),
        (
            "RightToeBase",
            Some(17),
            [0.0, -0.06, 0.12],
            Some([0.0, 0.0, 0.06]),
        ),
    ]
}

struct Params {
    speed: f64,
    strides: f64,
    /// Share of a stride each foot is on the floor.
    stance: f64,
    /// Share of the stance the foot is flat (then its heel rises about the
    /// toe joint, which stays put, until toe-off).
    flat: f64,
    /// Heel rise at toe-off (degrees).
    heel: f64,
    /// Swing foot lift at mid-swing (metres).
    lift: f64,
    arm: f64,
    elbow: f64,
    /// Pelvis height above its rest height at mid-stance and its bob
    /// (metres): `drop + bob cos(4π u)`, lowest at each mid-stance.
    drop: f64,
    bob: f64,
    lean: f64,
}

fn params(g: Gait) -> Params {
    match g {
        Gait::Walk | Gait::Turn => Params {
            speed: 1.4,
            strides: 0.95,
            stance: 0.6,
            flat: 0.55,
            heel: 35.0,
            lift: 0.10,
            arm: 18.0,
            elbow: 15.0,
            drop: -0.06,
            bob: 0.015,
            lean: 3.0,
        },
        Gait::Run => Params {
            speed: 3.2,
            strides: 1.45,
            stance: 0.32,
            flat: 0.5,
            heel: 40.0,
            lift: 0.25,
            arm: 35.0,
            elbow: 85.0,
            drop: -0.07,
            bob: 0.04,
            lean: 10.0,
        },
    }
}

/// Radius of the `Turn` circle (metres).
const TURN_RADIUS: f64 = 2.0;
/// Thigh and shin length (metres).
const BONE: f64 = 0.42;
/// The toe joint from the ankle in the rest (flat-foot) pose.
const TOE: DVec3 = DVec3::new(0.0, -0.06, 0.12);
/// Ankle height above the floor with the foot flat (metres).
const ANKLE_Y: f64 = 0.07;
/// Longest hip-to-ankle distance the IK asks of a leg (metres).
const REACH: f64 = 0.985 * 2.0 * BONE;

/// The root's place on its path after `dist` metres, and its heading
/// (radians about +Y from +Z).
fn path(g: Gait, dist: f64) -> (DVec3, f64) {
    match g {
        Gait::Turn => {
            let a = dist / TURN_RADIUS;
            (
                DVec3::new(TURN_RADIUS * (1.0 - a.cos()), 0.0, TURN_RADIUS * a.sin()),
                a,
            )
        }
        _ => (DVec3::new(0.0, 0.0, dist), 0.0),
    }
}

/// Where one foot is at time `t`: ankle (world), the foot's yaw and its
/// heel rise (radians), and whether it is in stance.
struct FootState {
    ankle: DVec3,
    yaw: f64,
    heel: f64,
    stance: bool,
}

/// The foot of leg `side` (+1 left, −1 right) at time `t`. The leg's
/// phase is `u = frac(f t + o)` (`o`: 0 left, ½ right); it is in stance
/// for `u < stance`. Footprint `k` (the stance that begins at cycle `k`)
/// is the ankle under the hip at the middle of the flat part, on the path
/// and `side · 0.09` m to its left: the ankle stays there while the foot
/// is flat, then the heel rises about the toe joint, which stays put, up
/// to `heel` at toe-off. The swing carries the ankle from toe-off to the
/// next footprint (smoothstep along the ground between 10 % and 85 % of the
/// swing, `lift · sin(π s)` up), so the foot lifts off and lands vertically.
fn foot(g: Gait, p: &Params, side: f64, t: f64) -> FootState {
    let offset = if side > 0.0 { 0.0 } else { 0.5 };
    let cyc = p.strides * t + offset;
    let k = cyc.floor();
    let u = cyc - k;
    let print = |k: f64| -> (DVec3, f64) {
        // Time of the middle of footprint k's flat part.
        let tm = (k + 0.5 * p.stance * p.flat - offset) / p.strides;
        let (pos, yaw) = path(g, p.speed * tm);
        let lateral = DQuat::from_rotation_y(yaw) * DVec3::new(side * 0.09, 0.0, 0.0);
        (pos + lateral + DVec3::new(0.0, ANKLE_Y, 0.0), yaw)
    };
    // The ankle about the fixed toe joint with the heel up by `h`.
    let rolled = |a: DVec3, yaw: f64, h: f64| {
        let q = DQuat::from_rotation_y(yaw);
        let toe = a + q * TOE;
        toe - q * (DQuat::from_rotation_x(h) * TOE)
    };
    let heel_max = p.heel.to_radians();
    let rise = |u: f64| {
        let r = ((u - p.stance * p.flat) / (p.stance * (1.0 - p.flat))).clamp(0.0, 1.0);
        heel_max * r * r
    };
    if u < p.stance {
        let (a, yaw) = print(k);
        let h = rise(u);
        FootState {
            ankle: rolled(a, yaw, h),
            yaw,
            heel: h,
            stance: true,
        }
    } else {
        let s = (u - p.stance) / (1.0 - p.stance);
        let (a0, y0) = print(k);
        let from = rolled(a0, y0, heel_max);
        let (to, y1) = print(k + 1.0);
        // Along the ground between 10 % and 85 % of the swing: the foot
        // lifts off and comes down vertically.
        let w = ((s - 0.1) / 0.75).clamp(0.0, 1.0);
        let e = w * w * (3.0 - 2.0 * w);
        let mut ankle = from.lerp(to, e);
        ankle.y += p.lift * (PI * s).sin();
        let h = heel_max * (1.0 - (s / 0.6).min(1.0)).powi(2);
        FootState {
            ankle,
            yaw: y0 + (y1 - y0) * e,
            heel: h,
            stance: false,
        }
    }
}

/// Local rotations of thigh and knee (about the hips' frame `root`) that
/// put the ankle at `ankle` from the hip joint at `hip`: two-bone IK, the
/// knee bending forward in the plane of the leg; the ankle is pulled in to
/// [`REACH`] when it is farther.
fn leg_ik(root: DQuat, hip: DVec3, ankle: DVec3) -> (DQuat, DQuat) {
    let d = root.inverse() * (ankle - hip);
    let len = d.length().clamp(1e-6, REACH);
    let dir = d.normalize_or(DVec3::NEG_Y);
    let alpha = (len / (2.0 * BONE)).clamp(-1.0, 1.0).acos();
    let swing = DQuat::from_rotation_arc(DVec3::NEG_Y, dir);
    (
        swing * DQuat::from_rotation_x(-alpha),
        DQuat::from_rotation_x(2.0 * alpha),
    )
}

/// Generates `seconds` of a gait at `fps`. Deterministic. The stance foot
/// is planted: its ankle (then, once the heel rises, its toe joint) holds
/// its world position while the root advances, the legs being solved by
/// IK ([`leg_ik`]); the swing foot lifts and lands with zero speed.
pub fn gait_clip(g: Gait, seconds: f64, fps: f64) -> Clip {
    let bones = skeleton();
    let joints: Vec<Joint> = bones
        .iter()
        .map(|(name, parent, off, end)| Joint {
            name: name.to_string(),
            parent: parent.map(|p| JointId(p as u32)),
            offset: DVec3::from_array(*off),
            channels: if parent.is_none() {
                Channel::ROOT6.to_vec()
            } else {
                Channel::ROT_ZYX.to_vec()
            },
            tail: end.map(DVec3::from_array),
        })
        .collect();
    let p = params(g);
    let n = joints.len();
    let frames = (seconds * fps).round().max(1.0) as usize;
    let mut rotations = Vec::with_capacity(frames * n);
    let mut translations = Vec::with_capacity(frames * n);
    let rad = |d: f64| d.to_radians();
    let hip_off = |side: f64| DVec3::new(side * 0.09, -0.04, 0.0);
    for f in 0..frames {
        let t = f as f64 / fps;
        let ph = TAU * p.strides * t;
        let (pos, heading) = path(g, p.speed * t);
        let feet = [foot(g, &p, 1.0, t), foot(g, &p, -1.0, t)];
        let yaw = heading + rad(4.0) * ph.sin();
        let root_q = DQuat::from_rotation_y(yaw) * DQuat::from_rotation_x(rad(p.lean));
        // Pelvis: lowest at each mid-stance, and no higher than the
        // stance legs reach.
        let mut y = 0.95 + p.drop + p.bob * (2.0 * ph).cos();
        for (side, ft) in [1.0, -1.0].into_iter().zip(&feet) {
            if !ft.stance {
                continue;
            }
            let hip = pos + DVec3::new(0.0, y, 0.0) + root_q * hip_off(side);
            let h = DVec3::new(hip.x - ft.ankle.x, 0.0, hip.z - ft.ankle.z).length();
            let top = ft.ankle.y + (REACH * REACH - h * h).max(0.0).sqrt();
            y -= (hip.y - top).max(0.0);
        }
        let root_t = pos + DVec3::new(0.0, y, 0.0);
        let mut legs = [(DQuat::IDENTITY, DQuat::IDENTITY, DQuat::IDENTITY); 2];
        for (leg, (side, ft)) in legs.iter_mut().zip([1.0, -1.0].into_iter().zip(&feet)) {
            let hip = root_t + root_q * hip_off(side);
            let (qh, qk) = leg_ik(root_q, hip, ft.ankle);
            let world = DQuat::from_rotation_y(ft.yaw) * DQuat::from_rotation_x(ft.heel);
            let qf = (root_q * qh * qk).inverse() * world;
            *leg = (qh, qk, qf);
        }
        for (name, _, off, _) in bones.iter() {
            let left = name.starts_with("Left");
            let s = if left { 0.0 } else { PI };
            let leg = legs[usize::from(!left)];
            let heel = feet[usize::from(!left)].heel;
            let q = match *name {
                "Hips" => root_q,
                "Spine" => DQuat::from_rotation_y(-rad(3.0) * ph.sin()),
                "Spine1" => DQuat::from_rotation_y(-rad(4.0) * ph.sin()),
                "Head" => DQuat::from_rotation_x(-rad(p.lean) * 0.8),
                _ if name.ends_with("UpLeg") => leg.0,
                _ if name.ends_with("Leg") => leg.1,
                _ if name.ends_with("Foot") => leg.2,
                // The toes stay flat while the heel rises.
                _ if name.ends_with("ToeBase") => DQuat::from_rotation_x(-heel),
                _ if name.ends_with("ForeArm") => {
                    DQuat::from_rotation_x(-rad(p.elbow) - rad(10.0) * (ph + s + PI).sin().max(0.0))
                }
                _ if name.ends_with("Arm") => {
                    let out = if left { -1.0 } else { 1.0 };
                    // The arm swings against its own leg.
                    DQuat::from_rotation_z(out * rad(6.0))
                        * DQuat::from_rotation_x(rad(p.arm) * (ph + s).cos())
                }
                _ => DQuat::IDENTITY,
            };
            rotations.push(q.normalize());
            translations.push(if *name == "Hips" {
                root_t
            } else {
                DVec3::from_array(*off)
            });
        }
    }
    let units = Units {
        metres_per_unit: 1.0,
        name: "m".into(),
        reason: "procedural clip, generated in metres".into(),
    };
    let mut c = Clip::new(
        joints,
        1.0 / fps,
        rotations,
        translations,
        units,
        UpAxis::Y,
        PointConvention::JointOrigins,
    )
    .expect("the procedural clip is valid by construction");
    c.up_reason = "procedural clip, Y-up".into();
    c
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walk_moves_forward_with_feet_near_the_ground_and_rigid_bones() {
        let c = gait_clip(Gait::Walk, 2.0, 30.0);
        assert_eq!(c.frame_count(), 60);
        let det = crate::rig::detect(&c.point_names());
        assert!(det.missing.is_empty(), "{:?}", det.missing);
        let a = c.world_positions(0);
        let b = c.world_positions(59);
        assert!((b[0].z - a[0].z - 1.4 * 59.0 / 30.0).abs() < 1e-9);
        let (la, lb) = (
            c.joint("LeftFoot").unwrap().idx(),
            c.joint("LeftLeg").unwrap().idx(),
        );
        let mut lowest = f64::MAX;
        for f in 0..60 {
            let p = c.world_positions(f);
            assert!(
                p[la].y > -0.05 && p[la].y < 0.4,
                "frame {f}: ankle at {}",
                p[la].y
            );
            lowest = lowest.min(p[la].y);
            assert!(((p[la] - p[lb]).length() - 0.42).abs() < 1e-9);
        }
        assert!(lowest < 0.12, "the foot never comes down: {lowest}");
    }

    #[test]
    fn turn_changes_heading() {
        let c = gait_clip(Gait::Turn, 4.0, 30.0);
        let last = c.world_positions(c.frame_count() - 1)[0];
        assert!(last.x > 1.0, "{last:?}");
    }
}
