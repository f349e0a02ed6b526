//! Mesh and mesh-sequence file formats. In: OBJ, PLY, PC2, MDD, OBJ folders,
//! glTF/GLB. Out: GLB (morph-target animation), PC2 + OBJ, MDD + OBJ, OBJ,
//! OBJ folders, PLY, USD text (`.usda`, time-sampled points). Every write is atomic. [`stream::SequenceWriter`]
//! writes a sequence frame by frame (point caches and OBJ folders without
//! holding the frames).

pub mod glb;
pub mod gltf;
pub mod mdd;
pub mod obj;
pub mod objseq;
pub mod pc2;
pub mod ply;
pub mod stream;
pub mod usd;

use super::{MeshError, MeshSequence};
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
            _ => return None,
        })
    }
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

/// Options for [`load_sequence`].
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// Topology for point caches. Default: the `.obj` of the same name beside the cache.
    pub topology: Option<PathBuf>,
    /// Frame rate to assume where the file has none.
    pub fps: Option<f64>,
}

fn cache_topology(path: &Path, opts: &LoadOptions) -> Result<super::Mesh, MeshError> {
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
            "obj" | "ply" | "pc2" | "mdd" | "gltf" | "glb" | "usda"
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
            "unknown mesh format (expected .obj .ply .pc2 .mdd .gltf .glb or a folder)",
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

/// Options of [`save_sequence_with`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SaveOptions {
    /// Frame rate where the sequence has none. Default value: `None` (30).
    pub fps: Option<f64>,
    /// GLB output (normals, quantisation). Default value: [`glb::GlbOptions::DEFAULT`].
    pub glb: glb::GlbOptions,
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

/// [`save_sequence`] with options for the GLB writer.
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
        MeshFormat::Gltf => {
            return Err(MeshError::invalid(
                out,
                "writing .gltf is not supported; use .glb",
            ));
        }
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
            usd::write_usda(seq, fps_v, out)?;
            vec![out.to_path_buf()]
        }
    })
}
