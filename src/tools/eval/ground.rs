//! Ground penetration and floating: the lowest vertex of each frame below
//! or above the floor.
//!
//! The floor of a 4D database is the median over its frames of the lowest
//! vertex height (a capture stands on its floor in most frames); for a
//! scan, the rest frame's lowest point ([`lowest_heights`] on it).

use super::summary::EvalSummary;
use glam::DVec3;
use serde::Serialize;

/// Height along `up` of the lowest vertex of each frame (frame-major,
/// `n` vertices each; the input's units). O(frames × n).
pub fn lowest_heights(frames: &[[f64; 3]], n: usize, up: DVec3) -> Vec<f64> {
    let up = up.normalize_or(DVec3::Y);
    frames
        .chunks_exact(n.max(1))
        .map(|f| {
            f.iter()
                .map(|p| DVec3::from_array(*p).dot(up))
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

/// The floor of a set of captured frames: the median of their lowest heights.
pub fn floor_height(lowest: &[f64]) -> f64 {
    EvalSummary::of(lowest).median
}

/// Penetration and floating over a sequence (centimetres, from metres).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct Ground {
    /// Depth of the lowest vertex below the floor, per frame (0 when above).
    pub penetration_cm: EvalSummary,
    /// Height of the lowest vertex above the floor, per frame (0 when below).
    pub floating_cm: EvalSummary,
}

/// Penetration and floating of frames with lowest heights `lowest` (metres)
/// against the floor at `floor`.
pub fn ground(lowest: &[f64], floor: f64) -> Ground {
    let below: Vec<f64> = lowest
        .iter()
        .map(|h| 100.0 * (floor - h).max(0.0))
        .collect();
    let above: Vec<f64> = lowest
        .iter()
        .map(|h| 100.0 * (h - floor).max(0.0))
        .collect();
    Ground {
        penetration_cm: EvalSummary::of(&below),
        floating_cm: EvalSummary::of(&above),
    }
}
