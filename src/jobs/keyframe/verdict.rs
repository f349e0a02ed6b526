//! Which targets a key-frame path misses.

use crate::keyframe::Report;
use serde::Serialize;

/// A heading target is flagged when the final facing misses it by more
/// than this (degrees): 1 % of a turn, as distance and time are flagged
/// beyond 1 % of their targets.
pub const HEADING_TOLERANCE_DEG: f64 = 3.6;

/// A target a path misses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Missed {
    /// The distance, by more than 1 % of a non-zero target.
    Distance,
    /// The time, by more than 1 % of a non-zero target.
    Time,
    /// The heading, by more than [`HEADING_TOLERANCE_DEG`].
    Heading,
}

/// The targets a path misses (a global target's distance and time, and
/// the heading), in that order.
pub fn missed_targets(r: &Report) -> Vec<Missed> {
    let mut out = Vec::new();
    if let (Some(de), Some(te)) = (r.distance_error, r.time_error) {
        let (dt, tt) = (r.distance - de, r.time - te);
        if dt > 0.0 && de.abs() > 0.01 * dt {
            out.push(Missed::Distance);
        }
        if tt > 0.0 && te.abs() > 0.01 * tt {
            out.push(Missed::Time);
        }
    }
    if r.heading_error_deg
        .is_some_and(|e| e.abs() > HEADING_TOLERANCE_DEG)
    {
        out.push(Missed::Heading);
    }
    out
}

/// Whether a segment with its own target misses its distance or time by
/// more than 1 % of a non-zero target.
pub fn segment_missed(seg: &crate::keyframe::SegmentReport) -> bool {
    let (Some(td), Some(tt)) = (seg.target_distance, seg.target_time) else {
        return false;
    };
    let (de, te) = (seg.distance - td, seg.time - tt);
    (td > 0.0 && de.abs() > 0.01 * td) || (tt > 0.0 && te.abs() > 0.01 * tt)
}
