//! Knee hyper-extension: how far a knee is bent the wrong way (degrees past
//! straight), from a skeleton (extracted from the output mesh, or the query).
//!
//! With hip `h`, knee `k`, ankle `a` and toe `t`: the foot's forward
//! direction `f` is `t − a` made normal to the leg axis `a − h`. A knee
//! bends the right way when it lies in front of the leg axis (`(k − h)·f >
//! 0` after removing the axis component); then it reads 0. Behind it, the
//! reading is the angle between thigh `k − h` and shin `a − k`: how far
//! past straight the leg is bent backwards.

use crate::rig::Canonical;
use crate::skeleton::Pose;
use glam::DVec3;

/// Hyper-extension of the left and right knee of `p` (degrees, ≥ 0).
pub fn knee_hyperextension(p: &Pose) -> [f64; 2] {
    use Canonical as C;
    [
        (C::LHip, C::LKnee, C::LAnkle, C::LToe),
        (C::RHip, C::RKnee, C::RAnkle, C::RToe),
    ]
    .map(|(h, k, a, t)| {
        let (h, k, a, t) = (p[h.index()], p[k.index()], p[a.index()], p[t.index()]);
        let axis = (a - h).normalize_or_zero();
        let off = |v: DVec3| v - axis * v.dot(axis);
        let f = off(t - a).normalize_or_zero();
        if f == DVec3::ZERO || off(k - h).dot(f) >= 0.0 {
            return 0.0;
        }
        (k - h).angle_between(a - k).to_degrees()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
