//! Table III over a grid of targets, and the least mean smoothness per
//! target (`keyframe::grid`, `keyframe::smoothest`).

use super::KeyframeJobError;
use crate::db::Character;
use crate::keyframe::grid::{FloorQuery, GridQuery, GridReport, check_grid, evaluate_with};
use crate::keyframe::smoothest::{FloorReport, floor_grid_with};
use crate::keyframe::{
    KeyframeError, KeyframeOptions, MAX_TARGET_METRES, MAX_TARGET_SECONDS, Planner, TransitionCost,
    describe, facing_change, key_graph,
};
use serde::Serialize;
use std::time::Instant;

/// The targets of a grid: every distance × every time.
#[derive(Debug, Clone, PartialEq)]
pub struct GridTargets {
    /// Metres, each at most [`MAX_TARGET_METRES`].
    pub distances: Vec<f64>,
    /// Seconds, each at most [`MAX_TARGET_SECONDS`].
    pub times: Vec<f64>,
}

impl GridTargets {
    /// The targets, bounded as a single query's are (the search's horizon
    /// grows with the target).
    pub fn new(distances: Vec<f64>, times: Vec<f64>) -> Result<GridTargets, KeyframeJobError> {
        for (option, v, max, unit) in [
            ("distances", &distances, MAX_TARGET_METRES, "m"),
            ("times", &times, MAX_TARGET_SECONDS, "s"),
        ] {
            if let Some(x) = v.iter().find(|x| **x > max) {
                // `{x}` of 1e308 is 309 digits.
                let value = if *x < 1e9 {
                    x.to_string()
                } else {
                    format!("{x:e}")
                };
                return Err(KeyframeJobError::TooLarge {
                    option,
                    value,
                    max,
                    unit,
                });
            }
        }
        Ok(GridTargets { distances, times })
    }

    /// Refuses a grid too large to run (its count, or its records over
    /// the memory budget: 8.9e9 targets aborted on a 1.28 TB allocation,
    /// issue 46.4), before the database is loaded.
    pub fn check_size(&self) -> Result<(), KeyframeJobError> {
        Ok(check_grid(self.distances.len(), self.times.len())?)
    }
}

/// The planner of the grid's queries through `keys` (the search prepared
/// once for every target).
pub fn grid_planner(
    ch: &Character,
    keys: &[crate::graph::FlatFrame],
    opts: &KeyframeOptions,
) -> Result<Planner, KeyframeJobError> {
    let mut planner = Planner::new(key_graph(ch, opts), keys, ch.manifest().fps, &opts.search)
        .map_err(|e| KeyframeError::Search(describe(ch, &e)))?;
    planner.facing = facing_change(ch, keys);
    Ok(planner)
}

/// Table III: one query per target of `targets` with `planner`
/// ([`grid_planner`]); `done` is told each query as it finishes.
pub fn grid(
    ch: &Character,
    planner: &Planner,
    opts: &KeyframeOptions,
    targets: &GridTargets,
    done: &mut dyn FnMut(&GridQuery),
) -> Result<GridReport, KeyframeJobError> {
    let (ds, ts) = (&targets.distances, &targets.times);
    evaluate_with(ch, planner, ds, ts, &opts.search, &opts.timeline, done)
        .map_err(|e| KeyframeError::Search(describe(ch, &e)).into())
}

/// The options of the least-mean search: `opts` with the transitions
/// priced by their measured smoothness.
fn priced(opts: &KeyframeOptions) -> KeyframeOptions {
    KeyframeOptions {
        transition_cost: TransitionCost::Smoothness,
        ..*opts
    }
}

/// The planner of [`least_mean`]: the graph priced by smoothness.
pub fn least_mean_planner(
    ch: &Character,
    keys: &[crate::graph::FlatFrame],
    opts: &KeyframeOptions,
) -> Result<Planner, KeyframeJobError> {
    let g = key_graph(ch, &priced(opts));
    Ok(Planner::new(g, keys, ch.manifest().fps, &opts.search)
        .map_err(|e| KeyframeError::Search(describe(ch, &e)))?)
}

/// [`least_mean`]'s report.
#[derive(Debug, Clone, Serialize)]
pub struct LeastMean {
    /// Per target and over the targets.
    #[serde(flatten)]
    pub report: FloorReport,
    /// Seconds of the whole evaluation.
    #[serde(skip)]
    pub seconds: f64,
}

/// Per target of `targets`, the least mean smoothness of any path within
/// 1 % of both the distance and the time, with an exact lower bound
/// ([`floor_grid_with`]), with `planner` ([`least_mean_planner`]); `done`
/// is told each target as it finishes.
pub fn least_mean(
    ch: &Character,
    planner: &Planner,
    opts: &KeyframeOptions,
    targets: &GridTargets,
    done: &mut dyn FnMut(&FloorQuery),
) -> Result<LeastMean, KeyframeJobError> {
    let t0 = Instant::now();
    let (ds, ts) = (&targets.distances, &targets.times);
    let report = floor_grid_with(
        ch,
        planner,
        ds,
        ts,
        &opts.search.lattice,
        &opts.timeline,
        done,
    )
    .map_err(|e| KeyframeError::Search(describe(ch, &e)))?;
    Ok(LeastMean {
        report,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grid_targets_over_the_bound_name_the_option_not_a_flag() {
        let e = GridTargets::new(vec![1.0, 1e308], vec![1.0]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "distances 1e308: at most 100000 m (the search's horizon grows with the target)"
        );
        let e = GridTargets::new(vec![1.0], vec![3600.5]).unwrap_err();
        assert!(
            e.to_string().starts_with("times 3600.5: at most 3600 s"),
            "{e}"
        );
        let t = GridTargets::new(vec![1.0; 1000], vec![1.0; 1000]).unwrap();
        let e = t.check_size().unwrap_err().to_string();
        assert!(
            e.starts_with("distances × times: a grid of 1,000,000 targets"),
            "{e}"
        );
        assert!(!e.contains("--"), "{e}");
    }
}
