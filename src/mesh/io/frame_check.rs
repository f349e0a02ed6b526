//! The checks every streamed sequence writer makes of each frame and of
//! the end of its output (the point caches and OBJ folders of
//! [`super::stream`], the `.usda` writer of [`super::usd`]), in one place
//! below both.

use crate::mesh::MeshError;
use std::path::Path;

/// The checks of a streamed frame (of [`super::stream::SequenceWriter`] and of the
/// writers it drives, [`super::usd::UsdaWriter`]): `vertices` positions,
/// within the `frames` announced (`written` so far), every coordinate
/// finite. Errors name `out`, the frame and the vertex.
pub(crate) fn check_frame(
    out: &Path,
    frame: &[[f64; 3]],
    vertices: usize,
    written: usize,
    frames: usize,
) -> Result<(), MeshError> {
    if frame.len() != vertices {
        return Err(MeshError::invalid(
            out,
            format!(
                "frame {written} has {} vertices, the mesh has {vertices}",
                frame.len()
            ),
        ));
    }
    if written >= frames {
        return Err(MeshError::invalid(
            out,
            format!("more than the {frames} frames announced"),
        ));
    }
    if let Some(v) = frame.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(MeshError::invalid(
            out,
            format!("frame {written}: vertex {v} has a non-finite coordinate"),
        ));
    }
    Ok(())
}

/// The check of a streamed output's end: every announced frame written.
pub(crate) fn check_complete(out: &Path, written: usize, frames: usize) -> Result<(), MeshError> {
    if written != frames {
        return Err(MeshError::invalid(
            out,
            format!("{written} of the {frames} frames announced were written"),
        ));
    }
    Ok(())
}
