//! The options of the key-frame search (Huang et al. 2015, Sec. 5.1): which
//! search ([`Method`]), Eq. 7's weights, the enumeration's bounds, the
//! repetition solver, the horizon, and the exact-length search's own
//! options ([`LatticeOptions`]), each default given on its field (the
//! key-frame job's own, `jobs::keyframe::KeyframeJobOptions`, start from
//! them).

use super::heading::HeadingTarget;
use serde::Serialize;

/// Weights of Eq. 7.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Weights {
    /// Per metre of distance error. Default: 1/0.3 (the paper).
    pub distance: f64,
    /// Per frame of time error. Default: 1/10 (the paper).
    pub time: f64,
}

impl Default for Weights {
    fn default() -> Self {
        Weights {
            distance: 1.0 / 0.3,
            time: 0.1,
        }
    }
}

/// Bounds on the enumeration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Limits {
    /// Simple cycles enumerated per segment. Default: 4000.
    pub cycles: usize,
    /// Walk prefixes expanded per segment. Default: 200 000.
    pub expansions: usize,
    /// Walks kept per segment. Default: 20 000.
    pub walks: usize,
    /// Loops handed to one repetition problem (the cheapest per frame of
    /// every distinct speed are kept). Default: 64.
    pub loops_per_walk: usize,
    /// Labels of the exact repetition solver for one walk. Default: 50 000.
    pub labels: usize,
    /// Walk combinations tried when one target is split over several
    /// segments. Default: 200 000.
    pub combinations: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            cycles: 4000,
            expansions: 200_000,
            walks: 20_000,
            loops_per_walk: 64,
            labels: 50_000,
            combinations: 200_000,
        }
    }
}

/// Which repetition solver to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Solver {
    /// The exact dynamic programme ([`super::repeats::solve_exact`]).
    #[default]
    Exact,
    /// The paper's four ILPs with `microlp` ([`super::repeats::solve_ilp`]).
    Ilp,
}

/// Which search finds the path.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// The exact-length search ([`super::lattice`]) first, the paper's
    /// walks and loops when it finds no path within its tolerance.
    #[default]
    Lattice,
    /// The paper's walks plus repeated loops only (Eqs. 13-25).
    Walks,
}

/// Options of the search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SearchOptions {
    /// Which search.
    pub method: Method,
    /// The exact-length search's options.
    pub lattice: LatticeOptions,
    /// Eq. 7 weights.
    pub weights: Weights,
    /// Enumeration bounds.
    pub limits: Limits,
    /// Repetition solver.
    pub solver: Solver,
    /// Optimality gap: a walk (or a label of the exact solver) is only
    /// explored if it could beat the best cost found by more than this.
    /// The result is within `gap` of the optimum of Eq. 13 (0: exact).
    /// Default: 0.03 (9 mm of distance or 0.3 frame at the paper's
    /// weights).
    pub gap: f64,
    /// Labels per loop-frame count kept by the exact solver once it has
    /// kept [`Limits::labels`] in all (then no longer exact, and reported).
    /// Default: 48.
    pub beam: usize,
    /// A target for the final facing (an extension, [`super::lattice`]):
    /// a term of the exact-length search, and of the walks-and-loops
    /// search (a term of each walk's repetition programme, so the counts
    /// are chosen with it, [`super::segment::Segment::solve`]). Default:
    /// none.
    pub heading: Option<HeadingTarget>,
    /// The longest path a query may return ([`Horizon`]).
    pub horizon: Horizon,
}

/// The longest path a query considers: `max(factor · t_V, t_V + slack)`
/// frames (and never fewer than the shortest path). A documented departure
/// from Eq. 7, whose optimum for a target out of reach can be far longer
/// than asked: 1000 m in 3 s on the README's synthetic database is 436 s
/// of running (the distance term outweighs the time term at the paper's
/// weights), minutes of search and of blending. Within the horizon the
/// search returns Eq. 7's best compromise, flagged; a reachable target
/// (within 1 % of its time) is always inside it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Horizon {
    /// Times the target's frames. Default: 2.
    pub factor: f64,
    /// Plus at least this many frames. Default: 250 (10 s at 25 fps; the
    /// CLI sets 10 s at the database's rate).
    pub slack: f64,
}

impl Default for Horizon {
    fn default() -> Self {
        Horizon {
            factor: 2.0,
            slack: 250.0,
        }
    }
}

impl Horizon {
    /// The horizon of a target of `frames` frames (frames, start counted
    /// as the target counts it).
    pub fn frames(&self, frames: f64) -> f64 {
        let f = frames.max(0.0);
        (self.factor * f).max(f + self.slack.max(0.0))
    }
}

impl Default for SearchOptions {
    fn default() -> Self {
        SearchOptions {
            method: Method::default(),
            lattice: LatticeOptions::default(),
            weights: Weights::default(),
            limits: Limits::default(),
            solver: Solver::default(),
            gap: 0.03,
            beam: 48,
            heading: None,
            horizon: Horizon::default(),
        }
    }
}

/// Options of the exact-length search.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LatticeOptions {
    /// Bins per `(node, frame count)`. Default: 32.
    pub bins: usize,
    /// Tolerance on the final distance, as a fraction of the target.
    /// Default: 0.02.
    pub tolerance: f64,
    /// Plus this many metres. Default: 0.01.
    pub tolerance_m: f64,
    /// Frame counts tried on either side of the target's (each must beat
    /// the best cost by its time term). Default: 3.
    pub frame_slack: u32,
    /// Longest path considered (frames). Default: 20 000.
    pub max_frames: usize,
    /// Fewest frames between two transitions (so that each keeps a blend
    /// window; the timeline shortens windows that would overlap).
    /// Default: 4.
    pub min_run: u32,
    /// Prefer a path within this fraction of both targets over a cheaper
    /// (Eq. 7) one that is not (module docs); 0: Eq. 7 alone. Default:
    /// 0.01 (the 1 % of the figures).
    pub within: f64,
    /// Prune by cost (module docs, "Pruning"): a frame count, or a label,
    /// whose cost bound reaches the best total found so far is not
    /// searched, or not extended. The result is the one without pruning
    /// (module docs); `false` searches everything (tests compare the two).
    /// Default: true.
    pub prune: bool,
    /// Labels a layer must hold before its nodes are shared among the
    /// threads of the current rayon pool (the result does not depend on
    /// it, module docs, "Threads"). Default: `usize::MAX`, never: on the
    /// shared 2-core machine a second thread made the bench's bandai9
    /// query slower (1.18 s → 1.85 s at load average 4); 4096 suits idle
    /// cores.
    pub parallel_from: usize,
    /// Dominance across the classes of frames since the last transition
    /// (module docs, "Classes"): in one distance bin, a label with more
    /// frames since its last transition (capped at
    /// [`LatticeOptions::min_run`]) that costs no more replaces the one
    /// with fewer. `false`: every class keeps its own bins (tests compare
    /// the two). Default: true.
    pub dominance: bool,
    /// Follow a label through the nodes that leave it one arc only (module
    /// docs, "Following") instead of binning it at each. `false`: every
    /// node is a layer's cell (tests compare the two). Default: true.
    pub follow: bool,
    /// Bins of a cell whose window is wider than
    /// [`LatticeOptions::coarse_from`] times the final window `2T` (module
    /// docs, "Coarse bins"); at most [`LatticeOptions::bins`]. Default: 4.
    pub coarse_bins: usize,
    /// The window width, in units of the final window `2T`, beyond which a
    /// cell keeps [`LatticeOptions::coarse_bins`] bins; `f64::INFINITY`:
    /// every cell keeps [`LatticeOptions::bins`] (the search before).
    /// Default: 4.
    pub coarse_from: f64,
    /// Coarse bins of the probe (module docs, "Probe"), a cheaper
    /// programme run first, with a heading target, when no path bounds a
    /// frame count yet; its path's score caps the full programme. 0: no
    /// probe. Default: 1.
    pub probe_bins: usize,
    /// Bins of the probe's cells near the goal. Default: 8.
    pub probe_fine: usize,
}

impl Default for LatticeOptions {
    fn default() -> Self {
        LatticeOptions {
            bins: 32,
            tolerance: 0.02,
            tolerance_m: 0.01,
            frame_slack: 3,
            max_frames: 20_000,
            min_run: 4,
            within: 0.01,
            prune: true,
            parallel_from: usize::MAX,
            dominance: true,
            follow: true,
            coarse_bins: 4,
            coarse_from: 4.0,
            probe_bins: 1,
            probe_fine: 8,
        }
    }
}
