//! Vertices in no triangle ("stray" vertices: a capture cut by a script,
//! an exporter's leftover point) carried through the deformation.
//!
//! Every surface operator of the pipeline — the gradient-domain blend
//! (Casas 2013, Eq. 1-2; Huang 2015 Sec. 5.2.2), the part-based Laplacian
//! (Huang 2015 Eq. 32), the fold repair — is built from triangles, so a
//! vertex in none has no equation there. Instead of refusing such a mesh,
//! each stray vertex follows the referenced vertex nearest to it in the
//! reference (the rest frame): it keeps its offset from that vertex in a
//! frame the caller chooses, `x_s = x_n + (f_s − f_n)` — the blend
//! blends the inputs' offsets; the deformation turns the source's offset by
//! the carrier's skinning rotation, `x_s = x_n + R_n (f_s − f_n)`. Nothing is dropped, so the output keeps the input's vertex
//! count and numbering.

use glam::{DQuat, DVec3};

/// The stray vertices of a mesh, each with the referenced vertex that
/// carries it.
#[derive(Debug, Clone, PartialEq)]
pub struct StrayVertices {
    /// `(stray, carrier)` pairs, strays in increasing order.
    pairs: Vec<(u32, u32)>,
}

impl StrayVertices {
    /// The stray vertices of a mesh of `positions` and `triangles`, each
    /// paired with its nearest referenced vertex (ties: the lowest index).
    /// `None` when every vertex is in a triangle, or none is.
    pub fn of(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Option<StrayVertices> {
        let mut used = vec![false; positions.len()];
        for t in triangles {
            for &v in t {
                if let Some(u) = used.get_mut(v as usize) {
                    *u = true;
                }
            }
        }
        if used.iter().all(|&u| u) || !used.iter().any(|&u| u) {
            return None;
        }
        // Referenced vertices sorted by x: a stray's search walks out from
        // its own x both ways and stops once |Δx| alone exceeds the best.
        let mut by_x: Vec<u32> = (0..positions.len() as u32)
            .filter(|&v| used[v as usize])
            .collect();
        by_x.sort_by(|&a, &b| {
            positions[a as usize][0]
                .total_cmp(&positions[b as usize][0])
                .then(a.cmp(&b))
        });
        let pairs = (0..positions.len())
            .filter(|&v| !used[v])
            .map(|s| (s as u32, nearest(positions, &by_x, positions[s])))
            .collect();
        Some(StrayVertices { pairs })
    }

    /// How many vertices are stray.
    pub fn len(&self) -> usize {
        self.pairs.len()
    }

    /// Always false (an empty set is `None` from [`StrayVertices::of`]).
    pub fn is_empty(&self) -> bool {
        self.pairs.is_empty()
    }

    /// The `(stray, carrier)` pairs.
    pub fn pairs(&self) -> &[(u32, u32)] {
        &self.pairs
    }

    /// Places each stray vertex of `out` at its carrier's position in `out`
    /// plus its offset from the carrier in `from` (the frame `out` was
    /// deformed from). No allocation.
    pub fn carry(&self, from: &[[f64; 3]], out: &mut [[f64; 3]]) {
        for &(s, c) in &self.pairs {
            let (s, c) = (s as usize, c as usize);
            out[s] = std::array::from_fn(|d| out[c][d] + (from[s][d] - from[c][d]));
        }
    }

    /// [`StrayVertices::carry`] with each offset turned by its carrier's
    /// rotation in `turns` (one per vertex: the skinning's turn from `from`
    /// to `out`), so the offset keeps its length. No allocation.
    pub fn carry_turned(&self, from: &[[f64; 3]], turns: &[DQuat], out: &mut [[f64; 3]]) {
        for &(s, c) in &self.pairs {
            let (s, c) = (s as usize, c as usize);
            let o = turns[c] * (DVec3::from_array(from[s]) - DVec3::from_array(from[c]));
            out[s] = (DVec3::from_array(out[c]) + o).to_array();
        }
    }

    /// Each stray's offset from its carrier in `from`, in pair order, into
    /// `out` (cleared first), for [`StrayVertices::carry_offsets`] (a caller
    /// that keeps offsets, not frames: the blend).
    pub fn offsets_into(&self, from: &[[f64; 3]], out: &mut Vec<[f64; 3]>) {
        out.clear();
        out.extend(
            self.pairs
                .iter()
                .map(|&(s, c)| std::array::from_fn(|d| from[s as usize][d] - from[c as usize][d])),
        );
    }

    /// [`StrayVertices::carry`] with the offsets kept by
    /// [`StrayVertices::offsets_into`].
    pub fn carry_offsets(&self, offsets: &[[f64; 3]], out: &mut [[f64; 3]]) {
        for (&(s, c), o) in self.pairs.iter().zip(offsets) {
            out[s as usize] = std::array::from_fn(|d| out[c as usize][d] + o[d]);
        }
    }
}

/// The vertex of `by_x` (sorted by x) nearest to `q`; ties by index.
fn nearest(p: &[[f64; 3]], by_x: &[u32], q: [f64; 3]) -> u32 {
    let d2 = |v: u32| {
        let a = p[v as usize];
        (a[0] - q[0]).powi(2) + (a[1] - q[1]).powi(2) + (a[2] - q[2]).powi(2)
    };
    let start = by_x.partition_point(|&v| p[v as usize][0] < q[0]);
    let mut best = (f64::INFINITY, u32::MAX);
    let consider = |v: u32, best: &mut (f64, u32)| {
        let d = d2(v);
        if d < best.0 || (d == best.0 && v < best.1) {
            *best = (d, v);
        }
    };
    // Upwards, then downwards, each until the x gap alone is farther.
    for &v in &by_x[start..] {
        if (p[v as usize][0] - q[0]).powi(2) > best.0 {
            break;
        }
        consider(v, &mut best);
    }
    for &v in by_x[..start].iter().rev() {
        if (q[0] - p[v as usize][0]).powi(2) > best.0 {
            break;
        }
        consider(v, &mut best);
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of two triangles plus strays at chosen places.
    fn strip_with(strays: &[[f64; 3]]) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let mut p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ];
        p.extend_from_slice(strays);
        (p, vec![[0, 1, 2], [1, 3, 2]])
    }

    #[test]
    fn a_clean_mesh_has_none() {
        let (p, t) = strip_with(&[]);
        assert_eq!(StrayVertices::of(&p, &t), None);
        assert_eq!(StrayVertices::of(&p, &[]), None, "no triangle at all");
    }

    #[test]
    fn each_stray_is_carried_by_its_nearest_referenced_vertex() {
        let (p, t) = strip_with(&[[1.2, 0.9, 0.0], [-5.0, 0.1, 3.0], [0.6, 0.4, 0.0]]);
        let s = StrayVertices::of(&p, &t).unwrap();
        // Brute force agrees, whatever the order of the sweep.
        let brute = |q: [f64; 3]| {
            (0..4u32)
                .min_by(|&a, &b| {
                    let d = |v: u32| {
                        (0..3)
                            .map(|k| (p[v as usize][k] - q[k]).powi(2))
                            .sum::<f64>()
                    };
                    d(a).total_cmp(&d(b)).then(a.cmp(&b))
                })
                .unwrap()
        };
        for &(v, c) in s.pairs() {
            assert_eq!(c, brute(p[v as usize]), "stray {v}");
        }
        assert_eq!(s.pairs()[0], (4, 3));
        assert_eq!(s.len(), 3);
    }

    #[test]
    fn carrying_keeps_the_offset_in_the_source_frame() {
        let (p, t) = strip_with(&[[1.5, 1.0, 0.0]]);
        let s = StrayVertices::of(&p, &t).unwrap();
        // The source moved the strip by +2 in z and the stray with it;
        // the output moved the carrier (3) by +1 in x only.
        let from: Vec<[f64; 3]> = p.iter().map(|q| [q[0], q[1], q[2] + 2.0]).collect();
        let mut out: Vec<[f64; 3]> = p.iter().map(|q| [q[0] + 1.0, q[1], q[2]]).collect();
        out[4] = [f64::NAN; 3];
        s.carry(&from, &mut out);
        assert_eq!(out[4], [2.5, 1.0, 0.0]);
    }
}
