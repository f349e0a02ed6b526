//! Lumped (diagonal) mass matrices, as libigl's `massmatrix`.
//!
//! Barycentric: each vertex gets a third of the area of its triangles.
//! Voronoi (libigl's default for triangles, Meyer et al. 2003): the mixed
//! Voronoi area — the circumcentric region for non-obtuse triangles, and for
//! an obtuse triangle half its area to the obtuse corner and a quarter to each
//! other corner.

use super::Mesh;

/// Which lumping.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum MassKind {
    /// A third of each incident triangle's area.
    Barycentric,
    /// Mixed Voronoi area (libigl default).
    #[default]
    Voronoi,
}

/// The diagonal of the mass matrix, one area per vertex (f64).
pub(crate) fn mass_diagonal(mesh: &Mesh, kind: MassKind) -> Vec<f64> {
    let p = mesh.positions();
    let mut m = vec![0.0; mesh.vertex_count()];
    for t in mesh.triangles() {
        let q = t.map(|v| glam::DVec3::from_array(p[v as usize]));
        let area = 0.5 * (q[1] - q[0]).cross(q[2] - q[0]).length();
        if area <= 0.0 || !area.is_finite() {
            continue;
        }
        match kind {
            MassKind::Barycentric => {
                for v in t {
                    m[*v as usize] += area / 3.0;
                }
            }
            MassKind::Voronoi => {
                // Squared lengths of the edges opposite each corner.
                let l2 = [
                    (q[1] - q[2]).length_squared(),
                    (q[2] - q[0]).length_squared(),
                    (q[0] - q[1]).length_squared(),
                ];
                // Cosines' signs: corner k is obtuse when l_k² > l_i² + l_j².
                let obtuse = (0..3).find(|&k| l2[k] > l2[(k + 1) % 3] + l2[(k + 2) % 3]);
                match obtuse {
                    Some(k) => {
                        m[t[k] as usize] += area / 2.0;
                        m[t[(k + 1) % 3] as usize] += area / 4.0;
                        m[t[(k + 2) % 3] as usize] += area / 4.0;
                    }
                    None => {
                        // Voronoi region of corner i: (l_j² cot_j + l_k² cot_k) / 8, with
                        // cot at corner k = (l_i² + l_j² − l_k²) / (4A).
                        let cot =
                            |k: usize| (l2[(k + 1) % 3] + l2[(k + 2) % 3] - l2[k]) / (4.0 * area);
                        for i in 0..3 {
                            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                            m[t[i] as usize] += (l2[k] * cot(k) + l2[j] * cot(j)) / 8.0;
                        }
                    }
                }
            }
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn masses_sum_to_the_area() {
        // One acute and one obtuse triangle (the second exercises the mixed rule).
        let p = vec![
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.5, 1.0, 0.0],
            [3.0, 0.25, 0.0],
        ];
        let m = Mesh::new(p, vec![[0, 1, 2], [1, 3, 2]]).unwrap();
        let area = 1.0 + 0.5 * (1.0f64 * 1.0 - 0.25 * -1.5).abs();
        for kind in [MassKind::Barycentric, MassKind::Voronoi] {
            let s: f64 = mass_diagonal(&m, kind).iter().sum();
            assert!((s - area).abs() < 1e-12, "{kind:?}: {s} vs {area}");
        }
    }
}
