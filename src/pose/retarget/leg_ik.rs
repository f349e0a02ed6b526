//! Two-bone leg IK (hip → knee → ankle) for the footfalls
//! ([`footfall`](super::footfall)): the ankle put on a goal, the knee kept
//! in the leg's own bending plane on the side it bends to.
//!
//! The analytic two-bone solution (the law of cosines for the hip's angle
//! between the thigh and the hip → goal line; e.g. Kulpa & Multon 2005,
//! "Fast inverse kinematics and kinetics solver for human-like figures",
//! Sec. 3.1): with thigh `l1`, shin `l2` and the goal at `d` from the hip
//! (clamped to `[|l1 − l2|, l1 + l2]`, so the leg never stretches past
//! straight), the knee is at `l1 (cos a · u + sin a · b)` from the hip,
//! `cos a = (l1² + d² − l2²) / (2 l1 d)`, `u` the unit hip → goal and `b`
//! the unit bending direction: the part of the posed hip → knee across
//! `u` (the leg's own plane, so a knee bent forward stays forward and
//! never flips), or, for a straight leg, the body's forward.

use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

use Canonical as C;

/// The hip, knee, ankle and toe joints of each leg (left, right).
pub(super) const LEGS: [[C; 4]; 2] = [
    [C::LHip, C::LKnee, C::LAnkle, C::LToe],
    [C::RHip, C::RKnee, C::RAnkle, C::RToe],
];

/// The body's forward of `t` (the hips' and shoulders' left → right axis
/// turned a quarter about the vertical), horizontal and unit; zero when
/// the axis is vertical.
pub(super) fn forward(t: &Pose) -> DVec3 {
    let v = (t[C::LHip.index()] - t[C::RHip.index()])
        + (t[C::LShoulder.index()] - t[C::RShoulder.index()]);
    DVec3::new(v.x, 0.0, v.z)
        .normalize_or_zero()
        .cross(DVec3::Y)
}

/// Puts leg `leg`'s ankle of the pose `t` (global rotations `g`) on
/// `goal` (or as near as the leg reaches, on the hip → goal line): the
/// thigh's and the shin's global rotations turned (the thigh by the
/// rotation carrying the hip → knee and the knee's hinge axis onto the
/// new ones, the shin by the least rotation about the hinge), the knee,
/// ankle and toe moved with them; the ankle's rotation (the foot's) is
/// kept. A goal or pose that is not finite leaves the leg.
pub(super) fn reach(t: &mut Pose, g: &mut [DQuat; Canonical::COUNT], leg: usize, goal: DVec3) {
    let [h, k, a, toe] = LEGS[leg].map(|c| c.index());
    let (hip, knee, ankle) = (t[h], t[k], t[a]);
    let (l1, l2) = (hip.distance(knee), knee.distance(ankle));
    let to = goal - hip;
    let d0 = to.length();
    if !(d0.is_finite() && l1 > 1e-9 && l2 > 1e-9 && d0 > 1e-9 && ankle.is_finite()) {
        return;
    }
    let u = to / d0;
    let d = d0.clamp((l1 - l2).abs() + 1e-9, (l1 + l2) * (1.0 - 1e-9));
    let across = |v: DVec3| (v - v.dot(u) * u).normalize_or_zero();
    let mut b = across(knee - hip);
    if b == DVec3::ZERO || (knee - hip).cross(ankle - knee).length() < 1e-9 * l1 * l2 {
        // A straight leg: it bends the way the body faces.
        let f = across(forward(t));
        if f != DVec3::ZERO {
            b = f;
        }
    }
    if b == DVec3::ZERO {
        return;
    }
    let cos_a = ((l1 * l1 + d * d - l2 * l2) / (2.0 * l1 * d)).clamp(-1.0, 1.0);
    let sin_a = (1.0 - cos_a * cos_a).sqrt();
    let new_knee = hip + l1 * (cos_a * u + sin_a * b);
    let new_ankle = hip + d * u;
    let turn_thigh = frame_turn(
        (knee - hip, ankle - knee),
        (new_knee - hip, new_ankle - new_knee),
    );
    let shin = turn_thigh * (ankle - knee);
    let turn_shin = DQuat::from_rotation_arc(
        shin.normalize_or_zero(),
        (new_ankle - new_knee).normalize_or_zero(),
    );
    if !(turn_thigh.is_finite() && turn_shin.is_finite()) {
        return;
    }
    g[h] = (turn_thigh * g[h]).normalize();
    g[k] = (turn_shin * turn_thigh * g[k]).normalize();
    let moved = new_ankle - ankle;
    t[k] = new_knee;
    t[a] = new_ankle;
    t[toe] += moved;
}

/// The rotation taking the thigh `from.0` onto `to.0` and the leg's
/// hinge axis (thigh × shin) onto the new one; the least rotation of the
/// thighs where either leg is straight (no hinge).
fn frame_turn(from: (DVec3, DVec3), to: (DVec3, DVec3)) -> DQuat {
    let (t0, t1) = (from.0.normalize_or_zero(), to.0.normalize_or_zero());
    let arc = DQuat::from_rotation_arc(t0, t1);
    let (n0, n1) = (
        from.0.cross(from.1).normalize_or_zero(),
        to.0.cross(to.1).normalize_or_zero(),
    );
    if n0 == DVec3::ZERO || n1 == DVec3::ZERO {
        return arc;
    }
    // Twist about the new thigh taking the carried hinge onto the new.
    let n = arc * n0;
    let (p, q) = (
        (n - n.dot(t1) * t1).normalize_or_zero(),
        (n1 - n1.dot(t1) * t1).normalize_or_zero(),
    );
    if p == DVec3::ZERO || q == DVec3::ZERO {
        return arc;
    }
    let angle = p.cross(q).dot(t1).atan2(p.dot(q));
    DQuat::from_axis_angle(t1, angle) * arc
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A leg standing at the origin's side, knee bent forward (+z) by
    /// `bend` radians, with a toe ahead of the ankle; a body facing +z.
    fn leg_pose(bend: f64) -> (Pose, [DQuat; Canonical::COUNT]) {
        let mut t = [DVec3::ZERO; Canonical::COUNT];
        t[C::LHip.index()] = DVec3::new(0.1, 0.9, 0.0);
        t[C::RHip.index()] = DVec3::new(-0.1, 0.9, 0.0);
        t[C::LShoulder.index()] = DVec3::new(0.2, 1.4, 0.0);
        t[C::RShoulder.index()] = DVec3::new(-0.2, 1.4, 0.0);
        let half = 0.5 * bend;
        let knee = t[C::LHip.index()] + 0.42 * DVec3::new(0.0, -half.cos(), half.sin());
        let ankle = knee + 0.4 * DVec3::new(0.0, -half.cos(), -half.sin());
        t[C::LKnee.index()] = knee;
        t[C::LAnkle.index()] = ankle;
        t[C::LToe.index()] = ankle + DVec3::new(0.0, -0.05, 0.14);
        (t, [DQuat::IDENTITY; Canonical::COUNT])
    }

    fn bend_dir(t: &Pose) -> DVec3 {
        let (h, k, a) = (
            t[C::LHip.index()],
            t[C::LKnee.index()],
            t[C::LAnkle.index()],
        );
        let u = (a - h).normalize();
        let v = k - h;
        v - v.dot(u) * u
    }

    #[test]
    fn the_ankle_reaches_a_reachable_goal_with_the_knee_on_its_side() {
        for bend in [0.0, 0.3, 1.0] {
            let (t0, g0) = leg_pose(bend);
            for goal in [
                DVec3::new(0.12, 0.15, 0.1),
                DVec3::new(0.05, 0.2, -0.15),
                DVec3::new(0.15, 0.3, 0.05),
            ] {
                let (mut t, mut g) = (t0, g0);
                reach(&mut t, &mut g, 0, goal);
                assert!(t[C::LAnkle.index()].distance(goal) < 1e-9, "{bend} {goal}");
                // Bones keep their lengths and the rotations carry them.
                for (p, c) in [(C::LHip, C::LKnee), (C::LKnee, C::LAnkle)] {
                    let (p, c) = (p.index(), c.index());
                    assert!((t[p].distance(t[c]) - t0[p].distance(t0[c])).abs() < 1e-9);
                    let carried = t[p] + g[p] * g0[p].inverse() * (t0[c] - t0[p]);
                    assert!(carried.distance(t[c]) < 1e-9, "{bend} {goal}");
                }
                // The foot keeps its turn; the toe moves with the ankle.
                let foot = t[C::LToe.index()] - t[C::LAnkle.index()];
                let foot0 = t0[C::LToe.index()] - t0[C::LAnkle.index()];
                assert!(foot.distance(foot0) < 1e-12);
                // The knee bends forward, never back.
                assert!(bend_dir(&t).z > 0.0, "{bend} {goal}");
            }
        }
    }

    #[test]
    fn an_unreachable_goal_straightens_the_leg_towards_it() {
        let (mut t, mut g) = leg_pose(0.4);
        let goal = DVec3::new(0.1, -0.5, 0.3);
        reach(&mut t, &mut g, 0, goal);
        let (h, a) = (t[C::LHip.index()], t[C::LAnkle.index()]);
        assert!((h.distance(a) - 0.82).abs() < 1e-6);
        let dir = (goal - h).normalize();
        assert!((a - h).normalize().distance(dir) < 1e-9);
        // Nothing finite to reach: the leg stays.
        let (t0, _) = leg_pose(0.4);
        let (mut t, mut g) = leg_pose(0.4);
        reach(&mut t, &mut g, 0, DVec3::new(f64::NAN, 0.0, 0.0));
        assert_eq!(t, t0);
    }

    #[test]
    fn a_mirrored_leg_solves_mirrored() {
        let (t0, g0) = leg_pose(0.5);
        let goal = DVec3::new(0.14, 0.12, 0.08);
        let (mut t, mut g) = (t0, g0);
        reach(&mut t, &mut g, 0, goal);
        let m = |v: DVec3| DVec3::new(-v.x, v.y, v.z);
        let mut tm = t0;
        for c in Canonical::ALL {
            let o = match c {
                C::LHip => C::RHip,
                C::RHip => C::LHip,
                C::LKnee => C::RKnee,
                C::RKnee => C::LKnee,
                C::LAnkle => C::RAnkle,
                C::RAnkle => C::LAnkle,
                C::LToe => C::RToe,
                C::RToe => C::LToe,
                C::LShoulder => C::RShoulder,
                C::RShoulder => C::LShoulder,
                _ => c,
            };
            tm[o.index()] = m(t0[c.index()]);
        }
        let mut gm = g0;
        reach(&mut tm, &mut gm, 1, m(goal));
        assert!(m(tm[C::RKnee.index()]).distance(t[C::LKnee.index()]) < 1e-9);
    }
}
