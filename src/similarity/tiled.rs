//! The sparse similarity's full measures evaluated in a cache-friendly
//! order (issue 43, session 29): the pairs of the diagonal runs
//! ([`super::sparse`]) taken [`TILE_ROWS`] rows at a time and, within such
//! a block, column by column, so that the block's row descriptors stay in
//! cache while each column's descriptor is read once per block — the
//! dense matrix's order ([`super::matrix::upper_rows`]). Along a diagonal
//! every pair `(a, a + d)` reads two descriptors no other pair near it in
//! time reads (45 KB each for the shape measure, 0.46 GB at 10⁴ frames,
//! more than the caches): evaluated run by run, the 10⁴ build spent about
//! 27 µs of CPU a pair, against about 10 µs in the dense order.
//!
//! The values are `set.distance(a, a + d)` bit for bit whatever the order
//! (each pair is one call, with its frames in the run's order).

use super::matrix::PairDistance;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Rows per block: 32 shape descriptors are 1.5 MB, within a core's cache
/// beside the column being read.
pub(crate) const TILE_ROWS: usize = 32;

/// A run of pairs `(r, r + diag)` for `r` in `r0..=r1` (the sparse
/// similarity's diagonal runs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct Run {
    /// Column minus row, at least 1.
    pub diag: u32,
    /// First row.
    pub r0: u32,
    /// Last row.
    pub r1: u32,
}

impl Run {
    /// Pairs of the run.
    pub fn len(&self) -> usize {
        (self.r1 - self.r0) as usize + 1
    }
    /// Always false: a run holds at least one pair.
    pub fn is_empty(&self) -> bool {
        false
    }
}

/// Where each run's values start in [`evaluate`]'s flat output (the
/// total last): `runs.len() + 1` offsets.
pub fn offsets(runs: &[Run]) -> Vec<usize> {
    let mut at = Vec::with_capacity(runs.len() + 1);
    let mut total = 0;
    at.push(0);
    for r in runs {
        total += r.len();
        at.push(total);
    }
    at
}

/// The full measure at every pair of `runs`, run after run, each run's
/// values in row order, starting at [`offsets`]`(runs)[k]`; evaluated in
/// parallel over blocks of [`TILE_ROWS`] rows, columns ascending within a
/// block. `progress` hears the pairs of each finished block.
pub fn evaluate(set: &dyn PairDistance, runs: &[Run], progress: &(dyn Fn(u64) + Sync)) -> Vec<f32> {
    let total = offsets(runs)[runs.len()];
    let values: Vec<AtomicU32> = (0..total).map(|_| AtomicU32::new(0)).collect();
    evaluate_each(set, runs, progress, &|_, _, slot, v| {
        values[slot].store(v.to_bits(), Ordering::Relaxed)
    });
    values
        .into_iter()
        .map(|v| f32::from_bits(v.into_inner()))
        .collect()
}

/// [`evaluate`]'s pairs in its order, each value handed to `put` as
/// `(row, column, slot in evaluate's flat output, value)` instead of kept
/// (issue 43, session 42: the sparse build writes them straight into its
/// rows, without the flat output's 4 bytes a pair). `put` is called once a
/// pair, from the pool's threads.
pub fn evaluate_each(
    set: &dyn PairDistance,
    runs: &[Run],
    progress: &(dyn Fn(u64) + Sync),
    put: &(dyn Fn(u32, u32, usize, f32) + Sync),
) {
    let at = offsets(runs);
    let blocks = block_pieces(runs);
    blocks.par_iter().enumerate().for_each(|(blk, pieces)| {
        let mut pairs = block_pairs(runs, &at, pieces, blk);
        pairs.sort_unstable();
        for &(b, a, slot) in &pairs {
            let v = set.distance(a as usize, b as usize) as f32;
            put(a, b, slot, v);
        }
        progress(pairs.len() as u64);
    });
}

/// A run's rows within one block: run `k`, rows `r0..=r1`.
type Piece = (u32, u32, u32);

/// Per block of [`TILE_ROWS`] rows, the pieces of the runs in it.
fn block_pieces(runs: &[Run]) -> Vec<Vec<Piece>> {
    let rows = runs.iter().map(|r| r.r1 as usize + 1).max().unwrap_or(0);
    let mut blocks: Vec<Vec<Piece>> = vec![Vec::new(); rows.div_ceil(TILE_ROWS)];
    for (k, r) in runs.iter().enumerate() {
        let mut a = r.r0 as usize;
        while a <= r.r1 as usize {
            let blk = a / TILE_ROWS;
            let end = ((blk + 1) * TILE_ROWS - 1).min(r.r1 as usize);
            blocks[blk].push((k as u32, a as u32, end as u32));
            a = end + 1;
        }
    }
    blocks
}

/// The pairs of one block as `(column, row, slot in the flat output)`.
fn block_pairs(runs: &[Run], at: &[usize], pieces: &[Piece], blk: usize) -> Vec<(u32, u32, usize)> {
    let mut pairs = Vec::with_capacity(pieces.iter().map(|p| (p.2 - p.1) as usize + 1).sum());
    for &(k, r0, r1) in pieces {
        let run = &runs[k as usize];
        debug_assert!(r0 as usize / TILE_ROWS == blk && r1 as usize / TILE_ROWS == blk);
        for a in r0..=r1 {
            pairs.push((a + run.diag, a, at[k as usize] + (a - run.r0) as usize));
        }
    }
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A distance that is not symmetric and tells its arguments apart, so
    /// that a pair evaluated the other way round or put in another slot is
    /// seen.
    struct Asym;
    impl PairDistance for Asym {
        fn frames(&self) -> usize {
            5000
        }
        fn distance(&self, a: usize, b: usize) -> f64 {
            (a as f64 * 1.000_123).sin() * 3.0 + (b as f64).sqrt() + (a * 7 + b) as f64 * 1e-6
        }
    }

    /// Issue 43, session 29: the tiled order gives every pair of every run
    /// the value the run-by-run order gives, in the run's slot — on runs
    /// crossing block edges, one-pair runs, runs of one diagonal side by
    /// side, far diagonals, runs given in any order; and an empty list.
    #[test]
    fn the_tiled_order_gives_the_run_order_values_bit_for_bit() {
        let mut rng = crate::similarity::test_rng::XorShift::new(0x2545_f491_4f6c_dd1d);
        let mut rnd = move |m: u32| rng.below(m);
        let mut runs = vec![
            Run {
                diag: 1,
                r0: 0,
                r1: 4998,
            },
            Run {
                diag: 2,
                r0: 31,
                r1: 32,
            },
            Run {
                diag: 4999,
                r0: 0,
                r1: 0,
            },
            Run {
                diag: 7,
                r0: 63,
                r1: 63,
            },
        ];
        for _ in 0..400 {
            let diag = 1 + rnd(3000);
            let r0 = rnd(5000 - diag);
            let r1 = (r0 + rnd(80)).min(4999 - diag);
            runs.push(Run { diag, r0, r1 });
        }
        let counted = AtomicU32::new(0);
        let got = evaluate(&Asym, &runs, &|k| {
            counted.fetch_add(k as u32, Ordering::Relaxed);
        });
        let at = offsets(&runs);
        assert_eq!(got.len(), at[runs.len()]);
        assert_eq!(counted.into_inner() as usize, got.len());
        for (k, r) in runs.iter().enumerate() {
            for (i, a) in (r.r0..=r.r1).enumerate() {
                let want = Asym.distance(a as usize, (a + r.diag) as usize) as f32;
                assert_eq!(got[at[k] + i].to_bits(), want.to_bits(), "run {k} row {a}");
            }
        }
        assert!(evaluate(&Asym, &[], &|_| {}).is_empty());
    }
}
