//! Automatic landmarks on a static scan, from its geometry alone (issue 41):
//! the chin, groin, wrists, elbows and knees (and the head top) that
//! [`super::landmarks`] otherwise asks a person to mark.
//!
//! The method, in order:
//!
//! 1. **Frame.** The principal axes of the surface (area-weighted); the
//!    body's symmetry plane is the principal plane whose reflection fits the
//!    surface best, refined by reflect-and-fit (each reflected vertex paired
//!    with its nearest vertex, the plane refitted to the pairs' midpoints, as
//!    in the symmetry detection of Mitra et al. 2006 reduced to one plane).
//!    Up is the longest principal direction in that plane (snapped to an
//!    axis of the file within 20°); its sign puts the floor at the end with
//!    the larger flat area (the soles). Facing is the other in-plane
//!    direction, signed by the feet: the toes reach forward of the shins.
//! 2. **Extremities.** Geodesic distance (Dijkstra on the edge graph) from
//!    the body's centre; the extremities are its local maxima over a
//!    geodesic ball of 12 % of the height, as skeletal extremities are found
//!    by geodesics in Pinocchio (Baran & Popović 2007) and in Reeb-graph
//!    skeletons (Hilaga et al. 2001). The lowest on each side of the plane
//!    are the feet, the farthest to each side above the knees the hands,
//!    the highest near the plane the head top.
//! 3. **Limb sections.** Geodesic rings around each hand and foot (the set
//!    of vertices at one geodesic distance from the tip is a ring across the
//!    limb): their centroids are the limb's centre line, their radii its
//!    thickness. The wrist is the narrowest ring at the hand's base; the
//!    elbow lies one forearm (14.5 % of the height, Drillis & Contini 1966)
//!    along the centre line from the wrist; the knee 57 % of the way along
//!    the leg's centre line from the ankle to the crotch (knee height
//!    0.285 H, ankle 0.039 H, crotch 0.47 H in the same tables).
//! 4. **Torso.** The groin is where the legs split: the lowest horizontal
//!    section whose loop encloses the mid-plane point between the legs. The
//!    chin is at the front of the section a quarter of the way from the
//!    neck's narrowest section (below the head) to the head top.
//!
//! Every landmark carries a confidence in 0..1 from how well its twin on
//! the other side mirrors it (wrists, elbows, knees), how clearly its
//! feature was found (a narrowing, a split), and the whole from the
//! symmetry fit and the extremities found. Below
//! [`ScanOptions::min_confidence`] the landmarks are refused with the
//! reason (a prop on a hand, a missing limb, a shape that is not a
//! standing human), never guessed.

use super::landmarks::{Landmark, Landmarks, Mark};
use super::section::{cross_section, encloses, part_loop};
use glam::DVec3;
use serde::Serialize;
use std::cmp::Ordering;
use std::collections::{BTreeMap, BinaryHeap, HashMap};

/// Options of [`find`].
#[derive(Debug, Clone, Copy)]
pub struct ScanOptions {
    /// Below this overall confidence (0..1) the landmarks are refused.
    /// Default 0.5.
    pub min_confidence: f64,
}

impl Default for ScanOptions {
    fn default() -> Self {
        ScanOptions {
            min_confidence: 0.5,
        }
    }
}

/// One automatic landmark.
#[derive(Debug, Clone, Serialize)]
pub struct AutoMark {
    /// Where it is (mesh units).
    pub point: [f64; 3],
    /// Confidence 0..1.
    pub confidence: f64,
    /// How it was found, and what lowered its confidence.
    pub how: String,
}

/// Landmarks found on a scan.
#[derive(Debug, Clone, Serialize)]
pub struct AutoLandmarks {
    /// Each landmark by its file name (`chin`, `l_wrist`, ...).
    pub marks: BTreeMap<&'static str, AutoMark>,
    /// The whole set's confidence 0..1: the least of the landmarks' and
    /// of the frame's (symmetry fit, extremities).
    pub confidence: f64,
    /// Unit up (floor to head).
    pub up: [f64; 3],
    /// Unit facing direction.
    pub facing: [f64; 3],
    /// The character's left (the symmetry plane's normal).
    pub left: [f64; 3],
    /// Height along `up` (mesh units).
    pub height: f64,
    /// The reflect-and-fit residual: median distance of a reflected vertex
    /// from the surface's nearest vertex, % of the height.
    pub symmetry_percent: f64,
    /// The extremities found (geodesic local maxima), as points.
    pub extremities: Vec<[f64; 3]>,
    /// What lowered the confidence, in words.
    pub doubts: Vec<String>,
}

impl AutoLandmarks {
    /// The landmarks as [`Landmarks`] (points).
    pub fn landmarks(&self) -> Landmarks {
        Landmarks {
            marks: self
                .marks
                .iter()
                .filter_map(|(k, m)| Landmark::from_name(k).map(|l| (l, Mark::Point(m.point))))
                .collect(),
        }
    }

    /// A landmark file (JSON) a user can edit and give back with
    /// `--landmarks`.
    pub fn to_json(&self) -> String {
        let mut m = serde_json::Map::new();
        for (k, v) in &self.marks {
            let r = |x: f64| (x * 1e5).round() / 1e5;
            m.insert(
                (*k).to_string(),
                serde_json::json!([r(v.point[0]), r(v.point[1]), r(v.point[2])]),
            );
        }
        serde_json::to_string_pretty(&serde_json::Value::Object(m)).unwrap_or_default() + "\n"
    }
}

/// Why no landmarks were found.
#[derive(Debug, thiserror::Error)]
pub enum ScanLandmarkError {
    /// The mesh cannot be measured (too small, flat, not finite).
    #[error("automatic landmarks: {0}")]
    Mesh(String),
    /// The shape does not read as a human body clearly enough.
    #[error(
        "automatic landmarks refused (confidence {confidence:.2} < {threshold:.2}): {reason}; give --landmarks"
    )]
    Refused {
        /// The confidence reached.
        confidence: f64,
        /// The threshold.
        threshold: f64,
        /// Why, in words.
        reason: String,
        /// What was found, for reports.
        found: Box<Option<AutoLandmarks>>,
    },
}

/// A landmark of a given file that disagrees with the automatic one.
#[derive(Debug, Clone, Serialize)]
pub struct Disagreement {
    /// The landmark.
    pub landmark: &'static str,
    /// Distance from the automatic one, % of the height.
    pub percent: f64,
    /// What it looks like (e.g. left and right swapped).
    pub reason: String,
}

/// Compares given landmarks with automatic ones: each given landmark
/// farther than `limit_percent` of the height from the automatic one is
/// listed, and a left landmark that lies at the automatic right one (and
/// the other way round) is called a left/right swap.
pub fn compare(
    auto: &AutoLandmarks,
    given: &Landmarks,
    positions: &[[f64; 3]],
    limit_percent: f64,
) -> Vec<Disagreement> {
    let h = auto.height.max(1e-12);
    let at = |name: &str| auto.marks.get(name).map(|m| DVec3::from_array(m.point));
    let mut out = Vec::new();
    for &l in given.marks.keys() {
        let (Some(p), Some(a)) = (given.point(l, positions), at(l.name())) else {
            continue;
        };
        let p = DVec3::from_array(p);
        let d = 100.0 * p.distance(a) / h;
        if d <= limit_percent {
            continue;
        }
        let twin = twin_name(l.name());
        let swapped = twin
            .and_then(at)
            .is_some_and(|t| 100.0 * p.distance(t) / h <= limit_percent);
        let reason = if swapped {
            format!(
                "it lies at the automatic {} ({d:.1}% of the height from the automatic {}): left and right swapped?",
                twin.unwrap_or(""),
                l.name()
            )
        } else {
            format!("{d:.1}% of the height from the automatic one (limit {limit_percent:.0}%)")
        };
        out.push(Disagreement {
            landmark: l.name(),
            percent: d,
            reason,
        });
    }
    out
}

fn twin_name(n: &str) -> Option<&'static str> {
    let t = if let Some(s) = n.strip_prefix("l_") {
        format!("r_{s}")
    } else if let Some(s) = n.strip_prefix("r_") {
        format!("l_{s}")
    } else {
        return None;
    };
    Landmark::from_name(&t).map(|l| l.name())
}

/// Finds the landmarks of the scan `(positions, triangles)`; refuses with
/// the reason below `o.min_confidence`.
pub fn find(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    o: &ScanOptions,
) -> Result<AutoLandmarks, ScanLandmarkError> {
    let (found, fatal) = estimate(positions, triangles)?;
    if let Some(reason) = fatal {
        return Err(ScanLandmarkError::Refused {
            confidence: found.as_ref().map_or(0.0, |f| f.confidence),
            threshold: o.min_confidence,
            reason,
            found: Box::new(found),
        });
    }
    let Some(f) = found else {
        return Err(ScanLandmarkError::Mesh("nothing found".into()));
    };
    if f.confidence < o.min_confidence {
        let reason = if f.doubts.is_empty() {
            "the shape does not read clearly as a standing human".to_string()
        } else {
            f.doubts.join("; ")
        };
        return Err(ScanLandmarkError::Refused {
            confidence: f.confidence,
            threshold: o.min_confidence,
            reason,
            found: Box::new(Some(f)),
        });
    }
    Ok(f)
}

// ---------------------------------------------------------------- geometry

/// The mesh's edge graph (CSR) and per-vertex areas.
struct Graph {
    start: Vec<usize>,
    to: Vec<(u32, f64)>,
    area: Vec<f64>,
}

impl Graph {
    fn new(p: &[DVec3], t: &[[u32; 3]]) -> Graph {
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

    fn nb(&self, v: usize) -> &[(u32, f64)] {
        &self.to[self.start[v]..self.start[v + 1]]
    }

    /// Geodesic (edge-path) distances from `sources`, up to `limit`
    /// (farther: infinity).
    fn dijkstra(&self, sources: &[usize], limit: f64) -> Vec<f64> {
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
struct Grid {
    cell: f64,
    cells: HashMap<[i64; 3], Vec<u32>>,
}

impl Grid {
    fn new(p: &[DVec3], cell: f64) -> Grid {
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
    fn nearest(&self, p: &[DVec3], q: DVec3, rings: i64) -> (f64, Option<u32>) {
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

fn clamp01(x: f64) -> f64 {
    if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) }
}

/// The symmetry plane `(normal, offset)` refined from `n0` by
/// reflect-and-fit; returns it with the median residual (mesh units).
fn fit_symmetry(
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
fn principal_axes(c: [[f64; 3]; 3]) -> [DVec3; 3] {
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
fn rings(g: &Graph, p: &[DVec3], dist: &[f64], step: f64, max: f64) -> Vec<(f64, DVec3, f64, f64)> {
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
fn along(pts: &[DVec3], s: f64) -> DVec3 {
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
fn bend(pts: &[DVec3], from: f64, to: f64, chord: f64) -> Option<(DVec3, f64)> {
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

fn arc_length(pts: &[DVec3]) -> f64 {
    pts.windows(2).map(|w| w[0].distance(w[1])).sum()
}

/// Estimates the landmarks; `Ok((found, Some(reason)))` when the shape is
/// refused whatever the threshold (a missing limb).
#[allow(clippy::type_complexity)]
pub fn estimate(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<(Option<AutoLandmarks>, Option<String>), ScanLandmarkError> {
    // Only the vertices of triangles (a group selected from a file keeps
    // the others, unreferenced).
    let mut index = vec![u32::MAX; positions.len()];
    let mut kept: Vec<[f64; 3]> = Vec::new();
    let mut tris: Vec<[u32; 3]> = Vec::with_capacity(triangles.len());
    for t in triangles {
        if let Some(v) = t.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(ScanLandmarkError::Mesh(format!(
                "triangle {t:?} names vertex {v}, out of range"
            )));
        }
        tris.push(t.map(|v| {
            let i = &mut index[v as usize];
            if *i == u32::MAX {
                *i = kept.len() as u32;
                kept.push(positions[v as usize]);
            }
            *i
        }));
    }
    let (positions, triangles) = (&kept[..], &tris[..]);
    let p: Vec<DVec3> = positions.iter().map(|q| DVec3::from_array(*q)).collect();
    if p.len() < 100 || triangles.len() < 100 {
        return Err(ScanLandmarkError::Mesh(format!(
            "{} vertices and {} triangles: too few to read a body from",
            p.len(),
            triangles.len()
        )));
    }
    if p.iter().any(|q| !q.is_finite()) {
        return Err(ScanLandmarkError::Mesh("a vertex is not finite".into()));
    }
    let g = Graph::new(&p, triangles);
    let total: f64 = g.area.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return Err(ScanLandmarkError::Mesh("the surface has no area".into()));
    }
    let centre = p.iter().zip(&g.area).map(|(q, a)| *q * *a).sum::<DVec3>() / total;
    let mut cov = [[0.0; 3]; 3];
    for (q, a) in p.iter().zip(&g.area) {
        let d = (*q - centre).to_array();
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += a * d[i] * d[j];
            }
        }
    }
    let axes = principal_axes(cov);
    let extent = |dir: DVec3| {
        let (lo, hi) = p
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
                (a.min(q.dot(dir)), b.max(q.dot(dir)))
            });
        hi - lo
    };
    let size = axes.iter().map(|a| extent(*a)).fold(0.0, f64::max);
    if size.is_nan() || size <= 0.0 {
        return Err(ScanLandmarkError::Mesh("the mesh has no extent".into()));
    }

    // 1. The symmetry plane: each principal plane, refined; the best fit.
    let grid = Grid::new(&p, size / 60.0);
    let stride = (p.len() / 3000).max(1);
    let sample: Vec<usize> = (0..p.len()).step_by(stride).collect();
    let (left0, off, sym) = axes
        .iter()
        .map(|a| fit_symmetry(&p, &sample, &grid, *a, centre.dot(*a), size))
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .unwrap_or((DVec3::X, 0.0, f64::INFINITY));
    // 2. Up: the longest in-plane principal direction, snapped to a file
    // axis within 20°.
    let mut cov2 = [[0.0; 3]; 3];
    for (q, a) in p.iter().zip(&g.area) {
        let mut d = *q - centre;
        d -= left0 * d.dot(left0);
        let d = d.to_array();
        for i in 0..3 {
            for j in 0..3 {
                cov2[i][j] += a * d[i] * d[j];
            }
        }
    }
    let mut up = principal_axes(cov2)[0];
    let snap = super::axes::nearest_axis(up);
    let snap = if snap.dot(up) < 0.0 { -snap } else { snap };
    let snap = [snap, -snap]
        .into_iter()
        .max_by(|a, b| a.dot(up).total_cmp(&b.dot(up)))
        .unwrap_or(snap);
    if snap.dot(up) > (20f64).to_radians().cos() && snap.dot(left0).abs() < 0.2 {
        up = snap;
    }
    let left_ax = (left0 - up * left0.dot(up)).normalize_or(left0);
    let (lo, hi) = p
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
            (a.min(q.dot(up)), b.max(q.dot(up)))
        });
    let h = hi - lo;
    // Sign: the soles are flat, the head round.
    let band = 0.02 * h;
    let (mut a_lo, mut a_hi) = (0.0, 0.0);
    for (q, a) in p.iter().zip(&g.area) {
        let y = q.dot(up);
        if y < lo + band {
            a_lo += a;
        }
        if y > hi - band {
            a_hi += a;
        }
    }
    let mut doubts = Vec::new();
    let (floor, up) = if a_lo >= a_hi { (lo, up) } else { (-hi, -up) };
    let flat_ratio = a_lo.max(a_hi) / a_lo.min(a_hi).max(1e-300);
    let hgt = |q: DVec3| q.dot(up) - floor;
    let plane_d = |q: DVec3| q.dot(left_ax) - off * left0.dot(left_ax);
    // Facing: the toes reach forward of the shins.
    let fwd0 = left_ax.cross(up);
    let (mut foot, mut fw, mut shin, mut sw) = (0.0, 0.0, 0.0, 0.0);
    for (q, a) in p.iter().zip(&g.area) {
        let y = hgt(*q) / h;
        if y < 0.04 {
            foot += q.dot(fwd0) * a;
            fw += a;
        } else if (0.12..0.2).contains(&y) {
            shin += q.dot(fwd0) * a;
            sw += a;
        }
    }
    let toe_reach = if fw > 0.0 && sw > 0.0 {
        foot / fw - shin / sw
    } else {
        0.0
    };
    let (facing, left) = if toe_reach >= 0.0 {
        (fwd0, left_ax)
    } else {
        (-fwd0, -left_ax)
    };
    let side = |q: DVec3| q.dot(left) - off * left0.dot(left);
    let _ = plane_d;
    let sym_pct = 100.0 * sym / h;
    let c_sym = clamp01(1.0 - (sym_pct - 1.5) / 3.0);
    if c_sym < 1.0 {
        doubts.push(format!(
            "the best symmetry plane leaves reflected points {sym_pct:.1}% of the height from the surface (a body: under 1.5%)"
        ));
    }
    let c_up = clamp01((flat_ratio - 1.2) / 1.0);
    if c_up < 1.0 {
        doubts.push(format!(
            "the floor end is not clear: the flat areas at the two ends differ by a factor {flat_ratio:.2}"
        ));
    }
    let c_face = clamp01(toe_reach.abs() / (0.01 * h));
    if c_face < 1.0 {
        doubts.push(format!(
            "the facing is not clear: the feet reach {:.1}% of the height forward of the shins",
            100.0 * toe_reach.abs() / h
        ));
    }

    // 3. Extremities: geodesic local maxima from the body's centre.
    let mid = {
        let target = centre + up * (floor + 0.55 * h - centre.dot(up));
        let target = target - left * side(target);
        (0..p.len())
            .min_by(|&a, &b| p[a].distance(target).total_cmp(&p[b].distance(target)))
            .unwrap_or(0)
    };
    let gd = g.dijkstra(&[mid], f64::INFINITY);
    let reach = gd
        .iter()
        .copied()
        .filter(|d| d.is_finite())
        .fold(0.0, f64::max);
    let unreached = gd.iter().filter(|d| !d.is_finite()).count();
    if unreached > p.len() / 20 {
        doubts.push(format!(
            "{unreached} vertices are not connected to the body's centre (pieces apart)"
        ));
    }
    let mut cands: Vec<usize> = (0..p.len())
        .filter(|&v| {
            gd[v].is_finite()
                && gd[v] > 0.25 * reach
                && g.nb(v).iter().all(|&(w, _)| gd[w as usize] <= gd[v])
        })
        .collect();
    cands.sort_by(|&a, &b| gd[b].total_cmp(&gd[a]));
    let radius = 0.12 * h;
    let mut ext: Vec<usize> = Vec::new();
    let mut taken = vec![false; p.len()];
    for v in cands {
        if taken[v] {
            continue;
        }
        let ball = g.dijkstra(&[v], radius);
        let is_max = ball
            .iter()
            .enumerate()
            .all(|(w, d)| !d.is_finite() || gd[w] <= gd[v]);
        for (w, d) in ball.iter().enumerate() {
            if d.is_finite() {
                taken[w] = true;
            }
        }
        if is_max {
            ext.push(v);
        }
    }
    let ext_pts: Vec<[f64; 3]> = ext.iter().map(|&v| positions[v]).collect();
    // Classify: feet lowest on each side; hands farthest to each side
    // above 35 % of the height; head the highest near the plane.
    let pick = |pred: &dyn Fn(usize) -> bool, key: &dyn Fn(usize) -> f64| {
        ext.iter()
            .copied()
            .filter(|&v| pred(v))
            .max_by(|&a, &b| key(a).total_cmp(&key(b)))
    };
    let lfoot = pick(&|v| side(p[v]) > 0.02 * h && hgt(p[v]) < 0.2 * h, &|v| {
        -hgt(p[v])
    });
    let rfoot = pick(&|v| side(p[v]) < -0.02 * h && hgt(p[v]) < 0.2 * h, &|v| {
        -hgt(p[v])
    });
    let lhand = pick(&|v| side(p[v]) > 0.08 * h && hgt(p[v]) > 0.3 * h, &|v| {
        side(p[v])
    });
    let rhand = pick(&|v| side(p[v]) < -0.08 * h && hgt(p[v]) > 0.3 * h, &|v| {
        -side(p[v])
    });
    let head = pick(
        &|v| side(p[v]).abs() < 0.08 * h && hgt(p[v]) > 0.75 * h,
        &|v| hgt(p[v]),
    );
    let mut missing = Vec::new();
    for (x, what) in [
        (lfoot, "left foot"),
        (rfoot, "right foot"),
        (lhand, "left hand"),
        (rhand, "right hand"),
    ] {
        if x.is_none() {
            missing.push(what);
        }
    }
    let frame_conf = c_sym.min(c_up).min(c_face);
    let mut base = AutoLandmarks {
        marks: BTreeMap::new(),
        confidence: 0.0,
        up: up.to_array(),
        facing: facing.to_array(),
        left: left.to_array(),
        height: h,
        symmetry_percent: sym_pct,
        extremities: ext_pts,
        doubts,
    };
    if !missing.is_empty() {
        let reason = format!(
            "no {} among the {} extremities found (geodesic local maxima): a missing limb, or not a standing human",
            missing.join(", no "),
            ext.len()
        );
        return Ok((Some(base), Some(reason)));
    }
    let (lfoot, rfoot, lhand, rhand) = (
        lfoot.unwrap_or(0),
        rfoot.unwrap_or(0),
        lhand.unwrap_or(0),
        rhand.unwrap_or(0),
    );
    let mirror = |q: DVec3| q - left * (2.0 * side(q));
    let mut marks: BTreeMap<&'static str, AutoMark> = BTreeMap::new();

    // 4. Arms: rings from each hand tip.
    // Rings at least 1.5 edges wide (a ring narrower than an edge misses
    // vertices on one side).
    let mut edges: Vec<f64> = g.to.iter().map(|x| x.1).collect();
    let med_edge = super::midplane::median(&mut edges);
    let step = (0.01 * h).max(1.5 * med_edge);
    let mut arm_pts = [[DVec3::ZERO; 2]; 2];
    let mut arm_conf = [1.0f64; 2];
    let mut arm_how = [String::new(), String::new()];
    let mut elbow_how = [String::new(), String::new()];
    for (k, tip) in [lhand, rhand].into_iter().enumerate() {
        let d = g.dijkstra(&[tip], 0.4 * h);
        let r = rings(&g, &p, &d, step, 0.4 * h);
        // The wrist: the ring of least perimeter between 5 and 16 % of the
        // height from the tip (the fingers and the flat palm are longer
        // around).
        // The hand's widest ring (the palm, 4-12 % of the height from the
        // tip), then the first narrowing after it.
        let palm = r
            .iter()
            .enumerate()
            .filter(|(_, x)| x.0 >= 0.04 * h && x.0 <= 0.12 * h)
            .max_by(|a, b| a.1.3.total_cmp(&b.1.3))
            .map(|(i, _)| i);
        let wide = palm.map_or(0.0, |i| r[i].3);
        let wrist = palm.and_then(|i| {
            let mut j = i;
            while j + 1 < r.len() && r[j + 1].3 <= r[j].3 && r[j + 1].0 <= 0.2 * h {
                j += 1;
            }
            if j > i {
                return Some(r[j]);
            }
            // No descent right after the palm: the least ring within 8 %
            // of the height beyond it.
            r[i + 1..]
                .iter()
                .filter(|x| x.0 <= r[i].0 + 0.08 * h)
                .min_by(|a, b| a.3.total_cmp(&b.3))
                .copied()
        });
        let Some(wrist) = wrist else {
            arm_conf[k] = 0.0;
            arm_how[k] = "no ring at the hand's base".into();
            continue;
        };
        let narrowing = if wide > 0.0 { wrist.3 / wide } else { 1.0 };
        let line: Vec<DVec3> = r.iter().filter(|x| x.0 >= wrist.0).map(|x| x.1).collect();
        let (elbow, bent) = match bend(&line, 0.08 * h, 0.25 * h, 0.05 * h) {
            Some((q, deg)) if deg > 40.0 => (q, Some(deg)),
            _ => (along(&line, 0.145 * h), None),
        };
        elbow_how[k] = match bent {
            Some(deg) => {
                format!("where the arm's centre line bends most ({deg:.0}°) above the wrist")
            }
            None => {
                "one forearm (14.5% of the height) up the arm's centre line from the wrist".into()
            }
        };
        if arc_length(&line) < 0.145 * h {
            arm_conf[k] = 0.0;
            arm_how[k] = "the arm is shorter than a forearm".into();
        }
        // A wrist shorter around than the hand: a hand; a wrist as thick
        // as a torso: something else (a prop).
        let c_thin = clamp01((0.95 - narrowing) / 0.2);
        let around = wrist.3 / h;
        let c_rad = clamp01((0.35 - around) / 0.1);
        if c_thin < 1.0 {
            arm_how[k] = format!(
                "the ring at the hand's base is {:.0}% of the hand's longest around (a wrist: shorter)",
                100.0 * narrowing
            );
        }
        if c_rad < 1.0 {
            arm_how[k] = format!(
                "the ring at the hand's base is {:.0}% of the height around (a wrist: under 25%)",
                100.0 * around
            );
        }
        arm_conf[k] = arm_conf[k].min(c_thin).min(c_rad);
        arm_pts[k] = [wrist.1, elbow];
    }

    // 5. The groin: the lowest section enclosing the point between the legs.
    let depth_of_legs = {
        let (mut s, mut w) = (0.0, 0.0);
        for (q, a) in p.iter().zip(&g.area) {
            let y = hgt(*q) / h;
            if (0.25..0.35).contains(&y) {
                s += q.dot(facing) * a;
                w += a;
            }
        }
        if w > 0.0 { s / w } else { centre.dot(facing) }
    };
    let axis_at = |y: f64, depth: f64| {
        let o = off * left0.dot(left);
        left * o + facing * depth + up * (floor + y)
    };
    let mut groin = None;
    let mut k = 0.25;
    while k < 0.7 {
        let q = axis_at(k * h, depth_of_legs);
        let loops = cross_section(positions, triangles, q, up);
        if loops
            .iter()
            .any(|l| l.points.len() >= 3 && encloses(l, q, up))
        {
            // The crotch point: the lowest point of that loop's surface
            // near the axis; refine between the last gap and here.
            let (mut a, mut b) = ((k - 0.005) * h, k * h);
            for _ in 0..8 {
                let m = 0.5 * (a + b);
                let qm = axis_at(m, depth_of_legs);
                let inside = cross_section(positions, triangles, qm, up)
                    .iter()
                    .any(|l| l.points.len() >= 3 && encloses(l, qm, up));
                if inside { b = m } else { a = m }
            }
            groin = Some(axis_at(b, depth_of_legs));
            break;
        }
        k += 0.005;
    }
    let (groin, c_groin, groin_how) = match groin {
        Some(q) => {
            let y = hgt(q) / h;
            // Human crotch heights: 0.40-0.52 H.
            let c = clamp01(1.0 - ((y - 0.46).abs() - 0.08).max(0.0) / 0.1);
            (
                q,
                c,
                format!("where the legs split, {:.0}% of the height up", 100.0 * y),
            )
        }
        None => (
            axis_at(0.47 * h, depth_of_legs),
            0.0,
            "the legs do not split below 70% of the height; placed at 47%".to_string(),
        ),
    };

    // 6. Legs: rings from each foot tip; the knee 57 % of the way from the
    // ankle to the crotch along the centre line.
    let mut knees = [DVec3::ZERO; 2];
    let mut knee_conf = [1.0f64; 2];
    let mut knee_how = [String::new(), String::new()];
    let groin_h = hgt(groin);
    for (k, tip) in [lfoot, rfoot].into_iter().enumerate() {
        let d = g.dijkstra(&[tip], 1.2 * groin_h + 0.2 * h);
        let r = rings(&g, &p, &d, step, 1.2 * groin_h + 0.2 * h);
        let Some(a0) = r.iter().position(|x| hgt(x.1) > 0.039 * h) else {
            knee_conf[k] = 0.0;
            knee_how[k] = "no leg above the foot".into();
            continue;
        };
        let top = r
            .iter()
            .position(|x| hgt(x.1) > groin_h - 0.03 * h)
            .unwrap_or(r.len());
        if top <= a0 + 2 {
            knee_conf[k] = 0.0;
            knee_how[k] = "the leg does not reach the groin".into();
            continue;
        }
        let line: Vec<DVec3> = r[a0..top].iter().map(|x| x.1).collect();
        let len = arc_length(&line);
        knees[k] = match bend(&line, 0.25 * len, 0.8 * len, 0.05 * h) {
            Some((q, deg)) if deg > 40.0 => {
                knee_how[k] = format!("where the leg's centre line bends most ({deg:.0}°)");
                q
            }
            // Shank and thigh of one length (Drillis & Contini): halfway
            // from the ankle to the hip, 9 % of the height above the
            // line's end below the crotch.
            _ => along(&line, 0.5 * (len + 0.09 * h)),
        };
    }

    // 7. The chin: the neck's narrowest section below the head, then a
    // quarter of the way to the head top, at its front.
    let head_pt = head.map(|v| p[v]);
    let top_h = head_pt.map_or(h, hgt);
    let head_depth = {
        let (mut s, mut w) = (0.0, 0.0);
        for (q, a) in p.iter().zip(&g.area) {
            let y = hgt(*q);
            if y > top_h - 0.06 * h && side(*q).abs() < 0.06 * h {
                s += q.dot(facing) * a;
                w += a;
            }
        }
        if w > 0.0 { s / w } else { centre.dot(facing) }
    };
    let mut neck: Option<(f64, f64)> = None;
    let mut y = top_h - 0.25 * h;
    while y < top_h - 0.06 * h {
        let q = axis_at(y, head_depth);
        if let Some(l) = part_loop(positions, triangles, q, up, q)
            && encloses(&l, q, up)
            && neck.is_none_or(|n| l.length < n.1)
        {
            neck = Some((y, l.length));
        }
        y += 0.005 * h;
    }
    let (chin, c_chin, chin_how) = match neck {
        Some((ny, len)) => {
            let q = axis_at(ny, head_depth);
            let front = part_loop(positions, triangles, q, up, q)
                .and_then(|l| {
                    l.points
                        .iter()
                        .copied()
                        .filter(|x| side(*x).abs() < 0.03 * h)
                        .max_by(|a, b| a.dot(facing).total_cmp(&b.dot(facing)))
                })
                .unwrap_or(q);
            let neck_w = len / std::f64::consts::PI / h;
            // A neck is 5-9 % of the height across.
            let c = clamp01(1.0 - (neck_w - 0.09).max(0.0) / 0.05);
            (
                front,
                c,
                format!(
                    "the front of the neck's narrowest section below the head ({:.0}% of the height up, {:.1}% across)",
                    100.0 * ny / h,
                    100.0 * neck_w
                ),
            )
        }
        None => (
            axis_at(0.87 * h, head_depth),
            0.0,
            "no neck section found; placed at 87% of the height".into(),
        ),
    };

    // 8. Confidences: twins mirror each other.
    let twin_conf = |a: DVec3, b: DVec3| clamp01(1.0 - (a.distance(mirror(b)) / h - 0.05) / 0.1);
    let c_w = twin_conf(arm_pts[0][0], arm_pts[1][0]);
    let c_e = twin_conf(arm_pts[0][1], arm_pts[1][1]);
    let c_k = twin_conf(knees[0], knees[1]);
    let mut put = |name: &'static str, q: DVec3, c: f64, how: String| {
        marks.insert(
            name,
            AutoMark {
                point: q.to_array(),
                confidence: c.min(frame_conf),
                how,
            },
        );
    };
    let twin_note = |c: f64, what: &str| {
        if c < 1.0 {
            format!("; the {what}s do not mirror each other")
        } else {
            String::new()
        }
    };
    for (k, pre) in [(0, "l"), (1, "r")] {
        let wn = Landmark::from_name(&format!("{pre}_wrist")).map_or("?", |l| l.name());
        let en = Landmark::from_name(&format!("{pre}_elbow")).map_or("?", |l| l.name());
        let kn = Landmark::from_name(&format!("{pre}_knee")).map_or("?", |l| l.name());
        let ah = if arm_how[k].is_empty() {
            "the narrowest ring at the hand's base".to_string()
        } else {
            arm_how[k].clone()
        };
        put(
            wn,
            arm_pts[k][0],
            arm_conf[k].min(c_w),
            format!("{ah}{}", twin_note(c_w, "wrist")),
        );
        put(
            en,
            arm_pts[k][1],
            arm_conf[k].min(c_e),
            format!("{}{}", elbow_how[k], twin_note(c_e, "elbow")),
        );
        let kh = if knee_how[k].is_empty() {
            "halfway up the leg's centre line from the ankle to the hip".to_string()
        } else {
            knee_how[k].clone()
        };
        put(
            kn,
            knees[k],
            knee_conf[k].min(c_k),
            format!("{kh}{}", twin_note(c_k, "knee")),
        );
    }
    put("groin", groin, c_groin, groin_how);
    put("chin", chin, c_chin, chin_how);
    if let Some(t) = head_pt {
        put(
            "head_top",
            t,
            1.0,
            "the highest extremity near the mid-plane".into(),
        );
    }
    for (name, m) in &marks {
        if m.confidence < 0.5 {
            base.doubts.push(format!(
                "{name}: {} (confidence {:.2})",
                m.how, m.confidence
            ));
        }
    }
    base.confidence = marks
        .values()
        .map(|m| m.confidence)
        .fold(frame_conf, f64::min);
    base.marks = marks;
    Ok((Some(base), None))
}
