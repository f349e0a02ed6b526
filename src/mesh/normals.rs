//! Area-weighted vertex normals.
//!
//! `n_v = normalize(Σ_{t ∋ v} (p1 − p0) × (p2 − p0))`: each incident triangle
//! contributes its unnormalised face normal, whose length is twice its area
//! (the "area-weighted" normal of Max, *Weights for Computing Vertex Normals
//! from Facet Normals*, JGT 1999, and of libigl's
//! `per_vertex_normals(..., PER_VERTEX_NORMALS_WEIGHTING_TYPE_AREA, ...)`).
//! Outward for a closed mesh whose triangles wind counter-clockwise seen from
//! outside (the OBJ/glTF convention). O(#V + #T).

use glam::DVec3;

/// Writes one normal per vertex into `out` (resized to `positions.len()`):
/// unit length, or zero where a vertex has no triangle of non-zero area
/// (isolated or only on degenerate triangles; the caller picks a fallback).
/// Triangles naming a vertex past `positions` are skipped. `out` is reused
/// across calls so a per-frame loop does not allocate.
pub(crate) fn vertex_normals_into(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    out: &mut Vec<[f64; 3]>,
) {
    out.clear();
    out.resize(positions.len(), [0.0; 3]);
    let n = positions.len();
    for t in triangles {
        let [a, b, c] = t.map(|i| i as usize);
        if a >= n || b >= n || c >= n {
            continue;
        }
        let p0 = DVec3::from_array(positions[a]);
        let face =
            (DVec3::from_array(positions[b]) - p0).cross(DVec3::from_array(positions[c]) - p0);
        for v in [a, b, c] {
            let o = &mut out[v];
            o[0] += face.x;
            o[1] += face.y;
            o[2] += face.z;
        }
    }
    for o in out.iter_mut() {
        *o = DVec3::from_array(*o).normalize_or_zero().to_array();
    }
}

/// Area-weighted unit vertex normals (zero where undefined); see
/// [`vertex_normals_into`].
pub fn vertex_normals(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<[f64; 3]> {
    let mut out = Vec::new();
    vertex_normals_into(positions, triangles, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit cube, triangles wound counter-clockwise from outside.
    fn cube() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let p = (0..8)
            .map(|i| [(i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64])
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (p, t)
    }

    #[test]
    fn cube_corner_normals_point_out_of_the_centre_and_are_unit() {
        let (p, t) = cube();
        let n = vertex_normals(&p, &t);
        for (v, q) in p.iter().enumerate() {
            let out = DVec3::from_array(*q) - DVec3::splat(0.5);
            let nv = DVec3::from_array(n[v]);
            assert!((nv.length() - 1.0).abs() < 1e-12, "vertex {v}");
            assert!(nv.dot(out.normalize()) > 0.5, "vertex {v}: {nv} vs {out}");
        }
    }

    #[test]
    fn isolated_and_degenerate_vertices_get_zero() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [5.0; 3]];
        let n = vertex_normals(&p, &[[0, 1, 2], [0, 1, 9]]);
        assert!(n.iter().all(|v| *v == [0.0; 3]), "{n:?}");
    }
}
