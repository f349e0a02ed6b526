//! The best cheap transitions of every sequence pair, the candidates that
//! keep the sparse similarity's transitions the dense method's (issue 43).
//!
//! The graph keeps the `top_n` best transitions of every ordered sequence
//! pair (Huang et al. 2015, Sec. 4.2, Eqs. 2–5), also between dissimilar
//! motions, whose frames are nobody's nearest frames overall. So for every
//! unordered pair of sequences `i ≤ j` (the matrix is symmetric: the
//! transitions `j → i` are those of `i → j` transposed) the transition
//! search itself ([`super::transitions::find`]: local minima, the
//! windowed cost of Eq. 3 per blended frame, suppression within a window)
//! runs on the block of cheap distances (the projected descriptors'
//! Euclidean distance, a lower bound of Eq. 1's), and the centres of its
//! best transitions become candidate pairs of the full measure.
//!
//! Work: one cheap distance (`dims` multiply-adds) for every frame pair,
//! `n² dims / 2` — at 10⁴ frames and 24 dimensions 1.2·10⁹, about a
//! thousandth of the full measure on every pair — held one block at a
//! time (`len_i × len_j` values per thread). The candidates are `top_n`
//! per sequence pair whatever the sequences' lengths: where the previous
//! scheme (every 4th frame's 12 nearest frames in each sequence) gave
//! `n × sequences × 3` candidates.

use super::matrix::Span;
use super::transitions::{TransitionOptions, find};
use rayon::prelude::*;

/// The cheap distances of sequences `si` (rows) and `sj` (columns),
/// row-major (`si.len × sj.len`): the Euclidean distance of the frames'
/// rows of `features` (`n × dims`, row-major).
fn cheap_block(features: &[f32], dims: usize, si: &Span, sj: &Span) -> Vec<f32> {
    let mut out = vec![0.0f32; si.len * sj.len];
    if sj.len == 0 || dims == 0 {
        return out;
    }
    let cols = &features[sj.start * dims..(sj.start + sj.len) * dims];
    for (r, row) in out.chunks_exact_mut(sj.len).enumerate() {
        let a = &features[(si.start + r) * dims..(si.start + r + 1) * dims];
        for (o, b) in row.iter_mut().zip(cols.chunks_exact(dims)) {
            *o = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y) * (x - y))
                .sum::<f32>()
                .sqrt();
        }
    }
    out
}

/// The centres `(frame, frame)` (global rows, the first in the earlier
/// sequence) of the `opts.top_n` best transitions of every unordered
/// sequence pair by the cheap distances of `features` (`n × dims`,
/// row-major); in parallel over sequence pairs, in a fixed order. Nothing
/// when `opts.top_n` is 0.
pub fn best_per_pair(
    features: &[f32],
    dims: usize,
    spans: &[Span],
    opts: &TransitionOptions,
) -> Vec<(usize, u32)> {
    if opts.top_n == 0 {
        return Vec::new();
    }
    let pairs: Vec<(usize, usize)> = (0..spans.len())
        .flat_map(|i| (i..spans.len()).map(move |j| (i, j)))
        .collect();
    pairs
        .par_iter()
        .flat_map_iter(|&(i, j)| {
            let (si, sj) = (&spans[i], &spans[j]);
            let c = cheap_block(features, dims, si, sj);
            let cols = sj.len;
            let at = |r: usize, s: usize| c[r * cols + s];
            let (a0, b0) = (si.start, sj.start);
            find(&at, si.len, sj.len, i == j, opts)
                .into_iter()
                .filter(move |&(m, n, _, _)| i != j || m < n)
                .map(move |(m, n, _, _)| (a0 + m, (b0 + n) as u32))
        })
        .collect()
}

/// `seeds` and, for each, the pairs `spread` frames either way along its
/// second frame's sequence (the cheap minimum's diagonal is often a few
/// off the full measure's): each seed's `(a, b − spread)` and
/// `(a, b + spread)` where they stay in `b`'s sequence. All of `seeds`
/// alone when `spread` is 0.
pub fn spread_seeds(
    seeds: &[(usize, u32)],
    spread: usize,
    spans: &[Span],
    seq: &[u32],
) -> Vec<(usize, u32)> {
    if spread == 0 {
        return seeds.to_vec();
    }
    let mut out = Vec::with_capacity(seeds.len() * 3);
    for &(a, b) in seeds {
        out.push((a, b));
        let s = &spans[seq[b as usize] as usize];
        let b = b as usize;
        if b >= s.start + spread {
            out.push((a, (b - spread) as u32));
        }
        if b + spread < s.start + s.len {
            out.push((a, (b + spread) as u32));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn span(name: &str, start: usize, len: usize) -> Span {
        Span {
            name: name.into(),
            start,
            len,
        }
    }

    /// Two "motions" on a 1-D line far apart, each with a stretch where
    /// the other's values come close: every sequence pair gets its
    /// transitions, also the pair whose frames are nobody's nearest.
    #[test]
    fn every_sequence_pair_gets_its_best_transitions() {
        let a: Vec<f32> = (0..120).map(|t| (t as f32 * 0.2).sin()).collect();
        let mut b: Vec<f32> = (0..90).map(|t| 10.0 + (t as f32 * 0.3).cos()).collect();
        // b comes nearest to a around its frames 40..60 (still 5 away).
        for (t, v) in b.iter_mut().enumerate().take(60).skip(40) {
            *v = 6.0 + (t as f32 * 0.2).sin();
        }
        let features: Vec<f32> = a.iter().chain(&b).copied().collect();
        let spans = vec![span("a", 0, 120), span("b", 120, 90)];
        let opts = TransitionOptions {
            top_n: 2,
            ..TransitionOptions::default()
        };
        let got = best_per_pair(&features, 1, &spans, &opts);
        let across: Vec<_> = got.iter().filter(|&&(x, y)| x < 120 && y >= 120).collect();
        assert!(!across.is_empty(), "{got:?}");
        for &&(_, y) in &across {
            assert!((160..180).contains(&y), "{got:?}");
        }
        // Within each sequence (loops): first frame before the second.
        assert!(got.iter().all(|&(x, y)| x < y as usize), "{got:?}");
        assert!(
            best_per_pair(
                &features,
                1,
                &spans,
                &TransitionOptions { top_n: 0, ..opts }
            )
            .is_empty()
        );
    }

    #[test]
    fn spread_stays_in_the_sequence() {
        let spans = vec![span("a", 0, 50), span("b", 50, 30)];
        let seq: Vec<u32> = (0..80).map(|f| u32::from(f >= 50)).collect();
        let out = spread_seeds(&[(10, 52), (20, 70)], 5, &spans, &seq);
        assert_eq!(out, vec![(10, 52), (10, 57), (20, 70), (20, 65), (20, 75)]);
        assert_eq!(spread_seeds(&[(1, 2)], 0, &spans, &seq), vec![(1, 2)]);
    }
}
