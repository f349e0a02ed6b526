//! Saving a sequence in the format of the output's extension.

use super::files::refuse_folder_as_file;
use super::format::MeshFormat;
use super::{glb, mdd, obj, objseq, pc2, ply, usd};
use crate::mesh::{MeshError, MeshSequence};
use std::path::{Path, PathBuf};

/// Options of [`save_sequence_with`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SaveOptions {
    /// Frame rate where the sequence has none. Default value: `None` (30).
    pub fps: Option<f64>,
    /// GLB output (normals, quantisation). Default value: [`glb::GlbOptions::DEFAULT`].
    pub glb: glb::GlbOptions,
    /// `.usda` output (normals). Default value: [`usd::UsdOptions::DEFAULT`].
    pub usd: usd::UsdOptions,
}

/// Saves a sequence in the format of `out`'s extension. PC2 and MDD get a
/// topology OBJ of the same name beside them; `.obj` takes one frame; a path
/// without extension is a folder of OBJ frames. Returns the files written.
pub fn save_sequence(
    seq: &MeshSequence,
    out: &Path,
    fps: Option<f64>,
) -> Result<Vec<PathBuf>, MeshError> {
    save_sequence_with(
        seq,
        out,
        &SaveOptions {
            fps,
            ..Default::default()
        },
    )
}

/// [`save_sequence`] with options for the GLB and USD writers.
pub fn save_sequence_with(
    seq: &MeshSequence,
    out: &Path,
    opts: &SaveOptions,
) -> Result<Vec<PathBuf>, MeshError> {
    let fps = opts.fps;
    refuse_folder_as_file(out)?;
    let fmt = MeshFormat::of(out).ok_or_else(|| {
        MeshError::invalid(
            out,
            "unknown output format (use .glb .pc2 .mdd .obj .ply .usda or a folder)",
        )
    })?;
    let fps_v = seq.fps.or(fps).unwrap_or(30.0);
    Ok(match fmt {
        MeshFormat::Glb => {
            glb::write_glb_with(seq, fps, &opts.glb, out)?;
            vec![out.to_path_buf()]
        }
        MeshFormat::Gltf | MeshFormat::Fbx => return Err(super::format::not_written(out, fmt)),
        MeshFormat::Pc2 | MeshFormat::Mdd => {
            let n = seq.mesh().vertex_count();
            if fmt == MeshFormat::Pc2 {
                pc2::write_pc2(n, seq.all_positions(), out)?;
            } else {
                mdd::write_mdd(n, seq.all_positions(), fps_v, out)?;
            }
            let topo = out.with_extension("obj");
            obj::write_obj(seq.mesh(), None, &topo)?;
            vec![out.to_path_buf(), topo]
        }
        MeshFormat::Obj | MeshFormat::Ply => {
            if seq.frame_count() != 1 {
                return Err(MeshError::invalid(
                    out,
                    format!(
                        "{} frames do not fit one {:?} file; write a folder, .pc2, .mdd or .glb",
                        seq.frame_count(),
                        fmt
                    ),
                ));
            }
            if fmt == MeshFormat::Obj {
                obj::write_obj(seq.mesh(), Some(seq.frame(0)), out)?;
            } else {
                ply::write_ply(seq.mesh(), Some(seq.frame(0)), out)?;
            }
            vec![out.to_path_buf()]
        }
        MeshFormat::ObjFolder => objseq::write_obj_folder(seq, out)?,
        MeshFormat::Usda => {
            usd::write_usda_with(seq, fps_v, out, opts.usd)?;
            vec![out.to_path_buf()]
        }
    })
}
