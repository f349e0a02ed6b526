//! The papers' metrics.
//!
//! Joint-velocity error (Huang et al. 2015, Sec. 6.2, Figs. 13-14): the
//! average over frames and joints of `‖v_q − v_o‖`, where `v = x(t+1) − x(t)`
//! is a joint's velocity vector per frame, `q` the query skeleton (on the
//! character's bones) and `o` the skeleton extracted from the output mesh;
//! in cm/frame, with the standard deviation of the per-frame means.

use crate::skeleton::Pose;
use serde::Serialize;

/// Joint-velocity error of an output against its query.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct VelocityError {
    /// Mean over frames and joints (cm/frame).
    pub mean_cm: f64,
    /// Standard deviation of the per-frame means (cm/frame).
    pub std_cm: f64,
    /// Frames compared (velocities).
    pub frames: usize,
    /// Mean over joints per frame (cm/frame), from the second frame on.
    pub per_frame: Vec<f64>,
}

/// The joint-velocity error of `output` against `query` (metres; the
/// shorter length is used).
pub fn velocity_error(query: &[Pose], output: &[Pose]) -> VelocityError {
    let n = query.len().min(output.len());
    let per: Vec<f64> = (1..n)
        .map(|t| {
            let s: f64 = (0..query[t].len())
                .map(|j| {
                    let vq = query[t][j] - query[t - 1][j];
                    let vo = output[t][j] - output[t - 1][j];
                    (vq - vo).length()
                })
                .sum();
            100.0 * s / query[t].len() as f64
        })
        .collect();
    let m = per.len().max(1) as f64;
    let mean = per.iter().sum::<f64>() / m;
    let var = per.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / m;
    VelocityError {
        mean_cm: mean,
        std_cm: var.sqrt(),
        frames: per.len(),
        per_frame: per,
    }
}

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
    use glam::DVec3;

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

    #[test]
    fn velocity_error_ignores_offsets_and_sees_speed() {
        let q: Vec<Pose> = (0..10)
            .map(|t| [DVec3::new(0.01 * t as f64, 1.0, 0.0); 19])
            .collect();
        let shifted: Vec<Pose> = q.iter().map(|p| p.map(|x| x + DVec3::X * 5.0)).collect();
        let e = velocity_error(&q, &shifted);
        assert!(e.mean_cm.abs() < 1e-9 && e.frames == 9);
        let still: Vec<Pose> = vec![q[0]; 10];
        assert!((velocity_error(&q, &still).mean_cm - 1.0).abs() < 1e-9);
    }
}
