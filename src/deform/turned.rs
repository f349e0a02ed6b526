//! What a turned-over triangle is, and finding them (the fold repair's
//! test, `unflip`): a triangle is turned over when its normal
//! opposes the source triangle's normal turned by the triangle's
//! skin-blended rotation from the source skeleton to the target.

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

pub(crate) fn normal(t: &[u32; 3], p: &[[f64; 3]]) -> DVec3 {
    let [a, b, c] = t.map(|v| DVec3::from_array(p[v as usize]));
    (b - a).cross(c - a)
}

/// Whether triangle `t` of `out` is turned over against `source`.
#[inline]
pub(crate) fn is_turned_over(
    t: &[u32; 3],
    source: &[[f64; 3]],
    out: &[[f64; 3]],
    turn: &[DQuat],
) -> bool {
    (triangle_turn(t, turn) * normal(t, source)).dot(normal(t, out)) < 0.0
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

/// [`turned_over_from`] through `flags` (one per triangle, kept by the
/// caller): each triangle's test in parallel into its flag, then the
/// flagged ones listed in increasing order — the same list, with no
/// allocation but the list itself (none when nothing is turned over),
/// where the parallel `collect` allocated per chunk.
pub fn turned_over_flagged(
    tris: &[[u32; 3]],
    source_normals: &[DVec3],
    out: &[[f64; 3]],
    turn: &[DQuat],
    flags: &mut Vec<bool>,
) -> Vec<u32> {
    turned_over_flagged_in(tris, source_normals, out, turn, flags, Vec::new())
}

/// [`turned_over_flagged`] listed into `list` (cleared; its buffer
/// reused: no allocation when it holds the count, issue 45).
pub(crate) fn turned_over_flagged_in(
    tris: &[[u32; 3]],
    source_normals: &[DVec3],
    out: &[[f64; 3]],
    turn: &[DQuat],
    flags: &mut Vec<bool>,
    list: Vec<u32>,
) -> Vec<u32> {
    flags.resize(tris.len(), false);
    flags
        .par_iter_mut()
        .zip(tris.par_iter().zip(source_normals.par_iter()))
        .with_min_len(CHUNK)
        .for_each(|(b, (t, n))| *b = faces_against(t, *n, out, turn));
    flagged_into(flags, list)
}

/// The indices of the set `flags`, increasing, in `list` (cleared; grown
/// once to the count when it holds less, not at all when none is set).
pub(crate) fn flagged_into(flags: &[bool], mut list: Vec<u32>) -> Vec<u32> {
    list.clear();
    let count = flags.iter().filter(|&&b| b).count();
    if count == 0 {
        return list;
    }
    list.reserve_exact(count);
    list.extend((0..flags.len() as u32).filter(|&t| flags[t as usize]));
    list
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
