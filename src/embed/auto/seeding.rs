//! The decomposition's vertex order and k-means seeds from the body's
//! positions, never from how the file numbers its vertices (issue 41).
//!
//! Session 28 measured samba's automatic right knee at 1.4 % of the
//! height from the landmark rig's with the capture's vertex numbering and
//! 0.1 % with the same vertices re-numbered: the k-means of
//! [`super::decompose`] was seeded at vertex `n / 2` and drew its next
//! seeds by walking the vertices in index order (k-means++ with a fixed
//! pseudo-random sequence), its sums ran in index order, and small pieces
//! were merged and labels numbered in index order.
//!
//! Here the decomposition runs on the vertices sorted by [`canonical_order`]
//! (a key made of their positions alone, compared exactly: no sum over
//! other vertices enters it), with every neighbour list sorted in that
//! order, so that every loop, sum, tie and label number of the
//! decomposition follows the positions, the k-means++ draws
//! (`decompose::Seeding::Draws`) included. Relabelling the
//! vertices of a capture therefore gives the same parts bit for bit,
//! through the relabelling. Two seedings by farthest-point sampling
//! (Gonzalez 1985, "Clustering to minimize the maximum intercluster
//! distance", the greedy 2-approximation of k-centre) are options:
//! [`farthest_seeds`] of the rest positions from the vertex nearest the
//! middle of the body's bounding box (hands, feet and head first), and
//! [`farthest_in`] of the motion signatures; both rigged samba worse
//! (joints 3.07 and 1.60 % of the height from the landmark rig's, k-means++
//! 0.69 %: session 29). None is the default yet (`decompose::Seeding`).

use glam::DVec3;
use std::cmp::Ordering;

/// Vertex ids sorted by their positions: first by the squared distance of
/// the rest position to the middle of the rest frame's bounding box (a
/// min/max, exact in any order), then by the rest coordinates, then by
/// each frame's coordinates in turn (vertices at one place on the rest
/// frame: seams). Only vertices identical in every frame keep their
/// relative index order, and they are interchangeable. O(n log n).
pub(crate) fn canonical_order(rest: &[[f64; 3]], frames: &[&[[f64; 3]]]) -> Vec<u32> {
    let mid = middle(rest);
    let key: Vec<f64> = rest
        .iter()
        .map(|p| (DVec3::from_array(*p) - mid).length_squared())
        .collect();
    let coords = |a: &[f64; 3], b: &[f64; 3]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| x.total_cmp(y))
            .find(|o| o.is_ne())
            .unwrap_or(Ordering::Equal)
    };
    let mut order: Vec<u32> = (0..rest.len() as u32).collect();
    order.sort_by(|&a, &b| {
        let (a, b) = (a as usize, b as usize);
        key[a]
            .total_cmp(&key[b])
            .then_with(|| coords(&rest[a], &rest[b]))
            .then_with(|| {
                frames
                    .iter()
                    .map(|f| coords(&f[a], &f[b]))
                    .find(|o| o.is_ne())
                    .unwrap_or(Ordering::Equal)
            })
    });
    order
}

/// The middle of the bounding box of `points` (the origin when empty).
fn middle(points: &[[f64; 3]]) -> DVec3 {
    if points.is_empty() {
        return DVec3::ZERO;
    }
    let (lo, hi) = points.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), p| {
            let q = DVec3::from_array(*p);
            (lo.min(q), hi.max(q))
        },
    );
    (lo + hi) * 0.5
}

/// `k` seed vertices (at most the vertex count) by farthest-point
/// sampling of `points`: the first the vertex nearest the middle of their
/// bounding box, each next the vertex farthest from those taken (ties: the
/// lower id; given in [`canonical_order`], the earlier there). O(n k).
pub(crate) fn farthest_seeds(points: &[[f64; 3]], k: usize) -> Vec<u32> {
    let n = points.len();
    let k = k.min(n);
    if k == 0 {
        return Vec::new();
    }
    let p: Vec<DVec3> = points.iter().map(|q| DVec3::from_array(*q)).collect();
    let mid = middle(points);
    let first = argbest(p.iter().map(|q| -q.distance_squared(mid)));
    let mut near: Vec<f64> = p.iter().map(|q| q.distance_squared(p[first])).collect();
    let mut seeds = vec![first as u32];
    while seeds.len() < k {
        let s = argbest(near.iter().copied());
        if near[s] <= 0.0 {
            break;
        }
        seeds.push(s as u32);
        for (d, q) in near.iter_mut().zip(&p) {
            *d = d.min(q.distance_squared(p[s]));
        }
    }
    seeds
}

/// `k` ids (at most `items.len()`) by farthest-point sampling of `items`
/// under the squared distance `d2` from `first`, each next the farthest
/// from those taken (ties: the lower id). O(n k) calls of `d2`.
pub(crate) fn farthest_in<T: Sync>(
    items: &[T],
    first: u32,
    k: usize,
    d2: impl Fn(&T, &T) -> f64 + Sync,
) -> Vec<u32> {
    use rayon::prelude::*;
    let k = k.min(items.len());
    if k == 0 || first as usize >= items.len() {
        return Vec::new();
    }
    let mut near: Vec<f64> = items
        .par_iter()
        .map(|x| d2(x, &items[first as usize]))
        .collect();
    let mut seeds = vec![first];
    while seeds.len() < k {
        let s = argbest(near.iter().copied());
        if near[s] <= 0.0 {
            break;
        }
        seeds.push(s as u32);
        let c = &items[s];
        near.par_iter_mut()
            .zip(items.par_iter())
            .for_each(|(d, x)| *d = d.min(d2(x, c)));
    }
    seeds
}

/// Index of the greatest value (the first of equal ones).
fn argbest(values: impl Iterator<Item = f64>) -> usize {
    let mut best = (0, f64::NEG_INFINITY);
    for (i, v) in values.enumerate() {
        if v > best.1 {
            best = (i, v);
        }
    }
    best.0
}

/// `values` (one per vertex) in `order`.
pub(crate) fn permuted<T: Clone>(values: &[T], order: &[u32]) -> Vec<T> {
    order.iter().map(|&v| values[v as usize].clone()).collect()
}

/// Neighbour lists `nb` renumbered into `order` (vertex `order[i]` is new
/// vertex `i`), each sorted.
pub(crate) fn permuted_neighbours(nb: &[Vec<u32>], order: &[u32]) -> Vec<Vec<u32>> {
    let mut new_of = vec![0u32; order.len()];
    for (i, &v) in order.iter().enumerate() {
        new_of[v as usize] = i as u32;
    }
    order
        .iter()
        .map(|&v| {
            let mut l: Vec<u32> = nb[v as usize].iter().map(|&u| new_of[u as usize]).collect();
            l.sort_unstable();
            l
        })
        .collect()
}

/// Per-vertex `labels` given in `order` put back in the original ids.
pub(crate) fn unpermuted(labels: &[u32], order: &[u32]) -> Vec<u32> {
    let mut out = vec![0u32; labels.len()];
    for (&l, &v) in labels.iter().zip(order) {
        out[v as usize] = l;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bent strip of points with a repeated point.
    fn strip() -> Vec<[f64; 3]> {
        let mut p: Vec<[f64; 3]> = (0..50)
            .map(|i| {
                let t = i as f64 * 0.1;
                [t, (t * 1.3).sin(), 0.2 * (i % 3) as f64]
            })
            .collect();
        p.push(p[7]);
        p
    }

    #[test]
    fn the_order_and_the_seeds_follow_the_points_not_their_ids() {
        let p = strip();
        let moved: Vec<[f64; 3]> = p.iter().map(|q| [q[0], q[1] + 1.0, q[2]]).collect();
        let order = canonical_order(&p, &[&moved]);
        let seeds: Vec<[f64; 3]> = farthest_seeds(&permuted(&p, &order), 6)
            .iter()
            .map(|&s| p[order[s as usize] as usize])
            .collect();
        // Reversed and rotated ids: the same points in the same order.
        let n = p.len();
        for perm in [
            (0..n).rev().collect::<Vec<usize>>(),
            (0..n).map(|i| (i * 7 + 3) % n).collect(),
        ] {
            let q: Vec<[f64; 3]> = perm.iter().map(|&i| p[i]).collect();
            let qm: Vec<[f64; 3]> = perm.iter().map(|&i| moved[i]).collect();
            let o = canonical_order(&q, &[&qm]);
            let a: Vec<[f64; 3]> = order.iter().map(|&v| p[v as usize]).collect();
            let b: Vec<[f64; 3]> = o.iter().map(|&v| q[v as usize]).collect();
            assert_eq!(a, b);
            let s: Vec<[f64; 3]> = farthest_seeds(&permuted(&q, &o), 6)
                .iter()
                .map(|&v| q[o[v as usize] as usize])
                .collect();
            assert_eq!(seeds, s);
        }
        // The seeds are distinct; the second is the farthest from the first.
        let first = DVec3::from_array(seeds[0]);
        let far = p
            .iter()
            .map(|q| DVec3::from_array(*q).distance(first))
            .fold(0.0, f64::max);
        assert_eq!(DVec3::from_array(seeds[1]).distance(first), far);
        assert!(farthest_seeds(&[], 3).is_empty());
        // Only one place: one seed, however many are asked.
        assert_eq!(farthest_seeds(&[[1.0, 2.0, 3.0]; 4], 3), vec![0]);
    }

    #[test]
    fn neighbours_and_labels_go_through_the_order_and_back() {
        let nb = vec![vec![1, 2], vec![0], vec![0]];
        let order = vec![2, 0, 1];
        let pn = permuted_neighbours(&nb, &order);
        // New 0 is old 2 (neighbour old 0 = new 1), new 1 is old 0.
        assert_eq!(pn, vec![vec![1], vec![0, 2], vec![1]]);
        let labels = vec![5, 6, 7];
        assert_eq!(unpermuted(&permuted(&labels, &order), &order), labels);
    }
}
