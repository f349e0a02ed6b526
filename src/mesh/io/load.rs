//! Loading any supported mesh or sequence file as a sequence.

use super::format::{MeshFormat, bad_frame_ref, split_frame_ref};
use super::{fbx, gltf, mdd, obj, objseq, pc2, ply};
use crate::mesh::{Mesh, MeshError, MeshSequence};
use std::path::{Path, PathBuf};

/// Options for [`load_sequence`].
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// Topology for point caches. Default: the `.obj` of the same name beside the cache.
    pub topology: Option<PathBuf>,
    /// Frame rate to assume where the file has none.
    pub fps: Option<f64>,
}

fn cache_topology(path: &Path, opts: &LoadOptions) -> Result<Mesh, MeshError> {
    let topo = match &opts.topology {
        Some(t) => t.clone(),
        None => {
            let p = path.with_extension("obj");
            if !p.exists() {
                return Err(MeshError::invalid(
                    path,
                    format!(
                        "a point cache needs a topology: no {} beside it; give one with `LoadOptions::topology`",
                        p.display()
                    ),
                ));
            }
            p
        }
    };
    match MeshFormat::of(&topo) {
        Some(MeshFormat::Ply) => ply::read_ply(&topo),
        _ => obj::read_obj(&topo),
    }
}

/// Reads a rigged character for its skin: a glTF/GLB, or an FBX by its
/// extension ([`fbx::read_fbx_character`], in the same form).
pub fn read_rigged(path: &Path) -> Result<gltf::GltfAsset, MeshError> {
    match MeshFormat::of(path) {
        Some(MeshFormat::Fbx) => fbx::read_fbx_character(path),
        _ => gltf::read_gltf(path),
    }
}

/// Loads any supported mesh or sequence file as a sequence (a single mesh is
/// a one-frame sequence). `spec` may name a frame: `samba.pc2:12`.
pub fn load_sequence(spec: &str, opts: &LoadOptions) -> Result<MeshSequence, MeshError> {
    if let Some(e) = bad_frame_ref(spec) {
        return Err(e);
    }
    let (path, frame) = split_frame_ref(spec);
    let path = path.as_path();
    let fmt = MeshFormat::of(path).ok_or_else(|| {
        MeshError::invalid(
            path,
            "unknown mesh format (expected .obj .ply .pc2 .mdd .gltf .glb .fbx or a folder)",
        )
    })?;
    let mut seq = match fmt {
        MeshFormat::Obj => MeshSequence::single(obj::read_obj(path)?),
        MeshFormat::Ply => MeshSequence::single(ply::read_ply(path)?),
        MeshFormat::Pc2 | MeshFormat::Mdd => {
            let cache = if fmt == MeshFormat::Pc2 {
                pc2::read_pc2(path)?
            } else {
                mdd::read_mdd(path)?
            };
            let topo = cache_topology(path, opts)?;
            if topo.vertex_count() != cache.points {
                return Err(MeshError::invalid(
                    path,
                    format!(
                        "{} points per frame, the topology has {} vertices",
                        cache.points,
                        topo.vertex_count()
                    ),
                ));
            }
            let fps = cache
                .times
                .as_ref()
                .and_then(|t| (t.len() > 1 && t[1] > t[0]).then(|| 1.0 / (t[1] - t[0]) as f64));
            MeshSequence::new(topo, cache.positions, fps.or(opts.fps))
                .map_err(|e| MeshError::from(e).in_file(path))?
        }
        MeshFormat::Gltf | MeshFormat::Glb => gltf::read_gltf(path)?
            .to_sequence()
            .map_err(|e| e.in_file(path))?,
        MeshFormat::ObjFolder => objseq::read_obj_folder(path)?,
        MeshFormat::Fbx => MeshSequence::single(fbx::read_fbx_character(path)?.mesh),
        MeshFormat::Usda => {
            return Err(MeshError::invalid(
                path,
                "reading .usda is not supported (it is an output format)",
            ));
        }
    };
    if seq.fps.is_none() {
        seq.fps = opts.fps;
    }
    if let Some(k) = frame {
        let n = seq.frame_count();
        seq = seq
            .select_frame(k)
            .ok_or_else(|| MeshError::invalid(path, format!("frame {k} out of range (0..{n})")))?;
    }
    Ok(seq)
}
