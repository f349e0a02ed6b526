//! The least mean smoothness of a path that meets the targets: the floor
//! of Table III's smoothness figure (Huang et al. 2015, Sec. 6.1) under
//! the 1 % bands.
//!
//! Sec. 6.1 reports, per query, the mean over the path's transitions of
//! the weighted Hausdorff distance of their overlapping frames (weights
//! `α′(k)` of Eq. 2); the grid averages it over the queries. Eq. 7 sums
//! the transition costs, so it pays for every extra loop, while a mean
//! falls when a path takes more smooth transitions. The question here is
//! per target `(d_V, t_V)`: what is the least mean
//! `s̄(P) = Σ_t s_t / k(P)` over the paths `P` with at least one
//! transition whose distance and time are both within 1 % of the target?
//!
//! A ratio objective, solved by **Dinkelbach's method**: for a fixed `λ`,
//! `F(λ) = min_P Σ_t (s_t − λ)` over the paths within the bands;
//! `F(λ) < 0` exactly when some path has `s̄(P) < λ`. Starting above
//! every transition's `s`, each step takes the minimiser's mean as the
//! next `λ`, and stops when `F(λ) ≥ 0` (the last path is then the least
//! mean, up to how exactly `F` is minimised). `F` is minimised by the
//! exact-length programme of [`super::lattice`] on the chain repriced
//! `s − λ` ([`Chain::repriced`]), with no distance term and the final
//! window the 1 % distance band, over every frame count of the 1 % time
//! band. With `s − λ < 0` a loop has negative cost; the programme's
//! frame count bounds the repetitions (the time band), its cost pruning
//! uses the least cost to the goal computed with the same (negative)
//! prices, which is still a lower bound, and its class dominance does not
//! depend on the sign. The programme bins labels by distance (module docs
//! of [`super::lattice`]), so the path returned is a feasible path whose
//! mean is an **upper bound** on the least mean; [`lower_bound`] gives an
//! exact **lower bound** (a Lagrangian relaxation of the distance band,
//! without [`super::options::LatticeOptions::min_run`], by bisection on
//! `λ` over the extremes' least cost), so the least mean lies between the
//! two.
//!
//! Prices: the chain must be built on a graph priced by the transitions'
//! smoothness at their own blend windows
//! ([`super::TransitionCost::Smoothness`]); what the grid measures on a
//! path can differ where the timeline shortens a window (two transitions
//! closer than their windows), so [`floor_grid_with`] reports the path's mean
//! measured as the grid measures it as well.

use super::error::SearchError;
use super::grid::FloorQuery;
use super::lattice::{Chain, Found, chain_extremes, solve_capped};
use super::options::LatticeOptions;
use super::segment::{ArcView, Target};
use super::{Planner, join, mean_smoothness, transitions};
use crate::db::Character;
use crate::drive::timeline::TimelineOptions;
use crate::util::budget::OverBudget;
use serde::Serialize;

/// The smoothest path found for one target.
#[derive(Debug, Clone, PartialEq)]
pub struct Smoothest {
    /// The path (arcs of the chain).
    pub found: Found,
    /// Its mean transition price (metres when priced by smoothness).
    pub mean: f64,
    /// Its transitions.
    pub transitions: usize,
    /// Dinkelbach steps taken.
    pub steps: usize,
}

/// The frame counts (start not counted) strictly within `within` of the
/// target's time whose exact-length extremes admit its distance within
/// `within`, and the largest of them.
fn band(c: &Chain, t: &Target, within: f64, max_frames: usize) -> Option<(Vec<usize>, usize)> {
    if !(t.distance > 0.0 && t.frames > 0.0 && t.distance.is_finite() && t.frames.is_finite()) {
        return None;
    }
    let cs = i64::from(c.counts_start());
    let least = i64::from(c.least_frames()).max(1);
    let hi = ((t.frames * (1.0 + within)).ceil() as i64 - cs).min(max_frames as i64);
    let ns: Vec<usize> = (least..=hi.max(least))
        .filter(|&n| ((n + cs) as f64 - t.frames).abs() < within * t.frames)
        .map(|n| n as usize)
        .collect();
    let top = *ns.last()?;
    Some((ns, top))
}

/// Transitions and their summed price along `arcs`.
fn tally(arcs: &[u32], by_index: &[Option<ArcView>]) -> (usize, f64) {
    let mut k = 0;
    let mut sum = 0.0;
    for &a in arcs {
        if let Some(Some(v)) = by_index.get(a as usize)
            && v.jump
        {
            k += 1;
            sum += v.m.cost;
        }
    }
    (k, sum)
}

/// The path of least mean transition price among those whose distance
/// and time (start counted) are strictly within `within` of `t` (module
/// docs), or `None` when the programme finds no such path with a
/// transition. At most `max_steps` Dinkelbach steps.
pub fn least_mean(
    c: &Chain,
    t: &Target,
    within: f64,
    opts: &LatticeOptions,
    max_steps: usize,
) -> Result<Option<Smoothest>, OverBudget> {
    let Some((ns, top)) = band(c, t, within, opts.max_frames) else {
        return Ok(None);
    };
    let by_index = c.arcs_by_index();
    let smax = by_index
        .iter()
        .flatten()
        .filter(|a| a.jump)
        .map(|a| a.m.cost)
        .fold(f64::NEG_INFINITY, f64::max);
    if !smax.is_finite() {
        return Ok(None);
    }
    let cs = i64::from(c.counts_start());
    let dt = within * t.distance;
    let start = c.start_node();
    // Above every price: every path with a transition has F < 0.
    let mut lambda = smax + 1e-3 * (1.0 + smax.abs());
    let mut best: Option<Smoothest> = None;
    for step in 1..=max_steps.max(1) {
        let cl = c.repriced(|a| if a.jump { a.m.cost - lambda } else { a.m.cost });
        let ext = chain_extremes(&cl, top)?;
        let mut cur: Option<(Found, f64)> = None;
        for &n in &ns {
            let (a, b) = ext.at(start, n);
            if !(a.is_finite() && a < t.distance + dt && b > t.distance - dt) {
                continue;
            }
            let cap = cur.as_ref().map_or(f64::INFINITY, |x| x.1);
            if ext.least_cost(start, n) >= cap {
                continue;
            }
            let got = solve_capped(
                &cl,
                &ext,
                n,
                t.distance,
                dt * (1.0 - 1e-9),
                0.0,
                None,
                opts,
                cap,
            );
            if let Some((f, sc)) = got {
                let fr = (i64::from(f.measure.frames) + cs) as f64;
                let inside = (f.measure.distance - t.distance).abs() < dt
                    && (fr - t.frames).abs() < within * t.frames;
                if inside && sc < cap {
                    cur = Some((f, sc));
                }
            }
        }
        let Some((f, sc)) = cur else { break };
        if sc >= -1e-12 {
            break;
        }
        let (k, sum) = tally(&f.arcs, &by_index);
        if k == 0 {
            break;
        }
        let mean = sum / k as f64;
        let better = best.as_ref().is_none_or(|b| mean < b.mean);
        if better {
            best = Some(Smoothest {
                found: f,
                mean,
                transitions: k,
                steps: step,
            });
        }
        if !better || mean >= lambda - 1e-12 {
            break;
        }
        lambda = mean;
    }
    Ok(best)
}

/// Multipliers of the distance tried by [`lower_bound`] (per metre, in
/// the units of the prices: metres of smoothness per metre travelled).
const MULTIPLIERS: [f64; 12] = [
    0.0, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0,
];

/// An exact lower bound on [`least_mean`]'s least mean (`tol`: the
/// bisection's final bracket width): the largest `λ` (to `tol`) at which
/// a Lagrangian relaxation proves that no path within the bands has a
/// mean below `λ`. For a path `P` within the bands, `|D(P) − d_V| < δ`
/// (`δ = within · d_V`), so for any multiplier `μ`
/// `Σ_t (s_t − λ) ≥ Σ_t (s_t − λ) + μ (D(P) − d_V) − |μ| δ`, and the
/// right side's minimum over every path whose time is within the band
/// (no distance band, and transitions allowed on consecutive arcs) is
/// the extremes' least cost with each arc priced `[jump] (s − λ) + μ ·
/// distance`, minus `μ d_V + |μ| δ`: exact, by the programme over frame
/// counts. When it is `≥ 0` for some `μ` (a few of either sign are
/// tried), every path within the bands has `Σ_t (s_t − λ) ≥ 0`, i.e. a
/// mean of at least `λ` (or no transition). The test is monotone in `λ`,
/// so a bisection finds the largest proven `λ`. `None` when nothing is
/// proven above the least price (no bound better than the trivial one:
/// the least price is returned then, when some path of the time band has
/// a transition).
pub fn lower_bound(
    c: &Chain,
    t: &Target,
    within: f64,
    max_frames: usize,
    tol: f64,
) -> Result<Option<f64>, OverBudget> {
    let Some((ns, top)) = band(c, t, within, max_frames) else {
        return Ok(None);
    };
    let (lo0, hi0) = c
        .arcs_by_index()
        .iter()
        .flatten()
        .filter(|a| a.jump)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x.m.cost), b.max(x.m.cost))
        });
    if !lo0.is_finite() {
        return Ok(None);
    }
    let start = c.start_node();
    let delta = within * t.distance;
    // Proven: no path within the bands has a transition and a mean
    // below `lambda`.
    let proven = |lambda: f64| -> Result<bool, OverBudget> {
        for m in MULTIPLIERS {
            for mu in [m, -m] {
                let cl = c
                    .repriced(|a| mu * a.m.distance + if a.jump { a.m.cost - lambda } else { 0.0 });
                let ext = chain_extremes(&cl, top)?;
                let g = ns
                    .iter()
                    .map(|&n| ext.least_cost(start, n))
                    .fold(f64::INFINITY, f64::min);
                if g - mu * t.distance - mu.abs() * delta >= 0.0 {
                    return Ok(true);
                }
                if m == 0.0 {
                    break;
                }
            }
        }
        Ok(false)
    };
    let (mut lo, mut hi) = (lo0, hi0 + 1e-9);
    if proven(hi)? {
        // Nothing within the bands has a transition at all (or none is
        // found by the relaxation): no mean to bound.
        return Ok(None);
    }
    while hi - lo > tol.max(1e-9) {
        let mid = 0.5 * (lo + hi);
        if proven(mid)? {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(Some(lo))
}

/// Min / mean / median / max of a set.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SmoothestSummary {
    /// Values.
    pub n: usize,
    /// Least.
    pub min: f64,
    /// Mean.
    pub mean: f64,
    /// Median.
    pub median: f64,
    /// Largest.
    pub max: f64,
}

/// The old name of [`SmoothestSummary`] (before session 40: one name per concept,
/// issue 40 — `Summary` named the smoothest-path grid's statistics and two other things).
#[deprecated(note = "renamed SmoothestSummary")]
pub type Summary = SmoothestSummary;

impl SmoothestSummary {
    /// Of `v` (`None` when empty).
    pub fn of(mut v: Vec<f64>) -> Option<SmoothestSummary> {
        if v.is_empty() {
            return None;
        }
        v.sort_by(f64::total_cmp);
        Some(SmoothestSummary {
            n: v.len(),
            min: v[0],
            mean: v.iter().sum::<f64>() / v.len() as f64,
            median: v[v.len() / 2],
            max: v[v.len() - 1],
        })
    }
}

/// The floor over a grid.
#[derive(Debug, Clone, Serialize)]
pub struct FloorReport {
    /// Reachable targets.
    pub reachable: usize,
    /// Of them, those with a path with a transition found within 1 %.
    pub kept: usize,
    /// Least mean (priced) over the kept reachable targets.
    pub least_mean: Option<SmoothestSummary>,
    /// Least mean as the grid measures it, over the same targets.
    pub least_mean_measured: Option<SmoothestSummary>,
    /// The exact lower bound over the reachable targets that have one.
    pub lower_bound: Option<SmoothestSummary>,
    /// Every target.
    pub queries: Vec<FloorQuery>,
}

/// [`least_mean`] and [`lower_bound`] for every target of a grid, on a
/// planner whose graph is priced by smoothness (module docs), within 1 %,
/// calling `done` with every target as it finishes
/// (distances outer, times inner). Errors: the grid's size
/// ([`super::grid::check_grid`]) or the search's.
pub(crate) fn floor_grid_with(
    ch: &Character,
    planner: &Planner,
    distances: &[f64],
    times: &[f64],
    opts: &LatticeOptions,
    timeline: &TimelineOptions,
    done: &mut dyn FnMut(&FloorQuery),
) -> Result<FloorReport, SearchError> {
    super::grid::check_grid(distances.len(), times.len())?;
    let Some(c) = &planner.chain else {
        return Ok(FloorReport {
            reachable: 0,
            kept: 0,
            least_mean: None,
            least_mean_measured: None,
            lower_bound: None,
            queries: Vec::new(),
        });
    };
    let mut cache = super::smoothness::Measurer::new(ch);
    cache.prefill(ch, &super::grid::graph_jumps(ch, &planner.graph));
    let within = 0.01;
    let mut queries = Vec::new();
    for &d in distances {
        for &tm in times {
            let t0 = std::time::Instant::now();
            let t = Target {
                distance: d,
                frames: tm * planner.fps,
            };
            let best = least_mean(c, &t, within, opts, 12)?;
            let seconds = t0.elapsed().as_secs_f64();
            let (mut measured, mut achieved, mut met) = (None, None, false);
            if let Some(b) = &best {
                let segs: Vec<_> = c
                    .split(&b.found.arcs)
                    .iter()
                    .zip(&planner.segments)
                    .map(|(arcs, s)| s.decompose(arcs))
                    .collect();
                let path = join(&segs);
                let frames: u32 = segs.iter().map(|s| s.measure.frames).sum();
                let dist: f64 = segs.iter().map(|s| s.measure.distance).sum();
                let at = frames as f64 / planner.fps;
                met = (dist - d).abs() < 0.01 * d && (at - tm).abs() < 0.01 * tm;
                achieved = Some((dist, at));
                let tr = transitions(ch, &planner.graph, &path, timeline, &mut cache);
                measured = mean_smoothness(&tr);
            }
            let class = super::grid::reachability(planner, d, tm, met)?;
            let reachable = class == super::lattice::Reachability::Reachable;
            // The bound only where the floor is asked (reachable targets).
            let lb = if reachable {
                lower_bound(c, &t, within, opts.max_frames, 5e-4)?
            } else {
                None
            };
            queries.push(FloorQuery {
                distance: d,
                time: tm,
                reachable,
                least_mean: best.as_ref().filter(|_| met).map(|b| b.mean),
                least_mean_measured: measured.filter(|_| met),
                transitions: best.as_ref().map_or(0, |b| b.transitions),
                achieved,
                lower_bound: lb,
                seconds,
            });
            if let Some(q) = queries.last() {
                done(q);
            }
        }
    }
    let r: Vec<&FloorQuery> = queries.iter().filter(|q| q.reachable).collect();
    Ok(FloorReport {
        reachable: r.len(),
        kept: r.iter().filter(|q| q.least_mean.is_some()).count(),
        least_mean: SmoothestSummary::of(r.iter().filter_map(|q| q.least_mean).collect()),
        least_mean_measured: SmoothestSummary::of(
            r.iter().filter_map(|q| q.least_mean_measured).collect(),
        ),
        lower_bound: SmoothestSummary::of(r.iter().filter_map(|q| q.lower_bound).collect()),
        queries,
    })
}
