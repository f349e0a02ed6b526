//! The job's inputs from the arguments: its options (the job's
//! defaults, overridden by what was given), the targets, and its errors in
//! the command line's words.

use super::args::{Args, CostArg, MethodArg, SolverArg, TransitionsArg};
use crate::cli::mirror::mirror;
use surfmotion::jobs::keyframe::{GridTargets, KeyframeJobError, KeyframeJobOptions};
use surfmotion::keyframe::grid::parse_range;
use surfmotion::keyframe::options::{Method, Solver};
use surfmotion::keyframe::{TransitionCost, TransitionSet};

/// The job's defaults.
const D: KeyframeJobOptions = KeyframeJobOptions::DEFAULT;

/// A job error in the command line's words: the options it names become
/// their flags.
pub fn flagged(e: KeyframeJobError) -> anyhow::Error {
    match e {
        KeyframeJobError::TooLarge { .. } => anyhow::anyhow!("--{e}"),
        KeyframeJobError::Grid(g) => anyhow::anyhow!("--distances × --times: {g}"),
        e => e.into(),
    }
}

/// The grid's targets (`--distances`, `--times`), parsed and bounded as a
/// single query's are.
pub fn grid_targets(a: &Args) -> anyhow::Result<GridTargets> {
    let ds = parse_range(&a.distances).map_err(|e| anyhow::anyhow!("--distances {e}"))?;
    let ts = parse_range(&a.times).map_err(|e| anyhow::anyhow!("--times {e}"))?;
    GridTargets::new(ds, ts).map_err(flagged)
}

mirror!(SolverArg, Solver, Exact, Ilp);
mirror!(MethodArg, Method, Lattice, Walks);
mirror!(CostArg, TransitionCost, Graph, Smoothness);
mirror!(TransitionsArg, TransitionSet, Graph, Measured);

impl Args {
    /// The job's options: its defaults, and what was given.
    pub fn options(&self) -> KeyframeJobOptions {
        KeyframeJobOptions {
            w_dist: self.w_dist.unwrap_or(D.w_dist),
            w_time: self.w_time.unwrap_or(D.w_time),
            heading: self.heading,
            w_heading: self.w_heading.unwrap_or(D.w_heading),
            horizon_seconds: self.horizon,
            within_pct: self.within,
            gap: self.gap,
            max_loops: self.max_loops,
            solver: self.solver.into(),
            method: self.search.into(),
            bins: self.bins as usize,
            transition_cost: self.transition_cost.into(),
            transitions: self.transitions.into(),
            blend: !self.no_blend,
            ..D
        }
    }
}
