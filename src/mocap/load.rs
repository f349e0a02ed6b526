//! Reading any supported clip file by its extension, or by its first bytes
//! for an FBX or binary glTF file with another name (the rig-aware
//! loader that decides a BVH's units and up axis is [`crate::rig::load_clip`]).

use super::asfamc::{AmcOptions, read_amc, read_asf};
use super::bvh::{BvhOptions, read_bvh};
use super::clip::Clip;
use super::error::MocapError;
use super::fbx::{FbxOptions, is_fbx, read_fbx};
use std::path::{Path, PathBuf};

/// A mocap file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MocapFormat {
    /// Biovision hierarchy.
    Bvh,
    /// Acclaim motion (needs an ASF).
    Amc,
    /// Acclaim skeleton (read as a one-frame rest pose).
    Asf,
    /// Autodesk FBX, binary or ASCII (skeleton and one take).
    Fbx,
    /// glTF 2.0 (`.gltf`, `.glb`): a skin and one animation
    /// ([`super::gltf`]). Also a character file: `inspect` reads it as one.
    Gltf,
}

impl MocapFormat {
    /// The format of a path, by extension (case-insensitive).
    pub fn of(path: &Path) -> Option<MocapFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "bvh" => MocapFormat::Bvh,
            "amc" => MocapFormat::Amc,
            "asf" => MocapFormat::Asf,
            "fbx" => MocapFormat::Fbx,
            "gltf" | "glb" => MocapFormat::Gltf,
            _ => return None,
        })
    }

    /// The format of a path by extension, else by its first bytes (an FBX
    /// file's magic: `Kaydara FBX Binary` or `; FBX`; a GLB's `glTF`).
    pub fn detect(path: &Path) -> Option<MocapFormat> {
        MocapFormat::of(path).or_else(|| {
            use std::io::Read;
            let mut head = [0u8; 64];
            let f =
                crate::util::fsutil::open_input(path, crate::util::fsutil::MAX_INPUT_BYTES).ok()?;
            let k = f.take(64).read(&mut head).ok()?;
            if is_fbx(&head[..k]) {
                Some(MocapFormat::Fbx)
            } else {
                head[..k].starts_with(b"glTF").then_some(MocapFormat::Gltf)
            }
        })
    }
}

/// Finds the ASF for an AMC: the only `.asf` file in its folder.
pub fn find_asf(amc: &Path) -> Result<PathBuf, MocapError> {
    let dir = match amc.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let rd = std::fs::read_dir(&dir).map_err(|e| {
        MocapError::invalid(
            amc,
            format!("cannot list {} for its ASF: {e}", dir.display()),
        )
    })?;
    let mut found: Vec<PathBuf> = rd
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| MocapFormat::of(p) == Some(MocapFormat::Asf))
        .collect();
    found.sort();
    match found.len() {
        1 => Ok(found.remove(0)),
        0 => Err(MocapError::invalid(
            amc,
            format!(
                "no .asf skeleton in {}; give one with `LoadOptions::asf`",
                dir.display()
            ),
        )),
        k => Err(MocapError::invalid(
            amc,
            format!(
                "{k} .asf files in {}; choose one with `LoadOptions::asf`",
                dir.display()
            ),
        )),
    }
}

/// Reads a BVH, AMC (with its ASF), ASF, FBX or glTF file, in file units.
/// AMC, ASF, FBX and glTF clips carry their units and up axis; a BVH's are left at the reader's
/// defaults (deciding them needs the rig convention:
/// [`crate::rig::load_clip`] does it). `fps` overrides the frame rate, `asf`
/// names the ASF of an AMC (default: the only `.asf` in its folder), `take`
/// the FBX animation stack (default: the first with keyed curves) or the
/// glTF animation, by name or index (default: the first that drives the
/// skeleton).
pub fn read_clip(
    path: &Path,
    fps: Option<f64>,
    asf: Option<&Path>,
    take: Option<&str>,
) -> Result<Clip, MocapError> {
    let fmt = MocapFormat::detect(path).ok_or_else(|| {
        MocapError::invalid(
            path,
            "unknown mocap format (expected .bvh, .amc, .asf, .fbx, .gltf or .glb)",
        )
    })?;
    if take.is_some() && !matches!(fmt, MocapFormat::Fbx | MocapFormat::Gltf) {
        return Err(MocapError::invalid(
            path,
            "`take` names an FBX animation stack or a glTF animation; this is neither an FBX nor a glTF file",
        ));
    }
    Ok(match fmt {
        MocapFormat::Bvh => read_bvh(path, &BvhOptions { fps })?,
        MocapFormat::Amc => {
            let asf = match asf {
                Some(a) => a.to_path_buf(),
                None => find_asf(path)?,
            };
            read_amc(path, &asf, &AmcOptions { fps })?
        }
        MocapFormat::Asf => {
            let skel = read_asf(path)?;
            skel.rest_clip(path)?
        }
        MocapFormat::Fbx => read_fbx(
            path,
            &FbxOptions {
                fps,
                take: take.map(str::to_string),
            },
        )?,
        MocapFormat::Gltf => {
            return Err(MocapError::invalid(
                path,
                "a glTF clip is read by `rig::read_any_clip` (the glTF reader is `mesh::io`'s)",
            ));
        }
    })
}
