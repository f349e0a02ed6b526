//! `surfmotion play`: a scripted session of parametric motion (Casas et
//! al. 2013, Sec. 3): the database's `[[space]]` motion spaces steered by
//! timed requests (space, speed, turn), written to any mesh output.

use anyhow::Context;
use std::path::PathBuf;
use std::time::Instant;
use surfmotion::mesh::io::SaveOptions;
use surfmotion::mesh::io::stream::SequenceWriter;
use surfmotion::parametric::MotionOptions;
use surfmotion::parametric::script::{parse_script, play};
use surfmotion::parametric::store::load_or_build;

/// Arguments of `play`.
#[derive(clap::Args)]
pub struct Args {
    /// The character database; its manifest declares `[[space]]` entries
    /// (built and cached on first use, as `db build` does).
    #[arg(long)]
    pub db: PathBuf,
    /// The control script: a JSON list of timed requests, e.g.
    /// `[{"t": 0, "space": "locomotion", "speed": 1.2}, {"t": 3, "turn": 30}]`
    /// (t in seconds, speed in m/s, turn in degrees per second, left positive).
    #[arg(long, value_name = "JSON")]
    pub script: PathBuf,
    /// Output: .glb, .pc2 (+ .obj), .mdd, or a folder of OBJ frames.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write -o into a folder that already holds files (its OBJ frames are
    /// replaced).
    #[arg(long)]
    pub force: bool,
    /// Length of the session in seconds, at most 3600 (default: the last
    /// request + 2 s).
    #[arg(long, value_parser = session_seconds)]
    pub seconds: Option<f64>,
    /// Write the JSON report: parameters asked and achieved per second,
    /// transitions (request, start, end, latency, cost), notices, spaces.
    #[arg(long, value_name = "JSON")]
    pub report: Option<PathBuf>,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `--seconds`: a length in (0, [`MAX_SECONDS`]], as a script's times
/// (`--seconds 1e12` was refused only by the memory budget, naming the
/// script).
fn session_seconds(s: &str) -> Result<f64, String> {
    use surfmotion::parametric::script::MAX_SECONDS;
    let v = super::positive(s)?;
    if v <= MAX_SECONDS {
        Ok(v)
    } else {
        Err(format!("{s}: expected seconds in (0, {MAX_SECONDS}]"))
    }
}

/// Runs `play`.
pub fn run(a: Args) -> anyhow::Result<()> {
    // The output is checked before the work, as every verb does: its
    // format, no input or other output overwritten, a folder that holds
    // files only with --force (none of it was checked).
    super::check_mesh_output(&a.output)?;
    let mut inputs = super::database_inputs(&a.db);
    inputs.push(a.script.clone());
    let mut outputs = super::mesh_outputs(&a.output);
    outputs.extend(a.report.clone().map(|p| ("--report", p)));
    super::refuse_colliding(&inputs, &outputs)?;
    super::check_folder_output(&a.output, a.force, &inputs)?;
    // The script is checked against the manifest's spaces before the
    // model is built (a typo was reported only after the build: 7.5 s on
    // the demo database, minutes on a real one).
    let text = surfmotion::util::fsutil::read_small_text(&a.script)
        .with_context(|| a.script.display().to_string())?;
    if let Ok(m) = surfmotion::db::Manifest::load(&a.db) {
        use surfmotion::parametric::Parameter;
        // A database without spaces is the database's fault, not the
        // script's (it said `unknown key "speed" (expected t, space)`).
        m.require_spaces(&a.db)?;
        let params: Vec<Vec<Parameter>> = m
            .spaces
            .iter()
            .map(|s| {
                s.parameters
                    .iter()
                    .filter_map(|p| Parameter::parse(p))
                    .collect()
            })
            .collect();
        let spaces: Vec<(&str, &[Parameter])> = m
            .spaces
            .iter()
            .zip(&params)
            .map(|(s, p)| (s.name.as_str(), p.as_slice()))
            .collect();
        surfmotion::parametric::script::parse_script_for(&text, &a.script, &spaces)?;
    }
    let t0 = Instant::now();
    let bar = super::spinner("loading or building the parametric model");
    let built = load_or_build(&a.db, &MotionOptions::default(), false);
    bar.finish_and_clear();
    let (motion, cached) = built?;
    let build_s = t0.elapsed().as_secs_f64();
    let script = parse_script(&text, &a.script, &motion)?;
    let seconds = a
        .seconds
        .unwrap_or_else(|| script.last().map_or(0.0, |r| r.t) + 2.0);
    let n = motion.topology.vertex_count();
    // Frames go to the output as they are made (point caches and OBJ
    // folders stream; a GLB, written whole, is checked against the memory
    // budget here, before the first frame). Every frame was held, then
    // the whole file's bytes: 1.1 GB for `--seconds 100` (attack s14,
    // item 3).
    let frames = surfmotion::parametric::script::session_frames(&script, Some(seconds), motion.fps);
    let mut writer = SequenceWriter::create(
        &motion.topology,
        &a.output,
        frames,
        &SaveOptions {
            fps: Some(motion.fps),
            ..Default::default()
        },
    )?;
    let mut write_s = 0.0;
    let report = play(&motion, &script, Some(seconds), |p| {
        let t = Instant::now();
        let r = writer.push(p);
        write_s += t.elapsed().as_secs_f64();
        r
    })?;
    // What could not be done (a speed clamped to the space's range) is
    // said once, on stderr, as the README says (issue 39, item 9: it went
    // to stdout); --json logs it as a warning, text mode as a note.
    for n in report.notices.iter().filter(|_| a.json) {
        tracing::warn!(
            "{}: request {} (t = {} s): {}",
            a.script.display(),
            n.request,
            n.t,
            n.message
        );
    }
    let t1 = Instant::now();
    let written = writer.finish()?;
    let write_s = write_s + t1.elapsed().as_secs_f64();
    if let Some(p) = &a.report {
        surfmotion::util::fsutil::write_bytes_atomic(
            p,
            serde_json::to_string_pretty(&report)?.as_bytes(),
        )?;
    }
    if a.json {
        let mut v = serde_json::to_value(&report)?;
        v["output"] = serde_json::to_value(&written)?;
        v["model_cached"] = cached.into();
        v["model_seconds"] = build_s.into();
        v["write_seconds"] = write_s.into();
        return super::emit(&(serde_json::to_string_pretty(&v)? + "\n"));
    }
    crate::outln!(
        "{} ({:.1} s at {} fps, {} vertices) → {}",
        super::count(report.frames, "frame"),
        report.seconds,
        report.fps,
        n,
        a.output.display()
    )?;
    crate::outln!(
        "synthesis {:.3} s ({:.0}× real time); model {} in {:.2} s; writing {:.2} s",
        report.synthesis_seconds,
        report.realtime_factor,
        if cached { "from the cache" } else { "built" },
        build_s,
        write_s
    )?;
    for t in &report.transitions {
        crate::outln!(
            "transition {} → {}: requested {:.2} s, start {:.2} s, end {:.2} s, latency {:.2} s, similarity {:.3}, cost {:.3}",
            t.from,
            t.to,
            t.request_frame as f64 / report.fps,
            t.start_frame as f64 / report.fps,
            t.end_frame as f64 / report.fps,
            t.latency,
            t.similarity,
            t.cost
        )?;
    }
    crate::outln!("second  space  speed asked/achieved (m/s)  turn asked/achieved (deg/s)")?;
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.2}"));
    for s in &report.per_second {
        crate::outln!(
            "{:>4}  {}{}  {} / {:.2}  {} / {:.1}",
            s.second,
            s.space,
            if s.transition { " (transition)" } else { "" },
            opt(s.speed_asked),
            s.speed,
            opt(s.turn_asked),
            s.turn
        )?;
    }
    for n in &report.notices {
        crate::errln!("note: request {} (t = {} s): {}", n.request, n.t, n.message);
    }
    Ok(())
}
