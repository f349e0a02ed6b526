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
//! [`super::candidates`] tells a tip from a point on a limb's side or on
//! the trunk (the disc ratio and the detour); this module keeps the first
//! five branches and a sixth, sought from the seed [`TipSeed`] says.
//! Not separated by the measures: with a hand held at the body's centre
//! (samba's frames 127-173, the hands going to the hips) the seed lies
//! near the hand, which is then no extremity; a tail of 20 % of the
//! height on the procedural body is not refused (one of 45 % and a third
//! arm are). Both are signs [`super::guard`] reads to seek the tips from
//! the geodesic centre instead (session 37, the default).

use super::centre::{TipSeed, geodesic_centre, nearest};
use super::guard::Guard;
use super::humanoid::geodesic;
use glam::DVec3;

pub use super::candidates::{Candidate, MARGIN, candidates};

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
