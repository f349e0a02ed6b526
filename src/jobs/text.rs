//! The text summaries of the jobs' reports, as the CLI prints them (a
//! verb's `--json` prints the report itself). Each is a function of the
//! report alone (plus the paths the caller named), so a library caller
//! gets the CLI's text.

use crate::batch::summary::count;
use crate::db::DbInfo;
use crate::graph::SurfaceMotionGraph;
use std::fmt::Write;
use std::path::Path;

use super::database::DatabaseReport;
use super::skeletons::SkeletonsReport;

/// `db build`'s summary of the database in `dir`: frames, pairs, the
/// graph and its first 40 transitions, the cache.
pub fn database(dir: &Path, graph: &SurfaceMotionGraph, r: &DatabaseReport) -> String {
    let mut out = format!(
        "{}: {} in {}, measure {} ({})\n",
        dir.display(),
        count(r.frames, "frame"),
        count(r.sequences.len(), "sequence"),
        r.measure.name(),
        r.unit
    );
    if r.similarity_cached {
        out += "similarity: cached\n";
    } else {
        let _ = writeln!(
            out,
            "similarity: {} pairs in {:.2} s (descriptors {:.2} s, {:.1} µs per pair)",
            r.pairs,
            r.pairs_seconds + r.describe_seconds,
            r.describe_seconds,
            1e6 * r.pairs_seconds / (r.pairs.max(1) as f64)
        );
    }
    let _ = writeln!(
        out,
        "graph: {} on {}{} in {:.3} s",
        count(r.transitions, "transition"),
        count(r.edges, "sequence edge"),
        if r.graph_cached { " (cached)" } else { "" },
        r.graph_seconds
    );
    for t in graph.transitions.iter().take(40) {
        let _ = writeln!(
            out,
            "  {}:{} -> {}:{}  L = {:2}  cost {:.4}",
            graph.sequences[t.from].name, t.m, graph.sequences[t.to].name, t.n, t.window, t.cost
        );
    }
    if graph.transitions.len() > 40 {
        let _ = writeln!(
            out,
            "  ... (`surfmotion graph {} --json` lists all)",
            dir.display()
        );
    }
    for e in &graph.removed {
        let _ = writeln!(out, "  removed by the manifest: {e}");
    }
    let _ = writeln!(out, "cache: {}", r.cache.display());
    out
}

/// `db info`'s listing: sequences, total, problems and notes.
pub fn info(i: &DbInfo) -> String {
    let mut s = format!(
        "{} ({} vertices, {} triangles)\n",
        i.name, i.vertices, i.triangles
    );
    for q in &i.sequences {
        let _ = writeln!(
            s,
            "  sequence {:<16} {:>6} frames at {} fps",
            q.name, q.frames, q.fps
        );
    }
    let _ = writeln!(s, "  total    {:>23} frames", i.total_frames);
    for p in &i.problems {
        let _ = writeln!(s, "  problem: {p}");
    }
    for n in &i.notes {
        let _ = writeln!(s, "  note: {n}");
    }
    s
}

/// `db skeleton`'s summary: frames, the bones' spread per sequence, the
/// rigid fit in millimetres (from the report's units), notes.
pub fn skeletons(r: &SkeletonsReport) -> String {
    let frames: usize = r.sequences.iter().map(|s| s.frames).sum();
    // Millimetres per model unit, from the manifest's units.
    let mm = crate::mocap::units::parse_unit(&r.units).map_or(1e3, |u| 1e3 * u.metres_per_unit);
    let mut out = format!(
        "embedded the rig and extracted {} ({}) in {:.3} s → {}\n",
        count(frames, "skeleton"),
        r.kind,
        r.seconds,
        r.output.display()
    );
    for s in &r.sequences {
        let _ = writeln!(
            out,
            "  {}: {} frames; bone lengths within {:.1}% of their median (worst: {})",
            s.sequence,
            s.frames,
            100.0 * s.worst_deviation,
            s.worst_bone
        );
        if let Some(f) = &s.rigid {
            let _ = writeln!(
                out,
                "    rigid fit to the regressor joints (whose bones vary by up to {:.1}%, {}): \
                 joints off by {:.1} mm RMS in the median frame, {:.1} mm RMS in the worst, \
                 {:.1} mm at most",
                100.0 * f.regressor_worst_deviation,
                f.regressor_worst_bone,
                mm * f.fit_rms_median,
                mm * f.fit_rms_max,
                mm * f.fit_joint_max,
            );
        }
    }
    for n in &r.notes {
        let _ = writeln!(out, "  note: {n}");
    }
    out
}
