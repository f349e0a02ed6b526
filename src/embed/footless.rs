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

/// How far a rim's vertices may lie from its centre (a fraction of the
/// height): an ankle's or a shin's section is 3-4 % of the height across.
const MAX_RADIUS: f64 = 0.05;

/// Whether both ankles of `joints` (on `positions`, the body `height`
/// tall) lie at the centre of an open boundary loop of `triangles` no
/// wider than a shin.
pub(crate) fn feet_cut(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    joints: &[DVec3],
    height: f64,
) -> bool {
    let loops = crate::mesh::boundary::boundary_loops(positions.len(), triangles);
    if loops.is_empty() {
        return false;
    }
    let rims: Vec<(DVec3, f64)> = loops
        .iter()
        .map(|l| {
            let q = |v: &u32| DVec3::from_array(positions[*v as usize]);
            let centre = l.iter().map(q).sum::<DVec3>() / l.len().max(1) as f64;
            let radius = l.iter().map(|v| q(v).distance(centre)).fold(0.0, f64::max);
            (centre, radius)
        })
        .collect();
    [Canonical::LAnkle, Canonical::RAnkle].iter().all(|a| {
        let ankle = joints[a.index()];
        rims.iter()
            .any(|(c, r)| *r <= MAX_RADIUS * height && c.distance(ankle) <= NEAR_RIM * height)
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
