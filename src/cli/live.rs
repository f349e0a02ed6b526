//! `surfmotion live`: a mocap stream drives the 4D character now (issue
//! 45). Parses, calls [`surfmotion::jobs::live::run_live`] and prints.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use surfmotion::jobs::live::{LiveInput, LiveOptions, LiveReport, run_live};

/// Arguments of `live`.
#[derive(clap::Args)]
pub struct Args {
    /// The character database (built and cached on first use, as `db build`
    /// does).
    #[arg(long)]
    pub db: PathBuf,
    /// Play a clip file (any format `retarget` reads) as the stream, at its
    /// real frame rate (see --speed).
    #[arg(long, value_name = "CLIP")]
    pub replay: PathBuf,
    /// Frames of future the retrieval sees before it decides a frame (the
    /// fixed-lag trellis); 0 decides each frame as it comes (greedy, with a
    /// hysteresis against flicker). Each lag frame adds one frame period
    /// of delay.
    #[arg(long, default_value_t = 3)]
    pub lag: usize,
    /// Replay speed: 1 plays the clip at its real rate, 2 twice as fast, 0
    /// as fast as meshes are made (for measuring throughput).
    #[arg(long, default_value_t = 1.0, value_name = "FACTOR")]
    pub speed: f64,
    /// Stop after this many seconds of streaming.
    #[arg(long, value_parser = super::positive)]
    pub seconds: Option<f64>,
    /// Record the output to any sequence format (.glb, .pc2, .mdd, .usda, a
    /// folder of OBJ frames), written atomically when the stream ends.
    #[arg(long, value_name = "OUT")]
    pub record: Option<PathBuf>,
    /// Print the latency and throughput report (frames/s, arrival to mesh
    /// ready median and p99, drops) when the stream ends.
    #[arg(long)]
    pub report: bool,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub clip: super::opts::ClipOpts,
}

/// Runs `live`.
pub fn run(a: Args) -> anyhow::Result<()> {
    if let Some(out) = &a.record {
        surfmotion::jobs::outputs::check_mesh_output(out)?;
        let mut inputs = surfmotion::jobs::outputs::database_inputs(&a.db);
        inputs.push(a.replay.clone());
        inputs.extend(a.clip.rig_map.clone());
        surfmotion::jobs::outputs::refuse_colliding(&inputs, &super::mesh_outputs(out))?;
    }
    if !(a.speed.is_finite() && a.speed >= 0.0) {
        anyhow::bail!("--speed {}: expected a factor ≥ 0", a.speed);
    }
    let opts = LiveOptions {
        lag: a.lag,
        speed: a.speed,
        seconds: a.seconds,
        load: a.clip.load_options()?,
        ..LiveOptions::default()
    };
    let stop = AtomicBool::new(false);
    let report = run_live(
        &a.db,
        &LiveInput::Replay(a.replay.clone()),
        a.record.as_deref(),
        &opts,
        &super::db::Bars::new(),
        &stop,
        &mut |_| {},
    )?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if a.report {
        print_report(&report);
    } else {
        println!(
            "{} frames at {:.1} frames/s, latency median {:.1} ms, p99 {:.1} ms",
            report.frames_out, report.output_fps, report.latency.median_ms, report.latency.p99_ms
        );
    }
    for f in &report.recorded {
        println!("wrote {}", f.display());
    }
    Ok(())
}

/// The report as text.
fn print_report(r: &LiveReport) {
    println!(
        "live: {} frames out over {:.2} s = {:.1} frames/s ({} vertices, database at {} fps, lag {})",
        r.frames_out, r.seconds, r.output_fps, r.vertices, r.fps, r.lag
    );
    println!(
        "arrival -> mesh ready: median {:.2} ms, p99 {:.2} ms, max {:.2} ms (mesh work median {:.2} ms)",
        r.latency.median_ms, r.latency.p99_ms, r.latency.max_ms, r.work_median_ms
    );
    let c = &r.input;
    println!(
        "input: {} received, {} dropped, {} duplicated, {} late, {} malformed, {} reconnects",
        c.received, c.dropped, c.duplicated, c.late, c.malformed, c.reconnects
    );
    let s = &r.retrieval;
    println!(
        "retrieval: {} decided, {} jumps, {} cuts, {} widened; T_skel {:.3} m; prepared in {:.2} s",
        s.committed, s.jumps, s.cuts, s.widened, s.t_skel, r.prepare_seconds
    );
}
