//! The options of a key-frame job, with the command line's defaults.

use crate::drive::timeline::TimelineOptions;
use crate::keyframe::heading::HeadingTarget;
use crate::keyframe::options::{
    Horizon, LatticeOptions, Limits, Method, SearchOptions, Solver, Weights,
};
use crate::keyframe::{KeyframeOptions, TransitionCost, TransitionSet};

/// The grid's distances by default (metres; the paper's Table III), as
/// [`crate::keyframe::grid::parse_range`] reads them.
pub const DEFAULT_DISTANCES: &str = "1:20:1";

/// The grid's times by default (seconds), as [`DEFAULT_DISTANCES`].
pub const DEFAULT_TIMES: &str = "1:40:1";

/// Options of a key-frame job (Huang et al. 2015, Sec. 5.1). The defaults
/// are those of `surfmotion keyframe` ([`KeyframeJobOptions::DEFAULT`]);
/// they differ from [`KeyframeOptions::default`] in the horizon (seconds at
/// the database's rate, not 250 frames) and carry the heading's weight and
/// sectors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KeyframeJobOptions {
    /// Eq. 7 weight of the distance error, per metre. Default: 1/0.3 (the
    /// paper).
    pub w_dist: f64,
    /// Eq. 7 weight of the time error, per frame. Default: 1/10 (the
    /// paper).
    pub w_time: f64,
    /// Target final facing, degrees relative to the start key-frame's
    /// (positive: from +Z towards +X), in [-360, 360]. Default: none.
    pub heading: Option<f64>,
    /// Weight of the heading error, per degree. Default: 1/30 (30° cost as
    /// much as 0.3 m of distance).
    pub w_heading: f64,
    /// Sectors of turn the exact-length search's bins are split into with
    /// a heading target. Default: 8.
    pub heading_sectors: usize,
    /// The longest path a query may return is max(2 × time, time + this
    /// many seconds) ([`Horizon`]). Default: 10.
    pub horizon_seconds: f64,
    /// Prefer a path within this percentage of both targets over a cheaper
    /// one (Eq. 7) that is not (0: Eq. 7 alone). Default: 1.
    pub within_pct: f64,
    /// Optimality gap of the walks' search (Eq. 7's cost units). Default:
    /// 0.03.
    pub gap: f64,
    /// Most distinct loops handed to one repetition problem (at least 2
    /// are used). Default: 64.
    pub max_loops: usize,
    /// Loop repetition solver of the walks' search. Default:
    /// [`Solver::Exact`].
    pub solver: Solver,
    /// Which search finds the path. Default: [`Method::Lattice`].
    pub method: Method,
    /// Distance bins kept per (node, frame count) by the exact-length
    /// search, 1 to 4096. Default: 32.
    pub bins: usize,
    /// What a transition costs. Default: [`TransitionCost::Graph`].
    pub transition_cost: TransitionCost,
    /// Which transitions the path may take. Default: [`TransitionSet::Graph`].
    pub transitions: TransitionSet,
    /// Blending across transitions. Default: true.
    pub blend: bool,
}

impl KeyframeJobOptions {
    /// The defaults (those of `surfmotion keyframe`).
    pub const DEFAULT: KeyframeJobOptions = KeyframeJobOptions {
        w_dist: 1.0 / 0.3,
        w_time: 0.1,
        heading: None,
        w_heading: 1.0 / 30.0,
        heading_sectors: 8,
        horizon_seconds: 10.0,
        within_pct: 1.0,
        gap: 0.03,
        max_loops: 64,
        solver: Solver::Exact,
        method: Method::Lattice,
        bins: 32,
        transition_cost: TransitionCost::Graph,
        transitions: TransitionSet::Graph,
        blend: true,
    };

    /// The key-frame query's options for a database at `fps` frames per
    /// second.
    pub fn keyframe_options(&self, fps: f64) -> KeyframeOptions {
        KeyframeOptions {
            search: SearchOptions {
                weights: Weights {
                    distance: self.w_dist,
                    time: self.w_time,
                },
                solver: self.solver,
                gap: self.gap,
                method: self.method,
                lattice: LatticeOptions {
                    bins: self.bins,
                    within: self.within_pct / 100.0,
                    ..Default::default()
                },
                heading: self.heading.map(|d| HeadingTarget {
                    degrees: d,
                    weight: self.w_heading,
                    sectors: self.heading_sectors,
                }),
                limits: Limits {
                    loops_per_walk: self.max_loops.max(2),
                    ..Default::default()
                },
                horizon: Horizon {
                    factor: 2.0,
                    slack: self.horizon_seconds * fps,
                },
                ..Default::default()
            },
            timeline: TimelineOptions {
                blend: self.blend,
                ..Default::default()
            },
            transition_cost: self.transition_cost,
            transitions: self.transitions,
        }
    }
}

impl Default for KeyframeJobOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_defaults_are_the_search_defaults_but_the_horizon() {
        let o = KeyframeJobOptions::default().keyframe_options(25.0);
        let d = KeyframeOptions::default();
        assert_eq!(o.search.weights, Weights::default());
        assert_eq!(o.search.lattice, d.search.lattice);
        assert_eq!(o.search.limits, d.search.limits);
        assert_eq!(o.search.horizon, Horizon::default());
        assert_eq!(o, d);
        let h = KeyframeJobOptions {
            heading: Some(30.0),
            ..Default::default()
        };
        let s = h.keyframe_options(30.0).search;
        assert_eq!(s.horizon.slack, 300.0);
        assert_eq!(
            s.heading.map(|x| (x.weight, x.sectors)),
            Some((1.0 / 30.0, 8))
        );
    }
}
