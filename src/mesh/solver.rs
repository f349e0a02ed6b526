//! Factor once, solve many: a sparse symmetric positive (semi-)definite
//! quadratic minimised with some unknowns fixed (libigl's
//! `min_quad_with_fixed`).
//!
//! `minimise ½ xᵀ K x − bᵀ x  subject to  x_C = c` gives
//! `K_FF x_F = b_F − K_FC c`. `K_FF` is factored once (faer sparse Cholesky
//! with a fill-reducing ordering, `Par::Seq`); a solve for `k` right-hand
//! sides costs two triangular sweeps and allocates nothing when given a
//! [`Workspace`].

use super::laplacian::{Triplets, to_rows};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{SymbolicCholesky, factorize_symbolic_cholesky};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, Mat, Par, Side};

/// Why a system cannot be factored.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// A connected component has no fixed vertex: its solution is not unique.
    #[error(
        "connected component {component} ({vertices} vertices, first vertex {first_vertex}) has no anchor: fix one of its vertices, or repair the mesh"
    )]
    UnanchoredComponent {
        /// Component number.
        component: usize,
        /// Its vertex count.
        vertices: usize,
        /// Its lowest vertex index.
        first_vertex: u32,
    },
    /// A vertex is in no triangle (its row of K is empty).
    #[error(
        "vertex {vertex} is in no triangle: repair the mesh (drop unreferenced vertices) first"
    )]
    Isolated {
        /// The vertex.
        vertex: u32,
    },
    /// The factorisation met a non-positive pivot.
    #[error(
        "the system is not positive definite at vertex {vertex} (degenerate triangles around it?)"
    )]
    NonPositivePivot {
        /// The vertex (original numbering).
        vertex: u32,
    },
    /// A fixed index is out of range or repeated.
    #[error("fixed vertex {vertex} is out of range or listed twice")]
    BadFixed {
        /// The vertex.
        vertex: u32,
    },
    /// Out of memory or another faer failure.
    #[error("sparse factorisation failed: {0}")]
    Factor(String),
}

/// Scratch memory for [`FixedSolver::solve`], reusable across calls.
pub struct Workspace {
    rhs: Mat<f64>,
    buf: MemBuffer,
}

/// A prefactored `K_FF` with the coupling `K_FC`.
pub struct FixedSolver {
    n: usize,
    /// Free index of each vertex, or `u32::MAX` for a fixed one.
    free_of: Vec<u32>,
    fixed: Vec<u32>,
    free: Vec<u32>,
    /// For each free unknown, its `(fixed index, K_ij)` couplings.
    coupling: Vec<Vec<(u32, f64)>>,
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
}

impl FixedSolver {
    /// Factors `K_FF` for an `n × n` matrix given as triplets (duplicates summed,
    /// both triangles present) with the unknowns `fixed` held.
    ///
    /// Checks that every connected component of K's graph has a fixed vertex
    /// and that no vertex is isolated, so a singular system is a typed error
    /// rather than NaNs.
    pub fn new(n: usize, k: Triplets, fixed: &[u32]) -> Result<FixedSolver, SolveError> {
        Self::build(n, k, fixed, true)
    }

    /// Factors a matrix the caller knows to be definite without fixed
    /// unknowns (e.g. a Laplacian plus a positive diagonal, as in bone-heat
    /// weights). A non-positive pivot is still a typed error.
    pub fn definite(n: usize, k: Triplets) -> Result<FixedSolver, SolveError> {
        Self::build(n, k, &[], false)
    }

    /// [`FixedSolver::new`] from the matrix's compressed rows (`n` rows,
    /// each its `(column, value)` pairs sorted by column without repeats,
    /// as [`to_rows`] gives them), for a caller that assembles them
    /// without sorting triplets. A column out of range is a typed error.
    /// The fold repair's solver before its patch system
    /// (`deform::patch_solve`), kept as that system's reference in the
    /// tests.
    #[cfg(test)]
    pub(crate) fn from_rows(
        n: usize,
        rows: Vec<Vec<(u32, f64)>>,
        fixed: &[u32],
    ) -> Result<FixedSolver, SolveError> {
        if rows.len() != n {
            return Err(SolveError::Factor(format!(
                "{} rows given for {n} unknowns",
                rows.len()
            )));
        }
        if let Some(r) = rows
            .iter()
            .position(|r| r.iter().any(|&(c, _)| c as usize >= n))
        {
            return Err(SolveError::Factor(format!(
                "row {r} has a column out of range (n = {n})"
            )));
        }
        Self::build_rows(n, rows, fixed, true)
    }

    fn build(n: usize, k: Triplets, fixed: &[u32], check: bool) -> Result<FixedSolver, SolveError> {
        Self::build_rows(n, to_rows(n, k), fixed, check)
    }

    fn build_rows(
        n: usize,
        rows: Vec<Vec<(u32, f64)>>,
        fixed: &[u32],
        check: bool,
    ) -> Result<FixedSolver, SolveError> {
        let mut free_of = vec![0u32; n];
        for &f in fixed {
            if f as usize >= n || free_of[f as usize] == u32::MAX {
                return Err(SolveError::BadFixed { vertex: f });
            }
            free_of[f as usize] = u32::MAX;
        }
        let mut free = Vec::with_capacity(n - fixed.len());
        for (i, slot) in free_of.iter_mut().enumerate() {
            if *slot != u32::MAX {
                *slot = free.len() as u32;
                free.push(i as u32);
            }
        }
        let mut fixed_pos = vec![u32::MAX; n];
        for (k, &f) in fixed.iter().enumerate() {
            fixed_pos[f as usize] = k as u32;
        }
        if check {
            check_anchored(&rows, &free_of)?;
        } else if let Some(v) = free
            .iter()
            .find(|&&v| rows[v as usize].iter().all(|&(_, x)| x == 0.0))
        {
            // A zero row fails the factorisation at a pivot that names
            // another vertex (the pivot's supernode): say which it is.
            return Err(SolveError::Isolated { vertex: *v });
        }
        let nf = free.len();
        let mut trip = Vec::with_capacity(rows.iter().map(Vec::len).sum());
        let mut coupling = vec![Vec::new(); nf];
        for (fi, &v) in free.iter().enumerate() {
            for &(c, val) in &rows[v as usize] {
                let cf = free_of[c as usize];
                if cf == u32::MAX {
                    coupling[fi].push((fixed_pos[c as usize], val));
                } else {
                    trip.push(Triplet::new(fi, cf as usize, val));
                }
            }
        }
        let kff = SparseColMat::<usize, f64>::try_new_from_triplets(nf, nf, &trip)
            .map_err(|e| SolveError::Factor(format!("{e:?}")))?;
        let symbolic = factorize_symbolic_cholesky(
            kff.symbolic(),
            Side::Lower,
            Default::default(),
            Default::default(),
        )
        .map_err(|e| SolveError::Factor(format!("{e:?}")))?;
        let mut values = vec![0.0; symbolic.len_val()];
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
        let mut buf = MemBuffer::try_new(req).map_err(|e| SolveError::Factor(format!("{e:?}")))?;
        let r = symbolic.factorize_numeric_llt::<f64>(
            &mut values,
            kff.as_ref(),
            Side::Lower,
            Default::default(),
            Par::Seq,
            MemStack::new(&mut buf),
            Default::default(),
        );
        if let Err(e) = r {
            let faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index: idx } = e;
            let orig = symbolic
                .perm()
                .map_or(idx, |p| p.arrays().0.get(idx).copied().unwrap_or(idx));
            let vertex = free.get(orig).copied().unwrap_or(0);
            return Err(SolveError::NonPositivePivot { vertex });
        }
        Ok(FixedSolver {
            n,
            free_of,
            fixed: fixed.to_vec(),
            free,
            coupling,
            symbolic,
            values,
        })
    }

    /// Number of unknowns.
    pub fn len(&self) -> usize {
        self.n
    }

    /// True if there are no unknowns.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The fixed vertices, in the order their values are given to [`FixedSolver::solve`].
    pub fn fixed(&self) -> &[u32] {
        &self.fixed
    }

    /// Scratch space for solves with `k` right-hand sides.
    pub fn workspace(&self, k: usize) -> Workspace {
        let req = self.symbolic.solve_in_place_scratch::<f64>(k, Par::Seq);
        Workspace {
            rhs: Mat::zeros(self.free.len(), k),
            buf: MemBuffer::new(req),
        }
    }

    /// Solves for `k` columns: `b` and `out` are `n × k` row-major
    /// (`b[i][c]`), `fixed_values` is `fixed.len() × k`. Rows of `b` at fixed
    /// vertices are ignored; `out` at fixed vertices receives their values.
    /// No allocation.
    ///
    /// # Panics
    /// If the slices do not have `n` (or `fixed.len()`) rows, or the workspace
    /// was made for another `k`.
    pub fn solve<const K: usize>(
        &self,
        b: &[[f64; K]],
        fixed_values: &[[f64; K]],
        out: &mut [[f64; K]],
        ws: &mut Workspace,
    ) {
        assert_eq!(b.len(), self.n);
        assert_eq!(out.len(), self.n);
        assert_eq!(fixed_values.len(), self.fixed.len());
        assert_eq!(ws.rhs.ncols(), K);
        for (fi, &v) in self.free.iter().enumerate() {
            let mut r = b[v as usize];
            for &(c, kv) in &self.coupling[fi] {
                for k in 0..K {
                    r[k] -= kv * fixed_values[c as usize][k];
                }
            }
            for (k, rk) in r.iter().enumerate() {
                ws.rhs[(fi, k)] = *rk;
            }
        }
        let llt = faer::sparse::linalg::cholesky::LltRef::<'_, usize, f64>::new(
            &self.symbolic,
            &self.values,
        );
        llt.solve_in_place_with_conj(
            Conj::No,
            ws.rhs.as_mut(),
            Par::Seq,
            MemStack::new(&mut ws.buf),
        );
        for (fi, &v) in self.free.iter().enumerate() {
            for (k, o) in out[v as usize].iter_mut().enumerate() {
                *o = ws.rhs[(fi, k)];
            }
        }
        for (c, &v) in self.fixed.iter().enumerate() {
            out[v as usize] = fixed_values[c];
        }
        let _ = &self.free_of;
    }
}

/// Every component of the matrix graph must contain a fixed unknown, and no
/// unknown may have an empty row.
fn check_anchored(rows: &[Vec<(u32, f64)>], free_of: &[u32]) -> Result<(), SolveError> {
    anchored_components(
        rows.len(),
        |v| rows[v].iter().copied(),
        |v| free_of[v] == u32::MAX,
        &mut Vec::new(),
        &mut Vec::new(),
    )
}

/// The anchoring check on a graph of `n` unknowns whose rows `row(v)` give
/// (column, value) pairs: every connected component (through non-zero
/// values) holds an unknown for which `held` is true, and no free unknown's
/// row is empty but for its diagonal. `comp` and `stack` are scratch,
/// reused by callers that keep them (the fold repair's patches).
pub(crate) fn anchored_components<I: Iterator<Item = (u32, f64)>>(
    n: usize,
    row: impl Fn(usize) -> I,
    held: impl Fn(usize) -> bool,
    comp: &mut Vec<u32>,
    stack: &mut Vec<usize>,
) -> Result<(), SolveError> {
    comp.clear();
    comp.resize(n, u32::MAX);
    let mut ncomp = 0u32;
    for s in 0..n {
        if comp[s] != u32::MAX {
            continue;
        }
        if !held(s) && row(s).all(|(c, v)| c as usize == s || v == 0.0) {
            return Err(SolveError::Isolated { vertex: s as u32 });
        }
        let (mut anchored, mut size) = (false, 0);
        comp[s] = ncomp;
        stack.clear();
        stack.push(s);
        while let Some(v) = stack.pop() {
            size += 1;
            anchored |= held(v);
            for (c, val) in row(v) {
                if val != 0.0 && comp[c as usize] == u32::MAX {
                    comp[c as usize] = ncomp;
                    stack.push(c as usize);
                }
            }
        }
        if !anchored {
            return Err(SolveError::UnanchoredComponent {
                component: ncomp as usize,
                vertices: size,
                first_vertex: s as u32,
            });
        }
        ncomp += 1;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A zero row of a "definite" system is named as the isolated vertex
    /// it is, not as the pivot where the factorisation stops.
    #[test]
    fn a_zero_row_of_a_definite_system_names_its_vertex() {
        for zero in [0u32, 2, 4] {
            let mut k: Triplets = Vec::new();
            for i in 0..5u32 {
                if i != zero {
                    k.push((i, i, 2.0));
                }
            }
            k.push((zero, zero, 0.0));
            match FixedSolver::definite(5, k) {
                Err(SolveError::Isolated { vertex }) => assert_eq!(vertex, zero),
                Err(e) => panic!("{e}"),
                Ok(_) => panic!("a zero row factored"),
            }
        }
    }
}
