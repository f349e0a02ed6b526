//! Smoothness of a transition (Huang et al. 2015, Sec. 6.1, Table III): the
//! weighted average of the Hausdorff distance between the overlapping
//! frames `M_i(t_m+k)` and `M_j(t_n+k)`, `k ∈ [−L, L]`, with the weights
//! `α′(k) = min(α(k), 1 − α(k))`, `α(k) = (k + L) / 2L` of Eq. 2. The frame
//! of `j` is first moved on the floor onto the frame of `i` (the rotation
//! about the vertical and translation that best fit their skeletons, as the
//! output places it). Metres.
//!
//! The Hausdorff distance is between the two surfaces, as the paper says
//! ("Hausdorff Distance for overlapping frames"): symmetric (max of the two
//! directed distances), each directed distance the largest, over the
//! vertices of one mesh, of the distance to the nearest point of the other
//! mesh's *surface* (its triangles), not to its nearest vertex and not to
//! the corresponding vertex. The nearest point is looked for on the
//! triangles around the nearest vertex (found with a uniform grid, `O(n)`
//! per frame pair for meshes of even density); it is never farther than
//! that vertex. `hausdorff` (vertex set to vertex set, the measure used
//! before) is kept and reported alongside as `smoothness_vertex`: it
//! exceeds the surface distance by up to about half an edge length.

use crate::db::Character;
use crate::drive::Floor;
use crate::embed::surface::closest_on_triangle;
use crate::graph::FlatFrame;
use glam::DVec3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// A multiplicative hash of the cell keys (the Fx hash of rustc): the
/// keys are small integer triples, so SipHash's protection against
/// chosen keys buys nothing and cost most of the grid's time.
#[derive(Default, Clone, Copy)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i32(&mut self, x: i32) {
        self.write_u64(u64::from(x as u32));
    }
    fn finish(&self) -> u64 {
        self.0
    }
}

type Cells = HashMap<(i32, i32, i32), Vec<u32>, BuildHasherDefault<CellHasher>>;

/// A uniform grid over a point set for nearest-neighbour queries.
struct Grid {
    cell: f64,
    cells: Cells,
    points: Vec<DVec3>,
}

impl Grid {
    fn new(points: Vec<DVec3>, cell: f64) -> Grid {
        let mut cells = Cells::default();
        for (i, p) in points.iter().enumerate() {
            cells.entry(key(*p, cell)).or_default().push(i as u32);
        }
        Grid {
            cell,
            cells,
            points,
        }
    }
}

fn key(p: DVec3, cell: f64) -> (i32, i32, i32) {
    (
        (p.x / cell).floor() as i32,
        (p.y / cell).floor() as i32,
        (p.z / cell).floor() as i32,
    )
}

/// Symmetric Hausdorff distance between two vertex sets (nearest vertex,
/// not nearest surface point; see `hausdorff_surface`).
#[cfg(test)]
pub(crate) fn hausdorff(a: &[DVec3], b: &[DVec3]) -> f64 {
    if a.is_empty() || b.is_empty() {
        return 0.0;
    }
    let cell = 0.03;
    let ga = Grid::new(a.to_vec(), cell);
    let gb = Grid::new(b.to_vec(), cell);
    directed_to_vertices(a, &gb).max(directed_to_vertices(b, &ga))
}

/// Largest distance from a point of `a` to its nearest point of `b`. A
/// point whose search meets a point of `b` within the largest distance so
/// far cannot raise it, so its search stops there (the maximum is the
/// full search's, [`Grid::nearest_within`]).
#[cfg(test)]
fn directed_to_vertices(a: &[DVec3], b: &Grid) -> f64 {
    let mut worst = 0.0f64;
    for pass in [COARSE, 1] {
        for &p in a.iter().step_by(pass) {
            let (v, d) = b.nearest_within(p, worst);
            if v != usize::MAX {
                worst = worst.max(d);
            }
        }
    }
    worst
}

/// The stride of the first pass of the directed distances: a sample of
/// the points raises the running maximum early, so that most points of
/// the full pass stop their search at the first near point.
const COARSE: usize = 16;

/// Triangles around every vertex of a mesh (for the nearest surface point).
pub struct Surface {
    tris: Vec<[u32; 3]>,
    /// CSR: triangles of vertex `v` are `around[start[v]..start[v + 1]]`.
    start: Vec<u32>,
    around: Vec<u32>,
}

impl Surface {
    /// Of a triangle list over `n` vertices (indices out of range are
    /// skipped).
    pub fn new(tris: &[[u32; 3]], n: usize) -> Surface {
        let tris: Vec<[u32; 3]> = tris
            .iter()
            .copied()
            .filter(|t| t.iter().all(|&v| (v as usize) < n))
            .collect();
        let mut count = vec![0u32; n + 1];
        for t in &tris {
            for &v in t {
                count[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let start = count.clone();
        let mut fill = count;
        let mut around = vec![0u32; tris.len() * 3];
        for (k, t) in tris.iter().enumerate() {
            for &v in t {
                around[fill[v as usize] as usize] = k as u32;
                fill[v as usize] += 1;
            }
        }
        Surface {
            tris,
            start,
            around,
        }
    }
}

impl Grid {
    /// The nearest point's index and distance, except that the search
    /// stops at the first point found within `stop` of `q` (that point is
    /// returned; callers that take a maximum of nearest distances need no
    /// more). With `stop < 0` it is the full search: rings of cells around
    /// `q`'s in the order `(dx, dy, dz)` until the next ring lies farther
    /// than the best found (a point in ring `r` is at least `(r − 1)·cell`
    /// away), the first nearest point kept, all points when none is within
    /// 14 cells; a cell is skipped when its box lies farther than the best
    /// so far (it cannot hold a nearer point, so the result is unchanged).
    fn nearest_within(&self, q: DVec3, stop: f64) -> (usize, f64) {
        let stop2 = if stop >= 0.0 { stop * stop } else { -1.0 };
        let cell = self.cell;
        let (cx, cy, cz) = key(q, cell);
        // Distance from `q` to the slab of cells `c + d` along one axis.
        let gap = |x: f64, c: i32, d: i32| -> f64 {
            if d > 0 {
                f64::from(c + d) * cell - x
            } else if d < 0 {
                x - f64::from(c + d + 1) * cell
            } else {
                0.0
            }
        };
        let mut best = (usize::MAX, f64::INFINITY);
        for r in 0..16i32 {
            if ((r - 1).max(0) as f64 * cell).powi(2) > best.1 {
                return (best.0, best.1.sqrt());
            }
            for dx in -r..=r {
                let gx = gap(q.x, cx, dx).max(0.0).powi(2);
                for dy in -r..=r {
                    let gy = gx + gap(q.y, cy, dy).max(0.0).powi(2);
                    let shell = dx.abs() == r || dy.abs() == r;
                    let mut dz = -r;
                    while dz <= r {
                        let g = gy + gap(q.z, cz, dz).max(0.0).powi(2);
                        // A margin for the rounding of `floor(p / cell)`.
                        if g * (1.0 - 1e-9) - 1e-15 <= best.1 {
                            if let Some(ids) = self.cells.get(&(cx + dx, cy + dy, cz + dz)) {
                                for &i in ids {
                                    let d = self.points[i as usize].distance_squared(q);
                                    if d < best.1 {
                                        best = (i as usize, d);
                                        if d <= stop2 {
                                            return (best.0, d.sqrt());
                                        }
                                    }
                                }
                            }
                        }
                        dz = if shell || dz == r { dz + 1 } else { r };
                    }
                }
            }
        }
        if best.1.is_finite() && (14.0 * self.cell).powi(2) >= best.1 {
            return (best.0, best.1.sqrt());
        }
        for (i, p) in self.points.iter().enumerate() {
            let d = p.distance_squared(q);
            if d < best.1 {
                best = (i, d);
            }
        }
        (best.0, best.1.sqrt())
    }
}

/// Largest distance from a point of `a` (every `stride`-th) to the
/// surface `(b, s)`, and to the nearest vertex of `b`: for each point, the
/// nearest vertex of `b` and then the nearest point on the triangles
/// around it. A point whose nearest-vertex search meets a vertex within
/// the surface maximum so far cannot raise either maximum (its surface
/// distance is at most its vertex distance, and the surface maximum is at
/// most the vertex one), so it stops there; the maxima are those of the
/// full search.
fn directed_to_surface(a: &[DVec3], b: &Grid, s: &Surface, stride: usize) -> (f64, f64) {
    let step = stride.max(1);
    let (mut worst, mut worst_v) = (0.0f64, 0.0f64);
    for pass in [COARSE * step, step] {
        for &p in a.iter().step_by(pass) {
            let (v, mut d) = b.nearest_within(p, worst);
            if v == usize::MAX || d <= worst {
                continue;
            }
            worst_v = worst_v.max(d);
            if let (Some(&lo), Some(&hi)) = (s.start.get(v), s.start.get(v + 1)) {
                for &t in &s.around[lo as usize..hi as usize] {
                    let [i, j, k] = s.tris[t as usize];
                    let q = closest_on_triangle(
                        p,
                        b.points[i as usize],
                        b.points[j as usize],
                        b.points[k as usize],
                    );
                    d = d.min(p.distance(q));
                }
            }
            worst = worst.max(d);
        }
    }
    (worst, worst_v)
}

/// Both symmetric distances `(surface, vertex)` of two vertex sets of the
/// topology `s`, each grid built once.
fn hausdorff_both(a: &[DVec3], b: &[DVec3], s: &Surface) -> (f64, f64) {
    if a.is_empty() || b.is_empty() {
        return (0.0, 0.0);
    }
    let cell = 0.03;
    let ga = Grid::new(a.to_vec(), cell);
    let gb = Grid::new(b.to_vec(), cell);
    let (sa, va) = directed_to_surface(a, &gb, s, 1);
    let (sb, vb) = directed_to_surface(b, &ga, s, 1);
    (sa.max(sb), va.max(vb))
}

/// Symmetric Hausdorff distance between two meshes of one topology `s`
/// with vertices `a` and `b`: the larger of the two directed distances
/// from the vertices of one to the surface of the other (module docs).
#[cfg(test)]
pub(crate) fn hausdorff_surface(a: &[DVec3], b: &[DVec3], s: &Surface) -> f64 {
    if a.is_empty() || b.is_empty() {
        return 0.0;
    }
    hausdorff_both(a, b, s).0
}

/// The surface Hausdorff distance of the centre frames of a jump `from →
/// to` (`to − 1` pairs with `from`), aligned as [`profile`], measured from
/// every `stride`-th vertex only (a lower bound of `hausdorff_surface`,
/// for screening candidates).
pub(crate) fn hausdorff_surface_stride(
    ch: &Character,
    s: &Surface,
    from: FlatFrame,
    to: FlatFrame,
    stride: usize,
) -> f64 {
    let (pa, pb) = aligned(ch, from, to.prev().unwrap_or(to));
    let cell = 0.03;
    let ga = Grid::new(pa.clone(), cell);
    let gb = Grid::new(pb.clone(), cell);
    directed_to_surface(&pa, &gb, s, stride)
        .0
        .max(directed_to_surface(&pb, &ga, s, stride).0)
}

/// Frames `ia` and `ib` in metres, `ib` moved on the floor onto `ia` (the
/// rotation about the vertical and translation that best fit their
/// skeletons, [`Floor::fit`]).
fn aligned(ch: &Character, ia: FlatFrame, ib: FlatFrame) -> (Vec<DVec3>, Vec<DVec3>) {
    let mut a = vec![[0.0; 3]; ch.n()];
    let mut b = vec![[0.0; 3]; ch.n()];
    ch.frame_metres(ia, &mut a);
    ch.frame_metres(ib, &mut b);
    let fit = Floor::fit(ch.pose(ib), ch.pose(ia));
    (
        a.iter().map(|p| DVec3::from_array(*p)).collect(),
        b.iter().map(|p| fit.apply(DVec3::from_array(*p))).collect(),
    )
}

/// Every frame of a character ready for the surface Hausdorff distance of
/// any frame pair (the nearest-vertex grid of each frame built once), for
/// measuring many pairs ([`super::floor`]). [`FrameSet::distance`] with
/// stride 1 is the distance [`profile`] measures for the pair.
pub struct FrameSet {
    grids: Vec<Grid>,
    surface: Surface,
    poses: Vec<crate::pose::Pose>,
}

impl FrameSet {
    /// Of every frame of `ch` (metres).
    pub fn new(ch: &Character) -> FrameSet {
        use rayon::prelude::*;
        let n = ch.n();
        let grids = (0..ch.frame_count() as u32)
            .into_par_iter()
            .map(|f| {
                let mut a = vec![[0.0; 3]; n];
                ch.frame_metres(FlatFrame::new(f), &mut a);
                Grid::new(a.iter().map(|p| DVec3::from_array(*p)).collect(), 0.03)
            })
            .collect();
        FrameSet {
            grids,
            surface: Surface::new(ch.topology().triangles(), n),
            poses: ch.poses().to_vec(),
        }
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.grids.len()
    }

    /// True without frames.
    pub fn is_empty(&self) -> bool {
        self.grids.is_empty()
    }

    /// The symmetric surface Hausdorff distance of frames `a` and `b` (flat
    /// ids), `b` moved on the floor onto `a` as [`profile`] does, measured
    /// from every `stride`-th vertex of each: with `stride` 1 the distance
    /// itself, with a larger stride a lower bound of it (a maximum over
    /// fewer vertices). Each directed distance is taken in the frame of
    /// the mesh measured against (the rigid floor motion moved onto the
    /// query points instead), so no grid is rebuilt.
    pub fn distance(&self, a: FlatFrame, b: FlatFrame, stride: usize) -> f64 {
        let (ga, gb) = (&self.grids[a.index()], &self.grids[b.index()]);
        let fit = Floor::fit(&self.poses[b.index()], &self.poses[a.index()]);
        let inv = Floor {
            theta: -fit.theta,
            t: Floor {
                theta: -fit.theta,
                t: DVec3::ZERO,
            }
            .apply(-fit.t),
        };
        let step = stride.max(1);
        let a_in_b: Vec<DVec3> = ga
            .points
            .iter()
            .step_by(step)
            .map(|p| inv.apply(*p))
            .collect();
        let b_in_a: Vec<DVec3> = gb
            .points
            .iter()
            .step_by(step)
            .map(|p| fit.apply(*p))
            .collect();
        directed_to_surface(&a_in_b, gb, &self.surface, 1)
            .0
            .max(directed_to_surface(&b_in_a, ga, &self.surface, 1).0)
    }
}

/// A transition's smoothness by both distances (metres).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Smoothness {
    /// Weighted surface Hausdorff distance (`hausdorff_surface`): the
    /// paper's measure.
    pub surface: f64,
    /// Weighted vertex-set Hausdorff distance (`hausdorff`): the measure
    /// reported before (an upper bound of `surface` up to sampling).
    pub vertex: f64,
}

/// The smoothness of a jump from frame `from` (of sequence `i`) to frame
/// `to` (of `j`; `to − 1` pairs with `from`) with half-window `window`:
/// [`Smoothness::surface`].
pub fn transition_smoothness(ch: &Character, from: FlatFrame, to: FlatFrame, window: usize) -> f64 {
    transition_smoothness_both(ch, from, to, window).surface
}

/// [`transition_smoothness`] by both distances ([`Smoothness`]).
pub fn transition_smoothness_both(
    ch: &Character,
    from: FlatFrame,
    to: FlatFrame,
    window: usize,
) -> Smoothness {
    let surface = Surface::new(ch.topology().triangles(), ch.n());
    let h = profile(ch, &surface, from, to, window.max(1), true);
    Smoothness {
        surface: weighted(&h, window, |x| x.0),
        vertex: weighted(&h, window, |x| x.1),
    }
}

/// The α′(k)-weighted average (Eq. 2) over `k ∈ [−L, L]` of a profile from
/// [`profile`] (centred: entry `k + K` for `K = (len − 1) / 2`), `L =
/// window`; frames outside the profile or outside their sequences are
/// left out. 0 when nothing is left.
pub fn weighted<T: Copy>(h: &[Option<T>], window: usize, f: impl Fn(T) -> f64) -> f64 {
    let l = window.max(1) as i64;
    let kk = (h.len() as i64 - 1) / 2;
    let (mut num, mut den) = (0.0, 0.0);
    for k in -l..=l {
        let alpha = (k + l) as f64 / (2 * l) as f64;
        let w = alpha.min(1.0 - alpha);
        if w <= 0.0 {
            continue;
        }
        if let Some(Some(x)) = usize::try_from(k + kk).ok().and_then(|i| h.get(i)) {
            num += w * f(*x);
            den += w;
        }
    }
    if den > 0.0 { num / den } else { 0.0 }
}

/// The overlapping frame pairs `(M_i(m + k), M_j(n + k))` of a jump
/// `from → to` for `k ∈ [−K, K]` (`None` where a frame is outside its
/// sequence).
pub(crate) fn profile_pairs(
    ch: &Character,
    from: FlatFrame,
    to: FlatFrame,
    half: usize,
) -> Vec<Option<(FlatFrame, FlatFrame)>> {
    let (sa, ta) = ch.graph().frame_of(from);
    let (sb, tb) = ch.graph().frame_of(to);
    let tb = tb.saturating_sub(1);
    let l = half as i64;
    let (la, lb) = (
        ch.graph().sequences()[sa].len as i64,
        ch.graph().sequences()[sb].len as i64,
    );
    (-l..=l)
        .map(|k| {
            let (fa, fb) = (ta as i64 + k, tb as i64 + k);
            if fa < 0 || fb < 0 || fa >= la || fb >= lb {
                return None;
            }
            Some((
                ch.graph().flat_id(sa, fa as usize),
                ch.graph().flat_id(sb, fb as usize),
            ))
        })
        .collect()
}

/// The distances `(surface, vertex)` of frames `ia` and `ib`, `ib` moved
/// on the floor onto `ia` (module docs).
fn pair_distances(ch: &Character, surface: &Surface, ia: FlatFrame, ib: FlatFrame) -> (f64, f64) {
    let (pa, pb) = aligned(ch, ia, ib);
    hausdorff_both(&pa, &pb, surface)
}

/// The Hausdorff distances `(surface, vertex)` of the overlapping frames
/// `M_i(m + k)`, `M_j(n + k)` for `k ∈ [−K, K]` (`None` where a frame is
/// outside its sequence), the frame of `j` moved on the floor onto that of
/// `i` (module docs). Both distances come from the same grids, so `both`
/// no longer changes the cost; `vertex` is 0 without it.
pub fn profile(
    ch: &Character,
    surface: &Surface,
    from: FlatFrame,
    to: FlatFrame,
    half: usize,
    both: bool,
) -> Vec<Option<(f64, f64)>> {
    profile_pairs(ch, from, to, half)
        .into_iter()
        .map(|p| {
            p.map(|(ia, ib)| {
                let (s, v) = pair_distances(ch, surface, ia, ib);
                (s, if both { v } else { 0.0 })
            })
        })
        .collect()
}

/// Transitions' smoothness measured through a cache of frame pairs: every
/// overlapping pair `(M_i(m + k), M_j(n + k))` is measured once, whatever
/// transition or blend window asks for it (the timeline shortens the
/// windows of close transitions, so one jump is asked for at several
/// windows; a grid of queries asks for the same jumps again and again).
/// The values are those of [`transition_smoothness_both`].
pub struct Measurer {
    surface: Surface,
    pairs: HashMap<(FlatFrame, FlatFrame), (f64, f64)>,
}

impl Measurer {
    /// For the frames of `ch`.
    pub fn new(ch: &Character) -> Measurer {
        Measurer {
            surface: Surface::new(ch.topology().triangles(), ch.n()),
            pairs: HashMap::new(),
        }
    }

    /// Frame pairs measured so far.
    pub fn len(&self) -> usize {
        self.pairs.len()
    }

    /// True before any pair is measured.
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// Measures the pairs of every jump `(from, to, window)` not measured
    /// yet, in parallel.
    pub fn prefill(&mut self, ch: &Character, jumps: &[(FlatFrame, FlatFrame, usize)]) {
        use rayon::prelude::*;
        let mut todo: Vec<(FlatFrame, FlatFrame)> = jumps
            .iter()
            .flat_map(|&(a, b, l)| profile_pairs(ch, a, b, l.max(1)))
            .flatten()
            .filter(|p| !self.pairs.contains_key(p))
            .collect();
        todo.sort_unstable();
        todo.dedup();
        let surface = &self.surface;
        let done: Vec<((FlatFrame, FlatFrame), (f64, f64))> = todo
            .par_iter()
            .map(|&(a, b)| ((a, b), pair_distances(ch, surface, a, b)))
            .collect();
        self.pairs.extend(done);
    }

    /// The smoothness of a jump `from → to` at half-window `window`
    /// ([`transition_smoothness_both`]).
    pub fn transition(
        &mut self,
        ch: &Character,
        from: FlatFrame,
        to: FlatFrame,
        window: usize,
    ) -> Smoothness {
        let h: Vec<Option<(f64, f64)>> = profile_pairs(ch, from, to, window.max(1))
            .into_iter()
            .map(|p| {
                p.map(|(a, b)| {
                    *self
                        .pairs
                        .entry((a, b))
                        .or_insert_with(|| pair_distances(ch, &self.surface, a, b))
                })
            })
            .collect();
        Smoothness {
            surface: weighted(&h, window, |x| x.0),
            vertex: weighted(&h, window, |x| x.1),
        }
    }
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

    /// An open cylinder of radius 1: `rings` rings of `n` vertices, 0.1
    /// apart, quads split in two; optionally turned about its axis.
    fn cylinder(n: usize, rings: usize, turn: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let mut v = Vec::new();
        for r in 0..rings {
            for i in 0..n {
                let a = i as f64 * std::f64::consts::TAU / n as f64 + turn;
                v.push(DVec3::new(a.cos(), 0.1 * r as f64, a.sin()));
            }
        }
        let mut t = Vec::new();
        for r in 0..rings - 1 {
            for i in 0..n {
                let (a, b) = ((r * n + i) as u32, (r * n + (i + 1) % n) as u32);
                let (c, d) = (a + n as u32, b + n as u32);
                t.push([a, b, d]);
                t.push([a, d, c]);
            }
        }
        (v, t)
    }

    #[test]
    fn surface_hausdorff_of_a_turned_cylinder_is_the_sagitta_not_the_vertex_gap() {
        // Turned by half a step, every vertex lies midway over a face of
        // the other cylinder: 1 − cos(π/n) from its surface, 2 sin(π/2n)
        // from its nearest vertex.
        let n = 16;
        let (a, tris) = cylinder(n, 6, 0.0);
        let (b, _) = cylinder(n, 6, std::f64::consts::PI / n as f64);
        let s = Surface::new(&tris, a.len());
        let pi = std::f64::consts::PI;
        let surface = hausdorff_surface(&a, &b, &s);
        assert!(
            (surface - (1.0 - (pi / n as f64).cos())).abs() < 1e-9,
            "{surface}"
        );
        let vertex = hausdorff(&a, &b);
        assert!((vertex - 2.0 * (pi / (2 * n) as f64).sin()).abs() < 1e-9);
        // Identical meshes: 0; a rigid shift along the axis by 0.05 (half
        // a ring): the end rings stick out by 0.05.
        assert_eq!(hausdorff_surface(&a, &a, &s), 0.0);
        let up: Vec<DVec3> = a.iter().map(|p| *p + DVec3::new(0.0, 0.05, 0.0)).collect();
        assert!((hausdorff_surface(&a, &up, &s) - 0.05).abs() < 1e-9);
    }

    /// The directed distances by a linear scan for the nearest vertex
    /// (no grid, no early exit, no pruning).
    fn brute_directed(a: &[DVec3], b: &[DVec3], s: &Surface) -> (f64, f64) {
        let (mut ws, mut wv) = (0.0f64, 0.0f64);
        for &p in a {
            let (mut v, mut d) = (0, f64::INFINITY);
            for (i, q) in b.iter().enumerate() {
                if p.distance(*q) < d {
                    (v, d) = (i, p.distance(*q));
                }
            }
            wv = wv.max(d);
            for &t in &s.around[s.start[v] as usize..s.start[v + 1] as usize] {
                let [i, j, k] = s.tris[t as usize];
                let q = closest_on_triangle(p, b[i as usize], b[j as usize], b[k as usize]);
                d = d.min(p.distance(q));
            }
            ws = ws.max(d);
        }
        (ws, wv)
    }

    #[test]
    fn fast_hausdorff_equals_a_linear_scan_near_and_far() {
        // A cylinder against a copy bent and shaken by up to 0.6 m (points
        // within a cell, several rings away, and past the 14 cells of the
        // ring search): the grid with its early exit, Fx-hashed cells and
        // box pruning gives the linear scan's maxima exactly.
        let (a, tris) = cylinder(40, 30, 0.0);
        let s = Surface::new(&tris, a.len());
        let mut seed = 17u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for amp in [0.01, 0.1, 0.6] {
            let b: Vec<DVec3> = a
                .iter()
                .map(|p| {
                    let bend = DVec3::new(0.3 * p.y * p.y, 0.0, 0.0);
                    *p + bend + amp * DVec3::new(rnd(), rnd(), rnd())
                })
                .collect();
            let want = {
                let (s1, v1) = brute_directed(&a, &b, &s);
                let (s2, v2) = brute_directed(&b, &a, &s);
                (s1.max(s2), v1.max(v2))
            };
            assert_eq!(hausdorff_both(&a, &b, &s), want, "amplitude {amp}");
            assert_eq!(hausdorff_surface(&a, &b, &s), want.0);
            assert_eq!(hausdorff(&a, &b), want.1);
        }
    }

    #[test]
    fn closest_point_on_a_triangle_in_every_region() {
        let (a, b, c) = (
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 2.0),
        );
        let cases = [
            (DVec3::new(0.5, 3.0, 0.5), DVec3::new(0.5, 0.0, 0.5)), // face
            (DVec3::new(-1.0, 1.0, -1.0), a),                       // vertex a
            (DVec3::new(3.0, 0.0, -1.0), b),                        // vertex b
            (DVec3::new(-1.0, 0.0, 3.0), c),                        // vertex c
            (DVec3::new(1.0, 1.0, -2.0), DVec3::new(1.0, 0.0, 0.0)), // edge ab
            (DVec3::new(-2.0, 0.0, 1.0), DVec3::new(0.0, 0.0, 1.0)), // edge ac
            (DVec3::new(2.0, 0.0, 2.0), DVec3::new(1.0, 0.0, 1.0)), // edge bc
        ];
        for (p, want) in cases {
            let got = closest_on_triangle(p, a, b, c);
            assert!(got.distance(want) < 1e-12, "{p}: {got} != {want}");
        }
    }

    #[test]
    fn weights_are_eq_2_alpha_prime_and_skip_missing_frames() {
        // L = 2: α = 0, ¼, ½, ¾, 1 → α′ = 0, ¼, ½, ¼, 0.
        let h = [Some(9.0), Some(1.0), Some(2.0), Some(3.0), Some(9.0)];
        let w = weighted(&h, 2, |x| x);
        assert!((w - (0.25 * 1.0 + 0.5 * 2.0 + 0.25 * 3.0) / 1.0).abs() < 1e-12);
        let h = [None, None, Some(2.0), Some(4.0), Some(9.0)];
        assert!((weighted(&h, 2, |x| x) - (0.5 * 2.0 + 0.25 * 4.0) / 0.75).abs() < 1e-12);
    }
}
