//! Harmonic interpolation of scalar fields (libigl `harmonic`, k = 1): the
//! fields solve the cotangent Laplace equation `L x = 0` away from the
//! constrained vertices and take the given values there. Used by Confluent
//! Motion to spread marker quaternion components over a scan (de Aguiar et
//! al. 2007, Eq. 2). The reduced system is factored once; only the boundary
//! values change per call.

use super::Mesh;
use super::laplacian::cotan_triplets;
use super::solver::{FixedSolver, SolveError, Workspace};

/// A prefactored harmonic interpolator for one mesh and one constrained set.
pub struct Harmonic {
    solver: FixedSolver,
    n: usize,
}

/// Scratch for [`Harmonic::solve`] with `K` fields.
pub struct HarmonicWorkspace<const K: usize> {
    zeros: Vec<[f64; K]>,
    ws: Workspace,
}

impl Harmonic {
    /// Factors the system for `mesh` with `boundary` vertices constrained.
    /// Every connected component needs a boundary vertex.
    pub fn new(mesh: &Mesh, boundary: &[u32]) -> Result<Harmonic, SolveError> {
        let k: Vec<(u32, u32, f64)> = cotan_triplets(mesh)
            .into_iter()
            .map(|(i, j, v)| (i, j, -v))
            .collect();
        Ok(Harmonic {
            solver: FixedSolver::new(mesh.vertex_count(), k, boundary)?,
            n: mesh.vertex_count(),
        })
    }

    /// The constrained vertices, in the order of the values given to `solve`.
    pub fn boundary(&self) -> &[u32] {
        self.solver.fixed()
    }

    /// Scratch space for `K` fields.
    pub fn workspace<const K: usize>(&self) -> HarmonicWorkspace<K> {
        HarmonicWorkspace {
            zeros: vec![[0.0; K]; self.n],
            ws: self.solver.workspace(K),
        }
    }

    /// Interpolates `K` fields given their values at the boundary vertices.
    pub fn solve<const K: usize>(
        &self,
        values: &[[f64; K]],
        out: &mut [[f64; K]],
        ws: &mut HarmonicWorkspace<K>,
    ) {
        self.solver.solve(&ws.zeros, values, out, &mut ws.ws);
    }
}
