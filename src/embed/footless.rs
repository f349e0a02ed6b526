//! A body cut above the feet (issue 41, partial bodies): each leg ends in
//! an open boundary loop, the cut's rim, at its ankle (the automatic rig
//! puts the ankle at the rim's centre, `embed::auto::cut_ends`; a hand-made
//! landmarks file puts it at the stump's end). The embedding still places
//! toes, on a foot that is not there; the foot checks (the toes' symmetry
//! and bones, their place inside the body, the feet's direction) are then
//! skipped and the rig says `absent: feet` once.
//!
//! One leg cut (`absent: l_foot` or `r_foot`): the embedding's toes for
//! that leg were sought where no foot is and landed towards the other
//! foot (samba with its left foot cut: the toes 8.6 % of the height apart
//! from the mid-plane, the foot bone across the other leg). That leg's toe
//! joint and tip are the other foot's mirrored across the mid-plane and
//! carried to its ankle ([`mirror_foot`]); the toes' symmetry, bones and
//! the feet's direction are not checked, and the cut toe is not asked to
//! lie inside the body.

use super::joints::JointEstimate;
use crate::rig::Canonical;
use glam::DVec3;

/// How far an ankle may lie from its rim's centre (a fraction of the
/// height): the automatic rig puts it on the centre; a hand-placed one
/// sits within a shin's radius of it.
const NEAR_RIM: f64 = 0.04;

/// Which ankles of `joints` (left, right; on `positions`, the body
/// `height` tall) lie at the centre of an open boundary loop of
/// `triangles` no wider than a limb's section (the rims the automatic rig
/// reads, [`super::auto::cut_ends::rims`]).
pub(crate) fn cut_feet(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    joints: &[DVec3],
    height: f64,
) -> [bool; 2] {
    let rims = super::auto::cut_ends::rims(positions, triangles);
    [Canonical::LAnkle, Canonical::RAnkle].map(|a| {
        let ankle = joints[a.index()];
        rims.iter()
            .any(|r| r.is_limb_section(height) && r.centre.distance(ankle) <= NEAR_RIM * height)
    })
}

/// The names `absent` gets for the feet `cut` (left, right): `feet`,
/// `l_foot` or `r_foot`, or none.
pub(crate) fn absent_names(cut: [bool; 2]) -> Option<&'static str> {
    match cut {
        [true, true] => Some("feet"),
        [true, false] => Some("l_foot"),
        [false, true] => Some("r_foot"),
        [false, false] => None,
    }
}

/// Gives the foot of side `cut` (0 left, 1 right) of `est` the other
/// foot's toe joint and tip ([`mirror_toes`]).
pub(crate) fn mirror_foot(est: &mut JointEstimate, cut: usize) {
    let left = est.left;
    mirror_toes(&mut est.joints, &mut est.toe_tips, left, cut);
}

/// The toe joint in `joints` and the toe tip in `tips` of side `cut` (0
/// left, 1 right): the other side's, mirrored across the plane whose
/// normal is `left` and carried from the other ankle to its own.
pub(crate) fn mirror_toes(
    joints: &mut [DVec3; Canonical::COUNT],
    tips: &mut [DVec3; 2],
    left: DVec3,
    cut: usize,
) {
    let (ankles, toes) = (
        [Canonical::LAnkle, Canonical::RAnkle],
        [Canonical::LToe, Canonical::RToe],
    );
    let (cut, other) = (cut.min(1), 1 - cut.min(1));
    let n = left.normalize_or_zero();
    let mirror = |d: DVec3| d - 2.0 * d.dot(n) * n;
    let from = joints[ankles[other].index()];
    let to = joints[ankles[cut].index()];
    joints[toes[cut].index()] = to + mirror(joints[toes[other].index()] - from);
    tips[cut] = to + mirror(tips[other] - from);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two open tubes (shins cut at the bottom) and the ankles at their
    /// rims: both cut; an ankle away from its rim: that foot not; a closed
    /// mesh: none.
    #[test]
    fn ankles_at_narrow_rims_are_cut_feet() {
        let mut p = Vec::new();
        let mut t = Vec::new();
        for x in [-0.1, 0.1] {
            let base = p.len() as u32;
            for k in 0..3 {
                for i in 0..8 {
                    let a = i as f64 * std::f64::consts::TAU / 8.0;
                    p.push([x + 0.02 * a.cos(), 0.1 * k as f64, 0.02 * a.sin()]);
                }
            }
            let at = |k: u32, i: u32| base + k * 8 + i % 8;
            for k in 0..2 {
                for i in 0..8 {
                    t.push([at(k, i), at(k + 1, i), at(k, i + 1)]);
                    t.push([at(k, i + 1), at(k + 1, i), at(k + 1, i + 1)]);
                }
            }
        }
        let mut j = vec![DVec3::ZERO; Canonical::COUNT];
        j[Canonical::LAnkle.index()] = DVec3::new(-0.1, 0.0, 0.0);
        j[Canonical::RAnkle.index()] = DVec3::new(0.1, 0.01, 0.0);
        // Each tube has two rims (top and bottom); the ankles at the bottom.
        assert_eq!(cut_feet(&p, &t, &j, 1.0), [true, true]);
        j[Canonical::RAnkle.index()] = DVec3::new(0.1, 0.1, 0.0);
        assert_eq!(cut_feet(&p, &t, &j, 1.0), [true, false]);
        assert_eq!(cut_feet(&p, &[], &j, 1.0), [false, false]);
    }

    /// The cut foot's toe is the other's mirrored across the mid-plane and
    /// carried to its ankle: a right foot pointing forward and out gives a
    /// left one pointing forward and out the other way, whatever the
    /// ankles' places; the right foot is not moved.
    #[test]
    fn a_cut_foot_gets_the_other_mirrored() {
        let mut j = [DVec3::ZERO; Canonical::COUNT];
        j[Canonical::LAnkle.index()] = DVec3::new(0.1, 0.08, 0.02);
        j[Canonical::RAnkle.index()] = DVec3::new(-0.1, 0.05, 0.0);
        j[Canonical::RToe.index()] = DVec3::new(-0.13, 0.01, 0.12);
        // The left toe where the embedding put it: towards the other foot.
        j[Canonical::LToe.index()] = DVec3::new(-0.05, 0.01, 0.05);
        let mut tips = [DVec3::ZERO, DVec3::new(-0.14, 0.0, 0.18)];
        let right = (j[Canonical::RToe.index()], tips[1]);
        mirror_toes(&mut j, &mut tips, DVec3::X * 2.0, 0);
        let ankle = j[Canonical::LAnkle.index()];
        let toe = j[Canonical::LToe.index()] - ankle;
        assert!(
            (toe - DVec3::new(0.03, -0.04, 0.12)).length() < 1e-12,
            "{toe}"
        );
        assert!((tips[0] - ankle - DVec3::new(0.04, -0.05, 0.18)).length() < 1e-12);
        assert_eq!((j[Canonical::RToe.index()], tips[1]), right);
    }

    /// The names `absent` gets: both feet, one, or none.
    #[test]
    fn cut_feet_are_named() {
        assert_eq!(absent_names([true, true]), Some("feet"));
        assert_eq!(absent_names([true, false]), Some("l_foot"));
        assert_eq!(absent_names([false, true]), Some("r_foot"));
        assert_eq!(absent_names([false, false]), None);
    }
}
