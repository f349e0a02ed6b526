//! Vertex error against ground truth of the same topology (the
//! self-transfer check of Confluent Motion, de Aguiar et al. 2007, Sec. 6):
//! per-vertex distances as a percentage of the character's height.

use serde::Serialize;

/// Vertex error of an output against ground truth of the same topology
/// (the self-transfer check of Confluent Motion): distances per vertex and
/// frame as a percentage of `height`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VertexError {
    /// Mean over frames and vertices (% of height).
    pub mean_pct: f64,
    /// 95th percentile over frames and vertices (% of height).
    pub p95_pct: f64,
    /// Largest (% of height).
    pub max_pct: f64,
    /// Mean per frame (% of height).
    pub per_frame: Vec<f64>,
}

/// The vertex error of `output` against `truth` (both frames × `n`
/// vertices, row-major; the shorter length is used).
pub fn vertex_error(output: &[[f64; 3]], truth: &[[f64; 3]], n: usize, height: f64) -> VertexError {
    let frames = output.len().min(truth.len()) / n.max(1);
    let scale = 100.0 / height.max(1e-300);
    let mut all: Vec<f64> = Vec::with_capacity(frames * n);
    let mut per_frame = Vec::with_capacity(frames);
    for f in 0..frames {
        let r = f * n..(f + 1) * n;
        let before = all.len();
        all.extend(output[r.clone()].iter().zip(&truth[r]).map(|(a, b)| {
            let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
            scale * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        }));
        per_frame.push(all[before..].iter().sum::<f64>() / n.max(1) as f64);
    }
    let mean = all.iter().sum::<f64>() / all.len().max(1) as f64;
    all.sort_by(f64::total_cmp);
    let pick = |q: f64| {
        all.get(((all.len() as f64 - 1.0) * q).round().max(0.0) as usize)
            .copied()
            .unwrap_or(0.0)
    };
    VertexError {
        mean_pct: mean,
        p95_pct: pick(0.95),
        max_pct: pick(1.0),
        per_frame,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vertex_error_in_percent_of_height() {
        let a = vec![[0.0; 3]; 20];
        let mut b = a.clone();
        b[19] = [0.0, 0.5, 0.0];
        let e = vertex_error(&a, &b, 10, 2.0);
        assert_eq!(e.per_frame, vec![0.0, 2.5]);
        assert_eq!(e.max_pct, 25.0);
        assert_eq!(e.p95_pct, 0.0);
        assert!((e.mean_pct - 1.25).abs() < 1e-12);
    }
}
