//! The fold repair's patch system ([`super::unflip`]), assembled and
//! factored in memory reused from patch to patch and frame to frame.
//!
//! A patch of `m` vertices, its first `free` unknown and the rest held, asks
//! for weighted edges: the `m × m` graph Laplacian `K` of the edges
//! `(i, j, w)` (libigl `min_quad_with_fixed`: `K_FF x_F = b_F − K_FC c`).
//! The rows are built in flat compressed buffers (a counting pass, each row
//! sorted and its repeats summed), `K_FF` is handed to faer as a view of
//! column buffers (no triplets), and the numeric factor, its scratch and
//! the solve's right-hand sides live in buffers that only grow. So a patch
//! allocates nothing but faer's symbolic analysis (a fill-reducing
//! ordering and the factor's structure, a few blocks whatever the patch's
//! size), where the [`crate::mesh::solver::FixedSolver`] it replaces
//! allocated a row per vertex, a coupling list per held neighbour, the
//! triplets and every scratch (6,146 allocation calls a frame on CMU 02_01,
//! session 37).
//!
//! The arithmetic is [`crate::mesh::solver::FixedSolver::from_rows`]' on
//! the same rows, step for step: the same matrix bit for bit (its columns
//! taken from the rows in increasing order, as the triplets' sort gives
//! them), the same ordering and factor, and the held columns subtracted in
//! the same order; so the repaired frame is the same bit for bit.

use crate::deform::resident::{Resident, page_in, page_in_bytes};
use crate::mesh::solver::{SolveError, anchored_components};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, factorize_symbolic_cholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
pub(crate) use rows::PatchRows;

pub(crate) mod counted;
mod rows;
#[cfg(test)]
mod tests;

/// Memory kept for a [`MemStack`]: grown (never shrunk) to the largest
/// request met.
#[derive(Default)]
struct Scratch {
    req: Option<StackReq>,
    buf: Option<MemBuffer>,
}

impl Scratch {
    /// A stack holding at least `req`.
    fn stack(&mut self, req: StackReq) -> Result<&mut MemStack, SolveError> {
        let fits = self.req.is_some_and(|have| {
            have.size_bytes() >= req.size_bytes() && have.align_bytes() >= req.align_bytes()
        });
        if !fits || self.buf.is_none() {
            let want = self.req.map_or(req, |have| have.or(req));
            let buf = MemBuffer::try_new(want).map_err(|e| SolveError::Factor(format!("{e:?}")))?;
            self.buf = Some(buf);
            self.req = Some(want);
        }
        match self.buf.as_mut() {
            Some(b) => Ok(MemStack::new(b)),
            None => Err(SolveError::Factor("no scratch".into())),
        }
    }

    /// Holds at least what `other` holds ([`PatchSystem::reserve_as`]);
    /// left as it is when that memory cannot be had (the next
    /// [`Scratch::stack`] asks again and reports it).
    fn reserve_as(&mut self, other: &Scratch) {
        if let Some(req) = other.req {
            let _ = self.stack(req);
        }
    }

    /// Its bytes ([`Resident`]).
    fn resident(&mut self, touch: bool) -> usize {
        self.buf.as_mut().map_or(0, |b| page_in_bytes(b, touch))
    }
}

/// Grows `v` to at least `other`'s capacity, exactly (no amortised
/// doubling, so two buffers grown to each other stay the same size).
pub(crate) fn reserve_as<T>(v: &mut Vec<T>, other: &Vec<T>) {
    if v.capacity() < other.capacity() {
        v.reserve_exact(other.capacity() - v.len());
    }
}

impl Resident for PatchSystem {
    fn resident(&mut self, touch: bool) -> usize {
        self.paged(touch)
    }
}

/// A patch's `K_FF` factored, with the couplings `K_FC`, in reused memory
/// ([`PatchSystem::factor`], then [`PatchSystem::solve`]).
#[derive(Default)]
pub(crate) struct PatchSystem {
    /// The rows of the last patch.
    rows: PatchRows,
    m: usize,
    free: usize,
    /// `K_FF` by columns.
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    col_vals: Vec<f64>,
    col_at: Vec<usize>,
    /// Per free row, its held columns `(index among the held, K_ij)`.
    coupling_ptr: Vec<usize>,
    coupling: Vec<(u32, f64)>,
    /// The anchoring check's component marks and stack.
    comp: Vec<u32>,
    stack: Vec<usize>,
    symbolic: Option<SymbolicCholesky<usize>>,
    values: Vec<f64>,
    factor_scratch: Scratch,
    rhs: Vec<f64>,
    solve_scratch: Scratch,
}

impl std::fmt::Debug for PatchSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PatchSystem")
            .field("m", &self.m)
            .field("free", &self.free)
            .finish_non_exhaustive()
    }
}

impl PatchSystem {
    /// Grows every buffer to at least `other`'s capacity: the two-frame
    /// overlap's slots each keep a system, and a slot that has not yet met
    /// a patch as large as the other slot's largest grows to it before
    /// the pair rather than in the middle of a later pair, on whichever
    /// pool thread runs it (the live session). O(buffers) when
    /// already as large; the solve's results do not depend on capacity.
    pub(crate) fn reserve_as(&mut self, other: &PatchSystem) {
        self.rows.reserve_as(&other.rows);
        reserve_as(&mut self.col_ptr, &other.col_ptr);
        reserve_as(&mut self.row_idx, &other.row_idx);
        reserve_as(&mut self.col_vals, &other.col_vals);
        reserve_as(&mut self.col_at, &other.col_at);
        reserve_as(&mut self.coupling_ptr, &other.coupling_ptr);
        reserve_as(&mut self.coupling, &other.coupling);
        reserve_as(&mut self.comp, &other.comp);
        reserve_as(&mut self.stack, &other.stack);
        reserve_as(&mut self.values, &other.values);
        reserve_as(&mut self.rhs, &other.rhs);
        self.factor_scratch.reserve_as(&other.factor_scratch);
        self.solve_scratch.reserve_as(&other.solve_scratch);
    }

    /// Every buffer's capacity in bytes, each paged in with `touch`
    /// ([`crate::deform::resident`]).
    fn paged(&mut self, touch: bool) -> usize {
        let t = touch;
        self.rows.resident(t)
            + page_in(&mut self.col_ptr, t)
            + page_in(&mut self.row_idx, t)
            + page_in(&mut self.col_vals, t)
            + page_in(&mut self.col_at, t)
            + page_in(&mut self.coupling_ptr, t)
            + page_in(&mut self.coupling, t)
            + page_in(&mut self.comp, t)
            + page_in(&mut self.stack, t)
            + page_in(&mut self.values, t)
            + page_in(&mut self.rhs, t)
            + self.factor_scratch.resident(t)
            + self.solve_scratch.resident(t)
    }

    /// Factors the patch of `m` vertices whose first `free` are unknown,
    /// from the Laplacian of `edges` (local indices below `m`). Errors as
    /// [`crate::mesh::solver::FixedSolver::new`]: a component of the
    /// patch's graph without a held vertex, a first vertex of a component
    /// without neighbours, a non-positive pivot.
    pub(crate) fn factor(
        &mut self,
        m: usize,
        free: usize,
        edges: &[(u32, u32, f64)],
    ) -> Result<(), SolveError> {
        self.symbolic = None;
        self.rows.assemble(m, edges);
        self.m = m;
        self.free = free;
        self.check_anchored()?;
        self.split();
        let kff = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(free, free, &self.col_ptr, None, &self.row_idx),
            &self.col_vals,
        );
        let symbolic = counted::faer_symbolic(|| {
            factorize_symbolic_cholesky(
                kff.symbolic(),
                Side::Lower,
                Default::default(),
                Default::default(),
            )
        })
        .map_err(|e| SolveError::Factor(format!("{e:?}")))?;
        self.values.clear();
        self.values.resize(symbolic.len_val(), 0.0);
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
        let stack = self.factor_scratch.stack(req)?;
        let r = symbolic.factorize_numeric_llt::<f64>(
            &mut self.values,
            kff,
            Side::Lower,
            Default::default(),
            Par::Seq,
            stack,
            Default::default(),
        );
        if let Err(e) = r {
            let faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index: idx } = e;
            let vertex = symbolic
                .perm()
                .map_or(idx, |p| p.arrays().0.get(idx).copied().unwrap_or(idx));
            return Err(SolveError::NonPositivePivot {
                vertex: vertex as u32,
            });
        }
        self.symbolic = Some(symbolic);
        Ok(())
    }

    /// `K_FF` by columns (row `r`'s entries placed in increasing `r`, so
    /// each column's rows increase: the triplets' sorted form) and each
    /// free row's held columns, in column order.
    fn split(&mut self) {
        let (m, free) = (self.m, self.free);
        self.col_ptr.clear();
        self.col_ptr.resize(free + 1, 0);
        self.coupling_ptr.clear();
        self.coupling.clear();
        for r in 0..free {
            for &c in self.rows.row(r).0 {
                if (c as usize) < free {
                    self.col_ptr[c as usize + 1] += 1;
                }
            }
        }
        for c in 0..free {
            self.col_ptr[c + 1] += self.col_ptr[c];
        }
        self.col_at.clear();
        self.col_at.extend_from_slice(&self.col_ptr[..free]);
        self.row_idx.clear();
        self.row_idx.resize(self.col_ptr[free], 0);
        self.col_vals.clear();
        self.col_vals.resize(self.col_ptr[free], 0.0);
        for r in 0..free {
            self.coupling_ptr.push(self.coupling.len());
            let (cols, vals) = self.rows.row(r);
            for (&c, &v) in cols.iter().zip(vals) {
                if (c as usize) < free {
                    let at = &mut self.col_at[c as usize];
                    self.row_idx[*at] = r;
                    self.col_vals[*at] = v;
                    *at += 1;
                } else {
                    self.coupling.push((c - free as u32, v));
                }
            }
        }
        self.coupling_ptr.push(self.coupling.len());
        debug_assert!(m >= free);
    }

    /// [`crate::mesh::solver`]'s anchoring check on the patch's rows:
    /// every component of the graph has a held vertex, and the first
    /// vertex of each, when free, has a neighbour.
    fn check_anchored(&mut self) -> Result<(), SolveError> {
        let (rows, free) = (&self.rows, self.free);
        anchored_components(
            self.m,
            |v| {
                let (cols, vals) = rows.row(v);
                cols.iter().copied().zip(vals.iter().copied())
            },
            |v| v >= free,
            &mut self.comp,
            &mut self.stack,
        )
    }

    /// Whether the last patch was factored by supernodes (faer's choice
    /// by the factor's density; else column by column).
    #[cfg(test)]
    fn supernodal(&self) -> bool {
        use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
        matches!(
            self.symbolic.as_ref().map(SymbolicCholesky::raw),
            Some(SymbolicCholeskyRaw::Supernodal(_))
        )
    }

    /// Solves the factored patch: `b` the right-hand sides of all `m`
    /// vertices (the held ones' ignored), `held` the values of the held
    /// `m − free`; writes all `m` into `out` (the held ones' their value).
    /// No allocation once the buffers have grown.
    pub(crate) fn solve(
        &mut self,
        b: &[[f64; 3]],
        held: &[[f64; 3]],
        out: &mut [[f64; 3]],
    ) -> Result<(), SolveError> {
        let (m, free) = (self.m, self.free);
        let Some(symbolic) = self.symbolic.as_ref() else {
            return Err(SolveError::Factor("no patch factored".into()));
        };
        if b.len() != m || out.len() != m || held.len() != m - free {
            return Err(SolveError::Factor(format!(
                "patch of {m} vertices given {} / {} / {} rows",
                b.len(),
                held.len(),
                out.len()
            )));
        }
        self.rhs.clear();
        self.rhs.resize(free * 3, 0.0);
        for (fi, row) in b[..free].iter().enumerate() {
            let mut r = *row;
            for &(c, kv) in &self.coupling[self.coupling_ptr[fi]..self.coupling_ptr[fi + 1]] {
                for k in 0..3 {
                    r[k] -= kv * held[c as usize][k];
                }
            }
            for (k, rk) in r.iter().enumerate() {
                self.rhs[k * free + fi] = *rk;
            }
        }
        let req = symbolic.solve_in_place_scratch::<f64>(3, Par::Seq);
        let stack = self.solve_scratch.stack(req)?;
        let llt = LltRef::<'_, usize, f64>::new(symbolic, &self.values);
        let rhs = MatMut::from_column_major_slice_mut(&mut self.rhs, free, 3);
        llt.solve_in_place_with_conj(Conj::No, rhs, Par::Seq, stack);
        for (fi, o) in out[..free].iter_mut().enumerate() {
            *o = std::array::from_fn(|k| self.rhs[k * free + fi]);
        }
        out[free..].copy_from_slice(held);
        Ok(())
    }
}
