//! `blend`: two meshes of one connectivity blended, non-linearly (rotations
//! slerped, stretch lerped, Poisson-stitched; Casas et al. 2013 Eqs. 1-2)
//! or linearly, with the edge-length and volume distortion of both.

use crate::mesh::MeshSequence;
use crate::mesh::blend::{Blender, linear_blend};
use crate::mesh::io::{LoadOptions, load_sequence, save_sequence};
use crate::mesh::measure::distortion;
use std::path::PathBuf;

use super::JobError;

/// What to blend.
#[derive(Clone, Debug, Default)]
pub struct BlendOptions {
    /// The first mesh (a file, or `SEQ:FRAME`): one frame.
    pub a: String,
    /// The second mesh, of the first's connectivity.
    pub b: String,
    /// Weight of the second, in [0, 1] (the CLI's default 0.5).
    pub alpha: f64,
    /// The mesh written.
    pub output: PathBuf,
    /// Blend linearly instead.
    pub linear: bool,
    /// Topology of point-cache inputs.
    pub topology: Option<PathBuf>,
}

/// What `blend` wrote and measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BlendReport {
    /// The mesh written.
    pub output: PathBuf,
    /// `linear` or `non-linear`.
    pub method: &'static str,
    /// The weight of the second mesh.
    pub alpha: f64,
    /// Vertices.
    pub vertices: usize,
    /// Blending time.
    pub seconds: f64,
    /// Edge-length distortion of the result (relative to the inputs' mean).
    pub edge_length_distortion: f64,
    /// Volume distortion of the result.
    pub volume_distortion: f64,
    /// Edge-length distortion of the linear blend.
    pub linear_edge_length_distortion: f64,
    /// Volume distortion of the linear blend.
    pub linear_volume_distortion: f64,
}

/// Blends `o.a` and `o.b` into `o.output` (never over an input).
pub fn blend(o: &BlendOptions) -> Result<BlendReport, JobError> {
    if !(0.0..=1.0).contains(&o.alpha) {
        return Err(JobError::Usage(format!(
            "`BlendOptions::alpha` {} is outside 0..1",
            o.alpha
        )));
    }
    let opts = LoadOptions {
        topology: o.topology.clone(),
        fps: None,
    };
    let inputs: Vec<_> = [&o.a, &o.b]
        .iter()
        .flat_map(|s| crate::mesh::io::input_files(s, o.topology.as_deref()))
        .collect();
    crate::mesh::io::refuse_overwriting(&inputs, &o.output)?;
    let one = |spec: &str| -> Result<MeshSequence, JobError> {
        let s = load_sequence(spec, &opts)?;
        if s.frame_count() != 1 {
            return Err(JobError::Usage(format!(
                "{spec}: {} frames; name one with {spec}:FRAME",
                s.frame_count()
            )));
        }
        Ok(s)
    };
    let (sa, sb) = (one(&o.a)?, one(&o.b)?);
    let (ma, mb) = (sa.frame_mesh(0), sb.frame_mesh(0));
    if ma.vertex_count() != mb.vertex_count() || ma.triangles() != mb.triangles() {
        return Err(JobError::Usage(format!(
            "{} and {}: not the same connectivity ({} vs {} vertices)",
            o.a,
            o.b,
            ma.vertex_count(),
            mb.vertex_count()
        )));
    }
    let t0 = std::time::Instant::now();
    let nonlinear = || -> Result<Vec<[f64; 3]>, JobError> {
        let bl = Blender::new(&ma)?;
        let mut ws = bl.workspace();
        let (ga, gb) = (
            bl.decompose(ma.positions(), &mut ws),
            bl.decompose(mb.positions(), &mut ws),
        );
        let mut out = vec![[0.0; 3]; ma.vertex_count()];
        bl.blend(&ga, &gb, o.alpha, &mut out, &mut ws);
        Ok(out)
    };
    let lin = linear_blend(ma.positions(), mb.positions(), o.alpha);
    let result = if o.linear { lin.clone() } else { nonlinear()? };
    let seconds = t0.elapsed().as_secs_f64();
    let out = MeshSequence::single(ma.with_positions(&result)?);
    save_sequence(&out, &o.output, None)?;
    let d = distortion(&ma, ma.positions(), mb.positions(), &result);
    let dl = distortion(&ma, ma.positions(), mb.positions(), &lin);
    Ok(BlendReport {
        output: o.output.clone(),
        method: if o.linear { "linear" } else { "non-linear" },
        alpha: o.alpha,
        vertices: ma.vertex_count(),
        seconds,
        edge_length_distortion: d.edge_length,
        volume_distortion: d.volume,
        linear_edge_length_distortion: dl.edge_length,
        linear_volume_distortion: dl.volume,
    })
}
