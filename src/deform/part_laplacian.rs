//! The Eq. 32 solver for one region (Huang et al. 2015, Sec. 5.2.3):
//!
//! `min_{r, x} ‖L x − δ₀ − E r‖² + ‖W_c (x − x_c)‖²`
//!
//! with `L` the region's uniform Laplacian, `δ₀ + E r` the deformation
//! space ([`super::pca`], orthonormal `E`) and `x_c` soft positional
//! constraints with weights `W_c`. The paper centres the space on the
//! examples' mean, `δ₀ = δ̄`; [`super`] centres it on the frame being
//! edited, `δ₀ = δ(x_s)`, so the captured detail of that frame is kept and
//! the learnt modes `E` say how it may change (with its own positions as
//! constraints a frame is returned unchanged). Eliminating
//! `r = Eᵀ(Lx − δ₀)` leaves `(LᵀL + WᵀW − U Uᵀ) x = Lᵀδ₀ − U Eᵀδ₀ + WᵀW x_c`
//! with `U = LᵀE` (ARCHITECTURE.md, Numerics). `S = LᵀL + WᵀW` is factored once; a frame
//! costs one prefactored solve `y₀ = S⁻¹ b` and the Woodbury correction
//! `x = y₀ + Z K Uᵀ y₀`, with `Z = S⁻¹ U` and `K = (I − UᵀZ)⁻¹` (an
//! `l × l` matrix) precomputed. Coordinates are coupled through `E`, so
//! the three are solved together.

use super::pca::Basis;
use crate::mesh::laplacian::uniform_region_rows;
use crate::mesh::solver::{FixedSolver, SolveError, Workspace};
use nalgebra::DMatrix;

/// A prefactored region.
pub(crate) struct RegionSolver {
    /// Global vertex ids of the region, in local order.
    pub vertices: Vec<u32>,
    /// Local constraint vertices and their weights.
    pub constraints: Vec<(u32, f64)>,
    lap: Vec<Vec<(u32, f64)>>,
    solver: FixedSolver,
    z: Vec<Vec<[f64; 3]>>,
    u: Vec<Vec<[f64; 3]>>,
    e: Vec<Vec<[f64; 3]>>,
    k: DMatrix<f64>,
}

/// Scratch of [`RegionSolver::solve`].
pub(crate) struct RegionWorkspace {
    rhs: Vec<[f64; 3]>,
    ws: Workspace,
    t: Vec<f64>,
}

/// `L x` for Laplacian rows.
pub fn apply(rows: &[Vec<(u32, f64)>], x: &[[f64; 3]], out: &mut [[f64; 3]]) {
    for (o, r) in out.iter_mut().zip(rows) {
        let mut s = [0.0; 3];
        for &(c, w) in r {
            for d in 0..3 {
                s[d] += w * x[c as usize][d];
            }
        }
        *o = s;
    }
}

/// `Lᵀ x` for symmetric Laplacian rows (the uniform Laplacian is symmetric).
fn apply_t(rows: &[Vec<(u32, f64)>], x: &[[f64; 3]], out: &mut [[f64; 3]]) {
    apply(rows, x, out)
}

fn dot(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
        .sum()
}

impl RegionSolver {
    /// Prefactors the region `vertices` (global ids) of a mesh with
    /// `triangles`, `vertex_count` vertices, constraints `(local index,
    /// weight)` and the deformation space `basis` (local rows).
    pub fn new(
        triangles: &[[u32; 3]],
        vertex_count: usize,
        vertices: Vec<u32>,
        constraints: Vec<(u32, f64)>,
        basis: &Basis,
    ) -> Result<RegionSolver, SolveError> {
        let n = vertices.len();
        let mut local = vec![u32::MAX; vertex_count];
        for (i, &v) in vertices.iter().enumerate() {
            local[v as usize] = i as u32;
        }
        let lap = uniform_region_rows(triangles, &local, n);
        // S = LᵀL + WᵀW (+ a tiny diagonal so an isolated vertex is not singular).
        let mut trip = Vec::new();
        for r in &lap {
            for &(a, wa) in r {
                for &(b, wb) in r {
                    trip.push((a, b, wa * wb));
                }
            }
        }
        for &(c, w) in &constraints {
            trip.push((c, c, w * w));
        }
        for i in 0..n as u32 {
            trip.push((i, i, 1e-10));
        }
        let solver = FixedSolver::definite(n, trip)?;
        let mut ws = solver.workspace(3);
        let mut u = Vec::with_capacity(basis.components.len());
        let mut z = Vec::with_capacity(basis.components.len());
        for e in &basis.components {
            let mut ue = vec![[0.0; 3]; n];
            apply_t(&lap, e, &mut ue);
            let mut ze = vec![[0.0; 3]; n];
            solver.solve::<3>(&ue, &[], &mut ze, &mut ws);
            u.push(ue);
            z.push(ze);
        }
        let l = u.len();
        let mut m = DMatrix::<f64>::identity(l, l);
        for i in 0..l {
            for j in 0..l {
                m[(i, j)] -= dot(&u[i], &z[j]);
            }
        }
        let k = m.try_inverse().ok_or_else(|| {
            SolveError::Factor("the deformation space makes Eq. 32 singular".into())
        })?;
        Ok(RegionSolver {
            vertices,
            constraints,
            lap,
            solver,
            z,
            u,
            e: basis.components.clone(),
            k,
        })
    }

    /// Scratch space.
    pub fn workspace(&self) -> RegionWorkspace {
        RegionWorkspace {
            rhs: vec![[0.0; 3]; self.vertices.len()],
            ws: self.solver.workspace(3),
            t: vec![0.0; self.u.len()],
        }
    }

    /// The region's Laplacian rows.
    pub fn laplacian(&self) -> &[Vec<(u32, f64)>] {
        &self.lap
    }

    /// Solves Eq. 32 centred on `delta` (the Laplacian coordinates `δ₀`, one
    /// per region vertex, in the basis's frame) with constraint targets
    /// `targets` (one per constraint) into `out` (one per region vertex).
    /// No allocation.
    pub fn solve(
        &self,
        delta: &[[f64; 3]],
        targets: &[[f64; 3]],
        out: &mut [[f64; 3]],
        ws: &mut RegionWorkspace,
    ) {
        // rhs = Lᵀδ₀ − U Eᵀδ₀ + WᵀW x_c.
        apply_t(&self.lap, delta, &mut ws.rhs);
        for (ue, e) in self.u.iter().zip(&self.e) {
            let c = dot(e, delta);
            for (r, uv) in ws.rhs.iter_mut().zip(ue) {
                for d in 0..3 {
                    r[d] -= c * uv[d];
                }
            }
        }
        for (&(c, w), t) in self.constraints.iter().zip(targets) {
            for (r, td) in ws.rhs[c as usize].iter_mut().zip(t) {
                *r += w * w * td;
            }
        }
        self.solver.solve::<3>(&ws.rhs, &[], out, &mut ws.ws);
        for (t, u) in ws.t.iter_mut().zip(&self.u) {
            *t = dot(u, out);
        }
        for (i, z) in self.z.iter().enumerate() {
            let s: f64 = (0..self.u.len()).map(|j| self.k[(i, j)] * ws.t[j]).sum();
            for (o, zv) in out.iter_mut().zip(z) {
                for d in 0..3 {
                    o[d] += s * zv[d];
                }
            }
        }
    }
}
