//! How many times to repeat each loop attached to a walk (Huang et al.
//! 2015, Eqs. 16-25): minimise over integers `n_i ≥ 0`
//!
//! ```text
//! C(n) = c_0 + Σ n_i c_i + w_d |Δd + Σ n_i d_i| + w_t |Δt + Σ n_i t_i|
//! ```
//!
//! with `c` the transition costs, `d` the distances (metres), `t` the
//! frames of the walk (`_0`) and of each loop, `Δd = d_0 − d_V`,
//! `Δt = t_0 − t_V`. Every coefficient is ≥ 0 and every loop has `t_i ≥ 1`.
//!
//! **Heading** (an extension, [`super::heading::Heading`]; [`Turns`]): with
//! a target for the final facing the cost has a fourth term,
//! `w_h ρ(Δθ + Σ n_i θ_i)`, with `θ_i` the turn of one repetition of loop
//! `i`, `Δθ = θ_0 − θ_V` (the walk's turn minus the target) and
//! `ρ(x) = |wrap(x)| = min_k |x − 2πk|` the angular error. The counts are
//! chosen with it (the walk's final facing is its own turn plus
//! `Σ θ_i n_i`), not scored with it afterwards.
//!
//! Three solvers, which the tests compare on random instances:
//!
//! - [`solve_ilp`]: the paper's method. `|·|` is split into its four sign
//!   cases (Eqs. 23-25); each is an integer linear programme solved by the
//!   pure-Rust `microlp` branch and bound through `good_lp`. With a
//!   heading, the wrap integer `k` is one more integer variable and
//!   `|Δθ + Σ n_i θ_i − 2πk|` one more sign-split term (eight ILPs):
//!   `min_{n,k} F(n) + w_h |x(n) − 2πk| = min_n F(n) + w_h min_k |x(n) − 2πk|
//!   = min_n F(n) + w_h ρ(x(n))`, so the joint optimum is the heading
//!   problem's; `k` is bounded by `⌊x_min/2π⌋ ≤ k ≤ ⌈x_max/2π⌉` over the
//!   box of `n`, which holds the nearest `k = round(x/2π)` of every `n`.
//! - [`solve_exact`]: a dynamic programme over the total loop frames
//!   `τ = Σ n_i t_i`. For each `τ` it keeps the labels `(c, d, θ)` (loop
//!   transition cost, distance and turn) that no other label at the same
//!   `τ` dominates, where `(c', d', θ')` dominates `(c, d, θ)` when
//!   `c' + w_d |d' − d| + w_h ρ(θ' − θ) ≤ c`: by the triangle inequality
//!   (`ρ` is a metric on the circle) any completion of `(c, d, θ)` is then
//!   matched by the same completion of `(c', d', θ')`. Without a heading
//!   `w_h = 0` and the turn plays no part. Labels
//!   whose lower bound (`c_0 + c` plus the linear relaxation of what is
//!   left, [`cone_gap`]; the heading term, never negative, is left out)
//!   reaches the incumbent are dropped, and `τ` is
//!   bounded by `w_t (Δt + τ) < bound`. Exact: every dropped label is provably no
//!   better than a kept one.
//! - [`brute_force`]: every `n` with `n_i ≤ limit`, for the tests.

use super::heading::wrap;
use good_lp::{Expression, ProblemVariables, Solution, SolverModel, Variable, microlp, variable};
use std::f64::consts::TAU;

/// What a walk or one loop adds up to (its tally): transition cost, floor distance
/// (metres), frames.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct Tally {
    /// Sum of the transition costs (Eq. 8).
    pub cost: f64,
    /// Distance travelled (Eq. 10), metres.
    pub distance: f64,
    /// Frames.
    pub frames: u32,
}

impl Tally {
    /// Componentwise sum.
    pub fn plus(self, o: Tally) -> Tally {
        Tally {
            cost: self.cost + o.cost,
            distance: self.distance + o.distance,
            frames: self.frames + o.frames,
        }
    }
    /// `k` times this.
    pub fn times(self, k: u32) -> Tally {
        Tally {
            cost: self.cost * k as f64,
            distance: self.distance * k as f64,
            frames: self.frames * k,
        }
    }
}

/// One instance of Eq. 20.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem<'a> {
    /// The walk.
    pub walk: Tally,
    /// The loops attached to it (every `frames ≥ 1`).
    pub loops: &'a [Tally],
    /// Target distance `d_V`, metres (0: as short as possible).
    pub distance: f64,
    /// Target time `t_V`, frames (0: as short as possible).
    pub frames: f64,
    /// Weight of the distance error, per metre.
    pub w_dist: f64,
    /// Weight of the time error, per frame.
    pub w_time: f64,
    /// The heading term (an extension; `None`: Eq. 20 alone).
    pub heading: Option<Turns<'a>>,
    /// Most loop frames `Σ n_i t_i` (the query's horizon less the walk's
    /// frames, [`super::options::Horizon`]; `None`: unbounded). The
    /// optimum is then Eq. 20's over the counts within it.
    pub max_loop_frames: Option<u32>,
}

/// The heading term of a repetition problem (module docs):
/// `w_h ρ(Δθ + Σ n_i θ_i)`, `ρ` the wrapped angular error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Turns<'a> {
    /// `Δθ`: the walk's turn minus the target turn (radians).
    pub offset: f64,
    /// `θ_i`: each loop's turn per repetition (radians), one per loop.
    pub loops: &'a [f64],
    /// `w_h`: cost per radian of error.
    pub weight: f64,
}

impl Turns<'_> {
    /// `θ_i` (0 past the list).
    fn of(&self, i: usize) -> f64 {
        self.loops.get(i).copied().unwrap_or(0.0)
    }
    /// `w_h ρ(x)`.
    fn cost(&self, x: f64) -> f64 {
        self.weight * wrap(x).abs()
    }
}

impl Problem<'_> {
    /// Eq. 16 for repetition counts `n` (plus the heading term).
    pub fn cost(&self, n: &[u32]) -> f64 {
        let m = self.total(n);
        m.cost
            + self.w_dist * (m.distance - self.distance).abs()
            + self.w_time * (m.frames as f64 - self.frames).abs()
            + self.heading.map_or(0.0, |h| {
                let turn: f64 = n.iter().enumerate().map(|(i, &k)| h.of(i) * k as f64).sum();
                h.cost(h.offset + turn)
            })
    }
    /// The heading term if it counts (a positive weight).
    fn turns(&self) -> Option<Turns<'_>> {
        self.heading.filter(|h| h.weight > 0.0)
    }
    /// The walk plus `n` repetitions of the loops.
    pub fn total(&self, n: &[u32]) -> Tally {
        self.loops
            .iter()
            .zip(n)
            .fold(self.walk, |acc, (l, &k)| acc.plus(l.times(k)))
    }
    fn delta(&self) -> (f64, f64) {
        (
            self.walk.distance - self.distance,
            self.walk.frames as f64 - self.frames,
        )
    }
    /// Loop frames past which no `n` can cost less than `bound`, or may
    /// not go ([`Problem::max_loop_frames`]).
    fn frame_bound(&self, bound: f64) -> f64 {
        let (_, dt) = self.delta();
        let b = if self.w_time > 0.0 {
            -dt + (bound - self.walk.cost) / self.w_time
        } else {
            f64::INFINITY
        };
        self.max_loop_frames.map_or(b, |m| b.min(f64::from(m)))
    }
}

/// The linear relaxation of a loop set: the lower convex hull of the
/// loops' `(speed, transition cost per frame)` points (metres per frame,
/// cost per frame), by increasing speed. Mixing loops with real counts
/// makes any speed between the slowest and the fastest loop, and the least
/// cost per frame at a speed is this hull there.
#[derive(Debug, Clone, PartialEq)]
pub struct Cone {
    /// Hull vertices `(speed, cost per frame)`.
    pub hull: Vec<(f64, f64)>,
}

impl Cone {
    /// Least cost per frame at speed `s` (inside the hull's range).
    fn at(&self, s: f64) -> f64 {
        let h = &self.hull;
        let k = h.partition_point(|p| p.0 < s).clamp(1, h.len().max(2) - 1);
        if h.len() == 1 {
            return h[0].1;
        }
        let (a, b) = (h[k - 1], h[k]);
        if b.0 - a.0 <= 0.0 {
            return a.1.min(b.1);
        }
        let t = ((s - a.0) / (b.0 - a.0)).clamp(0.0, 1.0);
        a.1 + t * (b.1 - a.1)
    }
}

/// The [`Cone`] of a loop set (`None` without loops).
pub fn cone(loops: &[Tally]) -> Option<Cone> {
    let mut p: Vec<(f64, f64)> = loops
        .iter()
        .filter(|l| l.frames > 0)
        .map(|l| {
            (
                l.distance / l.frames as f64,
                l.cost.max(0.0) / l.frames as f64,
            )
        })
        .collect();
    lower_hull(&mut p)
}

/// The [`Cone`] of the union of several loop sets, from their cones: the
/// lower hull of a union is the lower hull of the union of the hulls'
/// vertices (a point on or above one set's hull is on or above the
/// union's), so this equals [`cone`] of all the loops at the cost of a
/// few vertices. `buf` is scratch space.
pub fn merge_cones<'a>(
    cones: impl IntoIterator<Item = &'a Cone>,
    buf: &mut Vec<(f64, f64)>,
) -> Option<Cone> {
    buf.clear();
    for c in cones {
        buf.extend_from_slice(&c.hull);
    }
    lower_hull(buf)
}

/// The lower convex hull of `(speed, cost per frame)` points, by
/// increasing speed (the points are sorted in place).
fn lower_hull(p: &mut [(f64, f64)]) -> Option<Cone> {
    if p.is_empty() {
        return None;
    }
    p.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    let mut hull: Vec<(f64, f64)> = Vec::new();
    for &q in p.iter() {
        if let Some(l) = hull.last() {
            if (q.0 - l.0).abs() <= 1e-15 {
                continue; // same speed, higher cost (sorted)
            }
        }
        while hull.len() >= 2 {
            let (a, b) = (hull[hull.len() - 2], hull[hull.len() - 1]);
            // Drop b when it lies on or above the segment a–q.
            if (b.0 - a.0) * (q.1 - a.1) - (b.1 - a.1) * (q.0 - a.0) <= 0.0 {
                hull.pop();
            } else {
                break;
            }
        }
        hull.push(q);
    }
    Some(Cone { hull })
}

/// A lower bound on `g(p) + w_d |q_d − p_d| + w_t |q_t − p_t|` over every
/// `p = (p_d, p_t)` that real loop counts `n ≥ 0` make, `g(p)` their least
/// transition cost: the linear relaxation of the repetitions. `g(p) =
/// p_t · hull(p_d / p_t)` is convex and piecewise linear on the cone of
/// the loops' speeds, so the minimum is at a vertex: the apex, `q` itself
/// (when inside), or where a hull vertex's ray meets `p_d = q_d` or
/// `p_t = q_t`.
pub fn cone_gap(qd: f64, qt: f64, cone: Option<&Cone>, wd: f64, wt: f64) -> f64 {
    let direct = wd * qd.abs() + wt * qt.abs();
    let Some(c) = cone else {
        return direct;
    };
    let (lo, hi) = (c.hull[0].0, c.hull[c.hull.len() - 1].0);
    let mut best = direct;
    if qd >= 0.0 && qt > 0.0 && qd >= lo * qt - 1e-12 && qd <= hi * qt + 1e-12 {
        best = best.min(qt * c.at(qd / qt));
    }
    for &(s, kappa) in &c.hull {
        let ks = [qt, if s > 0.0 { qd / s } else { -1.0 }];
        for k in ks {
            if k > 0.0 {
                best = best.min(kappa * k + wd * (qd - k * s).abs() + wt * (qt - k).abs());
            }
        }
    }
    best
}

/// Repetition counts and their cost.
#[derive(Debug, Clone, PartialEq)]
pub struct Repeats {
    /// `n_i` per loop.
    pub n: Vec<u32>,
    /// Eq. 16.
    pub cost: f64,
}

/// Why a solver gave up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RepeatsError {
    /// The ILP solver failed.
    #[error("ILP solver: {0}")]
    Solver(String),
    /// The dynamic programme hit its label limit.
    #[error("the repetition search kept more than {0} labels")]
    Labels(usize),
}

/// Largest loop-frame total the exact solver explores, whatever the bound
/// (about 11 minutes at 25 fps).
pub(crate) const MAX_LOOP_FRAMES: usize = 16_384;

/// The paper's ILP (Eqs. 23-25), four `microlp` solves (eight with a
/// heading term: the wrap integer as one more variable, module docs);
/// every `n_i` is bounded by the loop frames past which the cost exceeds
/// `n = 0`'s.
pub fn solve_ilp(p: &Problem) -> Result<Repeats, RepeatsError> {
    let zero = vec![0u32; p.loops.len()];
    let mut best = Repeats {
        cost: p.cost(&zero),
        n: zero,
    };
    if p.loops.is_empty() {
        return Ok(best);
    }
    let limit = p.frame_bound(best.cost).clamp(0.0, MAX_LOOP_FRAMES as f64);
    let (dd, dt) = p.delta();
    let upper: Vec<f64> = p
        .loops
        .iter()
        .map(|l| (limit / l.frames.max(1) as f64).floor())
        .collect();
    let heading = p.turns();
    // The wrap integer's range over the box of `n`.
    let wraps = heading.map(|h| {
        let (mut lo, mut hi) = (h.offset, h.offset);
        for (i, u) in upper.iter().enumerate() {
            let x = h.of(i) * u;
            lo += x.min(0.0);
            hi += x.max(0.0);
        }
        ((lo / TAU).floor(), (hi / TAU).ceil())
    });
    let head_signs: &[f64] = if heading.is_some() {
        &[1.0, -1.0]
    } else {
        &[0.0]
    };
    for (sd, st) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)] {
        for &sh in head_signs {
            let mut vars = ProblemVariables::new();
            let xs: Vec<Variable> = upper
                .iter()
                .map(|&u| vars.add(variable().integer().min(0).max(u)))
                .collect();
            let k = wraps.map(|(lo, hi)| vars.add(variable().integer().min(lo).max(hi)));
            let mut obj = Expression::from(0.0);
            let mut dist = Expression::from(dd);
            let mut time = Expression::from(dt);
            let mut head = Expression::from(heading.map_or(0.0, |h| h.offset));
            for (i, (x, l)) in xs.iter().zip(p.loops).enumerate() {
                let th = heading.map_or(0.0, |h| h.of(i));
                let wh = heading.map_or(0.0, |h| h.weight);
                let coef = l.cost
                    + sd * p.w_dist * l.distance
                    + st * p.w_time * l.frames as f64
                    + sh * wh * th;
                obj += coef * *x;
                dist += l.distance * *x;
                time += l.frames as f64 * *x;
                head += th * *x;
            }
            if let (Some(k), Some(h)) = (k, heading) {
                obj += (-sh * h.weight * TAU) * k;
                head += (-TAU) * k;
            }
            let loop_frames: Expression = xs
                .iter()
                .zip(p.loops)
                .map(|(x, l)| l.frames as f64 * *x)
                .sum();
            let mut model = vars
                .minimise(obj)
                .using(microlp)
                .with((sd * dist).geq(0.0))
                .with((st * time).geq(0.0));
            if let Some(m) = p.max_loop_frames {
                model = model.with(loop_frames.leq(f64::from(m)));
            }
            if heading.is_some() {
                model = model.with((sh * head).geq(0.0));
            }
            match model.solve() {
                Ok(sol) => {
                    let n: Vec<u32> = xs
                        .iter()
                        .map(|x| sol.value(*x).round().max(0.0) as u32)
                        .collect();
                    let c = p.cost(&n);
                    if c < best.cost - 1e-12 {
                        best = Repeats { n, cost: c };
                    }
                }
                Err(good_lp::ResolutionError::Infeasible) => {}
                Err(e) => return Err(RepeatsError::Solver(e.to_string())),
            }
        }
    }
    Ok(best)
}

#[derive(Clone, Copy)]
struct Label {
    cost: f64,
    dist: f64,
    /// `Σ n_i θ_i` (radians; 0 without a heading).
    turn: f64,
    /// Lower bound of any completion.
    lb: f64,
    /// `(τ, index)` of the label this one extends, and the loop added.
    parent: (u32, u32, u32),
}

/// The exact dynamic programme (see the module docs). Returns the best `n`
/// whose cost is below `bound` (and `n = 0` when nothing beats it), or an
/// error when more than `max_labels` labels were kept.
pub fn solve_exact(p: &Problem, bound: f64, max_labels: usize) -> Result<Repeats, RepeatsError> {
    dp(p, bound, 0.0, max_labels, None)
}

/// [`solve_exact`] that only looks for improvements of more than `gap`
/// over `bound` and, with `beam`, keeps at most that many labels per loop
/// frame count (those with the smallest lower bound): bounded time, no
/// longer exact (the caller says so).
pub(crate) fn solve_bounded(
    p: &Problem,
    bound: f64,
    gap: f64,
    max_labels: usize,
    beam: Option<usize>,
) -> Result<Repeats, RepeatsError> {
    dp(p, bound, gap, max_labels, beam)
}

/// [`solve_bounded`]'s programme over the loop frame count `τ` (module
/// docs): labels `(cost, distance, turn)` per `τ`, extended by one loop at
/// a time, dominated labels dropped ([`Dp::offer`]), the best label traced
/// back to its repetition counts.
fn dp(
    p: &Problem,
    bound: f64,
    gap: f64,
    max_labels: usize,
    beam: Option<usize>,
) -> Result<Repeats, RepeatsError> {
    let zero = vec![0u32; p.loops.len()];
    let c0 = p.cost(&zero);
    let mut best_cost = c0;
    let mut best_at: Option<(usize, usize)> = None;
    let bound = bound.min(c0);
    if p.loops.is_empty() {
        return Ok(Repeats { n: zero, cost: c0 });
    }
    let (dd, dt) = p.delta();
    let tmax = p.frame_bound(bound).floor();
    if tmax < 1.0 {
        return Ok(Repeats { n: zero, cost: c0 });
    }
    let tmax = (tmax as usize).min(MAX_LOOP_FRAMES);
    let mut labels: Vec<Vec<Label>> = vec![Vec::new(); tmax + 1];
    labels[0].push(Label {
        cost: 0.0,
        dist: 0.0,
        turn: 0.0,
        lb: 0.0,
        parent: (u32::MAX, 0, 0),
    });
    let mut kept = 1usize;
    let heading = p.turns();
    let dp = Dp {
        p,
        dd,
        dt,
        wh: heading.map_or(0.0, |h| h.weight),
        th0: heading.map_or(0.0, |h| h.offset),
        nonneg: p.loops.iter().all(|l| l.cost >= 0.0),
        sp: cone(p.loops),
        beam,
    };
    // Each slot is kept sorted by distance, with an upper bound on its
    // costs (`top`, [`Dp::near`]).
    let mut top = vec![0.0f64; tmax + 1];
    for tau in 0..=tmax {
        let here = std::mem::take(&mut labels[tau]);
        for (k, l) in here.iter().enumerate() {
            // The label's own cost.
            if tau > 0 {
                let c = p.walk.cost
                    + l.cost
                    + p.w_dist * (dd + l.dist).abs()
                    + p.w_time * (dt + tau as f64).abs()
                    + dp.apart(dp.th0 + l.turn, 0.0);
                if c < best_cost - 1e-12 {
                    best_cost = c;
                    best_at = Some((tau, k));
                }
            }
            let cut = best_cost.min(bound) - gap;
            if dp.lower(l.cost, l.dist, tau) >= cut {
                continue;
            }
            for (i, lp) in p.loops.iter().enumerate() {
                let t2 = tau + lp.frames as usize;
                if lp.frames == 0 || t2 > tmax {
                    continue;
                }
                let (c2, d2) = (l.cost + lp.cost, l.dist + lp.distance);
                let a2 = l.turn + heading.map_or(0.0, |h| h.of(i));
                let lb2 = dp.lower(c2, d2, t2);
                if lb2 >= cut {
                    continue;
                }
                let new = Label {
                    cost: c2,
                    dist: d2,
                    turn: a2,
                    lb: lb2,
                    parent: (tau as u32, k as u32, i as u32),
                };
                if dp.offer(&mut labels[t2], &mut top[t2], new, &mut kept) && kept > max_labels {
                    return Err(RepeatsError::Labels(max_labels));
                }
            }
        }
        labels[tau] = here;
    }
    let mut n = zero;
    if let Some((mut tau, mut k)) = best_at {
        while tau > 0 {
            let l = labels[tau][k];
            n[l.parent.2 as usize] += 1;
            tau = l.parent.0 as usize;
            k = l.parent.1 as usize;
        }
    }
    Ok(Repeats { n, cost: best_cost })
}

/// What one run of [`dp`] fixes: the problem, its offsets from the target
/// and the heading term.
struct Dp<'a> {
    p: &'a Problem<'a>,
    /// The walk's distance and frames minus the target's.
    dd: f64,
    dt: f64,
    /// The heading term's weight (0 when it does not count) and the
    /// walk's offset.
    wh: f64,
    th0: f64,
    /// Every loop's cost is non-negative.
    nonneg: bool,
    /// The loops' relaxation.
    sp: Option<Cone>,
    /// Labels kept per loop frame count ([`solve_bounded`]).
    beam: Option<usize>,
}

impl Dp<'_> {
    /// `w_h ρ(a − b)`: the heading part of the dominance rule.
    fn apart(&self, a: f64, b: f64) -> f64 {
        if self.wh > 0.0 {
            self.wh * wrap(a - b).abs()
        } else {
            0.0
        }
    }

    /// The labels of a slot (sorted by distance) that may dominate or be
    /// dominated by a label at distance `d`: with costs ≥ 0, those whose
    /// distance is within `reach / w_d` of `d` (`reach` the label's cost,
    /// or the slot's top cost minus its cost).
    fn near(&self, slot: &[Label], d: f64, reach: f64) -> (usize, usize) {
        let p = self.p;
        if !(self.nonneg && p.w_dist > 0.0 && reach.is_finite()) {
            return (0, slot.len());
        }
        if reach < 0.0 {
            return (0, 0);
        }
        let r = reach / p.w_dist + 1e-12;
        let lo = slot.partition_point(|o| o.dist < d - r);
        (lo, lo + slot[lo..].partition_point(|o| o.dist <= d + r))
    }

    /// The lower bound of any completion of a label of cost `c`, distance
    /// `d` at loop frame count `tau`.
    fn lower(&self, c: f64, d: f64, tau: usize) -> f64 {
        let p = self.p;
        p.walk.cost
            + c
            + cone_gap(
                -(self.dd + d),
                -(self.dt + tau as f64),
                self.sp.as_ref(),
                p.w_dist,
                p.w_time,
            )
    }

    /// Offers `new` to its `slot` (top cost `top`): `false` when a label
    /// there dominates it; else the labels it dominates are dropped and it
    /// is inserted in distance order (with a beam, in place of the label
    /// of largest bound when that bound is larger than its own), `kept`
    /// counting the labels held.
    fn offer(&self, slot: &mut Vec<Label>, top: &mut f64, new: Label, kept: &mut usize) -> bool {
        let w_dist = self.p.w_dist;
        let (c2, d2, a2, lb2) = (new.cost, new.dist, new.turn, new.lb);
        let (lo, hi) = self.near(slot, d2, c2);
        if slot[lo..hi]
            .iter()
            .any(|o| o.cost + w_dist * (o.dist - d2).abs() + self.apart(o.turn, a2) <= c2)
        {
            return false;
        }
        let (lo, hi) = self.near(slot, d2, *top - c2);
        let mut w = lo;
        for r in lo..hi {
            let o = slot[r];
            if c2 + w_dist * (d2 - o.dist).abs() + self.apart(a2, o.turn) > o.cost {
                slot[w] = o;
                w += 1;
            }
        }
        slot.drain(w..hi);
        *kept -= hi - w;
        match self.beam {
            Some(b) if slot.len() >= b => {
                if let Some((worst, _)) = slot
                    .iter()
                    .enumerate()
                    .max_by(|x, y| x.1.lb.total_cmp(&y.1.lb))
                    .filter(|(_, w)| w.lb > lb2)
                {
                    slot.remove(worst);
                    let at = slot.partition_point(|o| o.dist < d2);
                    slot.insert(at, new);
                    *top = top.max(c2);
                }
            }
            _ => {
                let at = slot.partition_point(|o| o.dist < d2);
                slot.insert(at, new);
                *top = top.max(c2);
                *kept += 1;
            }
        }
        true
    }
}

/// Every `n` with `n_i ≤ limit` (and within [`Problem::max_loop_frames`])
/// (for tests; `(limit+1)^loops` evaluations).
pub fn brute_force(p: &Problem, limit: u32) -> Repeats {
    let k = p.loops.len();
    let mut n = vec![0u32; k];
    let mut best = Repeats {
        cost: p.cost(&n),
        n: n.clone(),
    };
    loop {
        let mut i = 0;
        while i < k {
            if n[i] < limit {
                n[i] += 1;
                break;
            }
            n[i] = 0;
            i += 1;
        }
        if i == k {
            return best;
        }
        if p.max_loop_frames
            .is_some_and(|m| p.total(&n).frames - p.walk.frames > m)
        {
            continue;
        }
        let c = p.cost(&n);
        if c < best.cost - 1e-12 {
            best = Repeats {
                n: n.clone(),
                cost: c,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_loop_reaches_the_target_exactly() {
        let loops = [Tally {
            cost: 0.1,
            distance: 1.0,
            frames: 25,
        }];
        let p = Problem {
            walk: Tally {
                cost: 0.0,
                distance: 2.0,
                frames: 50,
            },
            loops: &loops,
            distance: 7.0,
            frames: 175.0,
            w_dist: 1.0 / 0.3,
            w_time: 0.1,
            heading: None,
            max_loop_frames: None,
        };
        let e = solve_exact(&p, f64::INFINITY, 100_000).unwrap();
        assert_eq!(e.n, vec![5]);
        assert!((e.cost - 0.5).abs() < 1e-9);
        let i = solve_ilp(&p).unwrap();
        assert_eq!(i.n, vec![5]);
    }
}
