//! Poisson mesh reconstruction from per-triangle target transforms (the
//! gradient-domain step of de Aguiar et al. 2007, Eqs. 3-4, and the
//! Laplacian stitching of Casas et al. 2013, Eq. 2).
//!
//! Each triangle t asks that its edges become `T_t e`, with `e` its edges in
//! the reference mesh. Weighting the edge residuals by the reference's
//! half-cotangents,
//! `E(x) = Σ_t Σ_(i,j)∈t w_ij^t ‖(x_j − x_i) − T_t (p_j − p_i)‖²`,
//! whose minimiser solves `K x = b` with `K = −L` the cotangent Laplacian of
//! the reference (factored once per topology) and
//! `b_i = Σ w_ij^t T_t (p_i − p_j)`. This is the classical gradient-domain
//! Poisson equation: `∇ᵀ A ∇ = −L` and `∇ᵀ A (T ∇p)` is the divergence of
//! the target gradients. One vertex per connected component is anchored.

use super::Mesh;
use super::components::components;
use super::frames::dvec;
use super::laplacian::{cotan_triplets, half_cotangents};
use super::solver::{FixedSolver, SolveError, Workspace};
use glam::{DMat3, DVec3};

/// A prefactored Poisson reconstruction for one reference mesh.
pub struct Poisson {
    triangles: Vec<[u32; 3]>,
    /// Per triangle and corner k: `we_(k+2) − we_(k+1)` with
    /// `we_k = w_k · (p_(k+1) − p_(k+2))` the weighted reference edge facing
    /// corner k (see [`Poisson::corner_vectors`]).
    corner_vectors: Vec<[DVec3; 3]>,
    solver: FixedSolver,
    anchors: Vec<u32>,
    reference: Vec<[f64; 3]>,
}

/// Per-solve scratch for [`Poisson::solve`].
pub struct PoissonWorkspace {
    /// Right-hand side, one row per vertex.
    pub b: Vec<[f64; 3]>,
    anchor_values: Vec<[f64; 3]>,
    ws: Workspace,
}

impl Poisson {
    /// Factors the system for `reference`, anchoring the lowest vertex of each
    /// connected component. A vertex in no triangle has no equation: it is
    /// its own anchor (held at its reference position; the caller places
    /// it, [`crate::mesh::stray`]).
    pub fn new(reference: &Mesh) -> Result<Poisson, SolveError> {
        let c = components(reference);
        let mut anchors = vec![u32::MAX; c.count];
        let mut stray = Vec::new();
        for (v, &l) in c.label.iter().enumerate() {
            if l == u32::MAX {
                stray.push(v as u32);
            } else if anchors[l as usize] == u32::MAX {
                anchors[l as usize] = v as u32;
            }
        }
        anchors.append(&mut stray);
        Self::with_anchors(reference, &anchors)
    }

    /// Factors the system with the given anchor vertices (hard constraints).
    pub(crate) fn with_anchors(reference: &Mesh, anchors: &[u32]) -> Result<Poisson, SolveError> {
        let k: Vec<(u32, u32, f64)> = cotan_triplets(reference)
            .into_iter()
            .map(|(i, j, v)| (i, j, -v))
            .collect();
        let solver = FixedSolver::new(reference.vertex_count(), k, anchors)?;
        Ok(Self::from_solver(reference, solver, anchors))
    }

    fn from_solver(reference: &Mesh, solver: FixedSolver, anchors: &[u32]) -> Poisson {
        let p = reference.positions();
        let w = half_cotangents(p, reference.triangles());
        let weighted_edges: Vec<[DVec3; 3]> = reference
            .triangles()
            .iter()
            .zip(&w)
            .map(|(t, wt)| {
                std::array::from_fn(|k| {
                    let (i, j) = (t[(k + 1) % 3] as usize, t[(k + 2) % 3] as usize);
                    (dvec(p[i]) - dvec(p[j])) * wt[k]
                })
            })
            .collect();
        let corner_vectors = weighted_edges
            .iter()
            .map(|we| std::array::from_fn(|k| we[(k + 2) % 3] - we[(k + 1) % 3]))
            .collect();
        Poisson {
            triangles: reference.triangles().to_vec(),
            corner_vectors,
            solver,
            anchors: anchors.to_vec(),
            reference: p.iter().map(|&q| dvec(q).to_array()).collect(),
        }
    }

    /// Factors the system with no anchor and the centroid of each of
    /// `triangles` pulled towards a target with weight `weight` (soft
    /// constraints): `E(x) + weight Σ_m ‖c_m(x) − t_m‖²`, `c_m` the mean of
    /// triangle m's corners. Definite when every connected component has
    /// one of `triangles`; [`Poisson::pull_centroids`] adds the targets to
    /// `b` before [`Poisson::solve`].
    pub(crate) fn with_soft_centroids(
        reference: &Mesh,
        triangles: &[[u32; 3]],
        weight: f64,
    ) -> Result<Poisson, SolveError> {
        let mut k: Vec<(u32, u32, f64)> = cotan_triplets(reference)
            .into_iter()
            .map(|(i, j, v)| (i, j, -v))
            .collect();
        let w = weight / 9.0;
        for t in triangles {
            for &a in t {
                for &b in t {
                    k.push((a, b, w));
                }
            }
        }
        let solver = FixedSolver::definite(reference.vertex_count(), k)?;
        Ok(Self::from_solver(reference, solver, &[]))
    }

    /// Adds the pull of [`Poisson::with_soft_centroids`] towards `targets`
    /// (one per triangle, in its order) to the assembled `ws.b`.
    pub(crate) fn pull_centroids(
        ws: &mut PoissonWorkspace,
        triangles: &[[u32; 3]],
        targets: &[DVec3],
        weight: f64,
    ) {
        for (t, c) in triangles.iter().zip(targets) {
            let d = *c * (weight / 3.0);
            for &v in t {
                let r = &mut ws.b[v as usize];
                r[0] += d.x;
                r[1] += d.y;
                r[2] += d.z;
            }
        }
    }

    /// The reference triangles.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The anchored vertices.
    pub fn anchors(&self) -> &[u32] {
        &self.anchors
    }

    /// Scratch space for solves.
    pub fn workspace(&self) -> PoissonWorkspace {
        PoissonWorkspace {
            b: vec![[0.0; 3]; self.reference.len()],
            anchor_values: vec![[0.0; 3]; self.anchors.len()],
            ws: self.solver.workspace(3),
        }
    }

    /// Assembles `b` from per-triangle transforms into `ws.b`.
    pub fn assemble(&self, transforms: &[DMat3], ws: &mut PoissonWorkspace) {
        self.assemble_with(ws, |t| transforms[t]);
    }

    /// Assembles `b` with the transform of triangle `t` given by `f(t)`, so
    /// callers can compute transforms on the fly without storing them.
    #[inline]
    pub(crate) fn assemble_with(
        &self,
        ws: &mut PoissonWorkspace,
        mut f: impl FnMut(usize) -> DMat3,
    ) {
        ws.b.iter_mut().for_each(|r| *r = [0.0; 3]);
        for (ti, (t, g)) in self.triangles.iter().zip(&self.corner_vectors).enumerate() {
            let m = f(ti);
            for (&v, gk) in t.iter().zip(g) {
                let d = m * *gk;
                let r = &mut ws.b[v as usize];
                r[0] += d.x;
                r[1] += d.y;
                r[2] += d.z;
            }
        }
    }

    /// Per triangle and corner k: the vector `g_k` whose image `T_t g_k` is
    /// corner k's share of `b` (the two weighted edges meeting at corner k,
    /// `w_(k+2) e_(k+2) − w_(k+1) e_(k+1)`).
    pub(crate) fn corner_vectors(&self) -> &[[DVec3; 3]] {
        &self.corner_vectors
    }

    /// Assembles `b` from per-triangle corner shares already mapped:
    /// `shares[t][k] = T_t · corner_vectors()[t][k]`. Three scattered
    /// additions per triangle.
    pub(crate) fn assemble_shares(&self, shares: &[[DVec3; 3]], ws: &mut PoissonWorkspace) {
        ws.b.iter_mut().for_each(|r| *r = [0.0; 3]);
        for (t, sh) in self.triangles.iter().zip(shares) {
            for (&v, d) in t.iter().zip(sh) {
                let r = &mut ws.b[v as usize];
                r[0] += d.x;
                r[1] += d.y;
                r[2] += d.z;
            }
        }
    }

    /// Solves with the current `ws.b`; anchors take their reference positions.
    /// Writes positions into `out` (n rows). No allocation.
    pub fn solve(&self, ws: &mut PoissonWorkspace, out: &mut [[f64; 3]]) {
        for (a, &v) in ws.anchor_values.iter_mut().zip(&self.anchors) {
            *a = self.reference[v as usize];
        }
        self.solver.solve(&ws.b, &ws.anchor_values, out, &mut ws.ws);
    }

    /// The mesh whose triangles best follow `transforms` (one 3×3 map per
    /// triangle, from the reference). Translation is fixed by the anchors.
    pub fn reconstruct(
        &self,
        transforms: &[DMat3],
        ws: &mut PoissonWorkspace,
        out: &mut [[f64; 3]],
    ) {
        self.assemble(transforms, ws);
        self.solve(ws, out);
    }
}

/// Mean of a set of points.
pub fn centroid(p: &[[f64; 3]]) -> DVec3 {
    let s: DVec3 = p.iter().map(|q| DVec3::from_array(*q)).sum();
    s / p.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::frames::RestFrames;

    fn icosphere() -> Mesh {
        crate::mesh::subdivide::icosahedron()
    }

    #[test]
    fn own_gradients_reconstruct_the_mesh() {
        let rest = icosphere();
        let mut def: Vec<[f64; 3]> = rest.positions().to_vec();
        for (i, p) in def.iter_mut().enumerate() {
            p[0] *= 1.0 + 0.1 * (i % 3) as f64;
            p[1] += 0.05 * (i % 5) as f64;
        }
        let poisson = Poisson::new(&rest).unwrap();
        let g =
            RestFrames::new(rest.positions(), rest.triangles()).gradients(&def, rest.triangles());
        let mut ws = poisson.workspace();
        let mut out = vec![[0.0; 3]; 12];
        poisson.reconstruct(&g, &mut ws, &mut out);
        // Anchored at the reference's vertex 0: compare up to translation.
        let shift = DVec3::from_array(out[0]) - dvec(def[0]);
        for (o, d) in out.iter().zip(&def) {
            assert!((DVec3::from_array(*o) - shift - dvec(*d)).length() < 1e-9);
        }
    }

    #[test]
    fn a_component_without_anchor_is_an_error_not_nan() {
        let m = icosphere();
        let r = Poisson::with_anchors(&m, &[]);
        assert!(matches!(
            r,
            Err(SolveError::UnanchoredComponent { component: 0, .. })
        ));
        let mut p = m.positions().to_vec();
        p.push([9.0, 9.0, 9.0]);
        let loose = Mesh::new(p, m.triangles().to_vec()).unwrap();
        assert!(matches!(
            Poisson::with_anchors(&loose, &[0]),
            Err(SolveError::Isolated { vertex: 12 })
        ));
    }

    #[test]
    fn a_vertex_in_no_triangle_is_held_and_the_rest_solved_as_without_it() {
        let m = icosphere();
        let mut p = m.positions().to_vec();
        p.push([9.0, 9.0, 9.0]);
        let loose = Mesh::new(p, m.triangles().to_vec()).unwrap();
        let (a, b) = (Poisson::new(&m).unwrap(), Poisson::new(&loose).unwrap());
        assert_eq!(b.anchors(), &[0, 12]);
        let g = vec![DMat3::from_diagonal(DVec3::new(1.1, 0.9, 1.0)); m.triangles().len()];
        let (mut wa, mut wb) = (a.workspace(), b.workspace());
        let (mut xa, mut xb) = (vec![[0.0; 3]; 12], vec![[0.0; 3]; 13]);
        a.reconstruct(&g, &mut wa, &mut xa);
        b.reconstruct(&g, &mut wb, &mut xb);
        for (p, q) in xa.iter().zip(&xb) {
            assert!((DVec3::from_array(*p) - DVec3::from_array(*q)).length() < 1e-12);
        }
        assert_eq!(xb[12], [9.0, 9.0, 9.0]);
    }
}
