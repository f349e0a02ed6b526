//! One round of the fold repair's Poisson rebuild ([`super::unflip`]) in
//! memory held once per workspace ([`RepairScratch`]): the patch grown
//! around the turned-over triangles, its triangles, its weighted edges and
//! right-hand sides, and its system ([`super::patch_solve`]). The maps from
//! the mesh to the patch are reset at the entries a round touched only, and
//! every buffer grows to the largest patch met and is kept: a round
//! allocates nothing but faer's symbolic analysis of its patch.

use super::patch_solve::{PatchSystem, reserve_as};
use super::repair_options::{Budget, RepairOptions};
use super::resident::{Resident, page_in};
use super::turned::{Adjacency, is_turned_over, normal, triangle_turn};
use glam::{DQuat, DVec3};

/// What a round reads: the mesh, the retrieved frame, the turns and the
/// options.
#[derive(Clone, Copy)]
pub(crate) struct RoundOf<'a> {
    pub(crate) tris: &'a [[u32; 3]],
    pub(crate) adj: &'a Adjacency,
    pub(crate) source: &'a [[f64; 3]],
    pub(crate) turn: &'a [DQuat],
    pub(crate) opts: &'a RepairOptions,
}

/// The fold repair's memory, reused round to round and frame to frame
/// (a workspace's [`super::unflip::Replay`] holds one; a call without
/// makes its own). Cloning gives a fresh, empty one.
#[derive(Default)]
pub(crate) struct RepairScratch {
    /// Each vertex's index in the round's patch, `u32::MAX` outside it
    /// (reset after each round at the patch's vertices only).
    local: Vec<u32>,
    /// The round's patch: its free vertices, then its held ring.
    patch: Vec<u32>,
    /// Triangles listed in `touch` (false again after each listing).
    listed: Vec<bool>,
    /// Triangles touching a free vertex, increasing.
    touch: Vec<u32>,
    /// The still-turned-over candidates of a round or a smoothing step.
    cand: Vec<u32>,
    edges: Vec<(u32, u32, f64)>,
    b: Vec<[f64; 3]>,
    held: Vec<[f64; 3]>,
    x: Vec<[f64; 3]>,
    system: PatchSystem,
    /// The smoothing's vertices and their new places.
    pub(crate) vs: Vec<u32>,
    pub(crate) moved: Vec<[f64; 3]>,
}

impl Clone for RepairScratch {
    fn clone(&self) -> Self {
        RepairScratch::default()
    }
}

impl std::fmt::Debug for RepairScratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RepairScratch")
            .field("patch", &self.patch.len())
            .field("system", &self.system)
            .finish_non_exhaustive()
    }
}

impl Resident for RepairScratch {
    fn resident(&mut self, touch: bool) -> usize {
        let t = touch;
        let lists = [
            &mut self.local,
            &mut self.patch,
            &mut self.touch,
            &mut self.cand,
            &mut self.vs,
        ]
        .into_iter()
        .map(|v| page_in(v, t))
        .sum::<usize>();
        let points = [&mut self.b, &mut self.held, &mut self.x, &mut self.moved]
            .into_iter()
            .map(|v| page_in(v, t))
            .sum::<usize>();
        lists
            + points
            + page_in(&mut self.listed, t)
            + page_in(&mut self.edges, t)
            + self.system.resident(t)
    }
}

impl RepairScratch {
    /// Sizes the maps for `n` vertices and `triangles` triangles (only
    /// when they change: the maps are left clean by every round).
    pub(crate) fn fit(&mut self, n: usize, triangles: usize) {
        if self.local.len() != n {
            self.local.clear();
            self.local.resize(n, u32::MAX);
        }
        if self.listed.len() != triangles {
            self.listed.clear();
            self.listed.resize(triangles, false);
        }
    }

    /// Grows every buffer to at least `other`'s capacity
    /// ([`PatchSystem::reserve_as`]); the vertex and triangle maps are
    /// sized by [`RepairScratch::fit`].
    pub(crate) fn reserve_as(&mut self, other: &RepairScratch) {
        for (v, o) in [
            (&mut self.patch, &other.patch),
            (&mut self.touch, &other.touch),
            (&mut self.cand, &other.cand),
            (&mut self.vs, &other.vs),
        ] {
            reserve_as(v, o);
        }
        reserve_as(&mut self.edges, &other.edges);
        for (v, o) in [
            (&mut self.b, &other.b),
            (&mut self.held, &other.held),
            (&mut self.x, &other.x),
            (&mut self.moved, &other.moved),
        ] {
            reserve_as(v, o);
        }
        self.system.reserve_as(&other.system);
        if self.local.is_empty() {
            self.fit(other.local.len(), other.listed.len());
        }
    }

    /// One round: the patch of the `bad` triangles grown by `rings` rings
    /// (and its held ring) rebuilt in `out`, `bad` then the triangles
    /// still turned over among it and the patch's (increasing). False,
    /// with `out` and `bad` untouched, when the patch would pass the
    /// budget's patch unknowns or its solve fails.
    pub(crate) fn round(
        &mut self,
        f: &RoundOf,
        out: &mut [[f64; 3]],
        bad: &mut Vec<u32>,
        rings: usize,
        budget: &mut Budget,
    ) -> bool {
        let free = self.grow_patch(f.tris, f.adj, bad, rings);
        let solved = self.solve_patch(f, out, bad, free, budget);
        for &v in &self.patch {
            self.local[v as usize] = u32::MAX;
        }
        if !solved {
            return false;
        }
        // Only triangles touching a moved vertex can have changed: the
        // increasing union of both lists, those still turned over.
        if !bad.windows(2).all(|w| w[0] < w[1]) {
            bad.sort_unstable();
            bad.dedup();
        }
        union_sorted(bad, &self.touch, &mut self.cand);
        bad.clear();
        bad.extend(
            self.cand
                .iter()
                .copied()
                .filter(|&t| is_turned_over(&f.tris[t as usize], f.source, out, f.turn)),
        );
        true
    }

    /// The patch's system solved into `out` at its free vertices (see
    /// [`RepairScratch::round`]); counted in `budget`.
    fn solve_patch(
        &mut self,
        f: &RoundOf,
        out: &mut [[f64; 3]],
        bad: &[u32],
        free: usize,
        budget: &mut Budget,
    ) -> bool {
        let m = self.patch.len();
        if m > budget.patch_left() {
            budget.done.stopped += 1;
            return false;
        }
        budget.done.patch_vertices += m;
        budget.done.patches += 1;
        self.list_touched(f.adj, free);
        self.assemble(f, out, bad);
        if self.system.factor(m, free, &self.edges).is_err() {
            return false;
        }
        self.held.clear();
        self.held
            .extend(self.patch[free..].iter().map(|&v| out[v as usize]));
        self.x.clear();
        self.x.resize(m, [0.0; 3]);
        if self.system.solve(&self.b, &self.held, &mut self.x).is_err()
            || self.x.iter().flatten().any(|c| !c.is_finite())
        {
            return false;
        }
        for (k, &v) in self.patch[..free].iter().enumerate() {
            out[v as usize] = self.x[k];
        }
        true
    }

    /// The round's patch: the vertices of the `bad` triangles grown by
    /// `rings` rings, then the held ring around them, into `patch` and
    /// `local` (clean on entry). Returns the free count.
    ///
    /// Ring by ring, only the last ring's vertices can reach new ones
    /// (every earlier vertex had all its neighbours added when its own
    /// ring was grown), so each ring scans the last ring alone, in patch
    /// order: the same patch in the same order as scanning the whole
    /// patch every ring, which cost rings × patch size (the later surface
    /// rounds reach 2¹⁰ rings, session 28). A ring that adds nothing ends
    /// the growth (the patch holds its whole component).
    fn grow_patch(
        &mut self,
        tris: &[[u32; 3]],
        adj: &Adjacency,
        bad: &[u32],
        rings: usize,
    ) -> usize {
        let (local, patch) = (&mut self.local, &mut self.patch);
        patch.clear();
        let mut add = |u: u32, patch: &mut Vec<u32>| {
            if local[u as usize] == u32::MAX {
                local[u as usize] = patch.len() as u32;
                patch.push(u);
            }
        };
        for &t in bad {
            for &v in &tris[t as usize] {
                add(v, patch);
            }
        }
        let mut last = 0;
        for _ in 0..rings {
            let end = patch.len();
            for k in last..end {
                for &u in &adj.vertices[patch[k] as usize] {
                    add(u, patch);
                }
            }
            if patch.len() == end {
                break;
            }
            last = end;
        }
        let free = patch.len();
        for k in 0..free {
            for &u in &adj.vertices[patch[k] as usize] {
                add(u, patch);
            }
        }
        free
    }

    /// Triangles touching a free vertex, each listed once, then sorted
    /// (the list sorting and deduplicating every vertex's triangles gave,
    /// from a third of the entries: a triangle touches up to three free
    /// vertices).
    fn list_touched(&mut self, adj: &Adjacency, free: usize) {
        self.touch.clear();
        for &v in &self.patch[..free] {
            for &t in &adj.triangles[v as usize] {
                if !self.listed[t as usize] {
                    self.listed[t as usize] = true;
                    self.touch.push(t);
                }
            }
        }
        self.touch.sort_unstable();
        for &t in &self.touch {
            self.listed[t as usize] = false;
        }
    }

    /// The patch's weighted edges and right-hand sides: a triangle turned
    /// over or nearly so (its normal within [`RepairOptions::healthy_cos`]
    /// of edge-on to its turned source normal) asks for its source edges
    /// turned by its rotation, weighted [`RepairOptions::weight`]; every
    /// other asks for its current edges.
    fn assemble(&mut self, f: &RoundOf, out: &[[f64; 3]], bad: &[u32]) {
        self.edges.clear();
        self.b.clear();
        self.b.resize(self.patch.len(), [0.0; 3]);
        for &ti in &self.touch {
            let t = &f.tris[ti as usize];
            if t.iter().any(|&v| self.local[v as usize] == u32::MAX) {
                continue;
            }
            let q = triangle_turn(t, f.turn);
            let reference = (q * normal(t, f.source)).normalize_or_zero();
            let keep = bad.binary_search(&ti).is_err()
                && reference.dot(normal(t, out).normalize_or_zero()) >= f.opts.healthy_cos;
            let w = if keep { 1.0 } else { f.opts.weight };
            for k in 0..3 {
                let (i, j) = (t[k], t[(k + 1) % 3]);
                let (li, lj) = (self.local[i as usize], self.local[j as usize]);
                self.edges.push((li, lj, w));
                let e = if keep {
                    DVec3::from_array(out[i as usize]) - DVec3::from_array(out[j as usize])
                } else {
                    q * (DVec3::from_array(f.source[i as usize])
                        - DVec3::from_array(f.source[j as usize]))
                } * w;
                for d in 0..3 {
                    self.b[li as usize][d] += e[d];
                    self.b[lj as usize][d] -= e[d];
                }
            }
        }
    }

    /// The smoothing's candidates: `bad` and the triangles around the
    /// vertices `vs`, those still turned over, back into `bad`
    /// (increasing, without repeats).
    pub(crate) fn recount_around(
        &mut self,
        tris: &[[u32; 3]],
        adj: &Adjacency,
        source: &[[f64; 3]],
        out: &[[f64; 3]],
        turn: &[DQuat],
        bad: &mut Vec<u32>,
    ) {
        self.cand.clear();
        self.cand.extend_from_slice(bad);
        for &v in &self.vs {
            self.cand.extend_from_slice(&adj.triangles[v as usize]);
        }
        self.cand.sort_unstable();
        self.cand.dedup();
        bad.clear();
        bad.extend(
            self.cand
                .iter()
                .copied()
                .filter(|&t| is_turned_over(&tris[t as usize], source, out, turn)),
        );
    }
}

/// The union of the increasing lists `a` and `b` (each without repeats),
/// increasing and without repeats, into `out`.
fn union_sorted(a: &[u32], b: &[u32], out: &mut Vec<u32>) {
    out.clear();
    out.reserve(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        let (x, y) = (a[i], b[j]);
        out.push(x.min(y));
        i += usize::from(x <= y);
        j += usize::from(y <= x);
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
}
