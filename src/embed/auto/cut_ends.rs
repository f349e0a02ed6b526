//! Arms and legs that end in a cut (issue 41: "a body without a head, hands or
//! feet gets the joints it has"). A capture whose hands were cut off at
//! the wrists by a script leaves an open boundary loop, the cut's rim,
//! at each arm's end, and the arm's extremity (the geodesic farthest
//! point, [`super::branches`]) lies on it. Its joints are matched from
//! the tip as a whole arm's are ([`super::limbs::ARM`]: wrist, elbow,
//! shoulder at 0.10, 0.25 and 0.42 of the height from the fingertips),
//! so the elbow, 0.13-0.18 of the height from samba's cut wrists, was
//! taken for the wrist and the shoulder for the elbow: the upper arm's
//! part was empty and the arms swung stiff in retargeting. An arm whose
//! tip is on a rim is matched from the wrist instead (the hand's 0.10
//! taken off every distance), its wrist at the rim's centre.
//!
//! Legs the same (session 50): a leg whose tip is on a rim is matched
//! from the ankle ([`super::limbs::LEG`]'s foot 0.12 taken off), its ankle
//! at the rim's centre. Matched from the missing toes, samba cut 10 cm up
//! had its knees at the skirt's hem (11-13 % of the height high). A cut
//! leg has no toes to read the facing's sign from: its knee's bend over
//! the frames gives it ([`super::facing::knee_folds_towards`]), and the
//! floor is found from the knees ([`super::floor`]).

use glam::DVec3;

/// How near the tip a rim's vertex must lie (a fraction of the height):
/// the farthest point of a cut limb is on its rim.
const NEAR_TIP: f64 = 0.02;

/// How far a rim's vertices may lie from its centre (a fraction of the
/// height): a wrist's section is 2-3 % of the height across, an ankle's
/// 3-4 %; a larger opening at a tip (a sleeve left open round a hand
/// inside it) is no cut wrist.
pub(crate) const MAX_RADIUS: f64 = 0.05;

/// One open boundary loop of the rest frame: its centre and vertices.
pub(crate) struct Rim {
    /// The loop's vertices' centroid.
    pub centre: DVec3,
    /// The farthest vertex's distance from the centre.
    pub radius: f64,
    /// The loop's vertices, in order round it.
    pub vertices: Vec<u32>,
}

impl Rim {
    /// Whether the rim is no wider than a limb's section ([`MAX_RADIUS`])
    /// on a body `height` tall.
    pub(crate) fn is_limb_section(&self, height: f64) -> bool {
        self.radius <= MAX_RADIUS * height
    }
}

/// The open boundary loops of the mesh (`triangles` over the rest frame
/// `rest`), each with its centre (none on a closed mesh).
pub(crate) fn rims(rest: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<Rim> {
    crate::mesh::boundary::boundary_loops(rest.len(), triangles)
        .into_iter()
        .map(|vertices| {
            let q = |v: &u32| DVec3::from_array(rest[*v as usize]);
            let centre = vertices.iter().map(q).sum::<DVec3>() / vertices.len().max(1) as f64;
            let radius = vertices
                .iter()
                .map(|v| q(v).distance(centre))
                .fold(0.0, f64::max);
            Rim {
                centre,
                radius,
                vertices,
            }
        })
        .collect()
}

/// The centre of the cut the extremity `tip` ends in: the rim, no wider
/// than a limb's section, with a vertex within [`NEAR_TIP`] of the height
/// of the tip; `None` for a whole limb.
pub(crate) fn cut_at(rest: &[[f64; 3]], rims: &[Rim], tip: u32, height: f64) -> Option<DVec3> {
    let t = DVec3::from_array(rest[tip as usize]);
    rims.iter()
        .filter(|r| r.is_limb_section(height))
        .filter(|r| {
            r.vertices
                .iter()
                .any(|&v| DVec3::from_array(rest[v as usize]).distance(t) <= NEAR_TIP * height)
        })
        .min_by(|a, b| a.centre.distance(t).total_cmp(&b.centre.distance(t)))
        .map(|r| r.centre)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tube along +y from 0 to 1, radius `r`, open at the top (a rim),
    /// closed at the bottom by a fan; `rings` rings of 8.
    fn tube(r: f64, rings: u32) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut p = vec![[0.0, 0.0, 0.0]];
        for k in 0..rings {
            let y = (k + 1) as f64 / rings as f64;
            for i in 0..8 {
                let a = i as f64 * std::f64::consts::TAU / 8.0;
                p.push([r * a.cos(), y, r * a.sin()]);
            }
        }
        let at = |k: u32, i: u32| 1 + k * 8 + i % 8;
        let mut t = Vec::new();
        for i in 0..8 {
            t.push([0, at(0, i + 1), at(0, i)]);
        }
        for k in 0..rings - 1 {
            for i in 0..8 {
                t.push([at(k, i), at(k, i + 1), at(k + 1, i)]);
                t.push([at(k, i + 1), at(k + 1, i + 1), at(k + 1, i)]);
            }
        }
        (p, t)
    }

    #[test]
    fn a_tip_on_a_narrow_rim_is_a_cut_and_a_closed_end_or_wide_opening_is_not() {
        let (p, t) = tube(0.02, 10);
        let r = rims(&p, &t);
        assert_eq!(r.len(), 1);
        let top = 1 + 9 * 8;
        let c = cut_at(&p, &r, top, 1.0).unwrap();
        assert!((c - DVec3::new(0.0, 1.0, 0.0)).length() < 1e-9, "{c}");
        // The closed end is no cut.
        assert!(cut_at(&p, &r, 0, 1.0).is_none());
        // An opening wider than a limb's section is no cut.
        let (p, t) = tube(0.2, 10);
        assert!(cut_at(&p, &rims(&p, &t), top, 1.0).is_none());
    }
}
