//! A decimated copy of a triangle mesh for the tests' generated variants
//! (a capture at a lower resolution than the one a rig was tuned on).
//!
//! Half-edge collapses, shortest edges first: a collapse removes vertex
//! `v` into its neighbour `u`, so every vertex kept stays where it was and
//! a capture's frames decimate by dropping the removed vertices. A collapse
//! is made only when it keeps the surface a manifold of the same topology
//! (the link condition of Dey et al. 1999: the two vertices' common
//! neighbours are exactly the edge's two opposite vertices), never at a
//! boundary, never turning a triangle of `v`'s fan by more than 60° or to
//! a sliver, and at most once per neighbourhood a pass (so the
//! resolution falls evenly). Test code: for a library simplifier see
//! meshoptimizer or QEM (Garland & Heckbert 1997).

use std::collections::BTreeSet;
use surfmotion::mesh::Mesh;

/// `mesh` with about `keep` of its vertices (0 < keep ≤ 1) and, for each
/// vertex of the result, the index of the original vertex it is.
pub fn decimate(mesh: &Mesh, keep: f64) -> (Mesh, Vec<u32>) {
    let p = mesh.positions();
    let n = p.len();
    let mut tris: Vec<[u32; 3]> = mesh.triangles().to_vec();
    let mut alive_t = vec![true; tris.len()];
    let mut fan: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (t, tri) in tris.iter().enumerate() {
        for &v in tri {
            fan[v as usize].push(t as u32);
        }
    }
    let mut alive_v = vec![true; n];
    let mut left = n;
    let target = ((n as f64) * keep.clamp(0.0, 1.0)).ceil() as usize;
    while left > target {
        let mut edges: Vec<(f64, u32, u32)> = Vec::new();
        for (t, tri) in tris.iter().enumerate() {
            if !alive_t[t] {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if a < b {
                    edges.push((dist(p, a, b), a, b));
                }
            }
        }
        edges.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut touched = vec![false; n];
        let mut made = 0;
        for &(_, a, b) in &edges {
            if left <= target {
                break;
            }
            for (u, v) in [(a, b), (b, a)] {
                if touched[u as usize] || touched[v as usize] {
                    break;
                }
                if !collapsible(p, &tris, &alive_t, &fan, u, v) {
                    continue;
                }
                for &t in &fan[v as usize] {
                    for &w in &tris[t as usize] {
                        touched[w as usize] = true;
                    }
                }
                collapse(&mut tris, &mut alive_t, &mut fan, u, v);
                alive_v[v as usize] = false;
                left -= 1;
                made += 1;
                break;
            }
        }
        if made == 0 {
            break;
        }
    }
    let kept: Vec<u32> = (0..n as u32).filter(|&v| alive_v[v as usize]).collect();
    let mut local = vec![u32::MAX; n];
    for (i, &v) in kept.iter().enumerate() {
        local[v as usize] = i as u32;
    }
    let out_tris = tris
        .iter()
        .zip(&alive_t)
        .filter(|(_, a)| **a)
        .map(|(t, _)| t.map(|v| local[v as usize]))
        .collect();
    let positions = kept.iter().map(|&v| p[v as usize]).collect();
    (Mesh::new(positions, out_tris).unwrap(), kept)
}

fn dist(p: &[[f64; 3]], a: u32, b: u32) -> f64 {
    let (x, y) = (p[a as usize], p[b as usize]);
    ((x[0] - y[0]).powi(2) + (x[1] - y[1]).powi(2) + (x[2] - y[2]).powi(2)).sqrt()
}

fn neighbours(tris: &[[u32; 3]], fan: &[u32], v: u32) -> BTreeSet<u32> {
    fan.iter()
        .flat_map(|&t| tris[t as usize])
        .filter(|&w| w != v)
        .collect()
}

/// Whether `v` may be removed into `u` (see the module's rules).
fn collapsible(
    p: &[[f64; 3]],
    tris: &[[u32; 3]],
    alive_t: &[bool],
    fan: &[Vec<u32>],
    u: u32,
    v: u32,
) -> bool {
    let (fu, fv) = (&fan[u as usize], &fan[v as usize]);
    let shared: Vec<u32> = fv
        .iter()
        .copied()
        .filter(|&t| tris[t as usize].contains(&u))
        .collect();
    if shared.len() != 2 || !fv.iter().all(|&t| alive_t[t as usize]) {
        return false;
    }
    // Boundary: an edge of v's fan in only one of its triangles.
    let nv = neighbours(tris, fv, v);
    for &w in &nv {
        let count = fv
            .iter()
            .filter(|&&t| tris[t as usize].contains(&w))
            .count();
        if count != 2 {
            return false;
        }
    }
    let opposite: BTreeSet<u32> = shared
        .iter()
        .flat_map(|&t| tris[t as usize])
        .filter(|&w| w != u && w != v)
        .collect();
    let nu = neighbours(tris, fu, u);
    let common: BTreeSet<u32> = nu.intersection(&nv).copied().collect();
    if common != opposite || opposite.len() != 2 {
        return false;
    }
    fv.iter().filter(|t| !shared.contains(t)).all(|&t| {
        let tri = tris[t as usize];
        let moved = tri.map(|w| if w == v { u } else { w });
        let (a, b) = (normal(p, tri), normal(p, moved));
        let (la, lb) = (len(a), len(b));
        la > 0.0 && lb > 0.05 * la && dot(a, b) > 0.5 * la * lb
    })
}

/// Removes `v` into `u`: the two triangles of edge `uv` die, `v`'s other
/// triangles take `u`.
fn collapse(tris: &mut [[u32; 3]], alive_t: &mut [bool], fan: &mut [Vec<u32>], u: u32, v: u32) {
    let fv = std::mem::take(&mut fan[v as usize]);
    for &t in &fv {
        let tri = &mut tris[t as usize];
        if tri.contains(&u) {
            alive_t[t as usize] = false;
            for w in *tri {
                fan[w as usize].retain(|&x| x != t);
            }
        } else {
            for w in tri.iter_mut() {
                if *w == v {
                    *w = u;
                }
            }
            fan[u as usize].push(t);
        }
    }
}

fn normal(p: &[[f64; 3]], t: [u32; 3]) -> [f64; 3] {
    let [a, b, c] = t.map(|v| p[v as usize]);
    let (e, f) = (
        [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
        [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
    );
    [
        e[1] * f[2] - e[2] * f[1],
        e[2] * f[0] - e[0] * f[2],
        e[0] * f[1] - e[1] * f[0],
    ]
}

fn len(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Every edge of `mesh` in exactly two triangles (closed and manifold at
/// its edges) and its Euler characteristic `V − E + F`.
pub fn closed_euler(mesh: &Mesh) -> (bool, i64) {
    let mut edges = std::collections::BTreeMap::new();
    for t in mesh.triangles() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let closed = edges.values().all(|&c| c == 2);
    let chi = mesh.positions().len() as i64 - edges.len() as i64 + mesh.triangles().len() as i64;
    (closed, chi)
}
