//! Shape measures: edges, edge lengths, enclosed volume, and the distortion
//! of an in-between mesh relative to its two inputs.

use super::Mesh;
use super::frames::dvec;
use serde::Serialize;

/// Unique undirected edges `(a, b)` with `a < b`.
pub fn edges(mesh: &Mesh) -> Vec<(u32, u32)> {
    let mut e: Vec<(u32, u32)> = mesh
        .triangles()
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k].min(t[(k + 1) % 3]), t[k].max(t[(k + 1) % 3]))))
        .filter(|(a, b)| a != b)
        .collect();
    e.sort_unstable();
    e.dedup();
    e
}

/// Length of each edge for the given positions.
pub fn edge_lengths(positions: &[[f64; 3]], edges: &[(u32, u32)]) -> Vec<f64> {
    edges
        .iter()
        .map(|&(a, b)| (dvec(positions[a as usize]) - dvec(positions[b as usize])).length())
        .collect()
}

/// Signed enclosed volume (divergence theorem; positive for outward-facing
/// counter-clockwise triangles of a closed mesh).
pub fn volume(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> f64 {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| dvec(positions[v as usize]));
            a.dot(b.cross(c)) / 6.0
        })
        .sum()
}

/// How far an in-between mesh is from the mean of its two inputs' shape.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Distortion {
    /// Mean over edges of `|l − l̄| / l̄`, with `l̄` the mean of the inputs' lengths.
    pub edge_length: f64,
    /// `|V − V̄| / |V̄|`, with `V̄` the mean of the inputs' volumes.
    pub volume: f64,
}

/// Distortion of `mid` relative to inputs `a` and `b` (same topology).
pub fn distortion(mesh: &Mesh, a: &[[f64; 3]], b: &[[f64; 3]], mid: &[[f64; 3]]) -> Distortion {
    let e = edges(mesh);
    let (la, lb, lm) = (
        edge_lengths(a, &e),
        edge_lengths(b, &e),
        edge_lengths(mid, &e),
    );
    let mut s = 0.0;
    let mut n = 0usize;
    for ((x, y), m) in la.iter().zip(&lb).zip(&lm) {
        let r = 0.5 * (x + y);
        if r > 0.0 {
            s += (m - r).abs() / r;
            n += 1;
        }
    }
    let t = mesh.triangles();
    let vr = 0.5 * (volume(a, t) + volume(b, t));
    let vm = volume(mid, t);
    Distortion {
        edge_length: s / n.max(1) as f64,
        volume: if vr != 0.0 {
            ((vm - vr) / vr).abs()
        } else {
            0.0
        },
    }
}
