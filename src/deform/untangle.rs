//! Local untangling of the triangles still turned over after the patch
//! repair ([`super::unflip`]): each vertex of a turned-over triangle is
//! moved, one at a time, to where every triangle of its fan faces the
//! right way (Freitag & Plassmann 2000, "Local optimization-based simplicial
//! mesh untangling and improvement", Int. J. Numer. Meth. Eng. 49).
//!
//! Orientation is measured against each triangle's reference normal `n_t`
//! (its source normal turned by its skin rotation, the same test as
//! [`super::unflip::turned_over`]): the signed area
//! `a_t = ½ n_t · ((x_b − x_a) × (x_c − x_a))`. With the fan's other
//! corners fixed, `a_t` is affine in the moved vertex `v`:
//! `a_t(v) = ½ (n_t · (x_b × x_c) + v · ((x_b − x_c) × n_t))`, so a vertex
//! whose fan can face the right way at all has a feasible set that is an
//! intersection of half-spaces, found by cyclic projection onto the most
//! violated one (the relaxation method of Agmon and Motzkin), aiming at a
//! margin of a fraction of each triangle's source area. A move is kept
//! only if fewer triangles of the fan are turned over afterwards (all of
//! them facing the right way if it can), so the count of turned-over
//! triangles never rises. Every projection is followed by one onto the
//! ball around the vertex's ring (centred on the ring's centroid, reaching
//! its farthest ring vertex or the vertex itself), so the vertex stays in
//! its neighbourhood: in 3D a fan's half-spaces need not bound it (a flat
//! fan leaves it free along its normal), and a turned-over triangle nearly
//! edge-on to its reference normal has a gradient `g` near zero, so its
//! projection step `gap / |g|` is huge. Without the ball that sent single
//! vertices 0.2-1.5 m off the surface in retargeted results (CMU 131_01 on
//! a synthetic samba database: vertex 9760 1.33 m in frame 121, where its
//! fan's gradient was 10⁻³ of its neighbours'). A fan with no room (its ring is itself folded)
//! is opened up by moving its neighbours, whose fans all face the right
//! way: they move to raise their smallest area relative to the source
//! (Freitag & Plassmann's quality step), keeping every triangle the right
//! way round. Sweeps repeat over the vertices of the remaining triangles
//! and their first and second rings until none is left or three sweeps in
//! a row move nothing. Vertices of valence above 16 are left in place.
//!
//! The projection budget is adaptive: cyclic projection converges at a
//! rate set by the angle between the half-spaces it alternates between, so
//! in the thin feasible set of a crushed fan (a few percent of its source
//! area, its ring a sliver) it needs many more steps than in an open one.
//! A vertex whose fan still has a turned-over triangle after `steps`
//! projections continues from where it stopped, the budget doubling up to
//! `max_steps`; a vertex that succeeds stops early as before, and one
//! that still fails keeps the position its first `steps` gave. The
//! deformation runs it with the fixed budget (`max_steps` = `steps`) and
//! the adaptive one only as a last resort, on a frame the fixed budget and
//! the patch repair leave turned over (`Deformer::repair`). Measured on
//! CMU 131_01 retargeted onto the samba capture with the at-rest block
//! support: frame 110 (a deep lunge) left triangle 3674 on the inner
//! thigh turned over with 32 projections; 64 sweeps of 256 untangled it.
//!
//! Cost: a few microseconds per moved vertex (up to `max_steps / steps`
//! times that for a fan with no room at all); nothing at all on a frame
//! with nothing turned over.

use super::unflip::{Adjacency, Budget, WorkLimit, triangle_turn};
use glam::{DQuat, DVec3};
use rayon::prelude::*;

/// Options of [`untangle`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UntangleOptions {
    /// Most sweeps over the vertices of turned-over triangles. Default 16.
    pub sweeps: usize,
    /// Projections per vertex and margin. Default 32.
    pub steps: usize,
    /// Most projections per vertex and margin for a fan that still has a
    /// turned-over triangle after `steps`: the budget doubles from `steps`
    /// up to this. Default 256 (8 × `steps`); `steps` or less turns the
    /// doubling off.
    pub max_steps: usize,
    /// Margins tried, as fractions of a triangle's source area, largest
    /// first. Default `[0.1, 0.01, 1e-4]`.
    pub margins: [f64; 3],
}

impl Default for UntangleOptions {
    fn default() -> Self {
        UntangleOptions {
            sweeps: 16,
            steps: 32,
            max_steps: 256,
            margins: [0.1, 0.01, 1e-4],
        }
    }
}

/// ClipNeutral normals (unit, turned by each triangle's skin rotation) and
/// source areas of `tris`, written into `normals` and `areas`.
pub fn references(
    tris: &[[u32; 3]],
    source: &[[f64; 3]],
    turn: &[DQuat],
    normals: &mut [DVec3],
    areas: &mut [f64],
) {
    for ((t, n), a) in tris.iter().zip(normals.iter_mut()).zip(areas.iter_mut()) {
        let [p, q, r] = t.map(|v| DVec3::from_array(source[v as usize]));
        let c = (q - p).cross(r - p);
        *a = 0.5 * c.length();
        *n = (triangle_turn(t, turn) * c).normalize_or_zero();
    }
}

/// [`references`]' normals from the source normals
/// ([`super::unflip::source_normals`], computed once per frame): each
/// turned by its triangle's rotation under `turn`, normalised, into
/// `normals` (the same bits as [`references`]). Triangles in parallel.
pub fn turned_references(
    tris: &[[u32; 3]],
    source_normals: &[DVec3],
    turn: &[DQuat],
    normals: &mut [DVec3],
) {
    normals
        .par_iter_mut()
        .zip(tris.par_iter().zip(source_normals.par_iter()))
        .with_min_len(super::unflip::CHUNK)
        .for_each(|(n, (t, c))| *n = (triangle_turn(t, turn) * *c).normalize_or_zero());
}

/// [`references`]' source areas from the source normals
/// ([`super::unflip::source_normals`]), into `areas`.
pub(crate) fn source_areas(source_normals: &[DVec3], areas: &mut [f64]) {
    for (a, c) in areas.iter_mut().zip(source_normals) {
        *a = 0.5 * c.length();
    }
}

/// The reference normals of a frame's untangling computed when it first
/// reads them (issue 45): a normal is [`turned_references`]' arithmetic
/// for its one triangle, so the same bits, but only the triangles around
/// the vertices a sweep visits are computed, not all of them on every
/// repair (the full pass was 12.6 % of the deformation on CMU 02_02 onto
/// the samba capture, session 29's profile). Kept in the workspace;
/// [`LazyReferences::restart`] forgets them when the turns change.
#[derive(Debug, Clone, Default)]
pub struct LazyReferences {
    normals: Vec<DVec3>,
    /// The reading each triangle's normal was computed in.
    read_in: Vec<u32>,
    reading: u32,
    /// Normals computed so far (all readings; a measurement).
    pub computed: usize,
}

impl LazyReferences {
    /// Room for `triangles` normals, none computed.
    pub fn new(triangles: usize) -> LazyReferences {
        LazyReferences {
            normals: vec![DVec3::ZERO; triangles],
            read_in: vec![0; triangles],
            reading: 1,
            computed: 0,
        }
    }

    /// Forgets every normal: the next reads are under other turns.
    pub(crate) fn restart(&mut self) {
        self.reading = self.reading.wrapping_add(1);
        if self.reading == 0 {
            self.read_in.fill(0);
            self.reading = 1;
        }
    }
}

/// Where [`untangle_with`] reads each triangle's reference normal.
pub trait Normals {
    /// Makes the normals of the triangles around `verts` current.
    fn ready(&mut self, tris: &[[u32; 3]], adj: &Adjacency, verts: &[u32]);
    /// The normals (current at least around the vertices made ready).
    fn normals(&self) -> &[DVec3];
}

impl Normals for &[DVec3] {
    fn ready(&mut self, _: &[[u32; 3]], _: &Adjacency, _: &[u32]) {}
    fn normals(&self) -> &[DVec3] {
        self
    }
}

/// [`LazyReferences`] of the source normals `source_normals`
/// ([`super::unflip::source_normals`]) turned by `turn`.
pub struct OnDemand<'a> {
    /// The normals computed so far.
    pub lazy: &'a mut LazyReferences,
    /// The frame's source normals.
    pub source_normals: &'a [DVec3],
    /// Each vertex's rotation.
    pub turn: &'a [DQuat],
}

impl Normals for OnDemand<'_> {
    fn ready(&mut self, tris: &[[u32; 3]], adj: &Adjacency, verts: &[u32]) {
        let l = &mut *self.lazy;
        for &v in verts {
            for &t in &adj.triangles[v as usize] {
                let t = t as usize;
                if l.read_in[t] != l.reading {
                    l.normals[t] = (triangle_turn(&tris[t], self.turn) * self.source_normals[t])
                        .normalize_or_zero();
                    l.read_in[t] = l.reading;
                    l.computed += 1;
                }
            }
        }
    }
    fn normals(&self) -> &[DVec3] {
        &self.lazy.normals
    }
}

/// Signed area of triangle `t` of `x` against its reference normal `n`.
#[inline]
fn signed_area(t: &[u32; 3], x: &[[f64; 3]], n: DVec3) -> f64 {
    let [a, b, c] = t.map(|v| DVec3::from_array(x[v as usize]));
    0.5 * n.dot((b - a).cross(c - a))
}

/// Moves vertices of `out` until no triangle faces against its reference
/// normal (see the module docs), starting from the turned-over triangles
/// `bad`. Returns the triangles still turned over.
pub fn untangle(
    tris: &[[u32; 3]],
    adj: &Adjacency,
    normals: &[DVec3],
    areas: &[f64],
    out: &mut [[f64; 3]],
    bad: Vec<u32>,
    opts: &UntangleOptions,
) -> Vec<u32> {
    let mut budget = Budget::new(WorkLimit::NONE);
    untangle_within(tris, adj, normals, areas, out, bad, opts, &mut budget)
}

/// [`untangle`] within `budget`: no vertex is visited once the
/// projections left cannot pay for its whole projection budget
/// (`opts.max_steps` per margin); the projections made are added to it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn untangle_within(
    tris: &[[u32; 3]],
    adj: &Adjacency,
    mut normals: &[DVec3],
    areas: &[f64],
    out: &mut [[f64; 3]],
    bad: Vec<u32>,
    opts: &UntangleOptions,
    budget: &mut Budget,
) -> Vec<u32> {
    untangle_with(tris, adj, &mut normals, areas, out, bad, opts, budget)
}

/// [`untangle_within`] reading the reference normals from `normals`,
/// each sweep making those around its vertices current first (a sweep
/// reads no other: the fans of the vertices it moves, and the
/// turned-over triangles, whose corners are among them).
#[allow(clippy::too_many_arguments)]
pub fn untangle_with<N: Normals>(
    tris: &[[u32; 3]],
    adj: &Adjacency,
    normals: &mut N,
    areas: &[f64],
    out: &mut [[f64; 3]],
    bad: Vec<u32>,
    opts: &UntangleOptions,
    budget: &mut Budget,
) -> Vec<u32> {
    let lists = (bad, &mut Vec::new());
    untangle_kept(tris, adj, normals, areas, out, lists, opts, budget)
}

/// [`untangle_with`] with the sweeps' vertex list in `verts` (cleared
/// before use; a deformation workspace's, reused frame to frame: issue
/// 45).
#[allow(clippy::too_many_arguments)]
pub(crate) fn untangle_kept<N: Normals>(
    tris: &[[u32; 3]],
    adj: &Adjacency,
    normals: &mut N,
    areas: &[f64],
    out: &mut [[f64; 3]],
    (mut bad, verts): (Vec<u32>, &mut Vec<u32>),
    opts: &UntangleOptions,
    budget: &mut Budget,
) -> Vec<u32> {
    let most = opts.max_steps.max(opts.steps) * opts.margins.len();
    let flipped = |normals: &[DVec3], out: &[[f64; 3]], t: u32| {
        signed_area(&tris[t as usize], out, normals[t as usize]) <= 0.0
    };
    let mut idle = 0;
    for sweep in 0..opts.sweeps {
        if bad.is_empty() || idle == 3 {
            break;
        }
        verts.clear();
        verts.extend(bad.iter().flat_map(|&t| tris[t as usize]));
        // Sweeps 1 and 2 of every three also move the first and second
        // rings: a fan whose ring is itself folded has no room until the
        // ring moves.
        for _ in 0..sweep % 3 {
            let k = verts.len();
            for i in 0..k {
                verts.extend_from_slice(&adj.vertices[verts[i] as usize]);
            }
            verts.sort_unstable();
            verts.dedup();
        }
        verts.sort_unstable();
        verts.dedup();
        normals.ready(tris, adj, verts);
        let normals = normals.normals();
        let mut moved = false;
        let mut spent = false;
        for &v in verts.iter() {
            if budget.projections_left() < most {
                spent = true;
                budget.done.stopped += 1;
                break;
            }
            if relocate(
                tris,
                adj,
                normals,
                areas,
                out,
                v,
                opts,
                &mut budget.done.projections,
            ) {
                moved = true;
                // A move that fixes two of a fan's triangles may turn a
                // third over: track it too.
                bad.extend_from_slice(&adj.triangles[v as usize]);
            }
        }
        bad.sort_unstable();
        bad.dedup();
        bad.retain(|&t| flipped(normals, out, t));
        idle = if moved { 0 } else { idle + 1 };
        if spent {
            break;
        }
    }
    bad
}

/// Moves vertex `v` so that its whole fan faces the right way, if it can;
/// returns whether it moved. The projections made are added to `made`.
#[allow(clippy::too_many_arguments)]
fn relocate(
    tris: &[[u32; 3]],
    adj: &Adjacency,
    normals: &[DVec3],
    areas: &[f64],
    out: &mut [[f64; 3]],
    v: u32,
    opts: &UntangleOptions,
    made: &mut usize,
) -> bool {
    let fan = &adj.triangles[v as usize];
    // Each fan triangle as an affine function of the vertex: a(p) = c + g·p.
    let mut lin: [Half; 16] = [Half::default(); 16];
    let k = fan.len().min(16);
    if k < fan.len() {
        return false;
    }
    let mut worst = f64::INFINITY;
    let p0 = DVec3::from_array(out[v as usize]);
    let ball = ring_ball(adj, out, v, p0);
    for (l, &t) in lin.iter_mut().zip(fan.iter()) {
        let tri = &tris[t as usize];
        let n = normals[t as usize];
        // Rotate the corners so that `v` comes first.
        let i = tri.iter().position(|&u| u == v).unwrap_or(0);
        let b = DVec3::from_array(out[tri[(i + 1) % 3] as usize]);
        let c = DVec3::from_array(out[tri[(i + 2) % 3] as usize]);
        let g = 0.5 * (b - c).cross(n);
        *l = Half {
            c: 0.5 * n.dot(b.cross(c)),
            g,
            area: areas[t as usize],
            gg: g.length_squared(),
        };
        worst = worst.min(signed_area(tri, out, n));
    }
    if worst > 0.0 {
        // A fan that faces the right way: open it up (raise its smallest
        // area relative to the source), which makes room for a folded
        // neighbour, keeping every triangle the right way round.
        let ratio = |p: DVec3| {
            lin[..k]
                .iter()
                .map(|h| (h.c + h.g.dot(p)) / h.area.max(f64::MIN_POSITIVE))
                .fold(f64::INFINITY, f64::min)
        };
        let r0 = ratio(p0);
        let m = (2.0 * r0).min(0.5);
        if m <= r0 {
            return false;
        }
        let p = project(&lin[..k], p0, m, opts.steps, &ball, made);
        if p.is_finite() && ratio(p) > r0 {
            out[v as usize] = p.to_array();
            return true;
        }
        return false;
    }
    let wrong = |p: DVec3| lin[..k].iter().filter(|h| h.c + h.g.dot(p) <= 0.0).count();
    let (w0, mut best) = (wrong(p0), None::<(usize, DVec3)>);
    // Each margin's projection continues from where the last budget left
    // it (the same point as restarting with the larger budget), the budget
    // doubling while no margin has the whole fan facing the right way.
    let mut at = [p0; 3];
    let (mut done, mut budget) = (0, opts.steps);
    let cap = opts.max_steps.max(opts.steps);
    loop {
        for (&m, q) in opts.margins.iter().zip(at.iter_mut()) {
            if !q.is_finite() {
                continue;
            }
            *q = project(&lin[..k], *q, m, budget - done, &ball, made);
            let p = *q;
            if !p.is_finite() {
                continue;
            }
            let w = wrong(p);
            if w == 0 {
                out[v as usize] = p.to_array();
                return true;
            }
            // A partial fix only from the first budget: the doubling is
            // for fans it brings wholly the right way round; a fan with no
            // room moves as it did with `steps` projections (projected
            // further, it drifted: CMU 03_02 on samba, 110 -> 123 of its
            // triangles turned over against the rest frame).
            if budget == opts.steps && w < best.map_or(w0, |b| b.0) {
                best = Some((w, p));
            }
        }
        if budget >= cap {
            break;
        }
        done = budget;
        budget = (2 * budget).min(cap);
    }
    // No room for the whole fan: take the position that leaves the fewest
    // of its triangles turned over, if that is fewer than before.
    match best {
        Some((_, p)) => {
            out[v as usize] = p.to_array();
            true
        }
        None => false,
    }
}

/// The ball vertex `v` (now at `p0`) may move in: centred on the centroid
/// of its ring in `out`, reaching the farthest of its ring's vertices and
/// `p0` itself. It holds the ring's convex hull, where a planar fan's
/// feasible set (the kernel of its ring) lies, and the vertex's own place.
fn ring_ball(adj: &Adjacency, out: &[[f64; 3]], v: u32, p0: DVec3) -> Ball {
    let ring = &adj.vertices[v as usize];
    if ring.is_empty() {
        return Ball {
            centre: p0,
            radius: 0.0,
        };
    }
    let centre = ring
        .iter()
        .map(|&u| DVec3::from_array(out[u as usize]))
        .sum::<DVec3>()
        / ring.len() as f64;
    let radius = ring
        .iter()
        .map(|&u| DVec3::from_array(out[u as usize]).distance(centre))
        .fold(p0.distance(centre), f64::max);
    Ball { centre, radius }
}

/// A fan triangle's signed area as an affine function of the moved
/// vertex, `a(p) = c + g·p`, with its source area and `|g|²` (computed
/// once per fan, not on every projection step: the same value each time).
#[derive(Debug, Clone, Copy, Default)]
struct Half {
    c: f64,
    g: DVec3,
    area: f64,
    gg: f64,
}

/// Where a vertex may move ([`ring_ball`]).
#[derive(Debug, Clone, Copy)]
struct Ball {
    centre: DVec3,
    radius: f64,
}

impl Ball {
    /// The point of the ball nearest `p`.
    fn nearest(&self, p: DVec3) -> DVec3 {
        let d = p - self.centre;
        let l = d.length();
        if l > self.radius {
            self.centre + d * (self.radius / l)
        } else {
            p
        }
    }
}

/// Cyclic projection of `p` onto the half-spaces `c + g·p ≥ m · area`,
/// the most violated first, each step followed by the projection onto
/// `ball` (all convex sets, so a point of their intersection is found when
/// there is one), for at most `steps` projections (those made are added
/// to `made`).
fn project(
    lin: &[Half],
    mut p: DVec3,
    m: f64,
    steps: usize,
    ball: &Ball,
    made: &mut usize,
) -> DVec3 {
    for _ in 0..steps {
        let mut step = None;
        let mut most = 0.0;
        for &Half { c, g, area, gg } in lin {
            let gap = m * area - (c + g.dot(p));
            if gap > 0.0 && gg > 0.0 && gap * gap / gg > most {
                most = gap * gap / gg;
                step = Some(g * (gap / gg));
            }
        }
        match step {
            Some(s) => {
                *made += 1;
                p = ball.nearest(p + s)
            }
            None => break,
        }
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::subdivide::{icosahedron, midpoint};

    /// A vertex pushed through its own fan is put back inside it; nothing
    /// else moves and nothing new turns over.
    #[test]
    fn a_folded_fan_is_unfolded_and_nothing_new_turns_over() {
        let m = midpoint(&midpoint(&icosahedron()));
        let tris = m.triangles();
        let src = m.positions().to_vec();
        let nt = tris.len();
        let turn = vec![DQuat::IDENTITY; src.len()];
        let adj = Adjacency::new(src.len(), tris);
        let (mut normals, mut areas) = (vec![DVec3::ZERO; nt], vec![0.0; nt]);
        references(tris, &src, &turn, &mut normals, &mut areas);
        // Slide vertex 0 across its ring along the surface: part of its fan
        // turns over while the ring stays as it was.
        let mut out = src.clone();
        let ring = &adj.vertices[0];
        let far = DVec3::from_array(src[ring[0] as usize]);
        let p0 = DVec3::from_array(src[0]);
        out[0] = (p0 + (far - p0) * 1.6).to_array();
        let bad: Vec<u32> = (0..nt as u32)
            .filter(|&t| signed_area(&tris[t as usize], &out, normals[t as usize]) <= 0.0)
            .collect();
        assert!(!bad.is_empty());
        let left = untangle(
            tris,
            &adj,
            &normals,
            &areas,
            &mut out,
            bad,
            &Default::default(),
        );
        assert!(left.is_empty());
        for t in 0..nt {
            assert!(
                signed_area(&tris[t], &out, normals[t]) > 0.0,
                "triangle {t}"
            );
        }
        for v in 1..src.len() {
            if !ring.contains(&(v as u32)) {
                assert_eq!(out[v], src[v], "vertex {v} moved");
            }
        }
    }

    /// A fan crushed to a few percent of its source area (its ring squashed
    /// into a sliver, as on the inner thigh in a deep lunge) with its
    /// vertex pushed out past the sliver's sharp end, one triangle turned
    /// over: the fan has room, but cyclic projection between the sliver's
    /// nearly parallel sides creeps, so a fixed budget of `steps`
    /// projections leaves the triangle turned over and the doubled budget
    /// turns it back. Generated over valence, crush, where the vertex sits
    /// and the fan's orientation in space.
    #[test]
    fn a_crushed_fan_needs_and_gets_a_larger_projection_budget() {
        let fixed = UntangleOptions {
            max_steps: 32,
            ..Default::default()
        };
        let mut cases = 0;
        for (n, crush) in [(6usize, 0.03), (8, 0.02)] {
            for (x, y) in [(1.02, -0.5), (1.05, -0.2), (1.02, -0.2)] {
                for turn in [
                    DQuat::IDENTITY,
                    DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 1.1),
                ] {
                    // Vertex 0 in the middle, ring 1..=n on the unit circle
                    // (source) squashed by `crush` across (now).
                    let tris: Vec<[u32; 3]> = (0..n as u32)
                        .map(|i| [0, 1 + i, 1 + (i + 1) % n as u32])
                        .collect();
                    let ring = |s: f64| {
                        (0..n).map(move |i| {
                            let a = std::f64::consts::TAU * i as f64 / n as f64;
                            turn * DVec3::new(a.cos(), s * a.sin(), 0.0)
                        })
                    };
                    let src: Vec<[f64; 3]> = std::iter::once(DVec3::ZERO)
                        .chain(ring(1.0))
                        .map(|p| p.to_array())
                        .collect();
                    let mut now: Vec<[f64; 3]> =
                        std::iter::once(turn * DVec3::new(x, y * crush, 0.0))
                            .chain(ring(crush))
                            .map(|p| p.to_array())
                            .collect();
                    let adj = Adjacency::new(src.len(), &tris);
                    let (mut normals, mut areas) = (vec![DVec3::ZERO; n], vec![0.0; n]);
                    let ident = vec![DQuat::IDENTITY; src.len()];
                    references(&tris, &src, &ident, &mut normals, &mut areas);
                    let wrong = |x: &[[f64; 3]]| {
                        (0..n)
                            .filter(|&t| signed_area(&tris[t], x, normals[t]) <= 0.0)
                            .count()
                    };
                    assert_eq!(wrong(&now), 1, "n {n} crush {crush} at ({x}, {y})");
                    let crushed: f64 = (0..n)
                        .map(|t| signed_area(&tris[t], &now, normals[t]))
                        .sum::<f64>()
                        / areas.iter().sum::<f64>();
                    assert!(crushed < 0.05, "fan at {crushed} of its area");
                    let mut old = now.clone();
                    relocate(&tris, &adj, &normals, &areas, &mut old, 0, &fixed, &mut 0);
                    assert!(
                        wrong(&old) > 0,
                        "n {n} crush {crush} at ({x}, {y}): {} steps suffice",
                        fixed.steps
                    );
                    assert!(relocate(
                        &tris,
                        &adj,
                        &normals,
                        &areas,
                        &mut now,
                        0,
                        &Default::default(),
                        &mut 0
                    ));
                    assert_eq!(wrong(&now), 0, "n {n} crush {crush} at ({x}, {y})");
                    assert_eq!(now[1..], old[1..], "the ring moved");
                    cases += 1;
                }
            }
        }
        assert_eq!(cases, 12);
    }
}
