//! Knee hyper-extension: how far a knee is bent the wrong way (degrees past
//! straight), from a skeleton (extracted from the output mesh, or the query).
//!
//! The knee bends in the body's sagittal plane, about the pelvis's lateral
//! axis `L` (right hip → left hip). With hip `h`, knee `k` and ankle `a`,
//! thigh `u = k − h` and shin `s = a − k`, the sagittal flexion is the
//! signed angle `θ = atan2((u × s)·L, u·s)`: positive when the shin swings
//! back behind the thigh (a knee bent the right way), negative when the
//! knee is pushed back past straight. The reading is `max(0, −θ)`.
//!
//! The pelvis gives the reference rather than the foot: a foot pointed down
//! in the swing (or any toe placement) turns a foot-based "forward" around
//! and would read a well-bent knee as bent backwards by its whole flexion
//! (an earlier version did: 99° on CMU 03_02, whose knees look right). A
//! leg turned out at the hip moves the bend out of the sagittal plane,
//! which only shrinks `(u × s)·L`: the measure errs towards zero there.

use crate::pose::Pose;
use crate::rig::Canonical;

/// Hyper-extension of the left and right knee of `p` (degrees, ≥ 0).
pub fn knee_hyperextension(p: &Pose) -> [f64; 2] {
    use Canonical as C;
    let lateral = (p[C::LHip.index()] - p[C::RHip.index()]).normalize_or_zero();
    [
        (C::LHip, C::LKnee, C::LAnkle),
        (C::RHip, C::RKnee, C::RAnkle),
    ]
    .map(|(h, k, a)| {
        let (h, k, a) = (p[h.index()], p[k.index()], p[a.index()]);
        let (u, s) = (k - h, a - k);
        let theta = u.cross(s).dot(lateral).atan2(u.dot(s));
        (-theta).max(0.0).to_degrees()
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DQuat, DVec3};

    fn leg(knee_forward: f64) -> Pose {
        let mut p = [DVec3::ZERO; Canonical::COUNT];
        for (h, k, a, t, x) in [
            (
                Canonical::LHip,
                Canonical::LKnee,
                Canonical::LAnkle,
                Canonical::LToe,
                0.1,
            ),
            (
                Canonical::RHip,
                Canonical::RKnee,
                Canonical::RAnkle,
                Canonical::RToe,
                -0.1,
            ),
        ] {
            p[h.index()] = DVec3::new(x, 1.0, 0.0);
            p[k.index()] = DVec3::new(x, 0.55, knee_forward);
            p[a.index()] = DVec3::new(x, 0.1, 0.0);
            p[t.index()] = DVec3::new(x, 0.0, 0.15);
        }
        p
    }

    #[test]
    fn a_knee_bent_forward_reads_zero_and_backward_its_angle() {
        assert_eq!(knee_hyperextension(&leg(0.05)), [0.0, 0.0]);
        let back = knee_hyperextension(&leg(-0.05));
        let want = 2.0 * (0.05f64).atan2(0.45).to_degrees();
        assert!((back[0] - want).abs() < 1e-9 && (back[1] - want).abs() < 1e-9);
    }

    #[test]
    fn a_swing_knee_with_the_foot_pointed_back_reads_zero() {
        // Knee well bent (thigh forward, shin back) and the toe pointing
        // down and behind the ankle, as in a swing or a climb: the old
        // foot-based measure read this as ~90° of hyper-extension.
        let mut p = leg(0.0);
        for (k, a, t, x) in [
            (Canonical::LKnee, Canonical::LAnkle, Canonical::LToe, 0.1),
            (Canonical::RKnee, Canonical::RAnkle, Canonical::RToe, -0.1),
        ] {
            p[k.index()] = DVec3::new(x, 0.7, 0.35);
            p[a.index()] = DVec3::new(x, 0.3, 0.1);
            p[t.index()] = DVec3::new(x, 0.2, -0.05);
        }
        assert_eq!(knee_hyperextension(&p), [0.0, 0.0]);
    }

    #[test]
    fn the_reading_does_not_depend_on_where_the_body_faces() {
        let back = knee_hyperextension(&leg(-0.05));
        for q in [
            DQuat::from_rotation_y(std::f64::consts::PI),
            DQuat::from_rotation_y(1.0) * DQuat::from_rotation_x(0.3),
        ] {
            let p = leg(-0.05).map(|v| q * v + DVec3::new(3.0, 0.0, -2.0));
            let r = knee_hyperextension(&p);
            assert!((r[0] - back[0]).abs() < 1e-9 && (r[1] - back[1]).abs() < 1e-9);
            let p = leg(0.05).map(|v| q * v);
            assert_eq!(knee_hyperextension(&p), [0.0, 0.0]);
        }
    }
}
