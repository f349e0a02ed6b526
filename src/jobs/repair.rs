//! `repair`: one frame of a raw scan repaired ([`crate::mesh::repair`]:
//! welded, degenerate and duplicate triangles and unreferenced vertices
//! dropped, the connected components counted) and written, refused when
//! nothing that is a surface is left.

use crate::mesh::io::{LoadOptions, input_files, load_sequence, refuse_overwriting, save_sequence};
use crate::mesh::repair::{RepairOptions, RepairReport, repair};
use crate::mesh::{MeshError, MeshSequence};
use std::path::PathBuf;

/// What to repair.
#[derive(Clone, Debug, Default)]
pub struct RepairJobOptions {
    /// The input: one frame (a file, or `SEQ.pc2:FRAME`).
    pub input: String,
    /// The repaired mesh's path.
    pub output: PathBuf,
    /// Welding and component options.
    pub repair: RepairOptions,
}

/// A repaired mesh written ([`repair_file`]).
#[derive(Debug, Clone)]
pub struct RepairRun {
    /// Where it was written.
    pub output: PathBuf,
    /// Its vertices.
    pub vertices: usize,
    /// Its triangles.
    pub triangles: usize,
    /// What the repair did.
    pub report: RepairReport,
}

/// Why [`repair_file`] wrote nothing.
#[derive(Debug, thiserror::Error)]
pub enum RepairJobError {
    /// Reading or writing, or an output over the input.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The input is a sequence, not one frame.
    #[error("{input}: {frames} frames; repair one frame ({input}:FRAME)")]
    Frames {
        /// The input as given.
        input: String,
        /// Its frames.
        frames: usize,
    },
    /// Every triangle was degenerate or a duplicate (issue 18, item 16).
    #[error(
        "{input}: no triangle is left after repair ({degenerate} of {triangles} degenerate, {duplicate} duplicate): nothing to write"
    )]
    NothingLeft {
        /// The input as given.
        input: String,
        /// Degenerate triangles dropped.
        degenerate: usize,
        /// The input's triangles.
        triangles: usize,
        /// Duplicate triangles dropped.
        duplicate: usize,
    },
    /// Every triangle left has zero area.
    #[error(
        "{input}: all {triangles} triangles have zero area (collinear vertices): not a surface"
    )]
    ZeroArea {
        /// The input as given.
        input: String,
        /// The triangles left.
        triangles: usize,
    },
}

/// Repairs the one frame of `o.input` and writes it to `o.output`; no
/// output over the input, and nothing written when no triangle, or no
/// triangle with area, is left (a mesh that only looks repaired).
pub fn repair_file(o: &RepairJobOptions) -> Result<RepairRun, RepairJobError> {
    refuse_overwriting(&input_files(&o.input, None), &o.output)?;
    let s = load_sequence(&o.input, &LoadOptions::default())?;
    if s.frame_count() != 1 {
        return Err(RepairJobError::Frames {
            input: o.input.clone(),
            frames: s.frame_count(),
        });
    }
    let (m, rep, _) = repair(&s.frame_mesh(0), &o.repair);
    if m.triangle_count() == 0 {
        return Err(RepairJobError::NothingLeft {
            input: o.input.clone(),
            degenerate: rep.degenerate_triangles,
            triangles: s.frame_mesh(0).triangle_count(),
            duplicate: rep.duplicate_triangles,
        });
    }
    if rep.zero_area_triangles == m.triangle_count() {
        return Err(RepairJobError::ZeroArea {
            input: o.input.clone(),
            triangles: m.triangle_count(),
        });
    }
    let (vertices, triangles) = (m.vertex_count(), m.triangle_count());
    save_sequence(&MeshSequence::single(m), &o.output, None)?;
    Ok(RepairRun {
        output: o.output.clone(),
        vertices,
        triangles,
        report: rep,
    })
}

impl RepairRun {
    /// `repair`'s text: the file written and what the repair did, the
    /// first eight components.
    pub fn text(&self) -> String {
        let rep = &self.report;
        let c: Vec<String> = rep
            .components
            .iter()
            .take(8)
            .map(|c| format!("{}v/{}t", c.vertices, c.triangles))
            .collect();
        format!(
            "wrote {} ({} vertices, {} triangles)\n  welded vertices                      {}\n  degenerate triangles                 {}\n  zero-area triangles                  {} (kept)\n  duplicate triangles                  {}\n  unreferenced vertices                {}\n  triangles dropped with small pieces  {}\n  components (vertices v/triangles t)  {}: {}{}\n",
            self.output.display(),
            self.vertices,
            self.triangles,
            rep.welded_vertices,
            rep.degenerate_triangles,
            rep.zero_area_triangles,
            rep.duplicate_triangles,
            rep.unreferenced_vertices,
            rep.dropped_component_triangles,
            rep.components.len(),
            c.join(" "),
            if rep.components.len() > 8 { " …" } else { "" }
        )
    }
}
