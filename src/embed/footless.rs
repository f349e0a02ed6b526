//! A body cut above the feet (issue 41, partial bodies): each leg ends in
//! an open boundary loop, the cut's rim, at its ankle (the automatic rig
//! puts the ankle at the rim's centre, `embed::auto::cut_ends`; a hand-made
//! landmarks file puts it at the stump's end). The embedding still places
//! toes, on a foot that is not there; the foot checks (the toes' symmetry
//! and bones, their place inside the body, the feet's direction) are then
//! skipped and the rig says `absent: feet` once.

use crate::rig::Canonical;
use glam::DVec3;

/// How far an ankle may lie from its rim's centre (a fraction of the
/// height): the automatic rig puts it on the centre; a hand-placed one
/// sits within a shin's radius of it.
const NEAR_RIM: f64 = 0.04;

/// Whether both ankles of `joints` (on `positions`, the body `height`
/// tall) lie at the centre of an open boundary loop of `triangles` no
/// wider than a limb's section (the rims the automatic rig reads,
/// [`super::auto::cut_ends::rims`]).
pub(crate) fn feet_cut(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    joints: &[DVec3],
    height: f64,
) -> bool {
    let rims = super::auto::cut_ends::rims(positions, triangles);
    [Canonical::LAnkle, Canonical::RAnkle].iter().all(|a| {
        let ankle = joints[a.index()];
        rims.iter()
            .any(|r| r.is_limb_section(height) && r.centre.distance(ankle) <= NEAR_RIM * height)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two open tubes (shins cut at the bottom) and the ankles at their
    /// rims: cut; an ankle away from its rim, or a closed mesh: not.
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
        assert!(feet_cut(&p, &t, &j, 1.0));
        j[Canonical::RAnkle.index()] = DVec3::new(0.1, 0.1, 0.0);
        assert!(!feet_cut(&p, &t, &j, 1.0));
        assert!(!feet_cut(&p, &[], &j, 1.0));
    }
}
