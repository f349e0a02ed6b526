//! The path search between two key-frames (Huang et al. 2015, Sec. 5.1.1):
//! every path is a loop-free walk plus repetitions of loops attached to it
//! (Eq. 14); walks and loops are enumerated by depth-first search, and each
//! walk's repetition counts come from [`super::repeats`] (Eq. 20); the best
//! walk wins (Eq. 21).
//!
//! The search runs on a segment's compressed graph ([`super::segment`]),
//! whose walks and loops are enumerated when it is built.
//!
//! Guards against explosion: the cycle and walk enumerations and the
//! loops handed to one repetition problem are bounded
//! ([`super::options::Limits`]); a walk prefix is cut as soon as its lower
//! bound (its transition cost plus the cheapest completion, plus the
//! distance and time it must already overshoot) reaches the best cost
//! found; a hit bound is reported in [`super::segment::Stats::bounds_hit`].

use super::error::SearchError;
use super::heading::{Heading, wrap};
use super::lattice::{self, Chain, Found};
use super::options::{Method, SearchOptions, Solver};
use super::repeats::{self, Problem, RepeatsError, Tally, Turns, solve_bounded, solve_ilp};
use super::segment::{Segment, SegmentPath, Stats, Target};

/// The searches of a segment (Eqs. 20-22) and its exact-length search.
impl Segment {
    /// The exact-length search ([`super::lattice::search`]) on this
    /// segment alone; `None` when it finds nothing within its tolerance.
    pub(crate) fn solve_lattice(
        &self,
        t: &Target,
        heading: Option<&Heading>,
        opts: &SearchOptions,
    ) -> Result<Option<(SegmentPath, Found)>, SearchError> {
        let Some(c) = Chain::of(std::slice::from_ref(self)) else {
            return Ok(None);
        };
        self.solve_lattice_on(&c, t, heading, opts)
    }

    /// [`Segment::solve_lattice`] on this segment's chain `c` (built once
    /// by the caller, [`Chain::of`] of this segment alone,
    /// so that its extremes serve every query).
    pub(crate) fn solve_lattice_on(
        &self,
        c: &Chain,
        t: &Target,
        heading: Option<&Heading>,
        opts: &SearchOptions,
    ) -> Result<Option<(SegmentPath, Found)>, SearchError> {
        Ok(lattice::search(c, t, heading, opts)?
            .map(|(found, _)| (self.decompose(&found.arcs), found)))
    }

    /// The repetition counts of `loops` on `walk` (Eq. 20), with the
    /// heading term `turns` when there is a heading target.
    #[allow(clippy::too_many_arguments)]
    fn solve_repeats(
        &self,
        walk: Tally,
        loops: &[Tally],
        turns: Option<Turns<'_>>,
        t: &Target,
        opts: &SearchOptions,
        bound: f64,
        stats: &mut Stats,
    ) -> Result<(Vec<u32>, f64), SearchError> {
        // Loops may fill the horizon less the walk (a walk longer than
        // the horizon is taken without loops, so a path always exists).
        let room = (opts.horizon.frames(t.frames) - f64::from(walk.frames))
            .floor()
            .clamp(0.0, f64::from(u32::MAX));
        let p = Problem {
            walk,
            loops,
            distance: t.distance,
            frames: t.frames,
            w_dist: opts.weights.distance,
            w_time: opts.weights.time,
            heading: turns,
            max_loop_frames: Some(room as u32),
        };
        let r = match opts.solver {
            Solver::Exact => match solve_bounded(&p, bound, opts.gap, opts.limits.labels, None) {
                Ok(r) => r,
                Err(RepeatsError::Labels(_)) => {
                    stats.beamed += 1;
                    solve_bounded(&p, bound, opts.gap, usize::MAX, Some(opts.beam.max(1)))?
                }
                Err(e) => return Err(e.into()),
            },
            Solver::Ilp => solve_ilp(&p)?,
        };
        Ok((r.n, r.cost))
    }

    /// The best path for a target (Eqs. 20-22): every walk's lower bound
    /// (its transition cost plus the linear relaxation of its loops,
    /// [`super::repeats::cone_gap`]), then the repetition problems in
    /// increasing bound until the bound reaches the best cost.
    ///
    /// With a `heading` term (an extension, [`Heading`]),
    /// the path's turn is the walk's plus `n_i` times each loop's, and the
    /// heading term of that turn is part of each walk's repetition
    /// programme ([`super::repeats::Turns`]): the counts are chosen with
    /// it. The bounds stay valid (the term is never negative); a walk
    /// whose loops do not turn (or that has none) adds its own heading
    /// term to its bound.
    pub fn solve(
        &self,
        t: &Target,
        heading: Option<&Heading>,
        opts: &SearchOptions,
        stats: &mut Stats,
    ) -> Result<SegmentPath, SearchError> {
        let w = opts.weights;
        self.count(stats);
        if opts.method == Method::Lattice {
            if let Some((p, _)) = self.solve_lattice(t, heading, opts)? {
                stats.exact_length += 1;
                return Ok(p);
            }
        }
        stats.bounds_hit.extend(self.bounds_hit.iter().cloned());
        stats.walks_and_loops += 1;
        let mut order: Vec<(f64, usize)> = self
            .walks
            .iter()
            .enumerate()
            .map(|(i, wk)| {
                let lb = wk.m.cost
                    + repeats::cone_gap(
                        t.distance - wk.m.distance,
                        t.frames - wk.m.frames as f64,
                        wk.cone.as_ref(),
                        w.distance,
                        w.time,
                    )
                    + heading.map_or(0.0, |h| fixed_heading(h, wk.turn, &wk.loop_turns));
                (lb, i)
            })
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best: Option<(usize, Vec<u32>)> = None;
        let mut best_cost = f64::INFINITY;
        for (k, &(lb, i)) in order.iter().enumerate() {
            if lb >= best_cost - opts.gap.max(1e-12) {
                stats.pruned += order.len() - k;
                break;
            }
            let wk = &self.walks[i];
            stats.loops_per_walk = stats.loops_per_walk.max(wk.measures.len());
            let turns = heading.map(|h| Turns {
                offset: wk.turn - h.turn,
                loops: &wk.loop_turns,
                weight: h.weight,
            });
            let (n, c) =
                self.solve_repeats(wk.m, &wk.measures, turns, t, opts, best_cost, stats)?;
            stats.walks += 1;
            if c < best_cost {
                best_cost = c;
                best = Some((i, n));
            }
        }
        let Some((i, n)) = best else {
            return Err(SearchError::NoPath {
                from: self.from,
                to: self.to,
            });
        };
        let wk = &self.walks[i];
        Ok(self.expand(&wk.nodes, &wk.arcs, &wk.loops, &n))
    }
}

/// The heading term of a walk turning `walk` radians whose loops do not
/// turn (each a multiple of 2π), whatever their counts; 0 (a lower bound)
/// when some loop turns.
fn fixed_heading(h: &Heading, walk: f64, loop_turns: &[f64]) -> f64 {
    if loop_turns.iter().all(|&t| wrap(t).abs() < 1e-12) {
        h.cost(walk)
    } else {
        0.0
    }
}

/// One target split over several segments (Sec. 5.1, "a series of
/// key-frames"): the best combination of one walk per segment with the
/// loops of all of them, for the summed distance and time. Combinations
/// are enumerated depth-first, a prefix cut when its cost plus the
/// cheapest completion and the overshoot it must already make reaches the
/// best cost; a full combination is skipped when its linear relaxation
/// does (the relaxation of the union of the walks' loops, merged from
/// each walk's, [`super::repeats::merge_cones`]). A `heading` term is
/// part of each combination's repetition programme as in
/// [`Segment::solve`], over the whole path's turn.
pub(crate) fn solve_split(
    segs: &[Segment],
    t: &Target,
    heading: Option<&Heading>,
    opts: &SearchOptions,
    stats: &mut Stats,
) -> Result<Vec<SegmentPath>, SearchError> {
    let w = opts.weights;
    for s in segs {
        stats.nodes += s.frames.len();
        stats.arcs += s.arcs.len();
        stats.cycles += s.cycles.len();
        stats.bounds_hit.extend(s.bounds_hit.iter().cloned());
        if s.walks.is_empty() {
            return Err(SearchError::NoPath {
                from: s.from,
                to: s.to,
            });
        }
    }
    let k = segs.len();
    let rest = cheapest_rest(segs);
    let lower = |m: &Tally, i: usize| {
        let r = rest[i];
        m.cost
            + r.cost
            + w.distance * (m.distance + r.distance - t.distance).max(0.0)
            + w.time * ((m.frames + r.frames) as f64 - t.frames).max(0.0)
    };
    let mut best_cost = f64::INFINITY;
    let mut best: Option<(Vec<usize>, Vec<u32>)> = None;
    let mut choice = vec![0usize; k];
    let mut acc = vec![Tally::default(); k + 1];
    let mut next = vec![0usize; k];
    let mut tried = 0usize;
    let mut buf = Vec::new();
    // Iterative depth-first search over the segments' walks.
    let mut i = 0usize;
    loop {
        if i == k {
            tried += 1;
            let found = solve_combination(
                segs, &choice, acc[k], t, heading, opts, best_cost, stats, &mut buf,
            )?;
            if let Some((n, c)) = found
                && c < best_cost
            {
                best_cost = c;
                best = Some((choice.clone(), n));
            }
            if tried >= opts.limits.combinations {
                stats.bounds_hit.push(format!(
                    "walk combinations stopped at {}",
                    opts.limits.combinations
                ));
                break;
            }
            i -= 1;
            continue;
        }
        if next[i] >= segs[i].walks.len() {
            next[i] = 0;
            if i == 0 {
                break;
            }
            i -= 1;
            continue;
        }
        let c = next[i];
        next[i] += 1;
        let m = acc[i].plus(segs[i].walks[c].m);
        if lower(&m, i + 1) >= best_cost - opts.gap.max(1e-12) {
            stats.pruned += 1;
            continue;
        }
        choice[i] = c;
        acc[i + 1] = m;
        i += 1;
    }
    let Some((choice, n)) = best else {
        return Err(SearchError::NoPath {
            from: segs[0].from,
            to: segs[k - 1].to,
        });
    };
    let mut out = Vec::new();
    let mut off = 0;
    for (i, s) in segs.iter().enumerate() {
        let wk = &s.walks[choice[i]];
        let ni = &n[off..off + wk.loops.len()];
        off += wk.loops.len();
        out.push(s.expand(&wk.nodes, &wk.arcs, &wk.loops, ni));
    }
    Ok(out)
}

/// The cheapest completion of the segments from each on, per measure
/// (each minimised on its own over the walks; `rest[k]` is zero).
fn cheapest_rest(segs: &[Segment]) -> Vec<Tally> {
    let k = segs.len();
    let mut rest = vec![Tally::default(); k + 1];
    for i in (0..k).rev() {
        let ws = &segs[i].walks;
        rest[i] = rest[i + 1].plus(Tally {
            cost: ws.iter().map(|x| x.m.cost).fold(f64::INFINITY, f64::min),
            distance: ws
                .iter()
                .map(|x| x.m.distance)
                .fold(f64::INFINITY, f64::min),
            frames: ws.iter().map(|x| x.m.frames).min().unwrap_or(0),
        });
    }
    rest
}

/// One full combination of [`solve_split`] (walk `choice[j]` of segment
/// `j`, together measuring `m`): `None` (counted as pruned) when the
/// relaxation of its loops cannot beat `best_cost`, else the repetition
/// counts of all its loops and their cost.
#[allow(clippy::too_many_arguments)]
fn solve_combination(
    segs: &[Segment],
    choice: &[usize],
    m: Tally,
    t: &Target,
    heading: Option<&Heading>,
    opts: &SearchOptions,
    best_cost: f64,
    stats: &mut Stats,
    buf: &mut Vec<(f64, f64)>,
) -> Result<Option<(Vec<u32>, f64)>, SearchError> {
    let (k, w) = (segs.len(), opts.weights);
    let sp = repeats::merge_cones(
        (0..k).filter_map(|j| segs[j].walks[choice[j]].cone.as_ref()),
        buf,
    );
    let lb = m.cost
        + repeats::cone_gap(
            t.distance - m.distance,
            t.frames - m.frames as f64,
            sp.as_ref(),
            w.distance,
            w.time,
        );
    // Pruned also when `lb` is not a number (as the search always was).
    let beats = lb < best_cost - opts.gap.max(1e-12);
    if !beats {
        stats.pruned += 1;
        return Ok(None);
    }
    let walks = (0..k).map(|j| &segs[j].walks[choice[j]]);
    let loops: Vec<Tally> = walks
        .clone()
        .flat_map(|w| w.measures.iter().copied())
        .collect();
    stats.loops_per_walk = stats.loops_per_walk.max(loops.len());
    let loop_turns: Vec<f64> = walks
        .clone()
        .flat_map(|w| w.loop_turns.iter().copied())
        .collect();
    let walk_turn: f64 = walks.map(|w| w.turn).sum();
    let turns = heading.map(|h| Turns {
        offset: walk_turn - h.turn,
        loops: &loop_turns,
        weight: h.weight,
    });
    let (n, c) = segs[0].solve_repeats(m, &loops, turns, t, opts, best_cost, stats)?;
    stats.walks += 1;
    Ok(Some((n, c)))
}
