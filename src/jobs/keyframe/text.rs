//! The text summaries of the grid, least-mean and floor reports (the
//! lines `surfmotion keyframe` prints).

use super::floor::FloorReport;
use super::grid::LeastMean;
use crate::keyframe::floor::{PathFloor, Window};
use crate::keyframe::grid::{FloorQuery, GridQuery, GridReport};
use crate::keyframe::smoothest::SmoothestSummary;

/// The header of [`grid_row`]'s lines.
pub const GRID_HEADER: &str =
    "distance (m)  time (s)  achieved (m)  achieved (s)  within 1 %  reach  ms\n";

/// One grid query's line.
pub fn grid_row(q: &GridQuery) -> String {
    format!(
        "{} {} {:.3} {:.3} {} {} {:.1}\n",
        q.distance,
        q.time,
        q.achieved_distance,
        q.achieved_time,
        if q.within_1pct { "yes" } else { "no" },
        serde_json::to_value(q.reach)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default(),
        1e3 * q.seconds
    )
}

/// The header of [`least_mean_row`]'s lines.
pub const LEAST_MEAN_HEADER: &str =
    "distance (m)  time (s)  reachable  least mean (m)  lower bound (m)  s\n";

/// One least-mean target's line.
pub fn least_mean_row(q: &FloorQuery) -> String {
    let opt = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.4}"));
    format!(
        "{} {} {} {} {} {:.2}\n",
        q.distance,
        q.time,
        if q.reachable { "yes" } else { "no" },
        opt(q.least_mean),
        opt(q.lower_bound),
        q.seconds
    )
}

/// The least-mean summary over the reachable targets.
pub fn least_mean_summary(lm: &LeastMean) -> String {
    let r = &lm.report;
    let sum = |s: &Option<SmoothestSummary>| match s {
        Some(s) => format!(
            "mean {:.4} m, median {:.4}, min {:.4}, max {:.4} (over {})",
            s.mean, s.median, s.min, s.max, s.n
        ),
        None => "-".to_string(),
    };
    format!(
        "least mean smoothness of a path within 1 % of distance and time, over the reachable targets ({} reachable, {} with such a path found, {:.1} s):\n  priced (each transition at its own window): {}\n  as the grid measures it: {}\n  exact lower bound (Lagrangian relaxation of the distance band): {}\n",
        r.reachable,
        r.kept,
        lm.seconds,
        sum(&r.least_mean),
        sum(&r.least_mean_measured),
        sum(&r.lower_bound),
    )
}

/// The floor's summary: the transition floor, per sequence pair, and the
/// path floors between consecutive key-frames.
pub fn floor_summary(f: &FloorReport) -> String {
    let (t, o) = (&f.transitions, &f.options);
    let win = |w: &Option<Window>| {
        w.as_ref().map_or("none".to_string(), |w| {
            format!(
                "{:.4} m ({}:{} ~ {}:{}, L = {})",
                w.smoothness, w.from, w.m, w.to, w.n, w.window
            )
        })
    };
    let mut s = format!(
        "transition floor over {} frame pairs (L in [{}, {}], gap {} within a sequence): {}\n",
        t.candidates,
        o.min_window,
        o.max_window,
        o.min_gap,
        win(&t.best)
    );
    for p in &t.pairs {
        s += &format!(
            "  {} ~ {}: {}; <= {} m: {} distinct transitions ({} frame pairs by the bound); {} windows measured in full\n",
            p.a,
            p.b,
            win(&p.best),
            t.threshold,
            p.under_distinct,
            p.under_bound,
            p.measured
        );
    }
    for p in &f.paths {
        for (what, g) in [
            ("graph transitions", &p.graph),
            ("every frame pair (bound)", &p.every_frame_pair),
        ] {
            s += &path_floor_line(&p.from, &p.to, what, g, p.max_transitions);
        }
    }
    s
}

fn path_floor_line(from: &str, to: &str, what: &str, p: &PathFloor, k_max: usize) -> String {
    let by = |k: usize| {
        p.by_count
            .get(k - 1)
            .copied()
            .flatten()
            .map_or("-".to_string(), |v| format!("{v:.4}"))
    };
    format!(
        "path floor {from} -> {to}, {what}: k=1 {}, k=2 {}, k=3 {}; least over k <= {k_max}: {}{}\n",
        by(1),
        by(2),
        by(3),
        p.best
            .map_or("none".to_string(), |(k, v)| format!("{v:.4} m (k = {k})")),
        if p.direct {
            "; a path without transitions exists"
        } else {
            ""
        }
    )
}

/// The grid's summary: reachability, errors, smoothness and query time.
pub fn grid_summary(g: &GridReport) -> String {
    let n = g.queries.len();
    let mut s = format!(
        "{}: {} {} ({} distances x {} times)\n",
        g.keys.join(" -> "),
        n,
        if n == 1 { "query" } else { "queries" },
        g.distances.len(),
        g.times.len()
    );
    s += &format!(
        "reachable (some path within 1 % of both): {}; unreachable: {} ({} out of range, {} in a gap of the achievable distances; best compromise returned, flagged)\n",
        g.reachable.distance_m.count, g.unreachable.distance_m.count, g.out_of_range, g.gaps
    );
    for (what, e) in [("reachable", &g.reachable), ("unreachable", &g.unreachable)] {
        if e.distance_m.count == 0 {
            s += &format!("{what}: none\n");
            continue;
        }
        s += &format!(
            "{what} ({}): distance error min/rms/max {:.4}/{:.4}/{:.4} m = {:.3}/{:.3}/{:.3} %; time error {:.3}/{:.3}/{:.3} s = {:.3}/{:.3}/{:.3} %; {} within 1 %\n",
            e.distance_m.count,
            e.distance_m.min,
            e.distance_m.rms,
            e.distance_m.max,
            e.distance_pct.min,
            e.distance_pct.rms,
            e.distance_pct.max,
            e.time_s.min,
            e.time_s.rms,
            e.time_s.max,
            e.time_pct.min,
            e.time_pct.rms,
            e.time_pct.max,
            e.within_1pct
        );
    }
    if !g.missed.is_empty() {
        s += &format!(
            "reachable but missed by the search: {}\n",
            g.missed
                .iter()
                .map(|(d, t)| format!("{d} m in {t} s"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    s += &format!(
        "smoothness min/mean/max {:.4}/{:.4}/{:.4} m (vertex-set Hausdorff: mean {:.4} m) over {} queries with transitions; the graph's {} transitions: min/median/max {:.4}/{:.4}/{:.4} m\n",
        g.smoothness.min,
        g.smoothness_mean,
        g.smoothness.max,
        g.smoothness_vertex_mean,
        g.smoothness.count,
        g.graph_smoothness.count,
        g.graph_smoothness.min,
        g.graph_smoothness_median,
        g.graph_smoothness.max
    );
    let cpu = match (g.query_cpu_ms_mean, g.query_cpu_ms_std, g.query_cpu_ms_max) {
        (Some(m), Some(sd), Some(x)) => format!(" (CPU {m:.2} ± {sd:.2} ms, max {x:.1} ms)"),
        _ => String::new(),
    };
    s += &format!(
        "query time {:.2} ± {:.2} ms (max {:.1} ms){cpu}; preparation {:.1} ms once; {} hit a search bound; reachability oracle {:.0} ms in all\n",
        g.query_ms_mean, g.query_ms_std, g.query_ms_max, g.prepare_ms, g.bounded, g.oracle_ms
    );
    s
}

/// The JSON summary of a grid or least-mean report (`keyframe --grid
/// --json`): the report without its queries (the `--report` file keeps
/// them).
pub fn summary_json<T: serde::Serialize>(r: &T) -> Result<serde_json::Value, serde_json::Error> {
    let mut v = serde_json::to_value(r)?;
    if let Some(o) = v.as_object_mut() {
        o.remove("queries");
    }
    Ok(v)
}
