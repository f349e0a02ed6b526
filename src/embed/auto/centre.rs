//! Where the body's extremities are sought from ([`super::branches`]):
//! the vertex nearest the vertices' centroid, or the body's geodesic
//! centre.
//!
//! The centroid's nearest vertex lies in the trunk when the limbs are
//! clear of it; with a hand held at the body's centre (samba's frames
//! 127-173, the hands going to the hips) it lies on the hand, which is
//! then no extremity (session 35). Along the surface a hand touching the
//! hip is as far from the trunk as ever (the capture's mesh does not join
//! them), so the vertex whose greatest geodesic distance to the body's
//! far points is least (the graph centre: least eccentricity, as the
//! geodesic centre of Hilaga et al. 2001's Reeb graphs is taken) lies in
//! the trunk however the limbs are held. The far points are five
//! farthest-point samples started from the vertex farthest from the
//! centroid's (the ends of the limbs and the head: the first sample is
//! not the seed's own region, so a hand under the centroid is reached).

use super::humanoid::{farthest, geodesic};
use glam::DVec3;

/// Far points the centre is found from.
const FAR_POINTS: usize = 5;

/// How the seed of the extremities is chosen
/// ([`super::options::AutoOptions::tip_seed`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TipSeed {
    /// The vertex nearest the vertices' centroid (sessions 20-36).
    Centroid,
    /// The geodesic centre ([`geodesic_centre`]).
    Centre,
    /// The centroid's vertex unless a measured sign says it is wrong, then
    /// the geodesic centre ([`super::guard`], session 37; the default).
    Guarded,
}

impl TipSeed {
    /// `centroid`, `centre` or `guarded`.
    pub fn parse(name: &str) -> Option<TipSeed> {
        match name {
            "centroid" => Some(TipSeed::Centroid),
            "centre" => Some(TipSeed::Centre),
            "guarded" => Some(TipSeed::Guarded),
            _ => None,
        }
    }
}

/// The vertex of `p` nearest `centre` (0 for no vertex).
pub(crate) fn nearest(p: &[[f64; 3]], centre: DVec3) -> u32 {
    let d = |v: usize| DVec3::from_array(p[v]).distance_squared(centre);
    (0..p.len())
        .min_by(|&a, &b| d(a).total_cmp(&d(b)))
        .unwrap_or(0) as u32
}

/// The vertex of least greatest geodesic distance to [`FAR_POINTS`]
/// farthest-point samples of `p`'s surface (neighbours `nb`), the first
/// the vertex farthest from `start`; `start` when there is none.
pub fn geodesic_centre(p: &[[f64; 3]], nb: &[Vec<u32>], start: u32) -> u32 {
    let (d0, _) = geodesic(p, nb, &[start]);
    let Some((a, _)) = farthest(&d0) else {
        return start;
    };
    let (first, _) = geodesic(p, nb, &[a as u32]);
    let mut ecc = first.clone();
    let mut nearest_far = first;
    for _ in 1..FAR_POINTS {
        let Some((v, _)) = farthest(&nearest_far) else {
            break;
        };
        let (dv, _) = geodesic(p, nb, &[v as u32]);
        for ((e, m), x) in ecc.iter_mut().zip(&mut nearest_far).zip(&dv) {
            *e = e.max(*x);
            *m = m.min(*x);
        }
    }
    ecc.iter()
        .enumerate()
        .filter(|(_, e)| e.is_finite())
        .min_by(|a, b| a.1.total_cmp(b.1))
        .map_or(start, |(v, _)| v as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A star of five arms of different lengths from a hub, joined as a
    /// graph: the centre is the hub wherever the walk starts, while the
    /// point nearest the centroid is on the longest arm.
    #[test]
    fn the_centre_of_a_star_is_its_hub() {
        let lengths = [10usize, 10, 6, 6, 4];
        let dirs = [
            DVec3::new(0.3, -1.0, 0.0),
            DVec3::new(-0.3, -1.0, 0.0),
            DVec3::new(1.0, 0.2, 0.0),
            DVec3::new(-1.0, 0.2, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let mut p = vec![[0.0; 3]];
        let mut nb: Vec<Vec<u32>> = vec![Vec::new()];
        for (len, dir) in lengths.iter().zip(dirs) {
            let mut prev = 0u32;
            for k in 1..=*len {
                p.push((dir.normalize() * k as f64).to_array());
                let v = (p.len() - 1) as u32;
                nb.push(vec![prev]);
                nb[prev as usize].push(v);
                prev = v;
            }
        }
        for start in [0u32, 5, 12, 30, (p.len() - 1) as u32] {
            assert_eq!(geodesic_centre(&p, &nb, start), 0, "from {start}");
        }
        // The hub's eccentricity is the longest arm's; one step out along
        // it is no better (the other long arm is then 11 away).
        let c = p.iter().map(|q| DVec3::from_array(*q)).sum::<DVec3>() / p.len() as f64;
        assert_ne!(nearest(&p, c), 0, "the centroid's vertex is off the hub");
        assert_eq!(nearest(&[], c), 0);
    }
}
