//! `surfmotion blend A B --alpha 0.3 -o OUT [--linear]`.

use anyhow::bail;
use std::path::PathBuf;
use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::blend::{Blender, linear_blend};
use surfmotion::mesh::io::{LoadOptions, load_sequence, save_sequence};
use surfmotion::mesh::measure::distortion;

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
    if !(0.0..=1.0).contains(&a.alpha) {
        bail!("--alpha {} is outside 0..1", a.alpha);
    }
    let opts = LoadOptions {
        topology: a.topology.clone(),
        fps: None,
    };
    let inputs: Vec<_> = [&a.a, &a.b]
        .iter()
        .flat_map(|s| surfmotion::mesh::io::input_files(s, a.topology.as_deref()))
        .collect();
    surfmotion::mesh::io::refuse_overwriting(&inputs, &a.output)?;
    let one = |spec: &str| -> anyhow::Result<MeshSequence> {
        let s = load_sequence(spec, &opts)?;
        if s.frame_count() != 1 {
            bail!(
                "{spec}: {} frames; name one with {spec}:FRAME",
                s.frame_count()
            );
        }
        Ok(s)
    };
    let (sa, sb) = (one(&a.a)?, one(&a.b)?);
    let (ma, mb) = (sa.frame_mesh(0), sb.frame_mesh(0));
    if ma.vertex_count() != mb.vertex_count() || ma.triangles() != mb.triangles() {
        bail!(
            "{} and {}: not the same connectivity ({} vs {} vertices)",
            a.a,
            a.b,
            ma.vertex_count(),
            mb.vertex_count()
        );
    }
    let t0 = std::time::Instant::now();
    let nonlinear = || -> anyhow::Result<Vec<[f64; 3]>> {
        let bl = Blender::new(&ma)?;
        let mut ws = bl.workspace();
        let (ga, gb) = (
            bl.decompose(ma.positions(), &mut ws),
            bl.decompose(mb.positions(), &mut ws),
        );
        let mut out = vec![[0.0; 3]; ma.vertex_count()];
        bl.blend(&ga, &gb, a.alpha, &mut out, &mut ws);
        Ok(out)
    };
    let lin = linear_blend(ma.positions(), mb.positions(), a.alpha);
    let result = if a.linear { lin.clone() } else { nonlinear()? };
    let secs = t0.elapsed().as_secs_f64();
    let out = MeshSequence::single(ma.with_positions(&result)?);
    save_sequence(&out, &a.output, None)?;
    let d = distortion(&ma, ma.positions(), mb.positions(), &result);
    let dl = distortion(&ma, ma.positions(), mb.positions(), &lin);
    let report = serde_json::json!({
        "output": a.output,
        "method": if a.linear { "linear" } else { "non-linear" },
        "alpha": a.alpha,
        "vertices": ma.vertex_count(),
        "seconds": secs,
        "edge_length_distortion": d.edge_length,
        "volume_distortion": d.volume,
        "linear_edge_length_distortion": dl.edge_length,
        "linear_volume_distortion": dl.volume,
    });
    if a.json {
        crate::outln!("{}", serde_json::to_string_pretty(&report)?)?;
    } else {
        crate::outln!(
            "wrote {} ({} blend, α = {}, {:.1} ms)\n  edge-length distortion {:.4} (linear: {:.4})\n  volume distortion      {:.4} (linear: {:.4})\n  (relative to the mean of the inputs' edge lengths and volumes)",
            a.output.display(),
            if a.linear { "linear" } else { "non-linear" },
            a.alpha,
            secs * 1e3,
            d.edge_length,
            dl.edge_length,
            d.volume,
            dl.volume
        )?;
    }
    Ok(())
}
