//! `mesh convert`: a mesh or sequence written in another format, with the
//! error a reader gets back from a quantised GLB.

use crate::mesh::io::glb::GlbOptions;
use crate::mesh::io::usd::UsdOptions;
use crate::mesh::io::{LoadOptions, MeshFormat, SaveOptions, load_sequence, save_sequence_with};
use std::path::PathBuf;

use super::JobError;

/// What to convert.
#[derive(Clone, Debug, Default)]
pub struct MeshConvertOptions {
    /// The input (a file, a folder of OBJ frames, or `SEQ:FRAME`).
    pub input: String,
    /// The output, by extension (or a folder of OBJ frames).
    pub output: PathBuf,
    /// Topology of a point-cache input.
    pub topology: Option<PathBuf>,
    /// Frame rate (default: the input's).
    pub fps: Option<f64>,
    /// Replace the OBJ frames of an output folder that holds files.
    pub force: bool,
    /// GLB options (ignored for other outputs).
    pub glb: GlbOptions,
    /// `.usda` options (ignored for other outputs).
    pub usd: UsdOptions,
}

/// What `mesh convert` wrote.
#[derive(Clone, Debug, serde::Serialize)]
pub struct MeshConvertReport {
    /// The files written.
    pub output: Vec<PathBuf>,
    /// Vertices.
    pub vertices: usize,
    /// Triangles.
    pub triangles: usize,
    /// Frames.
    pub frames: usize,
    /// Frame rate.
    pub fps: Option<f64>,
    /// GLB options were set for an output that is not a GLB.
    pub glb_options_ignored: bool,
    /// Largest vertex error of a quantised GLB read back.
    pub quantised_max_vertex_error: Option<f64>,
    /// That error as a fraction of the bounding-box diagonal (none for a
    /// box of no size).
    pub quantised_error_of_diagonal: Option<f64>,
}

/// Converts `o.input` to `o.output` (never over an input; a folder that
/// holds files only with `force`).
pub fn convert_mesh(o: &MeshConvertOptions) -> Result<MeshConvertReport, JobError> {
    let inputs = crate::mesh::io::input_files(&o.input, o.topology.as_deref());
    crate::mesh::io::refuse_overwriting(&inputs, &o.output)?;
    super::outputs::check_folder_output("-o", &o.output, o.force, &inputs)?;
    let seq = load_sequence(
        &o.input,
        &LoadOptions {
            topology: o.topology.clone(),
            fps: o.fps,
        },
    )?;
    let files = save_sequence_with(
        &seq,
        &o.output,
        &SaveOptions {
            fps: o.fps,
            glb: o.glb,
            usd: o.usd,
        },
    )?;
    let glb = MeshFormat::of(&o.output) == Some(MeshFormat::Glb);
    let ignored = (o.glb.quantize || !o.glb.normals) && !glb;
    // The error of what a reader gets back, through our reader.
    let error = if o.glb.quantize && glb {
        let back = load_sequence(&o.output.display().to_string(), &LoadOptions::default())?;
        let e = max_vertex_error(seq.all_positions(), back.all_positions());
        // A box of no size has no ratio ("1.83e303 of the bounding-box
        // diagonal" for vertices all at one point).
        let d = seq.bounds().diagonal();
        Some((e, (d.is_finite() && d > 0.0).then(|| e / d)))
    } else {
        None
    };
    Ok(MeshConvertReport {
        output: files,
        vertices: seq.mesh().vertex_count(),
        triangles: seq.mesh().triangle_count(),
        frames: seq.frame_count(),
        fps: seq.fps,
        glb_options_ignored: ignored,
        quantised_max_vertex_error: error.map(|e| e.0),
        quantised_error_of_diagonal: error.and_then(|e| e.1),
    })
}

fn max_vertex_error(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    if a.len() != b.len() {
        return f64::INFINITY;
    }
    a.iter()
        .zip(b)
        .map(|(p, q)| glam::DVec3::from_array(*p).distance(glam::DVec3::from_array(*q)))
        .fold(0.0, f64::max)
}

/// The first frame of the mesh `spec` (a file, a folder of OBJ frames or
/// `SEQ:FRAME`), keeping only the named OBJ groups when any are given (the
/// scan of `transfer` and `batch --scan`, the mesh of `rig embed`).
pub fn load_mesh_groups(spec: &str, groups: &[String]) -> Result<crate::mesh::Mesh, JobError> {
    let seq = load_sequence(spec, &Default::default())?;
    let mesh = seq.frame_mesh(0);
    if groups.is_empty() {
        return Ok(mesh);
    }
    let known: Vec<&str> = seq
        .mesh()
        .groups()
        .iter()
        .map(|g| g.name.as_str())
        .collect();
    let mut m = seq.mesh().select_groups(groups).ok_or_else(|| {
        JobError::Usage(format!(
            "{spec}: no group named {} (groups: {})",
            groups.join(", "),
            if known.is_empty() {
                "none".to_string()
            } else {
                known.join(", ")
            }
        ))
    })?;
    m.set_positions(mesh.positions())?;
    Ok(m)
}

impl MeshConvertReport {
    /// What `mesh convert` says on stderr, one line each: the files
    /// written with their size, then the GLB options ignored (named as
    /// [`GlbOptions`]) or the quantisation's largest vertex error.
    pub fn lines(&self) -> Vec<String> {
        use crate::batch::summary::count;
        let mut v = vec![format!(
            "wrote {}: {}, {}, {}",
            super::text::written_list(&self.output, " and "),
            count(self.vertices, "vertex"),
            count(self.triangles, "triangle"),
            count(self.frames, "frame")
        )];
        if self.glb_options_ignored {
            v.push("note: the `GlbOptions` apply to .glb output only; ignored".into());
        } else if let Some(e) = self.quantised_max_vertex_error {
            v.push(match self.quantised_error_of_diagonal {
                Some(rel) => format!(
                    "quantised: max vertex error {e:.3e} ({rel:.2e} of the bounding-box diagonal)"
                ),
                None => format!(
                    "quantised: max vertex error {e:.3e} m (every vertex sits at one point: the bounding box has no size to compare it with)"
                ),
            });
        }
        v
    }
}
