//! `surfmotion synth`: a multi-motion 4D database from a rest mesh, its
//! landmarks and mocap clips (skinning plus secondary dynamics).

use std::path::PathBuf;
use surfmotion::jobs::SynthOptions;
use surfmotion::jobs::synth::synth_from_files;
use surfmotion::synth::database::Dynamics;

/// Arguments of `synth`.
#[derive(clap::Args)]
pub struct Args {
    /// Rest mesh of the character (a file, or SEQ.pc2:FRAME), metres, Y-up.
    #[arg(long, value_parser = super::mesh_spec)]
    pub mesh: String,
    /// Landmarks on the rest mesh (JSON; see `rig embed --help`).
    #[arg(long)]
    pub landmarks: PathBuf,
    /// Mocap clips (BVH or AMC), one sequence each; repeatable.
    #[arg(long = "mocap", required = true, num_args = 1..)]
    pub mocap: Vec<PathBuf>,
    /// Output database directory.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Frame rate of the database.
    #[arg(long, default_value_t = SynthOptions::default().fps, value_parser = super::frame_rate)]
    pub fps: f64,
    /// Use at most this many seconds of each clip.
    #[arg(long, value_parser = super::positive)]
    pub seconds: Option<f64>,
    /// Strength of the secondary dynamics: the scale of the softness map
    /// (0: pure skinning, 1: the default, at most 2; from about 3 the
    /// springs tear the surface at the waist).
    #[arg(long, default_value_t = Dynamics::default().amount, value_parser = super::dynamics_amount)]
    pub dynamics: f64,
    /// Overwrite an existing manifest in the output.
    #[arg(long)]
    pub force: bool,
    #[command(flatten)]
    pub run: super::RunOpts,
}

/// The job's options from the arguments.
pub(super) fn options(a: &Args) -> anyhow::Result<SynthOptions> {
    Ok(SynthOptions {
        fps: a.fps,
        seconds: a.seconds,
        dynamics: Dynamics {
            amount: a.dynamics.max(0.0),
            ..Dynamics::default()
        },
        force: a.force,
        load: a.run.clip.load_options()?,
        ..Default::default()
    })
}

/// Runs `synth` ([`surfmotion::jobs::synth::synth_from_files`]).
pub fn run(a: Args) -> anyhow::Result<()> {
    super::warnings_in_summary(!a.run.json);
    let dir = &a.output;
    let opts = options(&a)?;
    let bar = super::progress(a.mocap.len() as u64, "clips");
    let preview = a
        .run
        .preview
        .preview
        .as_ref()
        .map(|_| a.run.preview.options());
    let run = synth_from_files(
        dir,
        &a.mesh,
        &a.landmarks,
        &a.mocap,
        &opts,
        preview.as_ref(),
        &mut || bar.inc(1),
    )?;
    bar.finish_and_clear();
    let r = &run.report;
    super::report_sorted(a.run.json, r, || run.text(dir))?;
    // The contact sheets of all sequences, one above the other; plausibility.
    if let (Some(p), Some(img)) = (&a.run.preview.preview, &run.sheet) {
        img.save_png(p)?;
    }
    if !a.run.json {
        crate::outln!("{}", run.plausibility.trim_end())?;
    }
    Ok(())
}
