//! Geometry of the automatic landmarks: the mesh's edge graph and its
//! geodesic distances, nearest-vertex queries, the symmetry fit, principal
//! axes, and a limb's geodesic rings and centre line.

use glam::DVec3;
use std::cmp::Ordering;
use std::collections::{BinaryHeap, HashMap};

/// The mesh's edge graph (CSR) and per-vertex areas.
pub(super) struct Graph {
    start: Vec<usize>,
    pub(super) to: Vec<(u32, f64)>,
    pub(super) area: Vec<f64>,
}

impl Graph {
    pub(super) fn new(p: &[DVec3], t: &[[u32; 3]]) -> Graph {
        let n = p.len();
        let mut adj: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut area = vec![0.0; n];
        for tri in t {
            let [a, b, c] = tri.map(|v| v as usize);
            let ar = (p[b] - p[a]).cross(p[c] - p[a]).length() / 6.0;
            for (x, y) in [(a, b), (b, c), (c, a)] {
                adj[x].push(y as u32);
                adj[y].push(x as u32);
            }
            area[a] += ar;
            area[b] += ar;
            area[c] += ar;
        }
        let mut start = Vec::with_capacity(n + 1);
        let mut to = Vec::new();
        for (v, a) in adj.iter_mut().enumerate() {
            a.sort_unstable();
            a.dedup();
            start.push(to.len());
            to.extend(a.iter().map(|&w| (w, p[v].distance(p[w as usize]))));
        }
        start.push(to.len());
        Graph { start, to, area }
    }

    pub(super) fn nb(&self, v: usize) -> &[(u32, f64)] {
        &self.to[self.start[v]..self.start[v + 1]]
    }

    /// Geodesic (edge-path) distances from `sources`, up to `limit`
    /// (farther: infinity).
    pub(super) fn dijkstra(&self, sources: &[usize], limit: f64) -> Vec<f64> {
        #[derive(PartialEq)]
        struct S(f64, usize);
        impl Eq for S {}
        impl PartialOrd for S {
            fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
                Some(self.cmp(o))
            }
        }
        impl Ord for S {
            fn cmp(&self, o: &Self) -> Ordering {
                o.0.total_cmp(&self.0)
            }
        }
        let mut d = vec![f64::INFINITY; self.area.len()];
        let mut h = BinaryHeap::new();
        for &s in sources {
            d[s] = 0.0;
            h.push(S(0.0, s));
        }
        while let Some(S(dv, v)) = h.pop() {
            if dv > d[v] {
                continue;
            }
            for &(w, l) in self.nb(v) {
                let nd = dv + l;
                if nd < d[w as usize] && nd <= limit {
                    d[w as usize] = nd;
                    h.push(S(nd, w as usize));
                }
            }
        }
        d
    }
}

/// Nearest-vertex queries on a uniform grid.
pub(super) struct Grid {
    pub(super) cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl Grid {
    pub(super) fn new(p: &[DVec3], cell: f64) -> Grid {
        let mut cells: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (i, q) in p.iter().enumerate() {
            cells.entry(Self::key(*q, cell)).or_default().push(i as u32);
        }
        Grid { cell, cells }
    }

    fn key(q: DVec3, cell: f64) -> [i64; 3] {
        (q / cell).floor().as_i64vec3().to_array()
    }

    /// The distance to the nearest vertex (searching at most `rings`
    /// cells out; beyond: `rings · cell`).
    pub(super) fn nearest(&self, p: &[DVec3], q: DVec3, rings: i64) -> (f64, Option<u32>) {
        let k = Self::key(q, self.cell);
        let mut best = (f64::INFINITY, None);
        for r in 0..=rings {
            for x in -r..=r {
                for y in -r..=r {
                    for z in -r..=r {
                        if x.abs().max(y.abs()).max(z.abs()) != r {
                            continue;
                        }
                        if let Some(v) = self.cells.get(&[k[0] + x, k[1] + y, k[2] + z]) {
                            for &i in v {
                                let d = p[i as usize].distance(q);
                                if d < best.0 {
                                    best = (d, Some(i));
                                }
                            }
                        }
                    }
                }
            }
            if best.0 <= r as f64 * self.cell {
                break;
            }
        }
        if best.1.is_none() {
            best.0 = rings as f64 * self.cell;
        }
        best
    }
}

pub(super) fn clamp01(x: f64) -> f64 {
    if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) }
}

/// The symmetry plane `(normal, offset)` refined from `n0` by
/// reflect-and-fit; returns it with the median residual (mesh units).
pub(super) fn fit_symmetry(
    p: &[DVec3],
    sample: &[usize],
    grid: &Grid,
    n0: DVec3,
    d0: f64,
    h: f64,
) -> (DVec3, f64, f64) {
    let (mut n, mut d) = (n0, d0);
    let rings = ((0.08 * h) / grid.cell).ceil() as i64;
    let mut residual = f64::INFINITY;
    for it in 0..8 {
        let mut pairs: Vec<(f64, usize, u32)> = sample
            .iter()
            .filter_map(|&i| {
                let q = p[i] - n * (2.0 * (p[i].dot(n) - d));
                let (dist, j) = grid.nearest(p, q, rings);
                j.map(|j| (dist, i, j))
            })
            .collect();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        residual = pairs.get(pairs.len() / 2).map_or(f64::INFINITY, |x| x.0);
        if it == 7 {
            break;
        }
        // The best 70 %: a prop or an asymmetric limb does not tilt it.
        let keep = &pairs[..(pairs.len() * 7 / 10).max(1)];
        let mut dir = DVec3::ZERO;
        for &(_, i, j) in keep {
            let v = p[i] - p[j as usize];
            dir += if v.dot(n) < 0.0 { -v } else { v };
        }
        if let Some(nn) = dir.try_normalize() {
            n = nn;
        }
        d = keep
            .iter()
            .map(|&(_, i, j)| (p[i] + p[j as usize]).dot(n) * 0.5)
            .sum::<f64>()
            / keep.len() as f64;
    }
    (n, d, residual)
}

/// The symmetric 3×3 eigenvectors (columns), largest eigenvalue first.
pub(super) fn principal_axes(c: [[f64; 3]; 3]) -> [DVec3; 3] {
    let m = nalgebra::Matrix3::from_fn(|i, j| c[i][j]);
    let e = nalgebra::SymmetricEigen::new(m);
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| e.eigenvalues[b].total_cmp(&e.eigenvalues[a]));
    idx.map(|k| {
        let v = e.eigenvectors.column(k);
        DVec3::new(v[0], v[1], v[2]).normalize_or(DVec3::Y)
    })
}

/// A limb's geodesic rings from its tip: `(distance, centroid, radius,
/// perimeter)` (the perimeter: the ring's area over its width).
pub(super) fn rings(
    g: &Graph,
    p: &[DVec3],
    dist: &[f64],
    step: f64,
    max: f64,
) -> Vec<(f64, DVec3, f64, f64)> {
    let n = (max / step).ceil() as usize;
    let mut acc = vec![(DVec3::ZERO, 0.0); n];
    for (v, &d) in dist.iter().enumerate() {
        if d < max {
            let k = (d / step) as usize;
            if k < n {
                acc[k].0 += p[v] * g.area[v];
                acc[k].1 += g.area[v];
            }
        }
    }
    let centres: Vec<Option<DVec3>> = acc
        .iter()
        .map(|(s, w)| (*w > 0.0).then(|| *s / *w))
        .collect();
    let mut rad = vec![(0.0, 0.0); n];
    for (v, &d) in dist.iter().enumerate() {
        if d < max {
            let k = (d / step) as usize;
            if let Some(Some(c)) = centres.get(k) {
                rad[k].0 += p[v].distance(*c) * g.area[v];
                rad[k].1 += g.area[v];
            }
        }
    }
    let raw: Vec<(f64, DVec3, f64, f64)> = (0..n)
        .filter_map(|k| {
            centres[k].map(|c| {
                (
                    (k as f64 + 0.5) * step,
                    c,
                    rad[k].0 / rad[k].1.max(1e-300),
                    acc[k].1 / step,
                )
            })
        })
        .collect();
    // Averaged over five rings: on a coarse mesh a ring's vertices lie on
    // one side of the limb or the other.
    (0..raw.len())
        .map(|i| {
            let w = &raw[i.saturating_sub(2)..(i + 3).min(raw.len())];
            let m = w.len() as f64;
            (
                raw[i].0,
                w.iter().map(|x| x.1).sum::<DVec3>() / m,
                w.iter().map(|x| x.2).sum::<f64>() / m,
                w.iter().map(|x| x.3).sum::<f64>() / m,
            )
        })
        .collect()
}

/// The point at arc length `s` along the polyline `pts` (clamped).
pub(super) fn along(pts: &[DVec3], s: f64) -> DVec3 {
    let mut left = s.max(0.0);
    for w in pts.windows(2) {
        let l = w[0].distance(w[1]);
        if left <= l && l > 0.0 {
            return w[0].lerp(w[1], left / l);
        }
        left -= l;
    }
    pts.last().copied().unwrap_or(DVec3::ZERO)
}

/// Where the polyline `pts` turns most between arc lengths `from` and
/// `to`: the point and the angle (degrees) between its chords of length
/// `chord` before and after.
pub(super) fn bend(pts: &[DVec3], from: f64, to: f64, chord: f64) -> Option<(DVec3, f64)> {
    let mut best: Option<(DVec3, f64)> = None;
    let mut s = from;
    while s <= to {
        let (a, b, c) = (along(pts, s - chord), along(pts, s), along(pts, s + chord));
        let (u, v) = ((b - a).normalize_or_zero(), (c - b).normalize_or_zero());
        if u != DVec3::ZERO && v != DVec3::ZERO {
            let deg = u.dot(v).clamp(-1.0, 1.0).acos().to_degrees();
            if best.is_none_or(|x| deg > x.1) {
                best = Some((b, deg));
            }
        }
        s += 0.25 * chord;
    }
    best
}

pub(super) fn arc_length(pts: &[DVec3]) -> f64 {
    pts.windows(2).map(|w| w[0].distance(w[1])).sum()
}
