//! The files a load reads and a save writes, and the refusals that keep an
//! output from replacing an input or a folder.

use super::format::{MeshFormat, split_frame_ref};
use crate::mesh::MeshError;
use std::path::{Path, PathBuf};

/// The files [`load_sequence`] reads for `spec` (the file, and a point
/// cache's topology beside it or `topology`).
pub fn input_files(spec: &str, topology: Option<&Path>) -> Vec<PathBuf> {
    let (path, _) = split_frame_ref(spec);
    let mut v = vec![path.clone()];
    if matches!(
        MeshFormat::of(&path),
        Some(MeshFormat::Pc2 | MeshFormat::Mdd)
    ) {
        v.push(topology.map_or_else(|| path.with_extension("obj"), Path::to_path_buf));
    }
    v
}

/// The files [`save_sequence`] writes for `out` (a point cache writes its
/// topology `.obj` beside it).
pub fn output_files(out: &Path) -> Vec<PathBuf> {
    let mut v = vec![out.to_path_buf()];
    if matches!(MeshFormat::of(out), Some(MeshFormat::Pc2 | MeshFormat::Mdd)) {
        v.push(out.with_extension("obj"));
    }
    v
}

/// Refuses an output that would overwrite one of `inputs` (compared as
/// the same file on disk, whatever the spelling of the path). Regression
/// (issue 18, item 9): a `.pc2` output wrote its `.obj` topology over the
/// input scan of the same name, and `mesh convert m.obj m.obj` replaced
/// its input.
pub fn refuse_overwriting(inputs: &[PathBuf], out: &Path) -> Result<(), MeshError> {
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    };
    for o in output_files(out) {
        if let Some(i) = inputs.iter().find(|i| same(i, &o)) {
            return Err(MeshError::invalid(
                out,
                format!(
                    "writing it would overwrite the input {}{}; choose another output name",
                    i.display(),
                    if o != out {
                        format!(" (a point cache writes its topology to {})", o.display())
                    } else {
                        String::new()
                    }
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses an output that exists as a folder while its extension names a
/// file format (`-o out.glb` where `out.glb/` is a folder would otherwise
/// fill the folder with OBJ frames). Regression (issue 18, item 16).
pub fn refuse_folder_as_file(out: &Path) -> Result<(), MeshError> {
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if ext.is_empty() && out.exists() && !out.is_dir() {
        // `-o /dev/full` (or an existing file without extension) named a
        // folder of OBJ frames: "/dev/full/frame_0000.obj: File exists".
        return Err(MeshError::invalid(
            out,
            "exists and is not a folder, but a name without extension asks for a folder of OBJ frames; give the output an extension (.glb .pc2 .mdd .obj .ply .usda)",
        ));
    }
    if out.is_dir()
        && matches!(
            ext.as_str(),
            "obj" | "ply" | "pc2" | "mdd" | "gltf" | "glb" | "usda" | "fbx"
        )
    {
        return Err(MeshError::invalid(
            out,
            format!(
                "is a folder, but the .{ext} extension asks for a file; remove the folder or choose another output name (a folder of OBJ frames takes a name without extension)"
            ),
        ));
    }
    Ok(())
}
