//! An exact k-nearest-neighbour index over low-dimensional points (a
//! k-d tree, split at the median of the widest dimension), for the sparse
//! similarity's candidate pairs ([`super::sparse`]).
//!
//! Built in `O(n log n)`; a query visits `O(log n)` leaves when the points
//! lie near a low-dimensional manifold (the frames of human motion do),
//! and never returns a wrong answer: a subtree is skipped only when its
//! splitting plane is farther than the current k-th neighbour.

/// Points per leaf.
const LEAF: usize = 8;

/// A k-d tree over `n` points of `dims` f32 coordinates.
#[derive(Debug, Clone)]
pub struct KdTree {
    dims: usize,
    points: Vec<f32>,
    /// Point ids in tree order: node `lo..hi` has its splitting point at
    /// `(lo + hi) / 2`.
    order: Vec<u32>,
    /// Splitting dimension of the node whose splitting point sits at each
    /// position of `order`.
    split: Vec<u8>,
}

impl KdTree {
    /// Indexes `points` (`n × dims`, row-major). `dims` must be below 256.
    pub fn new(points: Vec<f32>, dims: usize) -> KdTree {
        let dims = dims.clamp(1, 255);
        let n = points.len() / dims;
        let mut tree = KdTree {
            dims,
            points,
            order: (0..n as u32).collect(),
            split: vec![0; n],
        };
        tree.build(0, n);
        tree
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.order.len()
    }

    /// True when there is no point.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    fn point(&self, i: u32) -> &[f32] {
        &self.points[i as usize * self.dims..(i as usize + 1) * self.dims]
    }

    fn build(&mut self, lo: usize, hi: usize) {
        if hi - lo <= LEAF {
            return;
        }
        let dims = self.dims;
        let mut best = (0, f32::NEG_INFINITY);
        for d in 0..dims {
            let (mut a, mut b) = (f32::INFINITY, f32::NEG_INFINITY);
            for &i in &self.order[lo..hi] {
                let v = self.points[i as usize * dims + d];
                a = a.min(v);
                b = b.max(v);
            }
            if b - a > best.1 {
                best = (d, b - a);
            }
        }
        let d = best.0;
        let mid = (lo + hi) / 2;
        let pts = &self.points;
        self.order[lo..hi].select_nth_unstable_by(mid - lo, |&x, &y| {
            pts[x as usize * dims + d].total_cmp(&pts[y as usize * dims + d])
        });
        self.split[mid] = d as u8;
        self.build(lo, mid);
        self.build(mid + 1, hi);
    }

    /// The `k` points nearest to `q` among those `keep` accepts, as
    /// `(squared distance, id)` nearest first (ties by id).
    pub fn nearest(&self, q: &[f32], k: usize, keep: &dyn Fn(u32) -> bool) -> Vec<(f32, u32)> {
        let mut best: Vec<(f32, u32)> = Vec::with_capacity(k + 1);
        if k > 0 {
            self.search(0, self.order.len(), q, k, keep, &mut best);
        }
        best
    }

    fn offer(
        &self,
        i: u32,
        q: &[f32],
        k: usize,
        keep: &dyn Fn(u32) -> bool,
        best: &mut Vec<(f32, u32)>,
    ) {
        if !keep(i) {
            return;
        }
        let d: f32 = self
            .point(i)
            .iter()
            .zip(q)
            .map(|(a, b)| (a - b) * (a - b))
            .sum();
        if best.len() == k && (d, i) >= best[k - 1] {
            return;
        }
        let at = best.partition_point(|c| *c < (d, i));
        best.insert(at, (d, i));
        best.truncate(k);
    }

    fn search(
        &self,
        lo: usize,
        hi: usize,
        q: &[f32],
        k: usize,
        keep: &dyn Fn(u32) -> bool,
        best: &mut Vec<(f32, u32)>,
    ) {
        if hi - lo <= LEAF {
            for &i in &self.order[lo..hi] {
                self.offer(i, q, k, keep, best);
            }
            return;
        }
        let mid = (lo + hi) / 2;
        let p = self.order[mid];
        let d = self.split[mid] as usize;
        let diff = q[d] - self.point(p)[d];
        let (near, far) = if diff < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.search(near.0, near.1, q, k, keep, best);
        self.offer(p, q, k, keep, best);
        if best.len() < k || diff * diff <= best[k - 1].0 {
            self.search(far.0, far.1, q, k, keep, best);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_same_neighbours_as_a_scan() {
        let dims = 5;
        let n = 700;
        let mut s = 12345u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 33) as f32 / (1u64 << 31) as f32) - 0.5
        };
        let pts: Vec<f32> = (0..n * dims).map(|_| rnd()).collect();
        let tree = KdTree::new(pts.clone(), dims);
        assert_eq!(tree.len(), n);
        for q in (0..n).step_by(37) {
            let qp = &pts[q * dims..(q + 1) * dims];
            let keep = |i: u32| i as usize != q && i % 3 != 0;
            let got = tree.nearest(qp, 10, &keep);
            let mut all: Vec<(f32, u32)> = (0..n as u32)
                .filter(|&i| keep(i))
                .map(|i| {
                    let p = &pts[i as usize * dims..(i as usize + 1) * dims];
                    (p.iter().zip(qp).map(|(a, b)| (a - b) * (a - b)).sum(), i)
                })
                .collect();
            all.sort_by(|a, b| a.partial_cmp(b).unwrap());
            all.truncate(10);
            assert_eq!(got, all);
        }
    }
}
