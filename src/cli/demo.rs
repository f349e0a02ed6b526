//! `surfmotion demo`: the main job end to end on an embedded character.

use std::path::PathBuf;
/// Arguments of `demo`.
#[derive(clap::Args)]
pub struct Args {
    /// Folder for the demo's files (database, result, pictures).
    #[arg(short, long, default_value = "surfmotion-demo")]
    pub output: PathBuf,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs the demo ([`surfmotion::jobs::demo::run_demo`]).
pub fn run(a: Args) -> anyhow::Result<()> {
    let r = surfmotion::jobs::demo::run_demo(&a.output, &super::Bars::new())?;
    super::report_sorted(a.json, &r, || surfmotion::jobs::text::demo(&r))
}
