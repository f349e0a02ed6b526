//! The mesh formats by file name, `PATH:FRAME` references, and the
//! coordinate limit every reader keeps to.

use crate::mesh::MeshError;
use std::path::{Path, PathBuf};

/// Largest coordinate magnitude a mesh reader accepts. No scan comes near
/// it (a kilometre in nanometres), and beyond it the 32-bit floats every
/// writer uses overflow: an OBJ vertex at 1e308 was read and written to a
/// GLB as Infinity, which the glTF validator rejects.
pub const MAX_ABS_COORDINATE: f64 = 1e12;

/// Refuses a vertex with a coordinate beyond [`MAX_ABS_COORDINATE`],
/// naming the vertex (0-based).
pub(crate) fn refuse_huge_coordinates(
    positions: &[[f64; 3]],
    path: &Path,
) -> Result<(), MeshError> {
    match positions
        .iter()
        .enumerate()
        .find(|(_, p)| p.iter().any(|x| x.abs() > MAX_ABS_COORDINATE))
    {
        Some((i, p)) => Err(MeshError::invalid(
            path,
            format!(
                "vertex {i} at ({}, {}, {}) is beyond ±{MAX_ABS_COORDINATE:e}",
                p[0], p[1], p[2]
            ),
        )),
        None => Ok(()),
    }
}

/// A mesh file format, by extension (or a folder of OBJ files).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MeshFormat {
    /// Wavefront OBJ.
    Obj,
    /// Stanford PLY.
    Ply,
    /// Point Cache 2 (needs a topology OBJ).
    Pc2,
    /// MDD point cache (needs a topology OBJ).
    Mdd,
    /// glTF JSON.
    Gltf,
    /// Binary glTF.
    Glb,
    /// A folder of OBJ frames.
    ObjFolder,
    /// USD text layer (written only).
    Usda,
    /// FBX, read only: a rigged character's meshes in their bind pose
    /// ([`super::fbx`]).
    Fbx,
}

impl MeshFormat {
    /// Format by extension; a path with no extension, or an existing folder, is an OBJ folder.
    pub fn of(path: &Path) -> Option<MeshFormat> {
        if path.is_dir() {
            return Some(MeshFormat::ObjFolder);
        }
        let Some(ext) = path.extension() else {
            return Some(MeshFormat::ObjFolder);
        };
        Some(match ext.to_str()?.to_ascii_lowercase().as_str() {
            "obj" => MeshFormat::Obj,
            "ply" => MeshFormat::Ply,
            "pc2" => MeshFormat::Pc2,
            "mdd" => MeshFormat::Mdd,
            "gltf" => MeshFormat::Gltf,
            "glb" => MeshFormat::Glb,
            "usda" => MeshFormat::Usda,
            "fbx" => MeshFormat::Fbx,
            _ => return None,
        })
    }
}

/// The error of an output in a format that is only read: `.gltf` (write
/// `.glb`) and `.fbx`.
pub(crate) fn not_written(out: &Path, fmt: MeshFormat) -> MeshError {
    MeshError::invalid(
        out,
        match fmt {
            MeshFormat::Gltf => "writing .gltf is not supported; use .glb",
            _ => "writing .fbx is not supported; use .glb, .usda, .pc2 or .mdd",
        },
    )
}

/// Splits `PATH:FRAME` (a 0-based frame of a sequence file) into its parts.
/// A path that exists as given is never split.
pub fn split_frame_ref(spec: &str) -> (PathBuf, Option<usize>) {
    if Path::new(spec).exists() {
        return (PathBuf::from(spec), None);
    }
    if let Some((p, f)) = spec.rsplit_once(':')
        && let Ok(k) = f.parse::<usize>()
        && !p.is_empty()
    {
        return (PathBuf::from(p), Some(k));
    }
    (PathBuf::from(spec), None)
}

/// The error of a `PATH:FRAME` whose file exists but whose frame is not a
/// frame index (`walk.pc2:-1`, `walk.pc2:abc`), which otherwise read as a
/// file named so ("unknown mesh format").
pub fn bad_frame_ref(spec: &str) -> Option<MeshError> {
    if Path::new(spec).exists() {
        return None;
    }
    let (p, f) = spec.rsplit_once(':')?;
    (!p.is_empty() && Path::new(p).exists() && f.parse::<usize>().is_err()).then(|| {
        MeshError::invalid(
            Path::new(p),
            format!("'{f}' is not a frame number (PATH:FRAME takes a frame index from 0)"),
        )
    })
}
