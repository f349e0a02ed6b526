//! The candidates for the body's extremities (the tips of its branches,
//! [`super::branches`]): geodesic farthest points from a seed on the
//! trunk, each with the two measures that tell a tip from a point on a
//! limb's side or on the trunk.
//!
//! The two measures (the first reads the level sets of the geodesic
//! distance from the point, as the level-set diagrams of Lazarus &
//! Verroust 1999 read a body's branches: a limb is where the level set
//! stays one short loop):
//! - the **disc ratio**: the length of the level set at a quarter of the
//!   point's reach over a flat disc's circle of that radius (2πr): about 1
//!   where the disc grows as on a sheet (a trunk, a thigh's side, a
//!   skirt), the tube's girth over 2πr on a limb, a tail or the neck below
//!   a head;
//! - the **detour**: the least `d(seed, x) + d(x, t) − d(seed, t)` over the
//!   earlier candidates `t`, over twice the point's reach: near 0 when the
//!   point lies on the way from the seed to an earlier tip (the side of
//!   that limb), about 1 for a tip (the way out along its own branch and
//!   back).
//!
//! A candidate is a branch when its detour less its disc ratio is over
//! [`MARGIN`]. Measured (`embed::auto_branches`, every candidate the rule
//! examines, each frame taken as the rest): on samba's frames 0-126 and
//! 174, SMPL and MakeHuman driven by the procedural turn (60 frames each)
//! the tips of limbs and heads score −0.13 and over, the points that are
//! not tips −0.34 and under (a thigh's front, the skirt, the chest, a
//! heel).

use super::humanoid::{farthest, geodesic};
use glam::DVec3;

/// A candidate's detour less its disc ratio over which it is the tip of
/// a branch (the module's measures).
pub const MARGIN: f64 = -0.3;
/// Candidates examined at most.
const MAX_CANDIDATES: usize = 24;

/// One geodesic farthest point: vertex, reach (distance to the seed and
/// the earlier candidates) and whether it is the tip of a branch.
#[derive(Debug, Clone, Copy)]
pub struct Candidate {
    /// The vertex.
    pub vertex: u32,
    /// Its geodesic distance to the seed and every earlier candidate.
    pub reach: f64,
    /// The disc ratio: the level set's length at a quarter of the reach
    /// over a flat disc's.
    pub sheet: f64,
    /// The least detour through it to an earlier candidate, over twice
    /// its reach (infinite for the first).
    pub detour: f64,
}

impl Candidate {
    /// The tip of a branch: its detour less its disc ratio over
    /// [`MARGIN`].
    pub fn is_branch(&self) -> bool {
        self.detour - self.sheet > MARGIN
    }
}

/// Geodesic farthest points from `seed` in order, while fewer than five
/// are branch tips or the reach is at least `limit(five branch reaches)`
/// (at most [`MAX_CANDIDATES`]).
pub fn candidates(
    p: &[[f64; 3]],
    triangles: &[[u32; 3]],
    nb: &[Vec<u32>],
    seed: u32,
    limit: impl Fn(&[f64]) -> f64,
) -> Vec<Candidate> {
    let (from_seed, _) = geodesic(p, nb, &[seed]);
    let mut d = from_seed.clone();
    let mut out: Vec<Candidate> = Vec::new();
    let mut fields: Vec<Vec<f64>> = Vec::new();
    while out.len() < MAX_CANDIDATES {
        let Some((v, reach)) = farthest(&d) else {
            break;
        };
        let branches: Vec<f64> = out
            .iter()
            .filter(|c| c.is_branch())
            .map(|c| c.reach)
            .collect();
        if branches.len() >= 5 && reach < limit(&branches[..5]) || reach <= 0.0 {
            break;
        }
        let (dn, _) = geodesic(p, nb, &[v as u32]);
        let r = 0.25 * reach;
        let sheet = level_length(p, triangles, &dn, r) / (std::f64::consts::TAU * r);
        let detour = out
            .iter()
            .zip(&fields)
            .map(|(t, dt)| (from_seed[v] + dt[v] - from_seed[t.vertex as usize]) / (2.0 * reach))
            .fold(f64::INFINITY, f64::min);
        out.push(Candidate {
            vertex: v as u32,
            reach,
            sheet,
            detour,
        });
        for (a, b) in d.iter_mut().zip(&dn) {
            *a = a.min(*b);
        }
        fields.push(dn);
    }
    out
}

/// Length of the level set `{d = level}` of the piecewise linear field
/// `d` over `triangles`.
pub(crate) fn level_length(p: &[[f64; 3]], triangles: &[[u32; 3]], d: &[f64], level: f64) -> f64 {
    let mut total = 0.0;
    for t in triangles {
        let mut ends = [DVec3::ZERO; 2];
        let mut k = 0;
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            let (da, db) = (d[a as usize] - level, d[b as usize] - level);
            if (da < 0.0) != (db < 0.0) && k < 2 && da.is_finite() && db.is_finite() {
                let s = da / (da - db);
                let (pa, pb) = (
                    DVec3::from_array(p[a as usize]),
                    DVec3::from_array(p[b as usize]),
                );
                ends[k] = pa + (pb - pa) * s;
                k += 1;
            }
        }
        if k == 2 {
            total += ends[0].distance(ends[1]);
        }
    }
    total
}
