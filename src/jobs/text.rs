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
    if let Some(scan) = &r.scan {
        let _ = writeln!(out, "sequence-pair scan: {}", scan.describe());
    }
    let _ = writeln!(
        out,
        "graph: {} on {}{} in {:.3} s",
        count(r.transitions, "transition"),
        count(r.edges, "sequence edge"),
        if r.graph_cached { " (cached)" } else { "" },
        r.graph_seconds
    );
    for t in graph.transitions().iter().take(40) {
        let _ = writeln!(
            out,
            "  {}:{} -> {}:{}  L = {:2}  cost {:.4}",
            graph.sequences()[t.from].name,
            t.m,
            graph.sequences()[t.to].name,
            t.n,
            t.window,
            t.cost
        );
    }
    if graph.transitions().len() > 40 {
        let _ = writeln!(
            out,
            "  ... (the graph of {} in JSON lists all)",
            dir.display()
        );
    }
    for e in graph.removed() {
        let _ = writeln!(out, "  removed by the manifest: {e}");
    }
    if let Some(s) = r.caches_beside_seconds {
        let _ = writeln!(
            out,
            "rig, frames and skeletons cached in {s:.2} s while the frames were compared"
        );
    }
    if let Some(s) = r.prepared_seconds {
        let _ = writeln!(
            out,
            "prepared for retargeting in {s:.2} s (frames, skeletons, rig, examples, plausibility reference cached)"
        );
    }
    if let Some(why) = &r.prepare_failed {
        let _ = writeln!(out, "not prepared for retargeting: {why}");
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

/// `retarget`'s summary of `clip` retargeted: files, retrieval, the path
/// (its first 12 runs), timings, deformation, plausibility.
pub fn retarget(clip: &Path, c: &super::retarget::ClipResult) -> String {
    let r = &c.report;
    let mut s = format!(
        "{} -> {}: {} at {} fps ({} rig)\n",
        clip.display(),
        written_list(&c.written, ", "),
        count(r.frames, "frame"),
        r.fps,
        c.convention
    );
    let _ = writeln!(
        s,
        "retrieval: T_skel {:.3} m (summed over the 19 joints), {}, {}, {}, {}",
        r.retrieval.t_skel,
        count(r.retrieval.nodes, "trellis node"),
        count(
            r.jumps.iter().filter(|j| j.transition).count(),
            "transition"
        ),
        count(r.retrieval.cuts.len(), "cut"),
        count(r.retrieval.widened.len(), "widened frame")
    );
    let mut runs: Vec<(String, usize, usize)> = Vec::new();
    for st in &r.steps {
        match runs.last_mut() {
            Some((n, _, b)) if *n == st.sequence && (st.frame == *b || st.frame == *b + 1) => {
                *b = st.frame
            }
            _ => runs.push((st.sequence.clone(), st.frame, st.frame)),
        }
    }
    s += "path:";
    for (n, a0, b0) in runs.iter().take(12) {
        let _ = write!(s, " {n}[{a0}..{b0}]");
    }
    if runs.len() > 12 {
        s += " ...";
    }
    s += "\n";
    let _ = writeln!(
        s,
        "time: query {:.3} s, retrieval {:.3} s, timeline {:.3} s, blend factor {:.3} s, meshes {:.3} s, deform factor {:.3} s, deform {:.3} s ({:.2} ms per output frame)",
        r.timings.query,
        r.timings.retrieval,
        r.timings.timeline,
        r.timings.factor,
        r.timings.meshes,
        r.timings.deform_factor,
        r.timings.deform,
        1e3 * super::retarget::per_frame_seconds(r)
    );
    let _ = writeln!(s, "deformation: {}", r.deform);
    if matches!(
        r.deform,
        crate::deform::DeformMode::Part | crate::deform::DeformMode::Global
    ) {
        let _ = writeln!(
            s,
            "triangle-frames turned over against the retrieved frames (the database frames each output frame blends): {} after the solve, {} after the repair (the plausibility below counts against the rest frame)",
            r.turned_over.before, r.turned_over.after
        );
    }
    if let Some(p) = &c.plausibility {
        if let Some(k) = c.partial {
            let _ = writeln!(
                s,
                "plausibility measured on the first {} of {} (streamed output):",
                count(k, "frame"),
                r.frames
            );
        }
        s += &p.text();
    }
    s
}

/// The files a mesh output wrote, for a summary line: each named, except
/// a folder of OBJ frames, named once with its count and first and last
/// frame (`mesh convert x.pc2 frames` listed all 180 frames joined by
/// "and", a line of 5 kB).
pub fn written_list(files: &[std::path::PathBuf], sep: &str) -> String {
    let name = |p: &std::path::PathBuf| p.display().to_string();
    let folder = files.first().and_then(|f| f.parent());
    let frames = files.len() > 2
        && files.iter().all(|f| {
            f.parent() == folder && f.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"))
        });
    match (frames, folder, files.first(), files.last()) {
        (true, Some(dir), Some(a), Some(b)) => format!(
            "{}{} ({} OBJ frames, {} .. {})",
            dir.display(),
            std::path::MAIN_SEPARATOR,
            files.len(),
            a.file_name().unwrap_or_default().to_string_lossy(),
            b.file_name().unwrap_or_default().to_string_lossy()
        ),
        _ => files.iter().map(name).collect::<Vec<_>>().join(sep),
    }
}

/// `transfer`'s summary of `scan` transferred (`truth`: the sequence the
/// error was measured against): files, scan and markers, timings, truth
/// error, plausibility.
pub fn transfer(scan: &str, truth: Option<&str>, r: &super::TransferReport) -> String {
    let mut s = format!(
        "{} -> {}: {} frames at {} fps from {}\n",
        scan,
        written_list(&r.output, ", "),
        r.frames,
        r.fps,
        r.source
    );
    let _ = writeln!(
        s,
        "scan: {} vertices, {} triangles; {} markers ({} unpaired); {} components dropped",
        r.vertices,
        r.triangles,
        r.markers,
        r.unpaired_markers,
        r.scan.dropped_components.len()
    );
    let rep = &r.scan.repair;
    if !rep.unchanged() {
        let _ = writeln!(
            s,
            "scan repaired before the transfer (the outputs hold the repaired mesh): {} vertices welded, {} in no triangle dropped; {} degenerate and {} duplicate triangles dropped",
            rep.welded_vertices,
            rep.unreferenced_vertices,
            rep.degenerate_triangles,
            rep.duplicate_triangles
        );
    }
    let _ = writeln!(
        s,
        "time: setup {:.2} s, factor {:.2} s, {:.2} ms/frame ({:.0} frames/s); {} frames near 180°",
        r.setup_seconds,
        r.factor_seconds,
        r.ms_per_frame,
        r.frames_per_second,
        r.transfer.singular_frames
    );
    if let Some(e) = &r.truth_error {
        let _ = writeln!(
            s,
            "error against {}: mean {:.3}%, p95 {:.3}%, max {:.3}% of height",
            truth.unwrap_or(""),
            e.mean_pct,
            e.p95_pct,
            e.max_pct
        );
    }
    if let Some(p) = &r.plausibility {
        s += &p.text();
    }
    s
}

/// The one-line summary of an export. Transitions and motion spaces are
/// said only when there are some ("0 spaces (0 frames, 0 KB)" was printed
/// for every database without a `[[space]]`).
pub fn web_export(r: &crate::web::ExportReport) -> String {
    let g = &r.geometry;
    let mut s = format!(
        "wrote {}: {} × {}, geometry {:.0} KB ({:.1} KB/frame, {:.1}× smaller than float32), max vertex error {} mm (step {} mm)",
        r.site.display(),
        count(g.frames, "frame"),
        count(r.vertices, "vertex"),
        g.bytes as f64 / 1e3,
        g.bytes as f64 / 1e3 / g.frames.max(1) as f64,
        r.raw_bytes as f64 / g.bytes.max(1) as f64,
        crate::util::numfmt::Short(g.max_error * 1e3),
        crate::util::numfmt::Short(g.step * 1e3),
    );
    match (r.transitions, r.transition_frames) {
        (0, _) => s += ", no transitions",
        (t, 0) => s += &format!(", {} (blended by the page)", count(t, "transition")),
        (t, f) => {
            s += &format!(
                ", {} ({} precomputed, {:.0} KB, {:.2} s)",
                count(t, "transition"),
                count(f, "frame"),
                r.transition_bytes as f64 / 1e3,
                r.transition_seconds
            )
        }
    }
    if r.spaces > 0 {
        s += &format!(
            ", {} ({}, {:.0} KB)",
            count(r.spaces, "motion space"),
            count(r.space_frames, "frame"),
            r.space_bytes as f64 / 1e3
        );
    }
    s + &format!(", {:.2} s\n", r.seconds)
}

/// `rig embed`'s summary: joints in the canonical order, parts, notes, the
/// self-check and its warnings.
pub fn rig_embed(r: &super::rig::RigEmbedReport) -> String {
    let mut s = format!(
        "embedded a rig in {} ({} vertices) in {:.2} s → {}\n",
        r.mesh,
        r.vertices,
        r.seconds,
        r.output.display()
    );
    let f = r.facing;
    let _ = writeln!(
        s,
        "  height {:.3}, facing ({:.2}, {:.2}, {:.2})",
        r.height, f[0], f[1], f[2]
    );
    s += "  joints:\n";
    for c in crate::rig::Canonical::ALL {
        if let Some(p) = r.joints.get(c.name()) {
            let _ = writeln!(
                s,
                "    {:<11} ({:>7.3}, {:>7.3}, {:>7.3})",
                c.name(),
                p[0],
                p[1],
                p[2]
            );
        }
    }
    s += "  parts (labelled vertices / overlapping region / pieces):\n";
    for p in crate::embed::parts::Part::ALL {
        if let Some(c) = r.parts.get(p.name()) {
            let _ = writeln!(
                s,
                "    {:<12} {:>6} {:>6} {:>3}",
                p.name(),
                c.vertices,
                c.region,
                c.pieces
            );
        }
    }
    for n in &r.notes {
        let _ = writeln!(s, "  note: {n}");
    }
    let v = &r.check;
    let _ = writeln!(
        s,
        "  self-check: pelvis {:.2}% of the height off the mid-plane, hips {:.2}% asymmetric: {}",
        v.pelvis_offset_percent,
        v.hip_asymmetry_percent,
        if v.passed() {
            "passed".to_string()
        } else {
            format!("{} warning(s)", v.warnings.len())
        }
    );
    for w in &v.warnings {
        let _ = writeln!(s, "  warning: {}", w.message);
    }
    if let Some(p) = &r.png {
        let _ = writeln!(s, "  drew {}", p.display());
    }
    s
}

/// The demo's summary: what was made, how long it took, what to try next.
pub fn demo(r: &super::demo::DemoReport) -> String {
    let (n, frames) = (r.vertices, r.query_frames);
    let (t_db, t_graph, t_retarget) = (r.seconds.database, r.seconds.graph, r.seconds.retarget);
    format!(
        "surfmotion demo: a procedural humanoid driven through its Surface Motion Graph\n\
         \n\
         character   {n} vertices (surface nets over capsules), rig from {} landmarks\n\
         database    walk + run, {} frames synthesised (skinning + soft-tissue lag) in {t_db:.2} s\n\
         graph       {} transitions (3D shape histograms) in {t_graph:.2} s\n\
         query       a procedural walk along a curve, {frames} frames (the database walks straight)\n\
         retarget    {} transitions, {} cuts, in {t_retarget:.2} s ({:.1} ms per frame)\n\
         accuracy    joint-velocity error {:.2} ± {:.2} cm/frame (Huang et al. 2015 report ~2 for walks)\n\
         \n\
         wrote {}\n\
         \x20     {}  (result: open in any glTF viewer)\n\
         \x20     {}  (5 frames)\n\
         \x20     {}  (the query clip)\n\
         \n\
         Next: `surfmotion retarget --db {} --mocap CLIP.bvh -o out.glb` with any BVH or AMC clip,\n\
         or build a database from a real capture (see README: Character databases).\n\
         The result is retrieved, blended, interpolated and then deformed part by part\n\
         (PCA Laplacian, Sec. 5.2.3) to follow the query skeleton.\n",
        r.landmarks,
        r.database_frames,
        r.transitions,
        r.used,
        r.cuts,
        1e3 * t_retarget / frames.max(1) as f64,
        r.velocity_error_cm_per_frame,
        r.velocity_error_std,
        r.database.display(),
        r.result.display(),
        r.picture.display(),
        r.query.display(),
        r.database.display(),
    )
}

/// `play`'s summary of a session written to `output`: frames, timings,
/// transitions, and the parameters asked and achieved per second.
pub fn play(run: &super::play::PlayRun, output: &Path) -> String {
    let report = &run.report;
    let mut s = format!(
        "{} ({:.1} s at {} fps, {} vertices) → {}\n",
        count(report.frames, "frame"),
        report.seconds,
        report.fps,
        run.vertices,
        output.display()
    );
    let _ = writeln!(
        s,
        "synthesis {:.3} s ({:.0}× real time); model {} in {:.2} s; writing {:.2} s",
        report.synthesis_seconds,
        report.realtime_factor,
        if run.model_cached {
            "from the cache"
        } else {
            "built"
        },
        run.model_seconds,
        run.write_seconds
    );
    for t in &report.transitions {
        let _ = writeln!(
            s,
            "transition {} → {}: requested {:.2} s, start {:.2} s, end {:.2} s, latency {:.2} s, similarity {:.3}, cost {:.3}",
            t.from,
            t.to,
            t.request_frame as f64 / report.fps,
            t.start_frame as f64 / report.fps,
            t.end_frame as f64 / report.fps,
            t.latency,
            t.similarity,
            t.cost
        );
    }
    s += "second  space  speed asked/achieved (m/s)  turn asked/achieved (deg/s)\n";
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.2}"));
    for q in &report.per_second {
        let _ = writeln!(
            s,
            "{:>4}  {}{}  {} / {:.2}  {} / {:.1}",
            q.second,
            q.space,
            if q.transition { " (transition)" } else { "" },
            opt(q.speed_asked),
            q.speed,
            opt(q.turn_asked),
            q.turn
        );
    }
    s
}
