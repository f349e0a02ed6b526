//! Joint-velocity error (Huang et al. 2015, Sec. 6.2, Figs. 13-14): the
//! average over frames and joints of `‖v_q − v_o‖`, where `v = x(t+1) − x(t)`
//! is a joint's velocity vector per frame, `q` the query skeleton (on the
//! character's bones) and `o` the skeleton extracted from the output mesh;
//! in cm/frame, with the standard deviation of the per-frame means.

use crate::pose::Pose;
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

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
