//! A learnt deformation space: PCA of example Laplacian coordinates
//! (Huang et al. 2015, Eqs. 33-34).
//!
//! The `F` examples' Laplacian coordinates (`n` vertices × 3) are centred on
//! their mean `δ̄` and decomposed; the leading components holding the
//! requested share of the variance form an orthonormal basis `E`, so a
//! deformation is `δ(r) = δ̄ + E r`. With `F ≪ 3n` the decomposition is done
//! on the `F × F` Gram matrix of the centred examples (the method of
//! snapshots): its eigenvectors `u_k` with eigenvalues `σ_k²` give the
//! principal directions `e_k = M_cᵀ u_k / σ_k`, the right singular vectors
//! of the SVD the paper uses.

use nalgebra::{DMatrix, SymmetricEigen};

/// Mean and orthonormal basis of a deformation space.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Basis {
    /// Mean Laplacian coordinates `δ̄` (one `[x, y, z]` per vertex).
    pub mean: Vec<[f64; 3]>,
    /// Orthonormal components `e_k`, largest variance first.
    pub components: Vec<Vec<[f64; 3]>>,
    /// Share of the variance each component holds.
    pub explained: Vec<f64>,
}

fn dot(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| p[0] * q[0] + p[1] * q[1] + p[2] * q[2])
        .sum()
}

/// PCA of `examples` (each `n` rows), keeping components up to `keep` of the
/// variance (0.95 in the paper; 1.0 keeps every non-zero one).
pub(crate) fn pca(examples: &[Vec<[f64; 3]>], keep: f64) -> Basis {
    let f = examples.len();
    let n = examples.first().map_or(0, Vec::len);
    let mut mean = vec![[0.0; 3]; n];
    for e in examples {
        for (m, v) in mean.iter_mut().zip(e) {
            for k in 0..3 {
                m[k] += v[k] / f as f64;
            }
        }
    }
    let centred: Vec<Vec<[f64; 3]>> = examples
        .iter()
        .map(|e| {
            e.iter()
                .zip(&mean)
                .map(|(v, m)| [v[0] - m[0], v[1] - m[1], v[2] - m[2]])
                .collect()
        })
        .collect();
    let gram = DMatrix::from_fn(f, f, |i, j| dot(&centred[i], &centred[j]));
    let eig = SymmetricEigen::new(gram);
    let mut order: Vec<usize> = (0..f).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let total: f64 = eig.eigenvalues.iter().map(|v| v.max(0.0)).sum();
    let mut components: Vec<Vec<[f64; 3]>> = Vec::new();
    let mut explained = Vec::new();
    let mut acc = 0.0;
    for &k in &order {
        let lambda = eig.eigenvalues[k];
        if total <= 0.0 || lambda <= total * 1e-12 || acc >= keep * total * (1.0 - 1e-12) {
            break;
        }
        let sigma = lambda.sqrt();
        let u = eig.eigenvectors.column(k);
        let mut e = vec![[0.0; 3]; n];
        for (i, c) in centred.iter().enumerate() {
            let w = u[i] / sigma;
            for (ev, cv) in e.iter_mut().zip(c) {
                for d in 0..3 {
                    ev[d] += w * cv[d];
                }
            }
        }
        // Re-orthonormalise against rounding.
        for prev in &components {
            let p = dot(&e, prev);
            for (ev, pv) in e.iter_mut().zip(prev) {
                for d in 0..3 {
                    ev[d] -= p * pv[d];
                }
            }
        }
        let norm = dot(&e, &e).sqrt();
        if norm <= 0.0 {
            break;
        }
        for ev in e.iter_mut() {
            for d in ev.iter_mut() {
                *d /= norm;
            }
        }
        components.push(e);
        explained.push(lambda / total);
        acc += lambda;
    }
    Basis {
        mean,
        components,
        explained,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn basis_is_orthonormal_and_spans_the_examples() {
        let ex: Vec<Vec<[f64; 3]>> = (0..6)
            .map(|k| {
                (0..40)
                    .map(|i| {
                        let t = (i * (k + 1)) as f64 * 0.1;
                        [t.sin(), (t * 0.7).cos() * k as f64, 0.3 * i as f64]
                    })
                    .collect()
            })
            .collect();
        let b = pca(&ex, 1.0);
        assert!(b.components.len() <= 5 && !b.components.is_empty());
        for (i, a) in b.components.iter().enumerate() {
            for (j, c) in b.components.iter().enumerate() {
                let d = dot(a, c);
                assert!((d - f64::from(u8::from(i == j))).abs() < 1e-9);
            }
        }
        // Every example is the mean plus its projection.
        for e in &ex {
            let c: Vec<[f64; 3]> = e
                .iter()
                .zip(&b.mean)
                .map(|(v, m)| [v[0] - m[0], v[1] - m[1], v[2] - m[2]])
                .collect();
            let mut r = c.clone();
            for comp in &b.components {
                let p = dot(&c, comp);
                for (rv, cv) in r.iter_mut().zip(comp) {
                    for d in 0..3 {
                        rv[d] -= p * cv[d];
                    }
                }
            }
            assert!(dot(&r, &r).sqrt() < 1e-8 * dot(&c, &c).sqrt().max(1.0));
        }
        // 95 % keeps fewer or as many.
        assert!(pca(&ex, 0.95).components.len() <= b.components.len());
        let total: f64 = b.explained.iter().sum();
        assert!((total - 1.0).abs() < 1e-9);
    }
}
