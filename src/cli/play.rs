//! `surfmotion play`: a scripted session of parametric motion (Casas et
//! al. 2013, Sec. 3): the database's `[[space]]` motion spaces steered by
//! timed requests (space, speed, turn), written to any mesh output.
//! Parses, calls [`surfmotion::jobs::play`] and prints.

use std::path::PathBuf;
use surfmotion::jobs::output_set::OutputSet;
use surfmotion::jobs::play::{PlayOptions, PlayStage, play_session};

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
    #[command(flatten)]
    pub glb: super::mesh::SequenceOutputArgs,
    /// Write -o into a folder that already holds files (its OBJ frames are
    /// replaced).
    #[arg(long)]
    pub force: bool,
    /// Length of the session in seconds, at most 3600 (default: the last
    /// request + 2 s).
    #[arg(long, value_parser = super::session_seconds)]
    pub seconds: Option<f64>,
    /// Write the JSON report: parameters asked and achieved per second,
    /// transitions (request, start, end, latency, cost), notices, spaces.
    #[arg(long, value_name = "JSON")]
    pub report: Option<PathBuf>,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `play`.
pub fn run(a: Args) -> anyhow::Result<()> {
    // The output is checked before the work, as every verb does: its
    // format, no input or other output overwritten, a folder that holds
    // files only with --force (none of it was checked).
    OutputSet::reading_database(&a.db)
        .input([a.script.clone()])
        .mesh("-o", &a.output, a.force)
        .file("--report", a.report.as_deref())
        .check(|o| a.glb.refuse_other_formats(o))?;
    let opts = PlayOptions {
        seconds: a.seconds,
        glb: a.glb.options(),
        usd: a.glb.usd_options(),
        ..Default::default()
    };
    let mut bar = None;
    let run = play_session(
        &a.db,
        &a.script,
        &a.output,
        &opts,
        &mut |stage| match stage {
            PlayStage::Model => {
                bar = Some(super::spinner("loading or building the parametric model"))
            }
            PlayStage::Playing => bar.take().iter().for_each(|b| b.finish_and_clear()),
        },
    )?;
    let report = &run.report;
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
    if let Some(p) = &a.report {
        super::write_json(p, report)?;
    }
    super::report_sorted(a.json, &run, || {
        surfmotion::jobs::text::play(&run, &a.output)
    })?;
    for n in report.notices.iter().filter(|_| !a.json) {
        crate::errln!("note: request {} (t = {} s): {}", n.request, n.t, n.message);
    }
    Ok(())
}
