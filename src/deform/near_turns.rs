//! Each vertex's rotation read off the surface itself: the best rigid
//! alignment (Kabsch, the rotation of the polar decomposition of
//! `Σ xᵢ oᵢᵀ`, `oᵢ` the reference offsets from their centroid) of a
//! neighbourhood, the vertices within a few edges of a seed vertex, from a
//! reference frame onto a frame. Every vertex is a seed or next to one (a
//! greedy dominating set, about a quarter of the vertices) and takes its
//! seed's rotation.
//!
//! The surface measure reads turned-over triangles this way against the
//! rest frame ([`crate::tools::eval::triangles`]); the fold repair
//! ([`super::unflip`]) reads them against the retrieved frame with the
//! skeleton's skin-blended rotations, which under a skirt (a blend of the
//! two thighs' turns) and along a twisted limb are not the surface's own.
//! [`crate::deform::RepairTurns`] lets the repair finish against these.

use super::unflip::Adjacency;
use crate::mesh::frames::polar;
use glam::{DMat3, DQuat, DVec3};
use rayon::prelude::*;

/// Edges from a seed to the farthest vertex of its neighbourhood: 3
/// (about 37 vertices on a regular mesh, a few centimetres on the samba
/// capture's): a fold of a few triangles moves a small share of it.
pub const RINGS: usize = 3;

/// Seeds (at least) a thread of [`Neighbourhoods::turns`] takes: a seed's
/// alignment is ~1 µs.
const SEEDS_CHUNK: usize = 128;

/// The seeds and their neighbourhoods of a mesh, built once.
#[derive(Debug, Clone)]
pub struct Neighbourhoods {
    /// The seed whose rotation each vertex takes (index into the seeds).
    pub seed_of: Vec<u32>,
    /// Neighbourhood of seed `s`: `start[s]..start[s + 1]` of `near`.
    pub start: Vec<usize>,
    /// The neighbourhoods' vertices, seed by seed.
    pub near: Vec<u32>,
}

impl Neighbourhoods {
    /// The seeds of `adj`'s mesh and their neighbourhoods of `rings` edges.
    pub fn new(adj: &Adjacency, rings: usize) -> Neighbourhoods {
        let n = adj.vertices.len();
        let (mut start, mut near) = (vec![0], Vec::new());
        let mut seed_of = vec![u32::MAX; n];
        let mut seen = vec![usize::MAX; n];
        let mut ring = Vec::new();
        for v in 0..n {
            if seed_of[v] != u32::MAX {
                continue;
            }
            // A seed: it and its uncovered neighbours take its rotation.
            let s = (start.len() - 1) as u32;
            seed_of[v] = s;
            for &w in &adj.vertices[v] {
                if seed_of[w as usize] == u32::MAX {
                    seed_of[w as usize] = s;
                }
            }
            seen[v] = v;
            near.push(v as u32);
            ring.clear();
            ring.push(v as u32);
            for _ in 0..rings {
                let mut next = Vec::new();
                for &u in &ring {
                    for &w in &adj.vertices[u as usize] {
                        if seen[w as usize] != v {
                            seen[w as usize] = v;
                            near.push(w);
                            next.push(w);
                        }
                    }
                }
                ring = next;
            }
            start.push(near.len());
        }
        Neighbourhoods {
            seed_of,
            start,
            near,
        }
    }

    /// The seeds whose neighbourhood holds each vertex, vertex `v`'s
    /// `holding[start[v]..start[v + 1]]`, increasing: `(start, holding)`
    /// (a counting pass over the neighbourhoods).
    pub(crate) fn holders(&self) -> (Vec<usize>, Vec<u32>) {
        let n = self.seed_of.len();
        let mut at = vec![0usize; n + 1];
        for &v in &self.near {
            at[v as usize + 1] += 1;
        }
        for v in 0..n {
            at[v + 1] += at[v];
        }
        let start = at.clone();
        let mut holding = vec![0u32; self.near.len()];
        for s in 0..self.seeds() {
            for &v in &self.near[self.start[s]..self.start[s + 1]] {
                holding[at[v as usize]] = s as u32;
                at[v as usize] += 1;
            }
        }
        (start, holding)
    }

    /// Seeds.
    pub fn seeds(&self) -> usize {
        self.start.len() - 1
    }

    /// The rotation of seed `s`'s neighbourhood from `reference` onto
    /// `frame` (identity where it is degenerate or not finite).
    pub(crate) fn seed_turn(&self, s: usize, reference: &[[f64; 3]], frame: &[[f64; 3]]) -> DQuat {
        let near = &self.near[self.start[s]..self.start[s + 1]];
        let c = near
            .iter()
            .map(|&u| DVec3::from_array(reference[u as usize]))
            .sum::<DVec3>()
            / near.len().max(1) as f64;
        best_turn(near.iter().map(|&u| {
            let o = DVec3::from_array(reference[u as usize]) - c;
            (DVec3::from_array(frame[u as usize]), o)
        }))
    }

    /// Each vertex's rotation from `reference` onto `frame`, into `turn`
    /// (`seeds`: scratch of one rotation a seed).
    pub fn turns(
        &self,
        reference: &[[f64; 3]],
        frame: &[[f64; 3]],
        seeds: &mut Vec<DQuat>,
        turn: &mut [DQuat],
    ) {
        // Seeds in parallel, each its own sum in its own order: the same
        // bits on any number of threads.
        seeds.clear();
        seeds.par_extend(
            (0..self.seeds())
                .into_par_iter()
                .with_min_len(SEEDS_CHUNK)
                .map(|s| self.seed_turn(s, reference, frame)),
        );
        for (t, &s) in turn.iter_mut().zip(&self.seed_of) {
            *t = seeds[s as usize];
        }
    }
}

/// Triangles of `out` turned over against `source` with each vertex
/// turned by its neighbourhood's own rotation from `source` onto `out`
/// ([`Neighbourhoods::turns`]; `seeds`, `turn`: scratch). The test of
/// "turned over" the deformation's tests and its report use (issue 42,
/// session 26): a triangle counts when it faces against its own
/// surroundings, as a fold, crease or sliver does on screen, not when the
/// skin's blend of two bones' turns (the skirt between the thighs) points
/// elsewhere than the cloth went.
pub(crate) fn turned_over_near(
    near: &Neighbourhoods,
    tris: &[[u32; 3]],
    source: &[[f64; 3]],
    out: &[[f64; 3]],
    seeds: &mut Vec<DQuat>,
    turn: &mut Vec<DQuat>,
) -> Vec<u32> {
    turn.resize(source.len(), DQuat::IDENTITY);
    near.turns(source, out, seeds, turn);
    super::unflip::turned_over(tris, source, out, turn)
}

/// [`turned_over_near`] with its neighbourhoods and scratch, built once
/// per mesh: what a caller outside the deformation (a test, a report)
/// counts a deformed frame's folds with.
#[derive(Debug, Clone)]
pub struct SurfaceFolds {
    near: Neighbourhoods,
    seeds: Vec<DQuat>,
    turn: Vec<DQuat>,
}

impl SurfaceFolds {
    /// The neighbourhoods ([`RINGS`] edges) of the mesh of `n` vertices
    /// and `tris`.
    pub fn new(n: usize, tris: &[[u32; 3]]) -> SurfaceFolds {
        SurfaceFolds {
            near: Neighbourhoods::new(&Adjacency::new(n, tris), RINGS),
            seeds: Vec::new(),
            turn: vec![DQuat::IDENTITY; n],
        }
    }

    /// The triangles of `out` turned over against `source`
    /// ([`turned_over_near`]).
    pub fn turned_over(
        &mut self,
        tris: &[[u32; 3]],
        source: &[[f64; 3]],
        out: &[[f64; 3]],
    ) -> Vec<u32> {
        turned_over_near(
            &self.near,
            tris,
            source,
            out,
            &mut self.seeds,
            &mut self.turn,
        )
    }
}

/// What a [`SurfaceReading`] reads a frame with: the mesh's
/// neighbourhoods, adjacency and triangles, the retrieved frame and its
/// source normals ([`super::unflip::source_normals`]).
#[derive(Clone, Copy)]
pub struct ReadingOf<'a> {
    /// The seeds and their neighbourhoods.
    pub near: &'a Neighbourhoods,
    /// Triangles around each vertex.
    pub adj: &'a Adjacency,
    /// The triangles.
    pub tris: &'a [[u32; 3]],
    /// The retrieved frame (the turns' reference).
    pub source: &'a [[f64; 3]],
    /// Its triangles' normals, unnormalised.
    pub source_normals: &'a [DVec3],
}

/// Seeds and triangles a reading evaluated (a measurement).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ReadingWork {
    /// Seed turns computed.
    pub seeds: usize,
    /// Triangles asked.
    pub triangles: usize,
}

/// The fold repair's readings of one frame against the surface's own
/// turns (each vertex its neighbourhood's turn, [`Neighbourhoods::turns`];
/// a triangle flagged by [`super::unflip::faces_against`]): the first
/// over every seed and triangle, each later one only where the frame
/// moved since the last (issue 45: the full readings were 34 % of the
/// deformation on CMU 02_02 onto the samba capture, up to seven a frame).
///
/// A seed's turn depends on the frame only at its neighbourhood's
/// vertices, and a triangle's flag only on its corners' positions and
/// turns (its source normal is the frame's), so recomputing the seeds
/// whose neighbourhood holds a moved vertex and asking again the
/// triangles with a moved corner or a corner whose turn changed gives the
/// full reading's turns and flags bit for bit. The moved vertices are
/// found by comparing the frame with its copy at the last reading, bit
/// for bit, so whatever moved them (patch solves, untangling, a pass put
/// back to the best so far) is seen, and a vertex moved and put back is
/// not.
#[derive(Debug, Clone, Default)]
pub struct SurfaceReading {
    /// Whether each triangle faced against its turn at the last reading.
    flagged: Vec<bool>,
    /// The frame at the last reading.
    last: Vec<[f64; 3]>,
    /// Scratch: the seeds to compute again (marked, listed) and their
    /// turns; the vertices whose triangles are asked again.
    seed_marked: Vec<bool>,
    dirty: Vec<u32>,
    fresh: Vec<DQuat>,
    vertex_marked: Vec<bool>,
    changed: Vec<u32>,
    /// The seeds holding each vertex ([`Neighbourhoods::holders`]), made
    /// at the first [`SurfaceReading::read_again`].
    holding_start: Vec<usize>,
    holding: Vec<u32>,
    /// What the last reading evaluated.
    pub work: ReadingWork,
}

impl SurfaceReading {
    /// Reads the whole frame `out`: each vertex's turn into `turn`, each
    /// seed's into `seeds`; returns the triangles facing against their
    /// turn, increasing ([`super::unflip::turned_over_from`]'s).
    pub fn read_all(
        &mut self,
        f: &ReadingOf,
        out: &[[f64; 3]],
        seeds: &mut Vec<DQuat>,
        turn: &mut [DQuat],
    ) -> Vec<u32> {
        self.read_all_in(f, out, (seeds, turn), Vec::new())
    }

    /// [`SurfaceReading::read_all`] listed into `list` (cleared; its
    /// buffer reused, issue 45).
    pub(crate) fn read_all_in(
        &mut self,
        f: &ReadingOf,
        out: &[[f64; 3]],
        (seeds, turn): (&mut Vec<DQuat>, &mut [DQuat]),
        list: Vec<u32>,
    ) -> Vec<u32> {
        f.near.turns(f.source, out, seeds, turn);
        self.flagged.resize(f.tris.len(), false);
        self.flagged
            .par_iter_mut()
            .zip(f.tris.par_iter().zip(f.source_normals.par_iter()))
            .with_min_len(super::unflip::CHUNK)
            .for_each(|(b, (t, n))| *b = super::unflip::faces_against(t, *n, out, turn));
        self.last.clear();
        self.last.extend_from_slice(out);
        self.work = ReadingWork {
            seeds: f.near.seeds(),
            triangles: f.tris.len(),
        };
        super::turned::flagged_into(&self.flagged, list)
    }

    /// Reads `out` again after [`SurfaceReading::read_all`] (or this) read
    /// it with the same `f`, `seeds` and `turn`: the same result as
    /// `read_all`, evaluating only what the moves since can change.
    pub fn read_again(
        &mut self,
        f: &ReadingOf,
        out: &[[f64; 3]],
        seeds: &mut [DQuat],
        turn: &mut [DQuat],
    ) -> Vec<u32> {
        self.read_again_in(f, out, (seeds, turn), Vec::new())
    }

    /// [`SurfaceReading::read_again`] listed into `list` (cleared; its
    /// buffer reused, issue 45).
    pub(crate) fn read_again_in(
        &mut self,
        f: &ReadingOf,
        out: &[[f64; 3]],
        (seeds, turn): (&mut [DQuat], &mut [DQuat]),
        list: Vec<u32>,
    ) -> Vec<u32> {
        let (near, n) = (f.near, out.len());
        if self.holding_start.len() != n + 1 {
            (self.holding_start, self.holding) = near.holders();
        }
        self.seed_marked.resize(near.seeds(), false);
        self.vertex_marked.resize(n, false);
        self.dirty.clear();
        self.changed.clear();
        // `v` indexes `out`, `last` and the marks alike.
        #[allow(clippy::needless_range_loop)]
        for v in 0..n {
            if out[v].map(f64::to_bits) == self.last[v].map(f64::to_bits) {
                continue;
            }
            self.last[v] = out[v];
            self.vertex_marked[v] = true;
            self.changed.push(v as u32);
            for &s in &self.holding[self.holding_start[v]..self.holding_start[v + 1]] {
                if !self.seed_marked[s as usize] {
                    self.seed_marked[s as usize] = true;
                    self.dirty.push(s);
                }
            }
        }
        self.fresh.clear();
        self.fresh.par_extend(
            self.dirty
                .par_iter()
                .with_min_len(SEEDS_CHUNK)
                .map(|&s| near.seed_turn(s as usize, f.source, out)),
        );
        for (&s, &q) in self.dirty.iter().zip(&self.fresh) {
            seeds[s as usize] = q;
        }
        for (v, t) in turn.iter_mut().enumerate() {
            let s = near.seed_of[v] as usize;
            if self.seed_marked[s]
                && seeds[s].to_array().map(f64::to_bits) != t.to_array().map(f64::to_bits)
            {
                *t = seeds[s];
                if !self.vertex_marked[v] {
                    self.vertex_marked[v] = true;
                    self.changed.push(v as u32);
                }
            }
        }
        let mut asked = 0;
        for &v in &self.changed {
            for &t in &f.adj.triangles[v as usize] {
                let t = t as usize;
                self.flagged[t] =
                    super::unflip::faces_against(&f.tris[t], f.source_normals[t], out, turn);
                asked += 1;
            }
            self.vertex_marked[v as usize] = false;
        }
        for &s in &self.dirty {
            self.seed_marked[s as usize] = false;
        }
        self.work = ReadingWork {
            seeds: self.dirty.len(),
            triangles: asked,
        };
        super::turned::flagged_into(&self.flagged, list)
    }
}

/// The rotation that best turns offsets `o` onto points `x` over the
/// pairs `(x, o)` (Kabsch: the polar factor of `Σ xᵢ oᵢᵀ`; the offsets sum
/// to zero, so `x` needs no centring); the identity where the sum is
/// degenerate or not finite. Shared with the surface measure
/// ([`crate::tools::eval::triangles`]), which asks the same question.
pub(crate) fn best_turn(pairs: impl Iterator<Item = (DVec3, DVec3)>) -> DQuat {
    let mut h = DMat3::ZERO;
    for (x, o) in pairs {
        h += DMat3::from_cols(x * o.x, x * o.y, x * o.z);
    }
    if h.is_finite() && h != DMat3::ZERO {
        polar(h).0
    } else {
        DQuat::IDENTITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::subdivide::{icosahedron, midpoint};

    #[test]
    fn every_vertex_reads_a_rigid_turn_of_the_whole_mesh() {
        let m = midpoint(&icosahedron());
        let src = m.positions().to_vec();
        let r = DQuat::from_rotation_y(2.9) * DQuat::from_rotation_x(0.4);
        let out: Vec<[f64; 3]> = src
            .iter()
            .map(|p| (r * DVec3::from_array(*p) + DVec3::new(1.0, -2.0, 3.0)).to_array())
            .collect();
        let adj = Adjacency::new(src.len(), m.triangles());
        let nb = Neighbourhoods::new(&adj, 2);
        assert!(nb.seeds() < src.len());
        let mut turn = vec![DQuat::IDENTITY; src.len()];
        nb.turns(&src, &out, &mut Vec::new(), &mut turn);
        for t in &turn {
            assert!(t.dot(r).abs() > 1.0 - 1e-9, "{t:?} against {r:?}");
        }
    }
}
