//! Loading a clip with its units and up axis decided: a BVH stores
//! neither, so they come from the rig convention (CMU names mean CMU
//! units; the head and pelvis say which way is up) and the skeleton's size
//! ([`crate::mocap::units`]). Here rather than in `mocap` because it needs
//! the rig detector, which reads clips.

use super::{Canonical, RigMap, detect, detect_clip};
use crate::mocap::read_clip;
use crate::mocap::units::{guess_units, up_from_joints};
use crate::mocap::{Clip, MocapError, MocapFormat, Units, UpAxis};
use std::path::{Path, PathBuf};

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
    pub rig_map: Option<RigMap>,
}

/// Reads a BVH, AMC (with its ASF) or ASF file, in file units, with the
/// clip's `units` and `up` decided (from the header, the rig convention and
/// the skeleton's size) or taken from `opts`.
pub fn load_clip(path: &Path, opts: &LoadOptions) -> Result<Clip, MocapError> {
    let mut clip = read_clip(path, opts.fps, opts.asf.as_deref())?;
    if MocapFormat::of(path) == Some(MocapFormat::Bvh) {
        let det = detect(&clip.point_names());
        let cmu = det.map.convention.starts_with("CMU");
        clip.units = guess_units(&clip, cmu);
        let (up, why) = guess_up(&clip, opts.rig_map.as_ref());
        clip.up = up;
        clip.up_reason = why;
    }
    if let Some(u) = &opts.units {
        clip.units = u.clone();
    }
    if let Some(up) = opts.up {
        clip.up = up;
        clip.up_reason = "given by the user".into();
    }
    Ok(clip)
}

/// Guesses the up axis from head − pelvis over the motion
/// ([`up_from_joints`]). `map` names the head and pelvis; by default the
/// convention is detected from the joint names. Returns the axis and the
/// reason.
pub fn guess_up(clip: &Clip, map: Option<&RigMap>) -> (UpAxis, String) {
    let detected;
    let map = match map {
        Some(m) => m,
        None => {
            detected = detect_clip(clip)
                .map(|d| d.map)
                .unwrap_or_else(|_| detect(&clip.point_names()).map);
            &detected
        }
    };
    // The head, or the neck when the head is derived.
    let head = map
        .joints
        .get(&Canonical::Head)
        .or_else(|| map.joints.get(&Canonical::Neck))
        .and_then(|n| clip.joint(n));
    let pelvis = map
        .joints
        .get(&Canonical::Pelvis)
        .and_then(|n| clip.joint(n));
    up_from_joints(clip, head, pelvis)
}
