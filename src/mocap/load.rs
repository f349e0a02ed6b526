//! Loading any supported clip file, with units and up axis decided.

use super::asfamc::{AmcOptions, read_amc, read_asf};
use super::bvh::{BvhOptions, read_bvh};
use super::clip::{Clip, Units, UpAxis};
use super::error::MocapError;
use super::units::{guess_units, guess_up};
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
}

impl MocapFormat {
    /// The format of a path, by extension (case-insensitive).
    pub fn of(path: &Path) -> Option<MocapFormat> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "bvh" => MocapFormat::Bvh,
            "amc" => MocapFormat::Amc,
            "asf" => MocapFormat::Asf,
            _ => return None,
        })
    }
}

/// Options for [`load_clip`]. All default to "decide from the file".
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// Frame rate override (BVH with a wrong `Frame Time`; AMC, which has none).
    pub fps: Option<f64>,
    /// The ASF for an AMC file. Default: the only `.asf` in the AMC's folder.
    pub asf: Option<PathBuf>,
    /// Unit override.
    pub units: Option<Units>,
    /// Up-axis override.
    pub up: Option<UpAxis>,
    /// Rig map to use instead of detecting the convention from joint names.
    pub rig_map: Option<crate::rig::RigMap>,
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
            format!("no .asf skeleton in {}; give one with --asf", dir.display()),
        )),
        k => Err(MocapError::invalid(
            amc,
            format!("{k} .asf files in {}; choose one with --asf", dir.display()),
        )),
    }
}

/// Reads a BVH, AMC (with its ASF) or ASF file, in file units, with the
/// clip's `units` and `up` decided (from the header, the rig convention and
/// the skeleton's size) or taken from `opts`.
pub fn load_clip(path: &Path, opts: &LoadOptions) -> Result<Clip, MocapError> {
    let fmt = MocapFormat::of(path).ok_or_else(|| {
        MocapError::invalid(path, "unknown mocap format (expected .bvh, .amc or .asf)")
    })?;
    let mut clip = match fmt {
        MocapFormat::Bvh => {
            let mut c = read_bvh(path, &BvhOptions { fps: opts.fps })?;
            let det = crate::rig::detect(&c.point_names());
            let cmu = det.map.convention.starts_with("CMU");
            c.units = guess_units(&c, cmu);
            let (up, why) = guess_up(&c, opts.rig_map.as_ref());
            c.up = up;
            c.up_reason = why;
            c
        }
        MocapFormat::Amc => {
            let asf = match &opts.asf {
                Some(a) => a.clone(),
                None => find_asf(path)?,
            };
            read_amc(path, &asf, &AmcOptions { fps: opts.fps })?
        }
        MocapFormat::Asf => {
            let skel = read_asf(path)?;
            skel.rest_clip(path)?
        }
    };
    if let Some(u) = &opts.units {
        clip.units = u.clone();
    }
    if let Some(up) = opts.up {
        clip.up = up;
        clip.up_reason = "given by the user".into();
    }
    Ok(clip)
}
