//! OBJ-sequence folders: one OBJ per frame, all with the same connectivity.

use super::obj::{read_obj, write_obj};
use crate::mesh::{MeshError, MeshSequence};
use std::path::{Path, PathBuf};

/// Sort key that orders `mesh_2.obj` before `mesh_10.obj`.
fn natural_key(p: &Path) -> Vec<(String, u64)> {
    let name = p
        .file_name()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    let mut out = Vec::new();
    let mut text = String::new();
    let mut num = String::new();
    for ch in name.chars() {
        if ch.is_ascii_digit() {
            num.push(ch);
        } else {
            if !num.is_empty() {
                out.push((std::mem::take(&mut text), num.parse().unwrap_or(u64::MAX)));
                num.clear();
            }
            text.push(ch);
        }
    }
    out.push((text, num.parse().unwrap_or(0)));
    out
}

/// The `.obj` files of a folder in natural order.
pub fn list_obj_frames(dir: &Path) -> Result<Vec<PathBuf>, MeshError> {
    // A file without an extension (`/dev/null`, `scan`) is taken for a
    // folder of frames by [`super::MeshFormat::of`]; "cannot list folder:
    // Not a directory" did not say why.
    if dir.exists() && !dir.is_dir() {
        return Err(MeshError::invalid(
            dir,
            "not a folder, and no extension to tell its format (expected .obj .ply .pc2 .mdd .gltf .glb, or a folder of OBJ frames)",
        ));
    }
    // A database folder holds OBJ files (its topology and each sequence's
    // topology), but they are not frames: `eval --result DB` read one as
    // "3 frames" and `mesh convert DB out.glb` wrote them as an animation.
    // (`db::MANIFEST`, named here: `mesh` comes before `db`.)
    if dir.join("character.toml").is_file() {
        return Err(MeshError::invalid(
            dir,
            "a character database folder (it holds character.toml), not a folder of OBJ frames; `surfmotion db info` shows what it holds",
        ));
    }
    let rd = std::fs::read_dir(dir)
        .map_err(|e| MeshError::invalid(dir, format!("cannot list folder: {e}")))?;
    let mut files: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")))
        .collect();
    files.sort_by_key(|p| natural_key(p));
    if files.is_empty() {
        return Err(MeshError::invalid(dir, "no .obj files in the folder"));
    }
    Ok(files)
}

/// Reads an OBJ-sequence folder. Every frame must have the first frame's
/// vertex count and triangles; the error names the first frame that does not.
pub fn read_obj_folder(dir: &Path) -> Result<MeshSequence, MeshError> {
    let files = list_obj_frames(dir)?;
    let first = read_obj(&files[0])?;
    let mut frames = Vec::with_capacity(files.len() * first.vertex_count());
    frames.extend_from_slice(first.positions());
    for f in &files[1..] {
        let m = read_obj(f)?;
        if m.vertex_count() != first.vertex_count() {
            return Err(MeshError::invalid(
                f,
                format!(
                    "{} vertices, but {} has {}: not the same connectivity",
                    m.vertex_count(),
                    files[0].display(),
                    first.vertex_count()
                ),
            ));
        }
        if let Some(t) = m
            .triangles()
            .iter()
            .zip(first.triangles())
            .position(|(a, b)| a != b)
        {
            return Err(MeshError::invalid(
                f,
                format!(
                    "triangle {t} differs from {}: not the same connectivity",
                    files[0].display()
                ),
            ));
        }
        if m.triangle_count() != first.triangle_count() {
            return Err(MeshError::invalid(
                f,
                format!(
                    "{} triangles, the first frame has {}",
                    m.triangle_count(),
                    first.triangle_count()
                ),
            ));
        }
        frames.extend_from_slice(m.positions());
    }
    Ok(MeshSequence::new(first, frames, None)?)
}

/// Writes every frame as `frame_NNNN.obj` in `dir` (each file atomically).
pub(crate) fn write_obj_folder(seq: &MeshSequence, dir: &Path) -> Result<Vec<PathBuf>, MeshError> {
    let width = seq.frame_count().saturating_sub(1).to_string().len().max(4);
    let mut out = Vec::with_capacity(seq.frame_count());
    for f in 0..seq.frame_count() {
        let p = dir.join(format!("frame_{f:0width$}.obj"));
        write_obj(seq.mesh(), Some(seq.frame(f)), &p)?;
        out.push(p);
    }
    Ok(out)
}
