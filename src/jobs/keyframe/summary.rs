//! The text summary of one key-frame query (Huang et al. 2015, Sec. 5.1,
//! Eq. 7: the targets achieved, missed, and why), as `surfmotion
//! keyframe` prints it. The options it names are
//! [`KeyframeJobOptions`](super::KeyframeJobOptions)'s, in backticks (the
//! command line prints its flags instead).

use super::keys::Keys;
use super::path::PathRun;
use super::verdict::{HEADING_TOLERANCE_DEG, Missed, segment_missed};
use crate::batch::summary::count;

/// The key-frames given as poses and the database frames they resolved to.
pub fn resolved(keys: &Keys) -> String {
    let mut head = String::new();
    for r in &keys.resolved {
        head += &format!(
            "key-frame {}: nearest database frame {} (skeleton distance {:.3} m{})\n",
            r.key,
            r.frame,
            r.distance,
            r.runner_up
                .as_ref()
                .map_or(String::new(), |(f, d)| format!("; next {f} at {d:.3} m"))
        );
    }
    head
}

/// The summary of a path written: files, achieved targets and what was
/// missed, facing, cost, segments, transitions and search figures.
pub fn path_summary(run: &PathRun, fps: f64) -> String {
    let (r, missed) = (&run.report.report, &run.report.missed);
    let mut s = String::new();
    s += &format!(
        "{} -> {}: {} at {} fps\n",
        r.keys.join(" -> "),
        crate::jobs::text::written_list(&run.written, ", "),
        count(r.frames, "frame"),
        fps
    );
    s += &format!("achieved: {:.3} m in {:.3} s", r.distance, r.time);
    let mut compromise = None;
    if let (Some(de), Some(te)) = (r.distance_error, r.time_error) {
        s += &format!(" (error {de:+.3} m, {te:+.3} s)");
        // Flag a compromise: an error over 1 % of a non-zero target.
        if missed.contains(&Missed::Distance) || missed.contains(&Missed::Time) {
            compromise = Some((r.distance - de, r.time - te));
        }
    }
    s += "\n";
    if let Some(target) = compromise {
        s += &not_met(r, target, fps);
    }
    s += &format!("final facing {:+.1}°", r.final_facing_deg);
    if let (Some(h), Some(e)) = (r.heading_target_deg, r.heading_error_deg) {
        s += &format!(" (target {h:+.1}°, error {e:+.1}°)");
    }
    s += "\n";
    if let (true, Some(h)) = (missed.contains(&Missed::Heading), r.heading_target_deg) {
        s += &format!(
            "heading not met within {HEADING_TOLERANCE_DEG}° (1 % of a turn): {:+.1}° for {h:+.1}°, the best compromise under Eq. 7 (the graph's transitions may not turn that far in this time; `KeyframeJobOptions::w_heading` weighs it against distance and time)\n",
            r.final_facing_deg
        );
    }
    s += &format!(
        "cost: transitions {:.4} + distance {:.4} + time {:.4}{} = {:.4}\n",
        r.cost.transition,
        r.cost.distance,
        r.cost.time,
        if r.heading_target_deg.is_some() {
            format!(" + heading {:.4}", r.cost.heading)
        } else {
            String::new()
        },
        r.cost.total
    );
    s += &segments(r);
    s += &format!(
        "{}, smoothness {}\n",
        count(r.transitions.len(), "transition"),
        r.smoothness
            .map_or("- (none)".to_string(), |x| format!("{x:.4} m"))
    );
    s += &format!(
        "search: {} nodes, {}, {} solved, {} pruned; {:.1} ms preparing, {:.1} ms searching{}, {:.2} s meshes\n",
        r.stats.nodes,
        count(r.stats.cycles, "loop"),
        count(r.stats.walks, "walk"),
        r.stats.pruned,
        1e3 * r.prepare_seconds,
        1e3 * r.search_seconds,
        r.search_cpu_seconds
            .map_or(String::new(), |c| format!(" ({:.1} ms CPU)", 1e3 * c)),
        r.mesh_seconds
    );
    for b in &r.stats.bounds_hit {
        s += &format!("bound hit: {b}\n");
    }
    s
}

/// Why the distance and time targets `(dt, tt)` were not met within 1 %,
/// and what the graph reaches.
fn not_met(r: &crate::keyframe::Report, (dt, tt): (f64, f64), fps: f64) -> String {
    let mut s = String::new();
    s += &format!(
        "not met within 1 %: {}\n",
        match r.reach {
            // The key-frames' own path is longer than the target's
            // horizon: it is taken as it is, no compromise is searched
            // (1000 --via gave "within the 13.0 s horizon" for 55.6 s).
            Some(x) if r.time > x.horizon + 0.5 / fps => format!(
                "the path through the {} key-frames takes {:.1} s, longer than the {:.1} s horizon of {dt:.3} m in {tt:.3} s, and is taken as it is (fewer or nearer via key-frames shorten it)",
                r.keys.len(),
                r.time,
                x.horizon
            ),
            reach => format!(
                "the best compromise for {dt:.3} m in {tt:.3} s under Eq. 7 within {} (the graph may not reach it; `KeyframeJobOptions::w_dist` and `KeyframeJobOptions::w_time` weigh the two)",
                reach.map_or("the horizon".to_string(), |x| format!(
                    "the {:.1} s horizon",
                    x.horizon
                ))
            ),
        }
    );
    if let Some(x) = r.reach {
        s += &format!(
            "reach: paths of {tt:.3} s travel {}; {dt:.3} m needs {}; at most {} within the horizon\n",
            x.at_time.map_or(
                "- (no path has exactly that length)".to_string(),
                |(a, b)| format!("{a:.3}-{b:.3} m")
            ),
            match (x.min_time, x.max_in_horizon) {
                (Some(m), _) => format!("at least {m:.2} s"),
                // Paths within the horizon travel farther, but no one
                // length's range holds the distance within 1 % (it is
                // below every path's, or between two lengths').
                (None, Some(most)) if most >= dt => format!(
                    "a path length none within the {:.1} s horizon has (none of their distance ranges holds it)",
                    x.horizon
                ),
                (None, _) => format!("more than {:.1} s", x.horizon),
            },
            x.max_in_horizon
                .map_or("-".to_string(), |m| format!("{m:.3} m"))
        );
    }
    s
}

/// Each segment's distance and time (with its targets and errors), walk
/// and loops, and how many missed their targets.
fn segments(r: &crate::keyframe::Report) -> String {
    let mut s = String::new();
    // Per-segment targets: each segment's target and error (the summary
    // printed the achieved totals alone, with no word that 11.6 m in 6.5 s
    // missed 5 m in 4 s twice).
    let mut missed_segments = 0;
    for seg in &r.segments {
        s += &format!(
            "segment {} -> {}: {:.3} m, {:.3} s",
            seg.from, seg.to, seg.distance, seg.time
        );
        if let (Some(td), Some(tt)) = (seg.target_distance, seg.target_time) {
            let (de, te) = (seg.distance - td, seg.time - tt);
            s += &format!(" (target {td:.3} m, {tt:.3} s; error {de:+.3} m, {te:+.3} s)");
            if segment_missed(seg) {
                missed_segments += 1;
            }
        }
        s += &format!("; walk {}", seg.walk.join(" "));
        for l in &seg.loops {
            s += &format!("; loop at {} ({}) x{}", l.at, l.frames.join(" "), l.repeats);
        }
        s += "\n";
    }
    if missed_segments > 0 {
        s += &format!(
            "not met within 1 % in {} of {}: the best compromise under Eq. 7 (the graph may not reach them; `KeyframeJobOptions::w_dist` and `KeyframeJobOptions::w_time` weigh the two)\n",
            count(missed_segments, "segment"),
            r.segments.len()
        );
    }
    s
}
