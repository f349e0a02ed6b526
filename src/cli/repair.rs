//! `surfmotion repair IN -o OUT`.

use std::path::PathBuf;
use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::{LoadOptions, load_sequence, save_sequence};
use surfmotion::mesh::repair::{RepairOptions, repair};

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

/// Runs `repair`: weld, drop degenerate/duplicate triangles and unreferenced
/// vertices, report the connected components.
pub fn run(a: Args) -> anyhow::Result<()> {
    surfmotion::mesh::io::refuse_overwriting(
        &surfmotion::mesh::io::input_files(&a.input, None),
        &a.output,
    )?;
    let s = load_sequence(&a.input, &LoadOptions::default())?;
    if s.frame_count() != 1 {
        anyhow::bail!(
            "{}: {} frames; repair one frame ({}:FRAME)",
            a.input,
            s.frame_count(),
            a.input
        );
    }
    let (m, rep, _) = repair(
        &s.frame_mesh(0),
        &RepairOptions {
            weld_tolerance: a.weld_tolerance,
            keep_largest: a.keep_largest,
        },
    );
    // Nothing left (every triangle degenerate) or nothing with area: a
    // mesh that only looks repaired (issue 18, item 16).
    if m.triangle_count() == 0 {
        anyhow::bail!(
            "{}: no triangle is left after repair ({} of {} degenerate, {} duplicate): nothing to write",
            a.input,
            rep.degenerate_triangles,
            s.frame_mesh(0).triangle_count(),
            rep.duplicate_triangles
        );
    }
    if rep.zero_area_triangles == m.triangle_count() {
        anyhow::bail!(
            "{}: all {} triangles have zero area (collinear vertices): not a surface",
            a.input,
            m.triangle_count()
        );
    }
    save_sequence(&MeshSequence::single(m.clone()), &a.output, None)?;
    if a.json {
        crate::outln!("{}", serde_json::to_string_pretty(&rep)?)?;
    } else {
        let c: Vec<String> = rep
            .components
            .iter()
            .take(8)
            .map(|c| format!("{}v/{}t", c.vertices, c.triangles))
            .collect();
        crate::outln!(
            "wrote {} ({} vertices, {} triangles)\n  welded vertices                      {}\n  degenerate triangles                 {}\n  zero-area triangles                  {} (kept)\n  duplicate triangles                  {}\n  unreferenced vertices                {}\n  triangles dropped with small pieces  {}\n  components (vertices v/triangles t)  {}: {}{}",
            a.output.display(),
            m.vertex_count(),
            m.triangle_count(),
            rep.welded_vertices,
            rep.degenerate_triangles,
            rep.zero_area_triangles,
            rep.duplicate_triangles,
            rep.unreferenced_vertices,
            rep.dropped_component_triangles,
            rep.components.len(),
            c.join(" "),
            if rep.components.len() > 8 { " …" } else { "" }
        )?;
    }
    Ok(())
}
