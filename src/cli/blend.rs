//! `surfmotion blend A B --alpha 0.3 -o OUT [--linear]`.

use std::path::PathBuf;
use surfmotion::jobs::blend::{BlendOptions, blend};

/// Arguments of `blend`.
#[derive(clap::Args)]
pub struct Args {
    /// First mesh (a file, or SEQ.pc2:FRAME).
    #[arg(value_parser = super::mesh_spec)]
    pub a: String,
    /// Second mesh, same connectivity.
    #[arg(value_parser = super::mesh_spec)]
    pub b: String,
    /// Blend weight: 0 gives A, 1 gives B.
    #[arg(long, default_value_t = 0.5, value_parser = super::fraction)]
    pub alpha: f64,
    /// Output mesh (.obj, .ply, .glb ...).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Plain per-vertex linear interpolation instead of the non-linear blend.
    #[arg(long)]
    pub linear: bool,
    /// Topology for point-cache inputs.
    #[arg(long, value_name = "MESH")]
    pub topology: Option<PathBuf>,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `blend`: non-linear blending (slerp of per-triangle rotations, lerp
/// of stretch, Poisson stitching; Casas et al. 2013) or plain lerp, and a
/// report of how well each keeps edge lengths and volume.
pub fn run(a: Args) -> anyhow::Result<()> {
    let r = blend(&BlendOptions {
        a: a.a,
        b: a.b,
        alpha: a.alpha,
        output: a.output,
        linear: a.linear,
        topology: a.topology,
    })?;
    super::report_sorted(a.json, &r, || surfmotion::jobs::short_text::blend(&r))
}
