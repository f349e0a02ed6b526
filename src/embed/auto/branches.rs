//! The body's extremities as the tips of its branches.
//!
//! The extremities are geodesic farthest points from a seed on the trunk,
//! as [`super::humanoid::extremities`] samples them. A farthest point is not always the tip of a branch: a point half way
//! down a long limb, on the side away from the seed, is as far from the
//! seed as from the limb's tip. On the SMPL template the seed lies on the
//! back and the fifth farthest point was the front of the left thigh
//! (41 % of the height from the seed and the four tips), ahead of the top
//! of the head (39 %); on MakeHuman's body and on samba with the hands cut
//! off a thigh's or the skirt's front came sixth at 78-85 % of the fifth's
//! reach, which the rule "a sixth extremity this far is a tail" refused.
//!
//! Two measures tell a tip from a point on a limb's side or on the trunk
//! (the first reads the level sets of the geodesic distance from the
//! point, as the level-set diagrams of Lazarus & Verroust 1999 read a
//! body's branches: a limb is where the level set stays one short loop):
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
//! heel). Not separated: with a hand held at the body's centre (samba's
//! frames 127-173, the hands going to the hips) the seed lies near the
//! hand, which is then no extremity; a tail of 20 % of the height on the
//! procedural body is not refused (one of 45 % and a third arm are). Both
//! are signs [`super::guard`] reads to seek the tips from the geodesic
//! centre instead (session 37, the default).

use super::centre::{TipSeed, geodesic_centre, nearest};
use super::guard::Guard;
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

/// How far a sixth branch may reach before the body is refused: 75 % of
/// the fifth branch's reach (sessions 20-34's rule) and half of the
/// third's (an arm's or a leg's: a tail as long as half a limb is refused
/// even when it outreaches the head, which then comes sixth), the lesser.
/// `five`: the first five branches' reaches, farthest first.
pub fn sixth_limit(five: &[f64]) -> f64 {
    (0.75 * five[4]).min(0.5 * five[2])
}

/// The body's extremities on `rest`: every candidate examined from the
/// trunk's seed ([`TipSeed`]) with [`candidates`] and `limit`, the first
/// five branches (fewer when the body has fewer) and the sixth branch
/// when there is one.
pub struct Tips {
    /// The seed: the vertex nearest the vertices' centroid, or the
    /// geodesic centre ([`TipSeed`]).
    pub seed: u32,
    /// The vertices' centroid.
    pub centre: DVec3,
    /// Every candidate examined, in order.
    pub candidates: Vec<Candidate>,
    /// The first five branches (vertex, reach).
    pub five: Vec<(u32, f64)>,
    /// A sixth branch reaching `limit` of the five.
    pub sixth: Option<Candidate>,
    /// With [`TipSeed::Guarded`], what the guard measured and kept.
    pub guard: Option<Guard>,
}

impl Tips {
    /// The least score (detour less disc ratio) of the five branches
    /// (infinite for none).
    pub fn least_score(&self) -> f64 {
        self.candidates
            .iter()
            .filter(|c| c.is_branch())
            .take(5)
            .map(|c| c.detour - c.sheet)
            .fold(f64::INFINITY, f64::min)
    }
}

/// [`Tips`] of `rest` (triangles `triangles`, neighbours `nb`), sought
/// from the seed `how` says ([`super::centre`], [`super::guard`]).
pub fn body_tips(
    rest: &[[f64; 3]],
    triangles: &[[u32; 3]],
    nb: &[Vec<u32>],
    limit: impl Fn(&[f64]) -> f64,
    how: TipSeed,
) -> Tips {
    let n = rest.len();
    let v3 = |q: [f64; 3]| DVec3::from_array(q);
    let centre = rest.iter().map(|q| v3(*q)).sum::<DVec3>() / n.max(1) as f64;
    let near = nearest(rest, centre);
    let from = |seed: u32| tips_from(rest, triangles, nb, seed, centre, &limit);
    match how {
        TipSeed::Centroid => from(near),
        TipSeed::Centre => from(geodesic_centre(rest, nb, near)),
        TipSeed::Guarded => {
            let mine = from(near);
            let middle = geodesic_centre(rest, nb, near);
            if middle == near {
                return mine;
            }
            let other = from(middle);
            let (to_seed, _) = geodesic(rest, nb, &[near]);
            let fifth = other.five.last().map_or(f64::INFINITY, |t| t.1);
            let seed_to_tip = other
                .five
                .iter()
                .map(|t| to_seed[t.0 as usize] / fifth)
                .fold(f64::INFINITY, f64::min);
            let score = |c: &Candidate| c.detour - c.sheet;
            let guard = Guard::decide(
                middle,
                seed_to_tip,
                mine.sixth.as_ref().map(score),
                other.sixth.as_ref().map(score),
                other.least_score(),
            );
            let mut kept = if guard.kept_centre { other } else { mine };
            kept.guard = Some(guard);
            kept
        }
    }
}

/// [`Tips`] of `rest` from `seed` (the vertices' centroid `centre`).
fn tips_from(
    rest: &[[f64; 3]],
    triangles: &[[u32; 3]],
    nb: &[Vec<u32>],
    seed: u32,
    centre: DVec3,
    limit: &impl Fn(&[f64]) -> f64,
) -> Tips {
    let found = candidates(rest, triangles, nb, seed, limit);
    let branches: Vec<Candidate> = found.iter().copied().filter(Candidate::is_branch).collect();
    Tips {
        seed,
        centre,
        five: branches
            .iter()
            .take(5)
            .map(|c| (c.vertex, c.reach))
            .collect(),
        sixth: branches.get(5).copied(),
        candidates: found,
        guard: None,
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
