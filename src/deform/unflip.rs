//! Repair of turned-over triangles after the part-based deformation.
//!
//! Where the part solutions meet under strong compression (a skirt between
//! the legs, a hem pushed by a knee) a few triangles of the deformed surface
//! can face the wrong way. A triangle is *turned over* when its normal
//! opposes the source triangle's normal turned by the triangle's
//! skin-blended rotation from the source skeleton to the target (a triangle
//! that simply rotates with its limb, however far, is not).
//!
//! Each patch of such triangles (their vertices grown by a few rings) is
//! rebuilt by a local Poisson solve with its surrounding ring fixed. A
//! triangle that is turned over or nearly so (its normal within
//! [`RepairOptions::healthy_cos`] of edge-on to the turned source normal)
//! asks for its source edges turned by its rotation, weighted up
//! ([`RepairOptions::weight`]); every other triangle of the patch asks for
//! its current edges, so the deformation's shape is kept and only the fold
//! is worked out (asking every triangle for its turned source shape, as an
//! earlier version did, undid the deformation over large patches and moved
//! the joints). If triangles are still turned over the patch is doubled and
//! the solve repeated, up to [`RepairOptions::rounds`]; the vertices of any
//! left then move to the mean of their neighbours (a few Jacobi steps of
//! umbrella smoothing), which unfolds small folds the solve keeps.
//! [`super::untangle`] finishes the job. Frames with nothing turned over
//! cost one pass over the triangles.

use crate::mesh::solver::{FixedSolver, SolveError};
use glam::{DQuat, DVec3};
use rayon::prelude::*;

/// Vertex adjacency of a mesh, built once.
pub struct Adjacency {
    /// Neighbouring vertices of each vertex.
    pub vertices: Vec<Vec<u32>>,
    /// Triangles around each vertex.
    pub triangles: Vec<Vec<u32>>,
}

impl Adjacency {
    /// Adjacency of `n` vertices and `tris`.
    pub fn new(n: usize, tris: &[[u32; 3]]) -> Adjacency {
        let mut vertices = vec![Vec::new(); n];
        let mut triangles = vec![Vec::new(); n];
        for (i, t) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k] as usize, t[(k + 1) % 3]);
                vertices[a].push(b);
                vertices[b as usize].push(t[k]);
                triangles[a].push(i as u32);
            }
        }
        for v in &mut vertices {
            v.sort_unstable();
            v.dedup();
        }
        Adjacency {
            vertices,
            triangles,
        }
    }
}

/// Each vertex's rotation: its joints' rotations `g` blended by its skin
/// weights (sign-aligned quaternion average), written into `out`.
pub fn skin_turns(skin: &[([u8; 4], [f64; 4])], g: &[DQuat], out: &mut [DQuat]) {
    for (t, (js, wts)) in out.iter_mut().zip(skin) {
        let q0 = g[js[0] as usize];
        let mut q = DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0);
        for (&j, &w) in js.iter().zip(wts) {
            let qj = g[j as usize];
            q += if qj.dot(q0) < 0.0 { -qj } else { qj } * w;
        }
        *t = if q.length_squared() > 0.0 {
            q.normalize()
        } else {
            q0
        };
    }
}

/// The rotation of triangle `t`: the mean of its vertices' (sign-aligned).
pub(crate) fn triangle_turn(t: &[u32; 3], turn: &[DQuat]) -> DQuat {
    let q0 = turn[t[0] as usize];
    let mut q = DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    for &v in t {
        let qv = turn[v as usize];
        q += if qv.dot(q0) < 0.0 { -qv } else { qv };
    }
    if q.length_squared() > 0.0 {
        q.normalize()
    } else {
        q0
    }
}

fn normal(t: &[u32; 3], p: &[[f64; 3]]) -> DVec3 {
    let [a, b, c] = t.map(|v| DVec3::from_array(p[v as usize]));
    (b - a).cross(c - a)
}

/// Whether triangle `t` of `out` is turned over against `source`.
#[inline]
fn is_turned_over(t: &[u32; 3], source: &[[f64; 3]], out: &[[f64; 3]], turn: &[DQuat]) -> bool {
    (triangle_turn(t, turn) * normal(t, source)).dot(normal(t, out)) < 0.0
}

/// Keeps, of the sorted candidate triangles `cand`, those turned over (the
/// triangles a local change can have affected: no full pass).
fn recount(
    tris: &[[u32; 3]],
    source: &[[f64; 3]],
    out: &[[f64; 3]],
    turn: &[DQuat],
    cand: &mut Vec<u32>,
) {
    cand.sort_unstable();
    cand.dedup();
    cand.retain(|&t| is_turned_over(&tris[t as usize], source, out, turn));
}

/// Triangles (at least) each thread of a data-parallel pass over the
/// triangles takes: the passes below cost ~20-60 ns a triangle, so a chunk
/// is tens of microseconds, well above rayon's cost of a split.
pub(crate) const CHUNK: usize = 2048;

/// The source normals `(b − a) × (c − a)` (not normalised: twice the
/// area) of `tris` in `source`, into `out`: what [`turned_over_from`] and
/// [`super::untangle::turned_references`] turn, computed once per frame
/// instead of on every reading of a repair (the same arithmetic as
/// [`turned_over`]'s, so the same bits). Triangles in parallel.
pub fn source_normals(tris: &[[u32; 3]], source: &[[f64; 3]], out: &mut [DVec3]) {
    out.par_iter_mut()
        .zip(tris.par_iter())
        .with_min_len(CHUNK)
        .for_each(|(n, t)| *n = normal(t, source));
}

/// [`turned_over`] with the source normals given ([`source_normals`]);
/// the same triangles, in the same (increasing) order. Triangles in
/// parallel.
pub fn turned_over_from(
    tris: &[[u32; 3]],
    source_normals: &[DVec3],
    out: &[[f64; 3]],
    turn: &[DQuat],
) -> Vec<u32> {
    tris.par_iter()
        .zip(source_normals.par_iter())
        .enumerate()
        .with_min_len(CHUNK)
        .filter(|(_, (t, n))| faces_against(t, **n, out, turn))
        .map(|(i, _)| i as u32)
        .collect()
}

/// Whether triangle `t` of `out` faces against its source normal
/// `source_normal` ([`source_normals`]) turned by its rotation under
/// `turn`: the test of [`turned_over_from`], one triangle (the same
/// arithmetic, so the same answer bit for bit wherever it is asked).
#[inline]
pub(crate) fn faces_against(
    t: &[u32; 3],
    source_normal: DVec3,
    out: &[[f64; 3]],
    turn: &[DQuat],
) -> bool {
    (triangle_turn(t, turn) * source_normal).dot(normal(t, out)) < 0.0
}

/// Triangles of `out` turned over against `source` under `turn`.
pub fn turned_over(
    tris: &[[u32; 3]],
    source: &[[f64; 3]],
    out: &[[f64; 3]],
    turn: &[DQuat],
) -> Vec<u32> {
    tris.iter()
        .enumerate()
        .filter(|(_, t)| is_turned_over(t, source, out, turn))
        .map(|(i, _)| i as u32)
        .collect()
}

/// The repair's work on one frame, counted, and the most it may do
/// (`Deformer::repair`'s budget): projections of [`super::untangle`] and
/// patch unknowns of [`unflip`] (each round's patch, free and fixed
/// vertices, summed over the rounds). A step that would go past a limit is
/// not started; what was done is still counted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct Work {
    /// Projections made by the untangling.
    pub projections: usize,
    /// Patch unknowns solved by the Poisson repair.
    pub patch_vertices: usize,
    /// Patch systems factored (one a round of [`unflip_within`]).
    pub patches: usize,
    /// Of `patches`, those of the surface repair's rounds (the repair
    /// against the surface's own turns, after the skin's).
    pub surface_patches: usize,
    /// Of `patches`, those of the adaptive retry (the repair again from
    /// the deformed frame with the adaptive untangling budget).
    pub retry_patches: usize,
    /// Of `patches`, those of the second and later repair passes.
    pub later_pass_patches: usize,
    /// Rounds not solved again because a pass that did not help had
    /// solved them from the same state ([`Replay`]): factorisations saved.
    pub replayed_rounds: usize,
}

/// Limits of a frame's [`Work`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WorkLimit {
    /// Most projections.
    pub projections: usize,
    /// Most patch unknowns.
    pub patch_vertices: usize,
}

impl WorkLimit {
    /// No limit.
    pub const NONE: WorkLimit = WorkLimit {
        projections: usize::MAX,
        patch_vertices: usize::MAX,
    };
}

/// A frame's work so far against its limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Budget {
    /// Done so far.
    pub done: Work,
    /// The limit.
    pub limit: WorkLimit,
}

impl Budget {
    /// Nothing done yet, within `limit`.
    pub fn new(limit: WorkLimit) -> Budget {
        Budget {
            done: Work::default(),
            limit,
        }
    }

    /// Projections left.
    pub(crate) fn projections_left(&self) -> usize {
        self.limit.projections.saturating_sub(self.done.projections)
    }

    /// Patch unknowns left.
    pub(crate) fn patch_left(&self) -> usize {
        self.limit
            .patch_vertices
            .saturating_sub(self.done.patch_vertices)
    }
}

/// Options of [`unflip`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RepairOptions {
    /// Poisson rounds, the patch doubling each round from 2 rings. 0 turns
    /// the repair off. Default 3 (up to 8 rings).
    pub rounds: usize,
    /// Most rings a patch grows around its turned-over triangles: the
    /// doubling stops here and later rounds solve patches of this many
    /// rings around what is still turned over. Default unbounded
    /// (`usize::MAX`, the repair as before). Measured (session 32, live
    /// `--replay` of CMU 02_02 at lag 0 onto the real samba capture,
    /// three interleaved pairs at load 13-15): 8 rings cut the patch
    /// unknowns a frame from 5,074 to 4,063 and the deformation's CPU from
    /// 28.5-30.4 to 24.5-25.9 ms a frame (p99 110-127 → 50-69 ms), but
    /// `eval --surface` flags 2 % more (22,822 → 23,290; creases 6,474 →
    /// 6,695, turned over against the rest frame 118 → 125), so it is not
    /// the default; CMU 131_02 is unchanged.
    pub most_rings: usize,
    /// A triangle whose unit normal has a dot product with its turned source
    /// normal below this is rebuilt towards its source shape; the others
    /// keep their deformed shape. Default 0.3.
    pub healthy_cos: f64,
    /// Weight of a rebuilt triangle's edges against a kept one's. Default 4.
    pub weight: f64,
    /// Most umbrella-smoothing steps on the vertices of triangles still
    /// turned over after the rounds. Default 20.
    pub smooth: usize,
    /// Take a pass's rounds that the pass before solved from the same
    /// state from that pass ([`Replay`]) instead of solving them again.
    /// The result is the same bit for bit (the rounds are deterministic);
    /// off only to measure what it saves. Default true.
    pub replay: bool,
}

/// The state after a pass's Poisson rounds (before its smoothing), kept
/// so the next pass, when it starts from the same state with the same
/// triangles (the pass did not help and the repair went back to where it
/// started), takes its first rounds from here instead of solving them
/// again: the rounds are deterministic, so the next pass's first rounds
/// would give this state bit for bit, and it only solves the rounds it
/// adds (one more doubling). Allocated once per workspace.
#[derive(Debug, Clone, Default)]
pub struct Replay {
    /// The frame after the rounds.
    out: Vec<[f64; 3]>,
    /// The triangles still turned over there.
    bad: Vec<u32>,
    /// Rounds solved and the rings of the next round.
    rounds: usize,
    rings: usize,
    /// Whether the state above is one a next pass can take.
    valid: bool,
}

impl Replay {
    /// Forgets the kept state.
    pub fn clear(&mut self) {
        self.valid = false;
    }
}

impl Default for RepairOptions {
    fn default() -> Self {
        RepairOptions {
            rounds: 3,
            most_rings: usize::MAX,
            healthy_cos: 0.3,
            weight: 4.0,
            smooth: 20,
            replay: true,
        }
    }
}

/// Rebuilds the patches around the turned-over triangles `bad` (sorted,
/// as [`turned_over`] gives them) of `out` in place (see the module docs);
/// returns the triangles still turned over.
pub fn unflip(
    tris: &[[u32; 3]],
    adj: &Adjacency,
    source: &[[f64; 3]],
    out: &mut [[f64; 3]],
    turn: &[DQuat],
    bad: Vec<u32>,
    opts: &RepairOptions,
) -> Vec<u32> {
    let mut budget = Budget::new(WorkLimit::NONE);
    unflip_within(tris, adj, source, out, turn, bad, opts, &mut budget, None)
}

/// [`unflip`] within `budget`: a round whose patch (free and fixed
/// vertices) would go past the patch unknowns left is not solved (the
/// smoothing still runs); the patch unknowns solved are added to it.
///
/// `replay`: `(kept, resume)`. With `resume` the call starts from the
/// state `kept` holds (when it holds one: the caller asks only when `out`
/// and `bad` are the state the last call that kept it started from, with
/// the same options but `rounds`) and solves only the rounds after it;
/// every call that runs all its rounds keeps its state in `kept`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn unflip_within(
    tris: &[[u32; 3]],
    adj: &Adjacency,
    source: &[[f64; 3]],
    out: &mut [[f64; 3]],
    turn: &[DQuat],
    mut bad: Vec<u32>,
    opts: &RepairOptions,
    budget: &mut Budget,
    mut replay: Option<(&mut Replay, bool)>,
) -> Vec<u32> {
    let n = out.len();
    let most_rings = opts.most_rings.max(1);
    let mut rings = most_rings.min(2);
    let mut first = 0;
    if let Some((kept, resume)) = replay.as_mut() {
        if *resume && kept.valid && kept.rounds <= opts.rounds && kept.out.len() == n {
            out.copy_from_slice(&kept.out);
            bad.clone_from(&kept.bad);
            rings = kept.rings;
            first = kept.rounds;
            budget.done.replayed_rounds += kept.rounds;
        }
        kept.valid = false;
    }
    // Whether every round ran (none stopped by the budget or a failed
    // solve): only then is the state one a next pass can take.
    let mut complete = true;
    // Triangles listed in `touch` (cleared after each round).
    let mut listed = vec![false; tris.len()];
    let mut union = Vec::new();
    for _ in first..opts.rounds {
        if bad.is_empty() {
            break;
        }
        let (local, patch, free) = grow_patch(tris, adj, &bad, rings, n);
        let fixed: Vec<u32> = (free as u32..patch.len() as u32).collect();
        let m = patch.len();
        if m > budget.patch_left() {
            complete = false;
            break;
        }
        budget.done.patch_vertices += m;
        budget.done.patches += 1;
        // Triangles touching a free vertex, each listed once, then sorted
        // (the list sorting and deduplicating every vertex's triangles
        // gave, from a third of the entries: a triangle touches up to
        // three free vertices).
        let mut touch: Vec<u32> = Vec::new();
        for &v in &patch[..free] {
            for &t in &adj.triangles[v as usize] {
                if !listed[t as usize] {
                    listed[t as usize] = true;
                    touch.push(t);
                }
            }
        }
        touch.sort_unstable();
        for &t in &touch {
            listed[t as usize] = false;
        }
        let mut edges = Vec::with_capacity(touch.len() * 3);
        let mut b = vec![[0.0; 3]; m];
        for &ti in &touch {
            let t = &tris[ti as usize];
            if t.iter().any(|&v| local[v as usize] == u32::MAX) {
                continue;
            }
            let q = triangle_turn(t, turn);
            let reference = (q * normal(t, source)).normalize_or_zero();
            let keep = bad.binary_search(&ti).is_err()
                && reference.dot(normal(t, out).normalize_or_zero()) >= opts.healthy_cos;
            let w = if keep { 1.0 } else { opts.weight };
            for k in 0..3 {
                let (i, j) = (t[k], t[(k + 1) % 3]);
                let (li, lj) = (local[i as usize], local[j as usize]);
                edges.push((li, lj, w));
                let e = if keep {
                    DVec3::from_array(out[i as usize]) - DVec3::from_array(out[j as usize])
                } else {
                    q * (DVec3::from_array(source[i as usize])
                        - DVec3::from_array(source[j as usize]))
                } * w;
                for d in 0..3 {
                    b[li as usize][d] += e[d];
                    b[lj as usize][d] -= e[d];
                }
            }
        }
        let solved: Result<Vec<[f64; 3]>, SolveError> = (|| {
            let s = FixedSolver::from_rows(m, edge_rows(m, &edges), &fixed)?;
            let vals: Vec<[f64; 3]> = patch[free..].iter().map(|&v| out[v as usize]).collect();
            let mut x = vec![[0.0; 3]; m];
            let mut ws = s.workspace(3);
            s.solve(&b, &vals, &mut x, &mut ws);
            Ok(x)
        })();
        let Ok(x) = solved else {
            complete = false;
            break;
        };
        if x.iter().flatten().any(|c| !c.is_finite()) {
            complete = false;
            break;
        }
        for (k, &v) in patch[..free].iter().enumerate() {
            out[v as usize] = x[k];
        }
        // Only triangles touching a moved vertex can have changed: the
        // increasing union of both lists (a merge; `recount`'s sort of
        // their concatenation gives the same), those still turned over.
        if !bad.windows(2).all(|w| w[0] < w[1]) {
            bad.sort_unstable();
            bad.dedup();
        }
        union_sorted(&bad, &touch, &mut union);
        std::mem::swap(&mut bad, &mut union);
        bad.retain(|&t| is_turned_over(&tris[t as usize], source, out, turn));
        rings = rings.saturating_mul(2).min(most_rings);
    }
    if let Some((kept, _)) = replay {
        if complete && opts.replay {
            kept.out.resize(n, [0.0; 3]);
            kept.out.copy_from_slice(out);
            kept.bad.clone_from(&bad);
            kept.rounds = opts.rounds;
            kept.rings = rings;
            kept.valid = true;
        }
    }
    smooth(tris, adj, source, out, turn, &mut bad, opts.smooth);
    bad
}

/// A round's patch ([`unflip_within`]): the vertices of the `bad`
/// triangles grown by `rings` rings, then the fixed ring around them.
/// Returns each vertex's index in the patch (`u32::MAX` outside it), the
/// patch's vertices (the free ones first) and the free count.
fn grow_patch(
    tris: &[[u32; 3]],
    adj: &Adjacency,
    bad: &[u32],
    rings: usize,
    n: usize,
) -> (Vec<u32>, Vec<u32>, usize) {
    // The patch: the bad triangles' vertices grown by `rings` rings.
    let mut local = vec![u32::MAX; n];
    let mut patch: Vec<u32> = Vec::new();
    for &t in bad {
        for &v in &tris[t as usize] {
            if local[v as usize] == u32::MAX {
                local[v as usize] = patch.len() as u32;
                patch.push(v);
            }
        }
    }
    // Ring by ring, only the last ring's vertices can reach new ones
    // (every earlier vertex had all its neighbours added when its own
    // ring was grown), so each ring scans the last ring alone, in patch
    // order: the same patch in the same order as scanning the whole
    // patch every ring, which cost rings × patch size (the later
    // surface rounds reach 2¹⁰ rings, session 28). A ring that adds
    // nothing ends the growth (the patch holds its whole component).
    let mut last = 0;
    for _ in 0..rings {
        let end = patch.len();
        for k in last..end {
            for &u in &adj.vertices[patch[k] as usize] {
                if local[u as usize] == u32::MAX {
                    local[u as usize] = patch.len() as u32;
                    patch.push(u);
                }
            }
        }
        if patch.len() == end {
            break;
        }
        last = end;
    }
    let free = patch.len();
    // The fixed ring around it.
    for k in 0..free {
        for &u in &adj.vertices[patch[k] as usize] {
            if local[u as usize] == u32::MAX {
                local[u as usize] = patch.len() as u32;
                patch.push(u);
            }
        }
    }
    (local, patch, free)
}

/// The compressed rows ([`crate::mesh::laplacian::to_rows`]' form) of the
/// `m × m` graph Laplacian of the weighted edges `(i, j, w)`: each adds `w`
/// at `(i, i)` and `(j, j)` and `−w` at `(i, j)` and `(j, i)`. A counting
/// pass places every entry in its row, then each row (a vertex's few
/// neighbours) is sorted and its repeats summed, into a row allocated at
/// its size: no sort of all the entries (the sort of the triplets was 17 %
/// of a frame's deformation on CMU 02_02, session 27) and no row grown by
/// pushes (session 27's binned version, 3 % slower for the reallocations).
/// A row's repeats are summed in another order than the triplets' sort
/// gave; the patch's weights (1 and [`RepairOptions::weight`], 4 by
/// default) are whole numbers, whose sums are exact in any order, so the
/// matrix is the same bit for bit.
fn edge_rows(m: usize, edges: &[(u32, u32, f64)]) -> Vec<Vec<(u32, f64)>> {
    let mut start = vec![0usize; m + 1];
    for &(i, j, _) in edges {
        start[i as usize + 1] += 2;
        start[j as usize + 1] += 2;
    }
    for r in 0..m {
        start[r + 1] += start[r];
    }
    let mut at = start[..m].to_vec();
    let mut flat = vec![(0u32, 0.0f64); start[m]];
    for &(i, j, w) in edges {
        for (r, c, v) in [(i, i, w), (j, j, w), (i, j, -w), (j, i, -w)] {
            flat[at[r as usize]] = (c, v);
            at[r as usize] += 1;
        }
    }
    (0..m)
        .map(|r| {
            let row = &mut flat[start[r]..start[r + 1]];
            row.sort_unstable_by_key(|&(c, _)| c);
            let distinct = row.len().min(1) + row.windows(2).filter(|p| p[0].0 != p[1].0).count();
            let mut out: Vec<(u32, f64)> = Vec::with_capacity(distinct);
            for &(c, v) in row.iter() {
                match out.last_mut() {
                    Some((lc, lv)) if *lc == c => *lv += v,
                    _ => out.push((c, v)),
                }
            }
            out
        })
        .collect()
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

/// Up to `steps` Jacobi steps of umbrella smoothing on the vertices of the
/// turned-over triangles `bad` (kept sorted and up to date).
fn smooth(
    tris: &[[u32; 3]],
    adj: &Adjacency,
    source: &[[f64; 3]],
    out: &mut [[f64; 3]],
    turn: &[DQuat],
    bad: &mut Vec<u32>,
    steps: usize,
) {
    let mut vs: Vec<u32> = Vec::new();
    let mut moved: Vec<[f64; 3]> = Vec::new();
    for _ in 0..steps {
        if bad.is_empty() {
            break;
        }
        vs.clear();
        vs.extend(bad.iter().flat_map(|&t| tris[t as usize]));
        vs.sort_unstable();
        vs.dedup();
        moved.clear();
        moved.extend(vs.iter().map(|&v| {
            let nb = &adj.vertices[v as usize];
            let s: DVec3 = nb.iter().map(|&u| DVec3::from_array(out[u as usize])).sum();
            (s / nb.len().max(1) as f64).to_array()
        }));
        for (&v, p) in vs.iter().zip(&moved) {
            out[v as usize] = *p;
        }
        for &v in &vs {
            bad.extend_from_slice(&adj.triangles[v as usize]);
        }
        recount(tris, source, out, turn, bad);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::subdivide::{icosahedron, midpoint};

    #[test]
    fn a_pushed_in_vertex_is_pulled_back_out() {
        let m = midpoint(&midpoint(&icosahedron()));
        let src = m.positions().to_vec();
        let mut out = src.clone();
        // Push one vertex through the opposite side: its fan turns over.
        out[0] = (DVec3::from_array(src[0]) * -0.5).to_array();
        let turn = vec![DQuat::IDENTITY; src.len()];
        let adj = Adjacency::new(src.len(), m.triangles());
        assert!(!turned_over(m.triangles(), &src, &out, &turn).is_empty());
        let opts = RepairOptions {
            rounds: 4,
            ..Default::default()
        };
        let bad = turned_over(m.triangles(), &src, &out, &turn);
        let before = bad.len();
        let after = unflip(m.triangles(), &adj, &src, &mut out, &turn, bad, &opts).len();
        assert!(before > 0 && after == 0, "{before} -> {after}");
        assert!(DVec3::from_array(out[0]).distance(DVec3::from_array(src[0])) < 1e-6);
    }

    /// With the rings bounded ([`RepairOptions::most_rings`]) no round's
    /// patch reaches past that many rings (plus its fixed ring) around the
    /// triangles turned over when it starts, every round's factorisation
    /// is counted, and generated folds (one to three vertices pushed
    /// through a sphere, at several depths) are still all turned back;
    /// without the bound the same rounds grow bigger patches.
    #[test]
    fn bounded_rings_keep_patches_small_and_still_unfold() {
        let m = midpoint(&midpoint(&midpoint(&icosahedron())));
        let (tris, src) = (m.triangles(), m.positions().to_vec());
        let adj = Adjacency::new(src.len(), tris);
        let turn = vec![DQuat::IDENTITY; src.len()];
        // Vertices within `r` rings of `seeds`.
        let within = |seeds: &[u32], r: usize| {
            let mut seen = vec![false; src.len()];
            let mut front: Vec<u32> = seeds.to_vec();
            for &v in seeds {
                seen[v as usize] = true;
            }
            for _ in 0..r {
                let mut next = Vec::new();
                for &v in &front {
                    for &u in &adj.vertices[v as usize] {
                        if !seen[u as usize] {
                            seen[u as usize] = true;
                            next.push(u);
                        }
                    }
                }
                front = next;
            }
            seen.iter().filter(|&&s| s).count()
        };
        let mut cases = 0;
        for pushed in [&[0u32][..], &[0, 7], &[0, 7, 40]] {
            for depth in [-0.2, -0.5, 0.3] {
                let mut out = src.clone();
                for &v in pushed {
                    out[v as usize] = (DVec3::from_array(src[v as usize]) * depth).to_array();
                }
                let bad = turned_over(tris, &src, &out, &turn);
                if bad.is_empty() {
                    continue;
                }
                cases += 1;
                let seeds: Vec<u32> = {
                    let mut s: Vec<u32> = bad.iter().flat_map(|&t| tris[t as usize]).collect();
                    s.sort_unstable();
                    s.dedup();
                    s
                };
                let run = |most_rings: usize, rounds: usize| {
                    let opts = RepairOptions {
                        rounds,
                        most_rings,
                        ..Default::default()
                    };
                    let mut o = out.clone();
                    let mut budget = Budget::new(WorkLimit::NONE);
                    let left = unflip_within(
                        tris,
                        &adj,
                        &src,
                        &mut o,
                        &turn,
                        bad.clone(),
                        &opts,
                        &mut budget,
                        None,
                    );
                    (left.len(), budget.done)
                };
                // One round: its patch is the seeds' 2 rings plus the fixed ring.
                let (_, one) = run(2, 1);
                assert_eq!(one.patches, 1);
                assert_eq!(one.patch_vertices, within(&seeds, 3), "{pushed:?} {depth}");
                let (left, capped) = run(2, 4);
                assert_eq!(left, 0, "{pushed:?} {depth}: left turned over");
                assert!(capped.patches >= 1 && capped.patches <= 4);
                // Each round's patch is within 3 rings of what it started
                // from, which the first round's seeds bound from above
                // only while the folds stay where they were: bound by the
                // whole mesh, and by the unbounded run's work.
                assert!(capped.patch_vertices <= capped.patches * src.len());
                let (left_all, all) = run(usize::MAX, 4);
                assert_eq!(left_all, 0);
                if all.patches == capped.patches && all.patches > 2 {
                    assert!(
                        capped.patch_vertices < all.patch_vertices,
                        "{pushed:?} {depth}: {capped:?} vs {all:?}"
                    );
                }
            }
        }
        assert!(cases >= 6, "only {cases} generated folds turned over");
    }

    /// A pass resumed from the kept state of a pass with one round fewer
    /// that started where it starts ([`Replay`]) gives the fresh pass's
    /// frame and triangles bit for bit, solving only the round it adds;
    /// over generated folds (one to three vertices pushed through a
    /// sphere at several depths), rings bounded and not, 1-4 rounds.
    #[test]
    fn a_replayed_pass_is_the_fresh_pass() {
        let m = midpoint(&midpoint(&midpoint(&icosahedron())));
        let (tris, src) = (m.triangles(), m.positions().to_vec());
        let adj = Adjacency::new(src.len(), tris);
        let turn = vec![DQuat::IDENTITY; src.len()];
        let (mut cases, mut moved) = (0, 0);
        for pushed in [&[0u32][..], &[0, 7], &[0, 7, 40], &[3, 90, 200]] {
            for depth in [-0.2, -0.5, 0.3, 0.6] {
                let mut start = src.clone();
                for &v in pushed {
                    start[v as usize] = (DVec3::from_array(src[v as usize]) * depth).to_array();
                }
                let bad = turned_over(tris, &src, &start, &turn);
                if bad.is_empty() {
                    continue;
                }
                for most_rings in [2, usize::MAX] {
                    for rounds in 1..4 {
                        cases += 1;
                        let opts = |rounds| RepairOptions {
                            rounds,
                            most_rings,
                            ..Default::default()
                        };
                        let run = |rounds, replay: Option<(&mut Replay, bool)>| {
                            let mut out = start.clone();
                            let mut budget = Budget::new(WorkLimit::NONE);
                            let left = unflip_within(
                                tris,
                                &adj,
                                &src,
                                &mut out,
                                &turn,
                                bad.clone(),
                                &opts(rounds),
                                &mut budget,
                                replay,
                            );
                            (out, left, budget.done)
                        };
                        let (fresh, fresh_left, fresh_work) = run(rounds + 1, None);
                        let mut kept = Replay::default();
                        let (first, _, first_work) = run(rounds, Some((&mut kept, false)));
                        moved += usize::from(first != start);
                        let (again, again_left, again_work) =
                            run(rounds + 1, Some((&mut kept, true)));
                        let bits = |p: &[[f64; 3]]| -> Vec<u64> {
                            p.iter().flatten().map(|c| c.to_bits()).collect()
                        };
                        assert_eq!(bits(&again), bits(&fresh), "{pushed:?} {depth} {rounds}");
                        assert_eq!(again_left, fresh_left, "{pushed:?} {depth} {rounds}");
                        assert_eq!(again_work.replayed_rounds, rounds);
                        // Only the added round is solved, when it runs.
                        assert!(again_work.patches <= 1);
                        assert_eq!(
                            again_work.patches + first_work.patches,
                            fresh_work.patches,
                            "{pushed:?} {depth} {rounds}"
                        );
                    }
                }
            }
        }
        assert!(cases >= 30 && moved > 0, "{cases} cases, {moved} moved");
    }

    /// The counting pass gives `to_rows`' matrix bit for bit on the repair
    /// patch's weights (whole numbers), over generated edge lists: a mesh's
    /// edges in triangle order, reversed, shuffled, with repeats and an
    /// isolated row; with weights that are not whole numbers, within a few
    /// units in the last place.
    #[test]
    fn counted_rows_are_the_sorted_triplets_rows() {
        use crate::mesh::laplacian::to_rows;
        let m = midpoint(&midpoint(&icosahedron()));
        let n = m.positions().len();
        let mut edges: Vec<(u32, u32, f64)> = Vec::new();
        for (k, t) in m.triangles().iter().enumerate() {
            for e in 0..3 {
                let w = if k % 3 == 0 { 4.0 } else { 1.0 };
                edges.push((t[e], t[(e + 1) % 3], w));
            }
        }
        let triplets = |edges: &[(u32, u32, f64)]| {
            let mut t = Vec::new();
            for &(i, j, w) in edges {
                t.extend([(i, i, w), (j, j, w), (i, j, -w), (j, i, -w)]);
            }
            t
        };
        let mut shuffled = edges.clone();
        let mut seed = 12345u64;
        for i in (1..shuffled.len()).rev() {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            shuffled.swap(i, (seed >> 33) as usize % (i + 1));
        }
        let reversed: Vec<_> = edges.iter().rev().copied().collect();
        let repeated: Vec<_> = edges.iter().chain(&edges[..40]).copied().collect();
        for (name, e, rows) in [
            ("mesh", &edges, n),
            ("reversed", &reversed, n),
            ("shuffled", &shuffled, n),
            ("repeated", &repeated, n),
            ("isolated row", &edges, n + 1),
        ] {
            let (a, b) = (edge_rows(rows, e), to_rows(rows, triplets(e)));
            assert_eq!(a.len(), b.len(), "{name}");
            for (r, (x, y)) in a.iter().zip(&b).enumerate() {
                assert_eq!(x.len(), y.len(), "{name}: row {r}");
                for (p, q) in x.iter().zip(y) {
                    assert!(
                        p.0 == q.0 && p.1.to_bits() == q.1.to_bits(),
                        "{name}: row {r}"
                    );
                }
            }
        }
        let odd: Vec<_> = shuffled.iter().map(|&(i, j, w)| (i, j, w * 0.3)).collect();
        for (x, y) in edge_rows(n, &odd).iter().zip(&to_rows(n, triplets(&odd))) {
            for (p, q) in x.iter().zip(y) {
                assert!(
                    p.0 == q.0 && (p.1 - q.1).abs() <= 1e-15 * q.1.abs(),
                    "{p:?} {q:?}"
                );
            }
        }
    }

    /// The frame's source normals, turned per reading, flag the same
    /// triangles as [`turned_over`] and give [`super::super::untangle::references`]'
    /// normals and areas bit for bit (a deformed, partly folded sphere under
    /// generated per-vertex turns).
    #[test]
    fn normals_once_per_frame_are_the_readings_own() {
        use super::super::untangle::{references, source_areas, turned_references};
        let m = midpoint(&midpoint(&midpoint(&icosahedron())));
        let (tris, src) = (m.triangles(), m.positions().to_vec());
        let nt = tris.len();
        let out: Vec<[f64; 3]> = src
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let v = DVec3::from_array(*p);
                (v * (1.0 + 0.3 * (i as f64 * 0.7).sin()) - DVec3::X * (0.4 * v.y).sin()).to_array()
            })
            .collect();
        let mut sn = vec![DVec3::ZERO; nt];
        source_normals(tris, &src, &mut sn);
        let mut seen = 0;
        for k in 0..4 {
            let turn: Vec<DQuat> = (0..src.len())
                .map(|i| DQuat::from_rotation_y(k as f64 * 0.9 + (i % 7) as f64 * 0.2))
                .collect();
            let bad = turned_over(tris, &src, &out, &turn);
            assert_eq!(turned_over_from(tris, &sn, &out, &turn), bad, "turns {k}");
            seen += bad.len();
            let (mut n0, mut a0) = (vec![DVec3::ZERO; nt], vec![0.0; nt]);
            references(tris, &src, &turn, &mut n0, &mut a0);
            let (mut n1, mut a1) = (vec![DVec3::ONE; nt], vec![1.0; nt]);
            turned_references(tris, &sn, &turn, &mut n1);
            source_areas(&sn, &mut a1);
            for t in 0..nt {
                assert_eq!(
                    n0[t].to_array().map(f64::to_bits),
                    n1[t].to_array().map(f64::to_bits)
                );
                assert_eq!(a0[t].to_bits(), a1[t].to_bits());
            }
        }
        assert!(
            seen > 0,
            "nothing turned over: the check has nothing to catch"
        );
    }

    #[test]
    fn rotated_triangles_are_not_turned_over() {
        let m = icosahedron();
        let src = m.positions().to_vec();
        let r = DQuat::from_rotation_x(2.5);
        let out: Vec<[f64; 3]> = src
            .iter()
            .map(|p| (r * DVec3::from_array(*p)).to_array())
            .collect();
        let turn = vec![r; src.len()];
        assert!(turned_over(m.triangles(), &src, &out, &turn).is_empty());
        let none = vec![DQuat::IDENTITY; src.len()];
        assert!(!turned_over(m.triangles(), &src, &out, &none).is_empty());
    }
}
