//! The one path from a job's positions to a file.

use super::JobError;

/// Writes `positions` (frame-major, `mesh`'s vertices) as a sequence at
/// `fps` to `out` (by extension, GLB options `glb`, USD options `usd`);
/// returns the files
/// written. The one path from a job's positions to a file (retarget,
/// transfer, scan transfer).
pub(crate) fn write_positions(
    mesh: crate::mesh::Mesh,
    positions: Vec<[f64; 3]>,
    fps: f64,
    glb: crate::mesh::io::glb::GlbOptions,
    usd: crate::mesh::io::usd::UsdOptions,
    out: &std::path::Path,
) -> Result<Vec<std::path::PathBuf>, JobError> {
    let seq = crate::mesh::MeshSequence::new(mesh, positions, Some(fps))?;
    Ok(crate::mesh::io::save_sequence_with(
        &seq,
        out,
        &crate::mesh::io::SaveOptions {
            fps: Some(fps),
            glb,
            usd,
        },
    )?)
}
