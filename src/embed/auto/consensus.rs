//! One partition from several (issue 41): the vertices' parts agreed by
//! a majority of decompositions drawn from different k-means++ seedings,
//! so that the boundaries do not depend on one lucky draw.
//!
//! A cluster ensemble (Strehl & Ghosh 2002, "Cluster ensembles — a
//! knowledge reuse framework for combining multiple partitions", JMLR 3)
//! by voting: the reference is the ensemble's medoid, the partition of
//! greatest summed adjusted Rand index to the others (Hubert & Arabie
//! 1985, "Comparing partitions", J. Classification 2, Eq. 5); every
//! partition's part is mapped to the reference part it overlaps most, and
//! every vertex takes the reference part most partitions map it to. The
//! parts' identities are the reference's, their boundaries the
//! majority's (a knee cut a little higher in some draws and lower in
//! others lands where most put it).
//!
//! Labels must be numbered by the vertices' positions (as
//! [`super::decompose`] numbers them in its canonical order), so that
//! every tie below, broken towards the lesser label or index, follows the
//! body and not the file. Cost: O(m² n) for m partitions of n vertices.

use std::collections::HashMap;

/// A contingency table: the count of each pair (label in `a`, label in
/// `b`), and each labeling's part sizes.
type Table = (HashMap<(u32, u32), usize>, Vec<usize>, Vec<usize>);

/// The contingency table of two labelings of the same vertices.
fn contingency(a: &[u32], b: &[u32]) -> Table {
    let mut cells: HashMap<(u32, u32), usize> = HashMap::new();
    let count = |l: &[u32]| l.iter().max().map_or(0, |&m| m as usize + 1);
    let (mut sa, mut sb) = (vec![0usize; count(a)], vec![0usize; count(b)]);
    for (&x, &y) in a.iter().zip(b) {
        *cells.entry((x, y)).or_default() += 1;
        sa[x as usize] += 1;
        sb[y as usize] += 1;
    }
    (cells, sa, sb)
}

/// Pairs among `k` items.
fn pairs(k: usize) -> f64 {
    let k = k as f64;
    k * (k - 1.0) / 2.0
}

/// The adjusted Rand index of two labelings of the same vertices (1 when
/// they are the same partition, about 0 for unrelated ones; Hubert &
/// Arabie 1985, Eq. 5). 1 when neither splits the vertices (the
/// expectation equals the maximum).
pub fn adjusted_rand(a: &[u32], b: &[u32]) -> f64 {
    let (cells, sa, sb) = contingency(a, b);
    let index: f64 = cells.values().map(|&c| pairs(c)).sum();
    let ra: f64 = sa.iter().map(|&c| pairs(c)).sum();
    let rb: f64 = sb.iter().map(|&c| pairs(c)).sum();
    let total = pairs(a.len().min(b.len()));
    if total <= 0.0 {
        return 1.0;
    }
    let expected = ra * rb / total;
    let max = 0.5 * (ra + rb);
    if (max - expected).abs() <= f64::EPSILON * max.max(1.0) {
        return 1.0;
    }
    (index - expected) / (max - expected)
}

/// The index of the medoid of `labelings`: the greatest summed
/// [`adjusted_rand`] to the others (ties: the lesser index). 0 for none.
pub(crate) fn medoid(labelings: &[Vec<u32>]) -> usize {
    use rayon::prelude::*;
    let m = labelings.len();
    let score: Vec<f64> = (0..m)
        .into_par_iter()
        .map(|i| {
            (0..m)
                .filter(|&j| j != i)
                .map(|j| adjusted_rand(&labelings[i], &labelings[j]))
                .sum()
        })
        .collect();
    let mut best = 0;
    for (i, s) in score.iter().enumerate() {
        if *s > score[best] {
            best = i;
        }
    }
    best
}

/// Each vertex's part by majority: the parts of `labelings[reference]`,
/// every labeling's part mapped to the reference part it overlaps most
/// (ties: the lesser reference label), every vertex given the reference
/// part most labelings map it to (ties: its own reference part when among
/// the tied, else the lesser label). Labels are the reference's (not
/// renumbered; a part may lose every vertex or its connection).
pub fn vote(labelings: &[Vec<u32>], reference: usize) -> Vec<u32> {
    let Some(refl) = labelings.get(reference) else {
        return Vec::new();
    };
    let parts = refl.iter().max().map_or(0, |&m| m as usize + 1);
    let n = refl.len();
    let mut votes = vec![0u16; n * parts];
    for l in labelings {
        let map = mapped_onto(l, refl);
        for (v, &x) in l.iter().enumerate().take(n) {
            votes[v * parts + map[x as usize] as usize] += 1;
        }
    }
    (0..n)
        .map(|v| {
            let row = &votes[v * parts..(v + 1) * parts];
            let own = refl[v];
            let mut best = own;
            for (p, &c) in row.iter().enumerate() {
                if c > row[best as usize] {
                    best = p as u32;
                }
            }
            best
        })
        .collect()
}

/// For every label of `l`, the label of `reference` it overlaps most
/// (ties: the lesser reference label).
fn mapped_onto(l: &[u32], reference: &[u32]) -> Vec<u32> {
    let (cells, sa, _) = contingency(l, reference);
    let mut best: Vec<(usize, u32)> = vec![(0, u32::MAX); sa.len()];
    for (&(x, y), &c) in &cells {
        let b = &mut best[x as usize];
        if c > b.0 || (c == b.0 && y < b.1) {
            *b = (c, y);
        }
    }
    best.into_iter().map(|(_, y)| y.min(u32::MAX - 1)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A line of 100 vertices cut into parts at `cuts`.
    fn cut(cuts: &[usize]) -> Vec<u32> {
        (0..100)
            .map(|v| cuts.iter().filter(|&&c| v >= c).count() as u32)
            .collect()
    }

    #[test]
    fn the_adjusted_rand_index_is_one_for_one_partition_and_small_for_unrelated_ones() {
        let a = cut(&[30, 60]);
        assert!((adjusted_rand(&a, &a) - 1.0).abs() < 1e-12);
        // Relabelled, the same partition.
        let b: Vec<u32> = a.iter().map(|&x| 2 - x).collect();
        assert!((adjusted_rand(&a, &b) - 1.0).abs() < 1e-12);
        // Alternating labels share nothing with contiguous blocks.
        let c: Vec<u32> = (0..100).map(|v| v % 3).collect();
        assert!(
            adjusted_rand(&a, &c).abs() < 0.05,
            "{}",
            adjusted_rand(&a, &c)
        );
        assert!(adjusted_rand(&a, &cut(&[31, 60])) > adjusted_rand(&a, &cut(&[40, 60])));
    }

    #[test]
    fn the_vote_puts_each_boundary_where_most_partitions_put_it() {
        // Five draws: the first cut at 28, 30, 30, 33, 45 (one outlier);
        // the second at 60 or 61; one draw splits the last part in two.
        let draws = vec![
            cut(&[45, 60]),
            cut(&[30, 61]),
            cut(&[28, 60]),
            cut(&[30, 60, 80]),
            cut(&[33, 60]),
        ];
        let m = medoid(&draws);
        let v = vote(&draws, m);
        // The majority: the first cut at 30 (three of five put 0..30 in
        // the first part), the second at 60.
        assert_eq!(v, cut(&[30, 60]));
        // The same draws in another order give the same partition.
        let mut back = draws.clone();
        back.reverse();
        let w = vote(&back, medoid(&back));
        assert!((adjusted_rand(&v, &w) - 1.0).abs() < 1e-12);
        // The outlier is not the medoid.
        assert_ne!(m, 0);
        assert!(vote(&[], 0).is_empty());
    }
}
