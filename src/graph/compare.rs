//! How far a graph built from the sparse similarity agrees with the dense
//! method's (issue 43: where both can run, the sparse one must find at
//! least 95 % of the dense transitions with costs within 5 %).

use super::SurfaceMotionGraph;
use serde::Serialize;

/// The agreement of a graph with a reference graph of the same database.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Agreement {
    /// Transitions of the reference (dense) graph.
    pub reference: usize,
    /// Transitions of the compared (sparse) graph.
    pub compared: usize,
    /// ClipNeutral transitions found at the same frames (same sequences,
    /// `m` and `n`).
    pub same_frames: usize,
    /// ClipNeutral transitions found within `frames` frames on both sides.
    pub near: usize,
    /// Of those found near, the ones whose cost is within `cost` (relative)
    /// of the reference's.
    pub near_and_cost: usize,
    /// The largest relative cost difference among those found near.
    pub worst_cost: f64,
}

impl Agreement {
    /// Share of the reference's transitions found near with their cost
    /// within the tolerance (1 for an empty reference).
    pub fn found(&self) -> f64 {
        if self.reference == 0 {
            1.0
        } else {
            self.near_and_cost as f64 / self.reference as f64
        }
    }
}

/// Compares `compared` with `reference` (graphs of the same sequences): a
/// reference transition is found when `compared` has one between the same
/// sequences within `frames` frames of its `m` and of its `n`; the nearest
/// such is the one whose cost is compared (relative difference at most
/// `cost`).
pub fn agreement(
    reference: &SurfaceMotionGraph,
    compared: &SurfaceMotionGraph,
    frames: usize,
    cost: f64,
) -> Agreement {
    let mut a = Agreement {
        reference: reference.transitions().len(),
        compared: compared.transitions().len(),
        same_frames: 0,
        near: 0,
        near_and_cost: 0,
        worst_cost: 0.0,
    };
    for t in reference.transitions() {
        let best = compared
            .transitions()
            .iter()
            .filter(|u| u.from == t.from && u.to == t.to)
            .filter(|u| u.m.abs_diff(t.m) <= frames && u.n.abs_diff(t.n) <= frames)
            .min_by_key(|u| u.m.abs_diff(t.m) + u.n.abs_diff(t.n));
        let Some(u) = best else { continue };
        a.near += 1;
        if u.m == t.m && u.n == t.n {
            a.same_frames += 1;
        }
        let rel = (u.cost - t.cost).abs() / t.cost.abs().max(1e-12);
        a.worst_cost = a.worst_cost.max(rel);
        if rel <= cost {
            a.near_and_cost += 1;
        }
    }
    a
}
