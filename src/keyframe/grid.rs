//! The Table III evaluation (Huang et al. 2015, Sec. 6.1): one query per
//! target of a grid of distances × times (the paper: 1-20 m by 1 m × 1-40 s
//! by 1 s), with the distance and time errors (absolute and as a
//! percentage of the target), the transitions' smoothness and the query
//! time.
//!
//! A target `(d, t)` is *reachable* when some path through the key-frames
//! (transitions at least [`super::options::LatticeOptions::min_run`] frames
//! apart, as the search's paths) travels within 1 % of `d` in a time within
//! 1 % of `t`. It is decided per target ([`super::lattice::oracle`]): the
//! query's own result when it lands within 1 % (a witness); else *out of
//! range* when no frame count within 1 % of `t` has exact-length extremes
//! `[r_min, r_max]` meeting `d ± 1 %` (certain); else the exact-length
//! programme with fine bins ([`ORACLE_BINS`]) over every such frame count:
//! a path found is a witness (the target was reachable and the search
//! missed it), none is a *gap* (the achievable distances of those lengths
//! skip `d ± 1 %`, up to the programme's resolution). The figures are
//! given for the reachable targets and, separately, for the others (where
//! the search returns its best compromise under Eq. 7, flagged).
//!
//! Smoothness (Table III) is measured on the raw database frames that
//! overlap at each transition ([`super::smoothness`]), not on the blended
//! output; [`GridReport::graph_smoothness`] gives the same measure over
//! every transition of the graph, the floor any path with a transition
//! can reach.

use super::error::{GridError, SearchError};
use super::lattice::{Reachability, oracle};
use super::options::SearchOptions;
use super::segment::{Reach, Target};
use super::{Planner, Targets, mean_smoothness, mean_smoothness_vertex, transitions};
use crate::db::Character;
use crate::drive::timeline::TimelineOptions;
use crate::graph::FlatFrame;
use serde::Serialize;
use std::time::Instant;

/// One query of the grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GridQuery {
    /// Target distance (metres).
    pub distance: f64,
    /// Target time (seconds).
    pub time: f64,
    /// Achieved distance (metres).
    pub achieved_distance: f64,
    /// Achieved time (seconds).
    pub achieved_time: f64,
    /// See the module docs.
    pub reachable: bool,
    /// How reachability was decided.
    pub reach: Reachability,
    /// Distance and time both within 1 % of the target.
    pub within_1pct: bool,
    /// Eq. 7's total of the path found (transition cost plus the
    /// distance, time and heading terms), so that two searches can be
    /// compared query by query.
    pub total: f64,
    /// Transitions taken.
    pub transitions: usize,
    /// Of them, transitions between two different sequences
    /// ([`is_across`]).
    pub across: usize,
    /// Mean smoothness over them (metres).
    pub smoothness: Option<f64>,
    /// The same with the vertex-set Hausdorff distance.
    pub smoothness_vertex: Option<f64>,
    /// Search seconds.
    pub seconds: f64,
    /// Search CPU seconds of the querying thread ([`super::clock`];
    /// `None` where the platform does not say).
    pub cpu_seconds: Option<f64>,
    /// A search bound was hit.
    pub bounded: bool,
    /// Final facing minus the heading target (degrees, wrapped to ±180;
    /// `None` without `--heading`).
    pub heading_error_deg: Option<f64>,
    /// Segments found by the walks-and-loops search (the exact-length
    /// search found the others).
    pub walks_and_loops: usize,
}

/// Min, root mean square and max of a set of values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct Spread {
    /// Smallest.
    pub min: f64,
    /// Root mean square.
    pub rms: f64,
    /// Largest.
    pub max: f64,
    /// How many.
    pub count: usize,
}

impl Spread {
    /// Of `v` (zeros when empty).
    pub fn of(v: impl Iterator<Item = f64>) -> Spread {
        let v: Vec<f64> = v.collect();
        if v.is_empty() {
            return Spread::default();
        }
        Spread {
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            rms: (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt(),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            count: v.len(),
        }
    }
}

/// Errors over a set of queries.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct Errors {
    /// |distance error|, metres.
    pub distance_m: Spread,
    /// |distance error| / target, percent.
    pub distance_pct: Spread,
    /// |time error|, seconds.
    pub time_s: Spread,
    /// |time error| / target, percent.
    pub time_pct: Spread,
    /// Queries whose distance and time errors are both under 1 % of the
    /// target.
    pub within_1pct: usize,
}

impl Errors {
    fn of(q: &[&GridQuery]) -> Errors {
        let de = |x: &&GridQuery| (x.achieved_distance - x.distance).abs();
        let te = |x: &&GridQuery| (x.achieved_time - x.time).abs();
        let pct = |e: f64, t: f64| if t > 0.0 { 100.0 * e / t } else { 0.0 };
        Errors {
            distance_m: Spread::of(q.iter().map(de)),
            distance_pct: Spread::of(q.iter().map(|x| pct(de(x), x.distance))),
            time_s: Spread::of(q.iter().map(te)),
            time_pct: Spread::of(q.iter().map(|x| pct(te(x), x.time))),
            within_1pct: q
                .iter()
                .filter(|x| pct(de(x), x.distance) < 1.0 && pct(te(x), x.time) < 1.0)
                .count(),
        }
    }
}

/// The evaluation.
#[derive(Debug, Clone, Serialize)]
pub struct GridReport {
    /// Key-frames.
    pub keys: Vec<String>,
    /// Distances (metres).
    pub distances: Vec<f64>,
    /// Times (seconds).
    pub times: Vec<f64>,
    /// What the key-frames can reach.
    pub reach: Vec<Reach>,
    /// Errors over the reachable targets.
    pub reachable: Errors,
    /// Errors over the others.
    pub unreachable: Errors,
    /// Smoothness (metres) over the queries with transitions.
    pub smoothness: Spread,
    /// Mean smoothness.
    pub smoothness_mean: f64,
    /// Mean smoothness with the vertex-set Hausdorff distance (the measure
    /// reported before the surface one).
    pub smoothness_vertex_mean: f64,
    /// Query time, milliseconds: mean.
    pub query_ms_mean: f64,
    /// Standard deviation.
    pub query_ms_std: f64,
    /// Largest.
    pub query_ms_max: f64,
    /// Query CPU time of the querying thread, milliseconds
    /// ([`super::clock`]; load-independent, unlike the wall time above):
    /// mean (`None` where the platform does not say).
    pub query_cpu_ms_mean: Option<f64>,
    /// Standard deviation.
    pub query_cpu_ms_std: Option<f64>,
    /// Largest.
    pub query_cpu_ms_max: Option<f64>,
    /// Preparation (once per key-frame list), milliseconds.
    pub prepare_ms: f64,
    /// Queries where a search bound was hit.
    pub bounded: usize,
    /// Unreachable targets out of range of the exact-length extremes.
    pub out_of_range: usize,
    /// Unreachable targets in a gap of the achievable distances.
    pub gaps: usize,
    /// Reachable targets the search did not meet within 1 % (`(d, t)`).
    pub missed: Vec<(f64, f64)>,
    /// Milliseconds spent by the reachability oracle (not in the query
    /// time).
    pub oracle_ms: f64,
    /// Smoothness (metres) of every transition of the graph at its own
    /// blend window: the best any path with a transition can do.
    pub graph_smoothness: Spread,
    /// Its median.
    pub graph_smoothness_median: f64,
    /// [`GridReport::graph_smoothness`] of the transitions within one
    /// sequence (a loop or a skip of one capture).
    pub graph_smoothness_within: Spread,
    /// [`GridReport::graph_smoothness`] of the transitions between two
    /// sequences ([`is_across`]): with key-frames in different sequences
    /// every path takes at least one of them.
    pub graph_smoothness_across: Spread,
    /// Smoothness of every transition the grid's paths take (each time
    /// it is taken), within one sequence.
    pub taken_within: Spread,
    /// The same, between two sequences.
    pub taken_across: Spread,
    /// |Heading error| (degrees) over the queries (empty without
    /// `--heading`).
    pub heading_error_deg: Spread,
    /// Every query.
    pub queries: Vec<GridQuery>,
}

/// One target of [`super::smoothest::floor_grid_with`] (here beside
/// [`GridQuery`], so that [`check_grid`] bounds the records of both grids).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FloorQuery {
    /// Target distance (metres).
    pub distance: f64,
    /// Target time (seconds).
    pub time: f64,
    /// Reachable within 1 % ([`reachability`]).
    pub reachable: bool,
    /// The smoothest path's mean price (the graph's transitions at their
    /// own windows, metres); `None`: no path with a transition found
    /// within the bands.
    pub least_mean: Option<f64>,
    /// The same path's mean smoothness as the grid measures it (the
    /// timeline's windows).
    pub least_mean_measured: Option<f64>,
    /// Its transitions.
    pub transitions: usize,
    /// Its achieved distance (metres) and time (seconds).
    pub achieved: Option<(f64, f64)>,
    /// The exact lower bound ([`super::smoothest::lower_bound`]).
    pub lower_bound: Option<f64>,
    /// Seconds of [`super::smoothest::least_mean`] for this target.
    pub seconds: f64,
}

/// Most values of one range of [`parse_range`].
pub const MAX_RANGE_VALUES: usize = 100_001;

/// Most targets of one grid (distances × times), the work of
/// [`evaluate`] and of [`super::smoothest::floor_grid_with`] (one query, and
/// for the floor several programmes, per target): each axis under
/// [`MAX_RANGE_VALUES`] still made 8.9e9 targets, a 1.28 TB allocation
/// (issue 46.4). The default grid has 800.
pub(crate) const MAX_GRID_TARGETS: usize = 100_000;

/// Refuses a grid of `distances × times` targets before any query runs:
/// more than [`MAX_GRID_TARGETS`], or records beyond the memory budget.
pub(crate) fn check_grid(distances: usize, times: usize) -> Result<(), GridError> {
    let count = distances as u128 * times as u128;
    if count > MAX_GRID_TARGETS as u128 {
        return Err(GridError::TooMany {
            count,
            distances,
            times,
            max: MAX_GRID_TARGETS,
        });
    }
    let each = std::mem::size_of::<GridQuery>().max(std::mem::size_of::<FloorQuery>());
    crate::util::budget::check(
        || {
            format!(
                "a grid of {} targets",
                crate::util::budget::thousands(count)
            )
        },
        count * each as u128,
    )?;
    Ok(())
}

/// A range `a:b:step` (inclusive) or a comma list.
pub fn parse_range(s: &str) -> Result<Vec<f64>, String> {
    let bad = || format!("'{s}': expected A:B:STEP or a comma list of numbers ≥ 0");
    let v: Vec<f64> = if s.contains(':') {
        let p: Vec<f64> = s
            .split(':')
            .map(|x| x.trim().parse::<f64>().map_err(|_| bad()))
            .collect::<Result<_, _>>()?;
        if p.len() != 3 || p[2] <= 0.0 || p[1] < p[0] {
            return Err(bad());
        }
        // Said "expected A:B:STEP" of a well-formed range that was too long.
        // The count is the one generated below (`0:3600:0.036` was refused
        // as "100001 values, at most 100001": the test divided without the
        // rounding slack the generation uses).
        let n = ((p[1] - p[0]) / p[2] + 1e-9).floor();
        if n + 1.0 > MAX_RANGE_VALUES as f64 {
            return Err(format!(
                "'{s}': {:.0} values, at most {MAX_RANGE_VALUES}: choose a larger STEP",
                n + 1.0
            ));
        }
        (0..=n as usize).map(|k| p[0] + k as f64 * p[2]).collect()
    } else {
        s.split(',')
            .map(|x| x.trim().parse::<f64>().map_err(|_| bad()))
            .collect::<Result<_, _>>()?
    };
    if v.is_empty() || v.iter().any(|x| !x.is_finite() || *x < 0.0) {
        return Err(bad());
    }
    Ok(v)
}

/// Distance bins of the reachability oracle per (node, frames, class).
pub(crate) const ORACLE_BINS: usize = 256;

/// Is `(d, t)` reachable (module docs)? `met`: the query's result landed
/// within 1 % (a witness).
pub fn reachability(
    planner: &Planner,
    d: f64,
    t: f64,
    met: bool,
) -> Result<Reachability, SearchError> {
    if met {
        return Ok(Reachability::Reachable);
    }
    let Some(c) = &planner.chain else {
        return Ok(Reachability::Gap);
    };
    let t = Target {
        distance: d,
        frames: t * planner.fps,
    };
    let min_run = SearchOptions::default().lattice.min_run;
    Ok(oracle(c, &t, 0.01, ORACLE_BINS, min_run)?)
}

/// Every transition the search may take, as `(from, to, window)` at its
/// own blend window: the key graph's own jumps when it chose them
/// ([`super::TransitionSet::Measured`]), else the Surface Motion Graph's.
pub fn graph_jumps(
    ch: &Character,
    g: &super::graph::KeyGraph,
) -> Vec<(FlatFrame, FlatFrame, usize)> {
    if !g.windows.is_empty() {
        return g.windows.iter().map(|(&(a, b), &l)| (a, b, l)).collect();
    }
    ch.graph()
        .transitions()
        .iter()
        .map(|t| {
            let from = ch.graph().flat_id(t.from, t.m);
            let to = ch.graph().flat_id(t.to, t.n).next();
            (from, to, t.window)
        })
        .collect()
}

/// Smoothness of every transition the search may take at its own blend
/// window ([`graph_jumps`], [`super::smoothness::transition_smoothness`]),
/// measured through `cache`.
pub fn graph_smoothness(
    ch: &Character,
    g: &super::graph::KeyGraph,
    cache: &mut super::smoothness::Measurer,
) -> Vec<f64> {
    let jumps = graph_jumps(ch, g);
    cache.prefill(ch, &jumps);
    jumps
        .iter()
        .map(|&(a, b, l)| cache.transition(ch, a, b, l).surface)
        .collect()
}

/// True when the jump `from → to` (`to − 1` pairs with `from`) joins two
/// different sequences.
pub(crate) fn is_across(ch: &Character, from: FlatFrame, to: FlatFrame) -> bool {
    ch.graph().frame_of(from).0 != ch.graph().frame_of(to.prev().unwrap_or(to)).0
}

/// [`is_across`] of a transition report's frames (`SEQ:F` names; the
/// frame entered is in the sequence it enters).
pub(crate) fn names_across(from: &str, to: &str) -> bool {
    let seq = |k: &str| {
        k.rsplit_once(':')
            .map_or(k.to_string(), |(s, _)| s.to_string())
    };
    seq(from) != seq(to)
}

/// [`graph_smoothness`] split into the transitions within one sequence
/// and those between two ([`is_across`]), each sorted.
pub(crate) fn graph_smoothness_split(
    ch: &Character,
    g: &super::graph::KeyGraph,
    cache: &mut super::smoothness::Measurer,
) -> (Vec<f64>, Vec<f64>) {
    let jumps = graph_jumps(ch, g);
    cache.prefill(ch, &jumps);
    let (mut within, mut across) = (Vec::new(), Vec::new());
    for &(a, b, l) in &jumps {
        let v = cache.transition(ch, a, b, l).surface;
        if is_across(ch, a, b) {
            across.push(v);
        } else {
            within.push(v);
        }
    }
    within.sort_by(f64::total_cmp);
    across.sort_by(f64::total_cmp);
    (within, across)
}

/// Runs the grid (one global target per query).
pub fn evaluate(
    ch: &Character,
    planner: &Planner,
    distances: &[f64],
    times: &[f64],
    search: &SearchOptions,
    timeline: &TimelineOptions,
) -> Result<GridReport, SearchError> {
    evaluate_with(ch, planner, distances, times, search, timeline, &mut |_| {})
}

/// [`evaluate`], calling `done` with every query as it finishes (in
/// order: distances outer, times inner), so that a caller can show
/// progress and rows before the grid ends. Errors: the grid's size
/// ([`check_grid`]) or the search's.
pub(crate) fn evaluate_with(
    ch: &Character,
    planner: &Planner,
    distances: &[f64],
    times: &[f64],
    search: &SearchOptions,
    timeline: &TimelineOptions,
    done: &mut dyn FnMut(&GridQuery),
) -> Result<GridReport, SearchError> {
    check_grid(distances.len(), times.len())?;
    let reach: Vec<Reach> = planner.segments.iter().map(|s| s.reach()).collect();
    // Every frame pair of every transition the paths may take, measured
    // once and in parallel before the queries (the timeline's shortened
    // windows are subsets of these).
    let mut cache = super::smoothness::Measurer::new(ch);
    cache.prefill(ch, &graph_jumps(ch, &planner.graph));
    let mut oracle_s = 0.0;
    let mut taken = (Vec::new(), Vec::new());
    let mut queries = Vec::with_capacity(distances.len() * times.len());
    for &d in distances {
        for &t in times {
            let q = query(ch, planner, d, t, search, timeline, &mut cache, &mut taken)?;
            oracle_s += q.1;
            queries.push(q.0);
            if let Some(q) = queries.last() {
                done(q);
            }
        }
    }
    Ok(report(
        ch, planner, distances, times, reach, &mut cache, oracle_s, taken, queries,
    ))
}

/// One query of the grid (module docs) and the seconds of its
/// reachability oracle; the smoothness of the transitions it takes goes to
/// `taken` (within one sequence, across two).
#[allow(clippy::too_many_arguments)]
fn query(
    ch: &Character,
    planner: &Planner,
    d: f64,
    t: f64,
    search: &SearchOptions,
    timeline: &TimelineOptions,
    cache: &mut super::smoothness::Measurer,
    taken: &mut (Vec<f64>, Vec<f64>),
) -> Result<(GridQuery, f64), SearchError> {
    let (taken_within, taken_across) = taken;
    let plan = planner.plan(
        &Targets::Global {
            distance: d,
            time: t,
        },
        search,
    )?;
    let (seconds, cpu_seconds) = (plan.search_seconds, plan.search_cpu_seconds);
    let tr = transitions(ch, &planner.graph, &plan.path, timeline, cache);
    let mut across = 0;
    for x in &tr {
        if names_across(&x.from, &x.to) {
            across += 1;
            taken_across.push(x.smoothness);
        } else {
            taken_within.push(x.smoothness);
        }
    }
    let (ad, at) = (
        plan.measure.distance,
        plan.measure.frames as f64 / planner.fps,
    );
    let met = (ad - d).abs() < 0.01 * d && (at - t).abs() < 0.01 * t;
    let o0 = Instant::now();
    let class = reachability(planner, d, t, met)?;
    let oracle_s = o0.elapsed().as_secs_f64();
    Ok((
        GridQuery {
            distance: d,
            time: t,
            achieved_distance: ad,
            achieved_time: at,
            reachable: class == Reachability::Reachable,
            reach: class,
            within_1pct: met,
            total: plan.cost.total,
            transitions: tr.len(),
            across,
            smoothness: mean_smoothness(&tr),
            smoothness_vertex: mean_smoothness_vertex(&tr),
            seconds,
            cpu_seconds,
            bounded: !plan.stats.bounds_hit.is_empty(),
            heading_error_deg: search.heading.map(|h| {
                super::heading::wrap((plan.facing_deg - h.degrees).to_radians()).to_degrees()
            }),
            walks_and_loops: plan.stats.walks_and_loops,
        },
        oracle_s,
    ))
}

/// The grid's report over its `queries` (module docs), with the
/// smoothness of every transition of the graph for comparison.
#[allow(clippy::too_many_arguments)]
fn report(
    ch: &Character,
    planner: &Planner,
    distances: &[f64],
    times: &[f64],
    reach: Vec<Reach>,
    cache: &mut super::smoothness::Measurer,
    oracle_s: f64,
    (taken_within, taken_across): (Vec<f64>, Vec<f64>),
    queries: Vec<GridQuery>,
) -> GridReport {
    let (gw, ga) = graph_smoothness_split(ch, &planner.graph, cache);
    let mut gsm: Vec<f64> = gw.iter().chain(&ga).copied().collect();
    gsm.sort_by(f64::total_cmp);
    let r: Vec<&GridQuery> = queries.iter().filter(|q| q.reachable).collect();
    let u: Vec<&GridQuery> = queries.iter().filter(|q| !q.reachable).collect();
    let sm: Vec<f64> = queries.iter().filter_map(|q| q.smoothness).collect();
    let ms: Vec<f64> = queries.iter().map(|q| 1e3 * q.seconds).collect();
    let (mean, std, max) = mean_std_max(&ms);
    let cpu: Option<Vec<f64>> = queries
        .iter()
        .map(|q| q.cpu_seconds.map(|s| 1e3 * s))
        .collect();
    let cpu = cpu.filter(|v| !v.is_empty()).map(|v| mean_std_max(&v));
    GridReport {
        keys: planner
            .keys
            .iter()
            .map(|&k| super::key_name(ch, k))
            .collect(),
        distances: distances.to_vec(),
        times: times.to_vec(),
        reach,
        reachable: Errors::of(&r),
        unreachable: Errors::of(&u),
        smoothness: Spread::of(sm.iter().copied()),
        smoothness_mean: sm.iter().sum::<f64>() / sm.len().max(1) as f64,
        smoothness_vertex_mean: {
            let v: Vec<f64> = queries.iter().filter_map(|q| q.smoothness_vertex).collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        },
        query_ms_mean: mean,
        query_ms_std: std,
        query_ms_max: max,
        query_cpu_ms_mean: cpu.map(|c| c.0),
        query_cpu_ms_std: cpu.map(|c| c.1),
        query_cpu_ms_max: cpu.map(|c| c.2),
        prepare_ms: 1e3 * planner.prepare_seconds,
        bounded: queries.iter().filter(|q| q.bounded).count(),
        out_of_range: queries
            .iter()
            .filter(|q| q.reach == Reachability::OutOfRange)
            .count(),
        gaps: queries
            .iter()
            .filter(|q| q.reach == Reachability::Gap)
            .count(),
        missed: queries
            .iter()
            .filter(|q| q.reachable && !q.within_1pct)
            .map(|q| (q.distance, q.time))
            .collect(),
        oracle_ms: 1e3 * oracle_s,
        graph_smoothness: Spread::of(gsm.iter().copied()),
        graph_smoothness_median: gsm.get(gsm.len() / 2).copied().unwrap_or(0.0),
        graph_smoothness_within: Spread::of(gw.into_iter()),
        graph_smoothness_across: Spread::of(ga.into_iter()),
        taken_within: Spread::of(taken_within.into_iter()),
        taken_across: Spread::of(taken_across.into_iter()),
        heading_error_deg: Spread::of(
            queries
                .iter()
                .filter_map(|q| q.heading_error_deg.map(f64::abs)),
        ),
        queries,
    }
}

/// Mean, standard deviation and largest of `v` (zeros when empty).
fn mean_std_max(v: &[f64]) -> (f64, f64, f64) {
    let n = v.len().max(1) as f64;
    let mean = v.iter().sum::<f64>() / n;
    let std = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt();
    (mean, std, v.iter().copied().fold(0.0, f64::max))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_across_compares_the_sequences_not_the_frames() {
        assert!(!names_across("walk:38", "walk:11"));
        assert!(names_across("walk:29", "walk-left:30"));
        // Sequence names may hold colons; the frame is after the last.
        assert!(!names_across("a:b:3", "a:b:40"));
        assert!(names_across("a:b:3", "a:c:3"));
    }
}
