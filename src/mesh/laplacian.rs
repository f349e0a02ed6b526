//! Discrete Laplacians of a triangle mesh.
//!
//! The cotangent Laplacian follows libigl's `cotmatrix`: #V by #V, symmetric,
//! off-diagonal `L_ij = (cot α_ij + cot β_ij) / 2` over the two angles facing
//! edge ij, diagonal minus the sum of the off-diagonals, so `L · 1 = 0` and
//! L is negative semi-definite. Computed in f64 from the f64 positions.
//! Per triangle, half the cotangent of the angle at corner k is
//! `(l_i² + l_j² − l_k²) / (8 A)` with `l_k` the length of the edge facing k
//! and `A` the area; a zero-area triangle contributes nothing.

use super::Mesh;

/// Half-cotangent weights of each triangle: entry k is `cot(angle at corner k) / 2`,
/// the weight of the edge opposite corner k (between corners k+1 and k+2).
pub(crate) fn half_cotangents(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Vec<[f64; 3]> {
    triangles
        .iter()
        .map(|t| {
            let p = t.map(|v| positions[v as usize]);
            let e = |a: usize, b: usize| [p[b][0] - p[a][0], p[b][1] - p[a][1], p[b][2] - p[a][2]];
            // Edge opposite corner k.
            let opp = [e(1, 2), e(2, 0), e(0, 1)];
            let l2 = opp.map(|v| v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
            let (u, w) = (opp[2], opp[1]);
            let c = [
                u[1] * w[2] - u[2] * w[1],
                u[2] * w[0] - u[0] * w[2],
                u[0] * w[1] - u[1] * w[0],
            ];
            let dbl_area = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
            if dbl_area <= f64::MIN_POSITIVE || !dbl_area.is_finite() {
                return [0.0; 3];
            }
            // cot(angle k) / 2 = (l_i² + l_j² − l_k²) / (4 · 2A)
            [
                (l2[1] + l2[2] - l2[0]) / (4.0 * dbl_area),
                (l2[2] + l2[0] - l2[1]) / (4.0 * dbl_area),
                (l2[0] + l2[1] - l2[2]) / (4.0 * dbl_area),
            ]
        })
        .collect()
}

/// A sparse symmetric matrix as summed triplets `(row, col, value)`.
pub(crate) type Triplets = Vec<(u32, u32, f64)>;

/// Triplets of the cotangent Laplacian (libigl sign: negative semi-definite).
/// Duplicates are meant to be summed.
pub fn cotan_triplets(mesh: &Mesh) -> Triplets {
    let w = half_cotangents(mesh.positions(), mesh.triangles());
    let mut out = Vec::with_capacity(mesh.triangle_count() * 12);
    for (t, wt) in mesh.triangles().iter().zip(&w) {
        for k in 0..3 {
            let (i, j) = (t[(k + 1) % 3], t[(k + 2) % 3]);
            let c = wt[k];
            out.push((i, j, c));
            out.push((j, i, c));
            out.push((i, i, -c));
            out.push((j, j, -c));
        }
    }
    out
}

/// Triplets of the uniform (graph) Laplacian: `L_ij = 1` per edge, diagonal
/// minus the degree.
#[cfg(test)]
pub(crate) fn uniform_triplets(mesh: &Mesh) -> Triplets {
    uniform_triplets_by(mesh.triangles(), Some)
}

/// Triplets of the uniform Laplacian of the edges of `triangles` with both
/// ends kept by `index` (which maps a vertex to its row, or `None` to drop
/// it): each edge once, `(a, b, 1), (b, a, 1), (a, a, −1), (b, b, −1)`, in
/// sorted edge order. The one implementation behind `uniform_triplets`
/// and [`uniform_region_rows`].
fn uniform_triplets_by(triangles: &[[u32; 3]], index: impl Fn(u32) -> Option<u32>) -> Triplets {
    let mut edges: Vec<(u32, u32)> = Vec::with_capacity(triangles.len() * 3);
    for t in triangles {
        for k in 0..3 {
            if let (Some(a), Some(b)) = (index(t[k]), index(t[(k + 1) % 3]))
                && a != b
            {
                edges.push((a.min(b), a.max(b)));
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    let mut out = Vec::with_capacity(edges.len() * 4);
    for (a, b) in edges {
        out.extend([(a, b, 1.0), (b, a, 1.0), (a, a, -1.0), (b, b, -1.0)]);
    }
    out
}

/// The uniform Laplacian rows (see [`to_rows`]) of a region of a mesh: the
/// edges of `triangles` with both ends in the region, `local[v]` being
/// vertex v's index in the region or `u32::MAX` outside it; `n` region
/// vertices, so `n` rows. Used per body part by the part-based deformation
/// (Huang et al. 2015, Eq. 32).
pub fn uniform_region_rows(
    triangles: &[[u32; 3]],
    local: &[u32],
    n: usize,
) -> Vec<Vec<(u32, f64)>> {
    let trip = uniform_triplets_by(triangles, |v| {
        let l = local[v as usize];
        (l != u32::MAX).then_some(l)
    });
    to_rows(n, trip)
}

/// Sums duplicate triplets and returns compressed rows: for each row, its
/// `(col, value)` pairs sorted by column.
pub fn to_rows(n: usize, mut t: Triplets) -> Vec<Vec<(u32, f64)>> {
    t.sort_unstable_by_key(|&(r, c, _)| (r, c));
    let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
    for (r, c, v) in t {
        let row = &mut rows[r as usize];
        match row.last_mut() {
            Some((lc, lv)) if *lc == c => *lv += v,
            _ => row.push((c, v)),
        }
    }
    rows
}

/// `y = L x` for a row-compressed matrix and `k` columns stored per row
/// (`x[i]` is a `[f64; K]`).
pub fn mul<const K: usize>(rows: &[Vec<(u32, f64)>], x: &[[f64; K]]) -> Vec<[f64; K]> {
    rows.iter()
        .map(|r| {
            let mut s = [0.0; K];
            for &(c, v) in r {
                for k in 0..K {
                    s[k] += v * x[c as usize][k];
                }
            }
            s
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A regular octahedron: every edge has weight 1/√3·… and rows sum to zero.
    fn octa() -> Mesh {
        let p = vec![
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
        ];
        let t = vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ];
        Mesh::new(p, t).unwrap()
    }

    #[test]
    fn rows_sum_to_zero_and_matrix_is_symmetric() {
        for trip in [cotan_triplets(&octa()), uniform_triplets(&octa())] {
            let rows = to_rows(6, trip);
            for (i, r) in rows.iter().enumerate() {
                let s: f64 = r.iter().map(|x| x.1).sum();
                assert!(s.abs() < 1e-12);
                for &(j, v) in r {
                    let back = rows[j as usize]
                        .iter()
                        .find(|x| x.0 as usize == i)
                        .unwrap()
                        .1;
                    assert!((back - v).abs() < 1e-15);
                }
            }
        }
    }

    /// Regression (issue 19): the region Laplacian of the part-based
    /// deformation was a second implementation of the uniform Laplacian.
    /// The shared one gives, for the whole mesh, exactly the rows of
    /// [`uniform_triplets`], and for a region exactly the rows of the
    /// former `deform::part_laplacian::region_laplacian` (kept here as the
    /// reference).
    #[test]
    fn uniform_region_rows_equal_the_former_region_laplacian() {
        fn former(triangles: &[[u32; 3]], local: &[u32], n: usize) -> Vec<Vec<(u32, f64)>> {
            let mut edges = Vec::new();
            for t in triangles {
                for k in 0..3 {
                    let (a, b) = (local[t[k] as usize], local[t[(k + 1) % 3] as usize]);
                    if a != u32::MAX && b != u32::MAX && a != b {
                        edges.push((a.min(b), a.max(b)));
                    }
                }
            }
            edges.sort_unstable();
            edges.dedup();
            let mut trip = Vec::with_capacity(edges.len() * 4);
            for (a, b) in edges {
                trip.extend([(a, b, 1.0), (b, a, 1.0), (a, a, -1.0), (b, b, -1.0)]);
            }
            to_rows(n, trip)
        }
        let m = octa();
        let all: Vec<u32> = (0..6).collect();
        let whole = uniform_region_rows(m.triangles(), &all, 6);
        assert_eq!(whole, to_rows(6, uniform_triplets(&m)));
        assert_eq!(whole, former(m.triangles(), &all, 6));
        // A region of four vertices in a shuffled local order.
        let local = [2, u32::MAX, 0, 3, 1, u32::MAX];
        let region = uniform_region_rows(m.triangles(), &local, 4);
        assert_eq!(region, former(m.triangles(), &local, 4));
        // Vertices 0, 2, 3, 4 of the octahedron: edges 0-2, 0-3, 0-4, 2-4, 3-4.
        let degrees: Vec<f64> = region
            .iter()
            .enumerate()
            .map(|(i, r)| -r.iter().find(|x| x.0 as usize == i).unwrap().1)
            .collect();
        assert_eq!(degrees, vec![2.0, 3.0, 3.0, 2.0]);
        for r in &region {
            assert_eq!(r.iter().map(|x| x.1).sum::<f64>(), 0.0);
        }
    }

    #[test]
    fn equilateral_weights_are_cot_60_over_2() {
        let h = 3f64.sqrt() / 2.0;
        let w = half_cotangents(
            &[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, h, 0.0]],
            &[[0, 1, 2]],
        );
        for c in w[0] {
            assert!((c - 0.5 / 3f64.sqrt()).abs() < 1e-7);
        }
        assert_eq!(
            half_cotangents(&[[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]], &[[0, 1, 2]])[0],
            [0.0; 3]
        );
    }
}
