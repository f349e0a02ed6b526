//! Frames chosen by their poses, never by their place in the capture
//! (issue 41): the automatic rig must come out the same whichever frame a
//! capture starts with, in whatever order its frames are given.
//!
//! A frame's pose descriptor is the distances between a fixed set of
//! vertices (every `n / K`-th, `K` = [`DESCRIPTOR_VERTICES`]): unchanged by
//! the body's place, heading and mirror image, and by the frame's index.
//! On it:
//!
//! - [`farthest_first`]: farthest-point sampling (Gonzalez 1985, the greedy
//!   2-approximation of the k-centre problem), seeded by a given pose (the
//!   rest frame's): which frames the skinning decomposition fits and the
//!   order it visits them;
//! - [`standing_first`]: frames ordered by [`spread`], how far they are
//!   from standing with the limbs in (the most neutral first), for the
//!   rest frame's choice; [`nearest`] and [`median`]: frames ordered by
//!   their distance from a pose (the per-coordinate median of all);
//! - [`quantiles`]: `k` frames at evenly spaced ranks of their distance
//!   from the rest frame's pose, the rest frame first: the capture's poses
//!   in proportion to how long it holds them, near and far (an even
//!   spread in time gave that, but followed the order).
//!
//! Ties (equal distances: repeated poses) are broken by the descriptors
//! themselves (lexicographic), so that only a frame identical in pose to
//! another can change places with it.
//!
//! Cost: O(F K²) for F frames, then O(F k) for k samples.

use std::cmp::Ordering;

/// Vertices of the descriptor (at most; all of a smaller mesh).
pub(crate) const DESCRIPTOR_VERTICES: usize = 96;

/// A frame's pose descriptor: the distances between every pair of
/// [`DESCRIPTOR_VERTICES`] vertices spread evenly over the vertex indices
/// (K(K−1)/2 numbers; empty for an empty frame).
pub fn descriptor(frame: &[[f64; 3]]) -> Vec<f64> {
    let n = frame.len();
    let k = DESCRIPTOR_VERTICES.min(n);
    let picked: Vec<glam::DVec3> = (0..k)
        .map(|i| glam::DVec3::from_array(frame[i * n / k]))
        .collect();
    let mut d = Vec::with_capacity(k * k.saturating_sub(1) / 2);
    for (i, a) in picked.iter().enumerate() {
        for b in &picked[i + 1..] {
            d.push(a.distance(*b));
        }
    }
    d
}

/// The [`DESCRIPTOR_VERTICES`] vertices (at most; all of a smaller mesh)
/// of [`descriptor_at`], chosen by how the vertices move over `frames`
/// rather than by their ids: the vertices sorted by their greatest squared
/// distance from the middle of the frame's bounding box over the frames,
/// then by their least, then by their least and greatest coordinates
/// (min and max over frames and vertices: exact in any order of either),
/// taken at evenly spaced ranks. The same vertices, through any
/// renumbering, whatever the frames' order; [`descriptor`]'s every
/// `n / K`-th id follows the numbering. O(F n + n log n).
pub(crate) fn descriptor_vertices(frames: &[&[[f64; 3]]]) -> Vec<u32> {
    use glam::DVec3;
    let n = frames.iter().map(|f| f.len()).min().unwrap_or(0);
    let mut far = vec![f64::NEG_INFINITY; n];
    let mut near = vec![f64::INFINITY; n];
    let mut lo = vec![[f64::INFINITY; 3]; n];
    let mut hi = vec![[f64::NEG_INFINITY; 3]; n];
    for f in frames {
        let (a, b) = f[..n].iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(a, b), p| (a.min(DVec3::from_array(*p)), b.max(DVec3::from_array(*p))),
        );
        let mid = (a + b) * 0.5;
        for (v, p) in f[..n].iter().enumerate() {
            let d = (DVec3::from_array(*p) - mid).length_squared();
            far[v] = far[v].max(d);
            near[v] = near[v].min(d);
            for k in 0..3 {
                lo[v][k] = lo[v][k].min(p[k]);
                hi[v][k] = hi[v][k].max(p[k]);
            }
        }
    }
    let cmp3 = |a: &[f64; 3], b: &[f64; 3]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| x.total_cmp(y))
            .find(|o| o.is_ne())
            .unwrap_or(Ordering::Equal)
    };
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by(|&a, &b| {
        let (a, b) = (a as usize, b as usize);
        far[a]
            .total_cmp(&far[b])
            .then_with(|| near[a].total_cmp(&near[b]))
            .then_with(|| cmp3(&lo[a], &lo[b]))
            .then_with(|| cmp3(&hi[a], &hi[b]))
    });
    let k = DESCRIPTOR_VERTICES.min(n);
    (0..k).map(|i| order[i * n / k]).collect()
}

/// [`descriptor`] on the vertices `picked` (of [`descriptor_vertices`]):
/// the distances between every pair of them in `frame`.
pub(crate) fn descriptor_at(frame: &[[f64; 3]], picked: &[u32]) -> Vec<f64> {
    let p: Vec<glam::DVec3> = picked
        .iter()
        .filter_map(|&v| frame.get(v as usize))
        .map(|q| glam::DVec3::from_array(*q))
        .collect();
    let mut d = Vec::with_capacity(p.len() * p.len().saturating_sub(1) / 2);
    for (i, a) in p.iter().enumerate() {
        for b in &p[i + 1..] {
            d.push(a.distance(*b));
        }
    }
    d
}

/// Squared distance of two descriptors.
pub(crate) fn distance2(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// Orders descriptors lexicographically (the tie-break by pose).
fn by_pose(a: &[f64], b: &[f64]) -> Ordering {
    a.iter()
        .zip(b)
        .map(|(x, y)| x.total_cmp(y))
        .find(|o| o.is_ne())
        .unwrap_or(Ordering::Equal)
}

/// Up to `k` indices of `descs`, farthest-point first: each the descriptor
/// farthest from `seed` and those already taken (ties: the greater
/// descriptor). The same poses give the same sequence of poses whatever
/// their order in `descs`.
pub(crate) fn farthest_first(descs: &[Vec<f64>], seed: &[f64], k: usize) -> Vec<usize> {
    let mut near: Vec<f64> = descs.iter().map(|d| distance2(d, seed)).collect();
    let mut taken = vec![false; descs.len()];
    let mut out = Vec::with_capacity(k.min(descs.len()));
    while out.len() < k.min(descs.len()) {
        let pick = (0..descs.len()).filter(|&i| !taken[i]).max_by(|&a, &b| {
            near[a]
                .total_cmp(&near[b])
                .then_with(|| by_pose(&descs[a], &descs[b]))
        });
        let Some(p) = pick else { break };
        taken[p] = true;
        out.push(p);
        for (i, d) in descs.iter().enumerate() {
            if !taken[i] {
                near[i] = near[i].min(distance2(d, &descs[p]));
            }
        }
    }
    out
}

/// How far a frame is from a standing, limbs-in pose: the ratio of its
/// vertices' spread across their long axis to the spread along it,
/// (λ₂ + λ₃) / λ₁ of their covariance (λ₁ the largest eigenvalue). Small
/// for a body standing with its arms and legs in; larger with the arms
/// out, a leg lifted, bent over or crouched. Unchanged by place, turn,
/// mirror and scale. On samba the capture's first 12 frames (standing
/// still before the dance) are the 12 smallest (0.157; the dance's
/// frames up to 0.3). `f64::INFINITY` for fewer than two vertices.
pub fn spread(frame: &[[f64; 3]]) -> f64 {
    use glam::DVec3;
    let n = frame.len();
    if n < 2 {
        return f64::INFINITY;
    }
    let c = frame.iter().map(|p| DVec3::from_array(*p)).sum::<DVec3>() / n as f64;
    let mut a = [[0.0f64; 3]; 3];
    for p in frame {
        let d = DVec3::from_array(*p) - c;
        let d = d.to_array();
        for (i, row) in a.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x += d[i] * d[j];
            }
        }
    }
    let trace = a[0][0] + a[1][1] + a[2][2];
    let top = largest_eigenvalue(a);
    if !(top > 0.0 && top.is_finite()) {
        return f64::INFINITY;
    }
    (trace - top) / top
}

/// The largest eigenvalue of a symmetric 3 × 3 matrix (the closed form
/// of Smith 1961, "Eigenvalues of a symmetric 3 × 3 matrix", CACM 4(4)).
fn largest_eigenvalue(a: [[f64; 3]; 3]) -> f64 {
    let p1 = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
    let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * p1;
    if p2 <= 0.0 {
        return q;
    }
    let p = (p2 / 6.0).sqrt();
    let b = |i: usize, j: usize| (a[i][j] - if i == j { q } else { 0.0 }) / p;
    let det = b(0, 0) * (b(1, 1) * b(2, 2) - b(1, 2) * b(2, 1))
        - b(0, 1) * (b(1, 0) * b(2, 2) - b(1, 2) * b(2, 0))
        + b(0, 2) * (b(1, 0) * b(2, 1) - b(1, 1) * b(2, 0));
    let phi = (det / 2.0).clamp(-1.0, 1.0).acos() / 3.0;
    q + 2.0 * p * phi.cos()
}

/// The indices `among` ordered by [`spread`] of their frames (the most
/// standing, limbs-in pose first; ties: the lesser descriptor).
pub(crate) fn standing_first(
    frames: &[&[[f64; 3]]],
    descs: &[Vec<f64>],
    among: &[usize],
) -> Vec<usize> {
    let mut order: Vec<(f64, usize)> = among.iter().map(|&i| (spread(frames[i]), i)).collect();
    order.sort_by(|a, b| {
        a.0.total_cmp(&b.0)
            .then_with(|| by_pose(&descs[a.1], &descs[b.1]))
    });
    order.into_iter().map(|(_, i)| i).collect()
}

/// The number of nearest frames [`hold_radius`] asks of a capture of
/// `frames` frames: about 3 % of them (5 of 175, a sixth of a second at
/// 30 fps), at least 2 and at most 16, and fewer than the frames.
pub(crate) fn hold_neighbours(frames: usize) -> usize {
    (frames / 32).clamp(2, 16).min(frames.saturating_sub(1))
}

/// How long the capture holds each frame's pose: the distance from its
/// descriptor to its `k`-th nearest among the other frames' (small for a
/// pose held still over many frames, a capture's calibration stance;
/// large for a pose passed through). 0 with `k` = 0; the farthest when
/// fewer than `k` others. Depends on the set of poses alone, not their
/// order. Cost O(F² K²) for F frames (samba's 175: 0.1 s).
pub(crate) fn hold_radius(descs: &[Vec<f64>], k: usize) -> Vec<f64> {
    use rayon::prelude::*;
    descs
        .par_iter()
        .enumerate()
        .map(|(i, a)| {
            let mut d: Vec<f64> = descs
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, b)| distance2(a, b))
                .collect();
            if k == 0 || d.is_empty() {
                return 0.0;
            }
            let at = (k - 1).min(d.len() - 1);
            d.select_nth_unstable_by(at, f64::total_cmp).1.sqrt()
        })
        .collect()
}

/// The indices `among` ordered by how long the capture holds their pose
/// ([`hold_radius`] with [`hold_neighbours`], the longest held first),
/// those no less standing than the median of `among` ([`spread`]) before
/// the others (a crouch held longer than the stance does not come
/// first); ties: the lesser descriptor. On samba the still start (frames
/// 4-10; its held end has the hands on the hips, a contact), on crane
/// the A-pose start (frames 2-9), where [`standing_first`] chose a step
/// of crane's walk (frame 86, a knee bent).
pub(crate) fn held_first(
    frames: &[&[[f64; 3]]],
    descs: &[Vec<f64>],
    among: &[usize],
) -> Vec<usize> {
    let radius = hold_radius(descs, hold_neighbours(descs.len()));
    let spreads: Vec<f64> = among.iter().map(|&i| spread(frames[i])).collect();
    let mut sorted = spreads.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len().saturating_sub(1) / 2).copied();
    let mut order: Vec<(bool, f64, usize)> = among
        .iter()
        .zip(&spreads)
        .map(|(&i, &s)| (median.is_some_and(|m| s > m), radius[i], i))
        .collect();
    order.sort_by(|a, b| {
        a.0.cmp(&b.0)
            .then_with(|| a.1.total_cmp(&b.1))
            .then_with(|| by_pose(&descs[a.2], &descs[b.2]))
    });
    order.into_iter().map(|(_, _, i)| i).collect()
}

/// The indices `among` ordered by their descriptor's distance from
/// `pose` (nearest first; ties: the lesser descriptor).
pub fn nearest(descs: &[Vec<f64>], pose: &[f64], among: &[usize]) -> Vec<usize> {
    let mut order: Vec<(f64, usize)> = among
        .iter()
        .map(|&i| (distance2(&descs[i], pose), i))
        .collect();
    order.sort_by(|a, b| {
        a.0.total_cmp(&b.0)
            .then_with(|| by_pose(&descs[a.1], &descs[b.1]))
    });
    order.into_iter().map(|(_, i)| i).collect()
}

/// The per-coordinate median of `descs` (the lower middle of an even
/// count; empty without descriptors). The same in any order of `descs`.
pub fn median(descs: &[Vec<f64>]) -> Vec<f64> {
    let Some(len) = descs.iter().map(Vec::len).min() else {
        return Vec::new();
    };
    let mid = (descs.len() - 1) / 2;
    let mut column = vec![0.0; descs.len()];
    (0..len)
        .map(|c| {
            for (x, d) in column.iter_mut().zip(descs) {
                *x = d[c];
            }
            *column.select_nth_unstable_by(mid, f64::total_cmp).1
        })
        .collect()
}

/// Up to `k` (at least 2 when there are) indices of `descs` at evenly
/// spaced ranks of their distance from `seed` ([`nearest`]: the nearest
/// first, the farthest last, ties by pose). The same poses in any order
/// give the same poses in the same order.
pub fn quantiles(descs: &[Vec<f64>], seed: &[f64], k: usize) -> Vec<usize> {
    let all: Vec<usize> = (0..descs.len()).collect();
    let ranked = nearest(descs, seed, &all);
    let n = ranked.len();
    let k = k.max(2).min(n);
    if k <= 1 {
        return ranked;
    }
    (0..k).map(|i| ranked[i * (n - 1) / (k - 1)]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eight "poses": a segment of 200 vertices bent by an angle.
    fn poses() -> Vec<Vec<[f64; 3]>> {
        (0..8)
            .map(|p| {
                let bend = 0.2 * p as f64;
                (0..200)
                    .map(|i| {
                        let t = i as f64 / 100.0;
                        if t <= 1.0 {
                            [t, 0.0, 0.0]
                        } else {
                            let s = t - 1.0;
                            [1.0 + s * bend.cos(), s * bend.sin(), 0.0]
                        }
                    })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn the_sample_is_the_same_poses_in_any_order() {
        let p = poses();
        let seed = descriptor(&p[0]);
        let descs: Vec<Vec<f64>> = p.iter().map(|f| descriptor(f)).collect();
        let a = farthest_first(&descs, &seed, 4);
        // Farthest from the straight pose first: the most bent.
        assert_eq!(a[0], 7);
        for perm in [[7, 6, 5, 4, 3, 2, 1, 0], [3, 0, 6, 1, 7, 2, 5, 4]] {
            let shuffled: Vec<Vec<f64>> = perm.iter().map(|&i| descs[i].clone()).collect();
            let b: Vec<usize> = farthest_first(&shuffled, &seed, 4)
                .into_iter()
                .map(|i| perm[i])
                .collect();
            assert_eq!(a, b);
            let all: Vec<usize> = (0..8).collect();
            let frames: Vec<&[[f64; 3]]> = perm.iter().map(|&i| p[i].as_slice()).collect();
            let m: Vec<usize> = standing_first(&frames, &shuffled, &all)
                .into_iter()
                .map(|i| perm[i])
                .collect();
            let own: Vec<&[[f64; 3]]> = p.iter().map(Vec::as_slice).collect();
            assert_eq!(m, standing_first(&own, &descs, &all));
            // The straight segment is the most stretched out.
            assert_eq!(m[0], 0);
        }
    }

    #[test]
    fn quantiles_and_the_median_are_the_same_poses_in_any_order() {
        let p = poses();
        let seed = descriptor(&p[2]);
        let descs: Vec<Vec<f64>> = p.iter().map(|f| descriptor(f)).collect();
        let q = quantiles(&descs, &seed, 4);
        // The seed's own pose first, the farthest (the most bent) last.
        assert_eq!(q.first(), Some(&2));
        assert_eq!(q.last(), Some(&7));
        assert_eq!(q.len(), 4);
        let med = median(&descs);
        let all: Vec<usize> = (0..8).collect();
        let m = nearest(&descs, &med, &all);
        for perm in [[7, 6, 5, 4, 3, 2, 1, 0], [3, 0, 6, 1, 7, 2, 5, 4]] {
            let shuffled: Vec<Vec<f64>> = perm.iter().map(|&i| descs[i].clone()).collect();
            let back = |v: Vec<usize>| -> Vec<usize> { v.into_iter().map(|i| perm[i]).collect() };
            assert_eq!(back(quantiles(&shuffled, &seed, 4)), q);
            assert_eq!(median(&shuffled), med);
            assert_eq!(back(nearest(&shuffled, &med, &all)), m);
        }
        // Each distance shrinks as the bend grows: the lower middle of the
        // eight is bend 4's, in every coordinate.
        assert_eq!(m[0], 4);
        assert!(median(&[]).is_empty());
        assert_eq!(quantiles(&descs[..1], &seed, 5).len(), 1);
    }

    #[test]
    fn the_pose_held_longest_of_the_standing_half_comes_first_in_any_order() {
        let p = poses();
        // Pose 2 held for 5 frames, pose 6 (more bent) for 7, the others
        // passed through once.
        let mut take = vec![0, 1, 3, 4, 5, 7];
        take.extend([2; 5]);
        take.extend([6; 7]);
        for perm in [0usize, 5, 11] {
            let mut order = take.clone();
            order.rotate_left(perm);
            order.reverse();
            let frames: Vec<&[[f64; 3]]> = order.iter().map(|&k| p[k].as_slice()).collect();
            let descs: Vec<Vec<f64>> = frames.iter().map(|f| descriptor(f)).collect();
            let all: Vec<usize> = (0..frames.len()).collect();
            let first = held_first(&frames, &descs, &all);
            // The bent pose is held longer, but it is of the less standing
            // half: the straighter held pose comes first.
            assert_eq!(order[first[0]], 2, "{order:?}");
            // Among the passed-through poses, none before a held one of
            // its half.
            assert!(first[..5].iter().all(|&i| order[i] == 2));
        }
        assert_eq!(hold_neighbours(175), 5);
        assert_eq!(hold_neighbours(2), 1);
        assert_eq!(hold_neighbours(10_000), 16);
        let descs: Vec<Vec<f64>> = p.iter().map(|f| descriptor(f)).collect();
        assert!(hold_radius(&descs, 0).iter().all(|&r| r == 0.0));
        assert_eq!(hold_radius(&descs[..1], 3), vec![0.0]);
    }

    #[test]
    fn the_spread_is_that_of_the_covariance() {
        // Points on the axes: variances 4, 1, 0.25 (×2/6 each).
        let mut f = Vec::new();
        for (k, s) in [2.0, 1.0, 0.5].into_iter().enumerate() {
            let mut p = [0.0; 3];
            p[k] = s;
            f.push(p);
            p[k] = -s;
            f.push(p);
        }
        assert!((spread(&f) - 1.25 / 4.0).abs() < 1e-12, "{}", spread(&f));
        // Turned 30° about z: the same.
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let turned: Vec<[f64; 3]> = f
            .iter()
            .map(|q| [c * q[0] - s * q[1], s * q[0] + c * q[1], q[2]])
            .collect();
        assert!((spread(&turned) - 1.25 / 4.0).abs() < 1e-12);
        assert_eq!(spread(&f[..1]), f64::INFINITY);
    }

    #[test]
    fn the_descriptor_ignores_place_turn_and_mirror() {
        let p = &poses()[3];
        let moved: Vec<[f64; 3]> = p.iter().map(|q| [-q[1] + 5.0, q[0], -q[2] + 1.0]).collect();
        let mirrored: Vec<[f64; 3]> = p.iter().map(|q| [-q[0], q[1], q[2]]).collect();
        let d = descriptor(p);
        assert!(distance2(&d, &descriptor(&moved)) < 1e-20);
        assert!(distance2(&d, &descriptor(&mirrored)) < 1e-20);
        assert!(descriptor(&[]).is_empty());
    }
}
