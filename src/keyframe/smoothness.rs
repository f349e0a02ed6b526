//! Smoothness of a transition (Huang et al. 2015, Sec. 6.1, Table III): the
//! weighted average of the Hausdorff distance between the overlapping
//! frames `M_i(t_m+k)` and `M_j(t_n+k)`, `k ∈ [−L, L]`, with the weights
//! `α′(k) = min(α(k), 1 − α(k))`, `α(k) = (k + L) / 2L` of Eq. 2. The frame
//! of `j` is first moved on the floor onto the frame of `i` (the rotation
//! about the vertical and translation that best fit their skeletons, as the
//! output places it). Metres.
//!
//! The Hausdorff distance is over the vertex sets (symmetric, max of the
//! two directed distances), with a uniform grid for the nearest neighbours:
//! `O(n)` per frame pair for meshes of even density.

use crate::retarget::Floor;
use crate::retarget::character::Character;
use glam::DVec3;
use std::collections::HashMap;

/// A uniform grid over a point set for nearest-neighbour queries.
struct Grid {
    cell: f64,
    cells: HashMap<(i32, i32, i32), Vec<u32>>,
    points: Vec<DVec3>,
}

impl Grid {
    fn new(points: Vec<DVec3>, cell: f64) -> Grid {
        let mut cells: HashMap<(i32, i32, i32), Vec<u32>> = HashMap::new();
        for (i, p) in points.iter().enumerate() {
            cells.entry(key(*p, cell)).or_default().push(i as u32);
        }
        Grid {
            cell,
            cells,
            points,
        }
    }

    /// Distance from `q` to the nearest point: rings of cells around
    /// `q`'s until the next ring lies farther than the best found (a point
    /// in ring `r` is at least `(r − 1)·cell` away); all points when none
    /// is within 14 cells.
    fn nearest(&self, q: DVec3) -> f64 {
        let (cx, cy, cz) = key(q, self.cell);
        let mut best = f64::INFINITY;
        for r in 0..16i32 {
            if ((r - 1).max(0) as f64 * self.cell).powi(2) > best {
                return best.sqrt();
            }
            for dx in -r..=r {
                for dy in -r..=r {
                    for dz in -r..=r {
                        if dx.abs().max(dy.abs()).max(dz.abs()) != r {
                            continue;
                        }
                        if let Some(ids) = self.cells.get(&(cx + dx, cy + dy, cz + dz)) {
                            for &i in ids {
                                best = best.min(self.points[i as usize].distance_squared(q));
                            }
                        }
                    }
                }
            }
        }
        if best.is_finite() && (14.0 * self.cell).powi(2) >= best {
            return best.sqrt();
        }
        self.points
            .iter()
            .map(|p| p.distance_squared(q))
            .fold(f64::INFINITY, f64::min)
            .sqrt()
    }
}

fn key(p: DVec3, cell: f64) -> (i32, i32, i32) {
    (
        (p.x / cell).floor() as i32,
        (p.y / cell).floor() as i32,
        (p.z / cell).floor() as i32,
    )
}

/// Symmetric Hausdorff distance between two vertex sets.
pub fn hausdorff(a: &[DVec3], b: &[DVec3]) -> f64 {
    if a.is_empty() || b.is_empty() {
        return 0.0;
    }
    let cell = 0.03;
    let ga = Grid::new(a.to_vec(), cell);
    let gb = Grid::new(b.to_vec(), cell);
    let ab = a.iter().map(|&p| gb.nearest(p)).fold(0.0, f64::max);
    let ba = b.iter().map(|&p| ga.nearest(p)).fold(0.0, f64::max);
    ab.max(ba)
}

/// The smoothness of a jump from frame `from` (of sequence `i`) to frame
/// `to` (of `j`; `to − 1` pairs with `from`) with half-window `window`.
pub fn transition_smoothness(ch: &Character, from: u32, to: u32, window: usize) -> f64 {
    let (sa, ta) = ch.graph().frame_of(from);
    let (sb, tb) = ch.graph().frame_of(to);
    let tb = tb.saturating_sub(1);
    let l = window.max(1) as i64;
    let (la, lb) = (
        ch.graph().sequences[sa].len as i64,
        ch.graph().sequences[sb].len as i64,
    );
    let mut a = vec![[0.0; 3]; ch.n()];
    let mut b = vec![[0.0; 3]; ch.n()];
    let (mut num, mut den) = (0.0, 0.0);
    for k in -l..=l {
        let alpha = (k + l) as f64 / (2 * l) as f64;
        let w = alpha.min(1.0 - alpha);
        if w <= 0.0 {
            continue;
        }
        let (fa, fb) = (ta as i64 + k, tb as i64 + k);
        if fa < 0 || fb < 0 || fa >= la || fb >= lb {
            continue;
        }
        let (ia, ib) = (
            ch.graph().frame_id(sa, fa as usize),
            ch.graph().frame_id(sb, fb as usize),
        );
        ch.frame_metres(ia, &mut a);
        ch.frame_metres(ib, &mut b);
        let fit = Floor::fit(&ch.poses()[ib as usize], &ch.poses()[ia as usize]);
        let pa: Vec<DVec3> = a.iter().map(|p| DVec3::from_array(*p)).collect();
        let pb: Vec<DVec3> = b.iter().map(|p| fit.apply(DVec3::from_array(*p))).collect();
        num += w * hausdorff(&pa, &pb);
        den += w;
    }
    if den > 0.0 { num / den } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hausdorff_of_a_shifted_set_is_the_shift() {
        let a: Vec<DVec3> = (0..500)
            .map(|i| {
                let t = i as f64 * 0.37;
                DVec3::new(t.sin(), (t * 0.7).cos(), (t * 1.3).sin() * 0.5)
            })
            .collect();
        let b: Vec<DVec3> = a.iter().map(|p| *p + DVec3::new(0.0, 0.0, 5.0)).collect();
        let brute = a
            .iter()
            .map(|p| {
                b.iter()
                    .map(|q| p.distance(*q))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max)
            .max(
                b.iter()
                    .map(|p| {
                        a.iter()
                            .map(|q| p.distance(*q))
                            .fold(f64::INFINITY, f64::min)
                    })
                    .fold(0.0, f64::max),
            );
        assert!((hausdorff(&a, &b) - brute).abs() < 1e-12);
        assert_eq!(hausdorff(&a, &a), 0.0);
    }
}
