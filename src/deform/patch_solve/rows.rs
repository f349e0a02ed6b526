//! A patch's Laplacian rows assembled in reused compressed buffers (the
//! fold repair's patch system, [`super::PatchSystem`]).

use super::reserve_as;
use crate::deform::resident::{Resident, page_in};

/// A patch's Laplacian rows in compressed form, reused: row `r`'s
/// `(column, value)` pairs are `cols[ptr[r]..ptr[r + 1]]` and `vals[..]`,
/// sorted by column without repeats.
#[derive(Default)]
pub(crate) struct PatchRows {
    ptr: Vec<usize>,
    at: Vec<usize>,
    entries: Vec<(u32, f64)>,
    cols: Vec<u32>,
    vals: Vec<f64>,
}

impl PatchRows {
    /// The rows of the `m × m` Laplacian of the weighted edges `(i, j, w)`:
    /// each adds `w` at `(i, i)` and `(j, j)` and `−w` at `(i, j)` and
    /// `(j, i)`. A counting pass places every entry in its row, then each
    /// row is sorted (`sort_unstable_by_key`, as before) and its repeats
    /// summed in that order; O(entries) plus the rows' sorts, no
    /// allocation once the buffers have grown to the patch.
    pub(crate) fn assemble(&mut self, m: usize, edges: &[(u32, u32, f64)]) {
        self.ptr.clear();
        self.ptr.resize(m + 1, 0);
        for &(i, j, _) in edges {
            self.ptr[i as usize + 1] += 2;
            self.ptr[j as usize + 1] += 2;
        }
        for r in 0..m {
            self.ptr[r + 1] += self.ptr[r];
        }
        self.at.clear();
        self.at.extend_from_slice(&self.ptr[..m]);
        self.entries.clear();
        self.entries.resize(self.ptr[m], (0, 0.0));
        for &(i, j, w) in edges {
            for (r, c, v) in [(i, i, w), (j, j, w), (i, j, -w), (j, i, -w)] {
                self.entries[self.at[r as usize]] = (c, v);
                self.at[r as usize] += 1;
            }
        }
        self.cols.clear();
        self.vals.clear();
        let mut begin = 0;
        for r in 0..m {
            let row = &mut self.entries[begin..self.ptr[r + 1]];
            begin = self.ptr[r + 1];
            row.sort_unstable_by_key(|&(c, _)| c);
            self.ptr[r] = self.cols.len();
            for (k, &(c, v)) in row.iter().enumerate() {
                match self.vals.last_mut() {
                    Some(last) if k > 0 && row[k - 1].0 == c => *last += v,
                    _ => {
                        self.cols.push(c);
                        self.vals.push(v);
                    }
                }
            }
        }
        self.ptr[m] = self.cols.len();
    }

    /// Grows every buffer to at least `other`'s capacity
    /// ([`PatchSystem::reserve_as`]).
    pub(super) fn reserve_as(&mut self, other: &PatchRows) {
        reserve_as(&mut self.ptr, &other.ptr);
        reserve_as(&mut self.at, &other.at);
        reserve_as(&mut self.entries, &other.entries);
        reserve_as(&mut self.cols, &other.cols);
        reserve_as(&mut self.vals, &other.vals);
    }

    /// Number of rows.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.ptr.len().saturating_sub(1)
    }

    /// Row `r`'s columns and values.
    pub(crate) fn row(&self, r: usize) -> (&[u32], &[f64]) {
        let s = self.ptr[r]..self.ptr[r + 1];
        (&self.cols[s.clone()], &self.vals[s])
    }
}

impl Resident for PatchRows {
    fn resident(&mut self, touch: bool) -> usize {
        page_in(&mut self.ptr, touch)
            + page_in(&mut self.at, touch)
            + page_in(&mut self.entries, touch)
            + page_in(&mut self.cols, touch)
            + page_in(&mut self.vals, touch)
    }
}
