//! Where the rotation-aware local steps ([`super::arap`]) and a
//! non-linear constraint skinning ([`super::dqs`]) act
//! ([`super::DeformOptions::step_zone`]): everywhere, or only near the
//! knees (and elbows), issue 42.
//!
//! Session 36 measured the creases behind the knee per stage: each thigh's
//! and shin's own solve keeps half of skinning's, because the retrieved
//! frame's Laplacian coordinates turned by the skin's blend of the two
//! bones' turns do not describe a knee bent further than the retrieved
//! one; two local steps (each vertex's turn re-fitted to its solved
//! one-ring, Sorkine & Alexa 2007, Eq. 6) took them down by 30-45 % but
//! everywhere else they turned more triangles over, raised the velocity
//! error and cost 1.6× the retarget's CPU. A zone keeps the steps where
//! the creases are: a vertex's weight is 1 within `reach` of the joint
//! (a fraction of the child bone's rest length, so the zone scales with
//! the character) and falls linearly to 0 at twice that; the fitted turn
//! is slerped from the skin's by the weight, and a region with no vertex
//! in the zone takes no step.

use crate::pose::Pose;
use crate::rig::Canonical;
use glam::DVec3;

/// Where the local steps and the constraint skinning act.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StepZone {
    /// Every vertex of every region (sessions 22-36).
    #[default]
    Everywhere,
    /// Near the knees.
    Knees,
    /// Near the knees and the elbows.
    Limbs,
}

impl StepZone {
    /// The (joint, child joint) pairs whose neighbourhoods are the zone;
    /// `None` for [`StepZone::Everywhere`].
    fn joints(self) -> Option<&'static [(Canonical, Canonical)]> {
        use Canonical::*;
        match self {
            StepZone::Everywhere => None,
            StepZone::Knees => Some(&[(LKnee, LAnkle), (RKnee, RAnkle)]),
            StepZone::Limbs => Some(&[
                (LKnee, LAnkle),
                (RKnee, RAnkle),
                (LElbow, LWrist),
                (RElbow, RWrist),
            ]),
        }
    }
}

/// Each vertex's weight in `zone` on the rest frame `rest` with joints
/// `pose` (one unit, any): 1 within `reach` × the child bone's length of a
/// zone joint, falling linearly to 0 at twice that; `None` for
/// [`StepZone::Everywhere`] (every vertex weight 1).
pub(crate) fn zone_weights(
    rest: &[[f64; 3]],
    pose: &Pose,
    zone: StepZone,
    reach: f64,
) -> Option<Vec<f64>> {
    let joints = zone.joints()?;
    let balls: Vec<(DVec3, f64)> = joints
        .iter()
        .map(|&(j, c)| {
            let (a, b) = (pose[j.index()], pose[c.index()]);
            (a, (reach * (b - a).length()).max(f64::MIN_POSITIVE))
        })
        .collect();
    Some(
        rest.iter()
            .map(|p| {
                let p = DVec3::from_array(*p);
                balls
                    .iter()
                    .map(|&(c, r)| (2.0 - (p - c).length() / r).clamp(0.0, 1.0))
                    .fold(0.0, f64::max)
            })
            .collect(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A leg along −Y: a knee at the origin, the ankle 0.4 below; with
    /// reach 0.2 the weight is 1 up to 8 cm from the knee, ½ at 12 cm, 0
    /// from 16 cm; the same scaled by 10; `Everywhere` gives none; `Knees`
    /// leaves the elbows out, `Limbs` takes them.
    #[test]
    fn the_zone_is_a_ball_scaled_by_the_bone() {
        let mut pose: Pose = [DVec3::ZERO; Canonical::COUNT];
        pose[Canonical::LKnee.index()] = DVec3::ZERO;
        pose[Canonical::LAnkle.index()] = DVec3::new(0.0, -0.4, 0.0);
        pose[Canonical::RKnee.index()] = DVec3::new(5.0, 0.0, 0.0);
        pose[Canonical::RAnkle.index()] = DVec3::new(5.0, -0.4, 0.0);
        pose[Canonical::LElbow.index()] = DVec3::new(0.0, 5.0, 0.0);
        pose[Canonical::LWrist.index()] = DVec3::new(0.0, 5.3, 0.0);
        pose[Canonical::RElbow.index()] = DVec3::new(9.0, 5.0, 0.0);
        pose[Canonical::RWrist.index()] = DVec3::new(9.0, 5.3, 0.0);
        let rest = [
            [0.0, 0.07, 0.0],
            [0.0, -0.12, 0.0],
            [0.17, 0.0, 0.0],
            [0.0, 5.0, 0.03],
        ];
        let w = zone_weights(&rest, &pose, StepZone::Knees, 0.2).unwrap();
        assert_eq!(w[0], 1.0);
        assert!((w[1] - 0.5).abs() < 1e-9, "{}", w[1]);
        assert_eq!(w[2], 0.0);
        assert_eq!(w[3], 0.0);
        let big: Vec<[f64; 3]> = rest.iter().map(|p| p.map(|x| 10.0 * x)).collect();
        let mut pose10 = pose;
        for j in &mut pose10 {
            *j *= 10.0;
        }
        let w10 = zone_weights(&big, &pose10, StepZone::Knees, 0.2).unwrap();
        for (a, b) in w.iter().zip(&w10) {
            assert!((a - b).abs() < 1e-9, "{a} {b}");
        }
        assert!(zone_weights(&rest, &pose, StepZone::Everywhere, 0.2).is_none());
        let l = zone_weights(&rest, &pose, StepZone::Limbs, 0.2).unwrap();
        assert_eq!(l[3], 1.0);
    }
}
