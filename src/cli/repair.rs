//! `surfmotion repair IN -o OUT`.

use std::path::PathBuf;
use surfmotion::jobs::repair::{RepairJobOptions, repair_file};
use surfmotion::mesh::repair::RepairOptions;

/// Arguments of `repair`.
#[derive(clap::Args)]
pub struct Args {
    /// Input mesh (a file, or SEQ.pc2:FRAME).
    #[arg(value_parser = super::mesh_spec)]
    pub input: String,
    /// Output mesh.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also weld vertices closer than this fraction of the bounding-box
    /// diagonal (default: only exact duplicates).
    #[arg(long, default_value_t = surfmotion::mesh::repair::RepairOptions::default().weld_tolerance, value_parser = super::non_negative)]
    pub weld_tolerance: f64,
    /// Keep only the largest connected component.
    #[arg(long)]
    pub keep_largest: bool,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `repair` ([`surfmotion::jobs::repair::repair_file`]): weld, drop
/// degenerate/duplicate triangles and unreferenced vertices, report the
/// connected components.
pub fn run(a: Args) -> anyhow::Result<()> {
    let r = repair_file(&RepairJobOptions {
        input: a.input,
        output: a.output,
        repair: RepairOptions {
            weld_tolerance: a.weld_tolerance,
            keep_largest: a.keep_largest,
        },
    })?;
    super::report(a.json, &r.report, || r.text())
}
