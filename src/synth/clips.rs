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
    hip: f64,
    knee: f64,
    arm: f64,
    elbow: f64,
    bob: f64,
    lean: f64,
}

fn params(g: Gait) -> Params {
    match g {
        Gait::Walk | Gait::Turn => Params {
            speed: 1.4,
            strides: 0.9,
            hip: 25.0,
            knee: 45.0,
            arm: 18.0,
            elbow: 15.0,
            bob: 0.025,
            lean: 3.0,
        },
        Gait::Run => Params {
            speed: 3.2,
            strides: 1.4,
            hip: 40.0,
            knee: 95.0,
            arm: 35.0,
            elbow: 85.0,
            bob: 0.06,
            lean: 10.0,
        },
    }
}

/// Generates `seconds` of a gait at `fps`. Deterministic.
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
    let radius = 2.0;
    for f in 0..frames {
        let t = f as f64 / fps;
        let ph = TAU * p.strides * t;
        // Root: forward along +Z, or along a circle for Turn.
        let dist = p.speed * t;
        let (pos, heading) = match g {
            Gait::Turn => {
                let a = dist / radius;
                (
                    DVec3::new(radius * (1.0 - a.cos()), 0.0, radius * a.sin()),
                    a,
                )
            }
            _ => (DVec3::new(0.0, 0.0, dist), 0.0),
        };
        let bob = p.bob * (2.0 * ph).cos();
        let root_t = pos + DVec3::new(0.0, 0.95 + bob, 0.0);
        let yaw = heading + rad(4.0) * ph.sin();
        let root_q = DQuat::from_rotation_y(yaw) * DQuat::from_rotation_x(rad(p.lean));
        for (j, (name, _, off, _)) in bones.iter().enumerate() {
            let (q, tr) = match *name {
                "Hips" => (root_q, root_t),
                "Spine" => (
                    DQuat::from_rotation_y(-rad(3.0) * ph.sin()),
                    DVec3::from_array(*off),
                ),
                "Spine1" => (
                    DQuat::from_rotation_y(-rad(4.0) * ph.sin()),
                    DVec3::from_array(*off),
                ),
                "Head" => (
                    DQuat::from_rotation_x(-rad(p.lean) * 0.8),
                    DVec3::from_array(*off),
                ),
                _ => {
                    let left = name.starts_with("Left");
                    let s = if left { 0.0 } else { PI };
                    let q = if name.ends_with("UpLeg") {
                        // Negative about x swings the leg forward (+Z).
                        DQuat::from_rotation_x(-rad(p.hip) * (ph + s).sin())
                    } else if name.ends_with("Leg") {
                        DQuat::from_rotation_x(
                            rad(p.knee) * (ph + s - PI / 2.0).sin().max(0.0) + rad(5.0),
                        )
                    } else if name.ends_with("Foot") {
                        DQuat::from_rotation_x(rad(10.0) * (ph + s + PI / 3.0).sin())
                    } else if name.ends_with("ForeArm") {
                        DQuat::from_rotation_x(
                            -rad(p.elbow) - rad(10.0) * (ph + s + PI).sin().max(0.0),
                        )
                    } else if name.ends_with("Arm") {
                        let out = if left { -1.0 } else { 1.0 };
                        DQuat::from_rotation_z(out * rad(6.0))
                            * DQuat::from_rotation_x(-rad(p.arm) * (ph + s + PI).sin())
                    } else {
                        DQuat::IDENTITY
                    };
                    (q, DVec3::from_array(*off))
                }
            };
            let _ = j;
            rotations.push(q.normalize());
            translations.push(tr);
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
