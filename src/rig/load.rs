//! Loading a clip with its units and up axis decided: a BVH stores
//! neither, so they come from the rig convention (CMU names mean CMU
//! units; the head and pelvis say which way is up) and the skeleton's size
//! ([`crate::mocap::units`]). Here rather than in `mocap` because it needs
//! the rig detector, which reads clips.

use super::{Canonical, RigMap, detect, detect_clip};
use crate::mesh::io::gltf::clip::{GltfClipOptions, read_gltf_clip};
use crate::mocap::read_clip;
use crate::mocap::units::{
    UnitFamily, guess_units, stature_from_limbs, units_from_stature, up_from_ground, up_from_joints,
};
use crate::mocap::{Clip, MocapError, MocapFormat, Units, UpAxis};
use std::path::{Path, PathBuf};

/// Options for [`load_clip`]. All default to "decide from the file".
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// Frame rate override (BVH with a wrong `Frame Time`; AMC, which has none).
    pub fps: Option<f64>,
    /// The ASF for an AMC file. Default: the only `.asf` in the AMC's folder.
    pub asf: Option<PathBuf>,
    /// The FBX take (animation stack). Default: the first with keyed curves.
    pub take: Option<String>,
    /// Unit override.
    pub units: Option<Units>,
    /// Up-axis override.
    pub up: Option<UpAxis>,
    /// Rig map to use instead of detecting the convention from joint names.
    pub rig_map: Option<RigMap>,
}

/// [`read_clip`] of any clip the tool reads, glTF included: a `.gltf` or
/// `.glb` (by extension or magic) through the glTF reader of `mesh::io`
/// ([`read_gltf_clip`]: the first skin driven by one animation, `take` by
/// name or index), every other format through [`read_clip`]. Here rather
/// than in `mocap` because the glTF document reader is `mesh`'s, which
/// itself reads `mocap`.
pub fn read_any_clip(
    path: &Path,
    fps: Option<f64>,
    asf: Option<&Path>,
    take: Option<&str>,
) -> Result<Clip, MocapError> {
    match MocapFormat::detect(path) {
        Some(MocapFormat::Gltf) => read_gltf_clip(
            path,
            &GltfClipOptions {
                fps,
                take: take.map(str::to_string),
            },
        ),
        _ => read_clip(path, fps, asf, take),
    }
}

/// Reads a BVH, AMC (with its ASF) or ASF file, in file units, with the
/// clip's `units` and `up` decided (from the header, the rig convention and
/// the skeleton's size) or taken from `opts`.
pub fn load_clip(path: &Path, opts: &LoadOptions) -> Result<Clip, MocapError> {
    let mut clip = read_any_clip(path, opts.fps, opts.asf.as_deref(), opts.take.as_deref())?;
    // A given map is checked against the clip's hierarchy and rest pose
    // (a map with pelvis and head swapped was taken without a word).
    if let Some(m) = &opts.rig_map {
        m.check(&clip).map_err(|msg| {
            MocapError::invalid(
                m.file.as_deref().unwrap_or(path),
                format!("{msg} (rig map for {})", path.display()),
            )
        })?;
    }
    if MocapFormat::of(path) == Some(MocapFormat::Bvh) {
        let names = clip.point_names();
        let family = if detect(&names).map.convention.starts_with("CMU") {
            UnitFamily::Cmu
        } else if super::names::mmd_rig(&names) {
            UnitFamily::Mmd
        } else {
            UnitFamily::Other
        };
        let cmu = family == UnitFamily::Cmu;
        // The map (names and structure) is scale-free: it comes first, and
        // its limbs give the stature the unit is chosen by.
        let detected = match &opts.rig_map {
            Some(_) => None,
            None => Some(detect_clip(&clip)),
        };
        let map = opts.rig_map.as_ref().or_else(|| {
            detected
                .as_ref()
                .and_then(|d| d.as_ref().ok())
                .map(|d| &d.map)
        });
        clip.units = match map.and_then(|m| stature(&clip, m)) {
            Some((h, basis)) => units_from_stature(h, &basis, family),
            None => {
                let mut u = guess_units(&clip, cmu);
                u.reason = format!("no humanoid limbs to measure; {}", u.reason);
                u
            }
        };
        // Without a humanoid, head − pelvis says nothing (a horizontal
        // body's head is ahead of its pelvis): the feet on the ground do.
        let (up, why) = match map {
            Some(m) => guess_up(&clip, Some(m)),
            None => up_from_ground(&clip),
        };
        clip.up = up;
        clip.up_reason = why;
    }
    if MocapFormat::of(path) == Some(MocapFormat::Fbx) && opts.units.is_none() {
        // The file's UnitScaleFactor, checked against the body's stature.
        let map = (opts.rig_map.clone()).or_else(|| detect_clip(&clip).ok().map(|d| d.map));
        let h = map.as_ref().and_then(|m| stature(&clip, m));
        clip.units = crate::mocap::fbx::units_with_stature(&clip.units, h);
    }
    if MocapFormat::detect(path) == Some(MocapFormat::Gltf) {
        // glTF's metre and Y up (glTF 2.0 §3.4) checked against the body:
        // the stature, as for FBX, and head above pelvis (a Z-up skeleton
        // written without the root's turn says Z).
        let map = (opts.rig_map.clone()).or_else(|| detect_clip(&clip).ok().map(|d| d.map));
        if opts.units.is_none() {
            let h = map.as_ref().and_then(|m| stature(&clip, m));
            clip.units = crate::mocap::fbx::units_with_stature(&clip.units, h);
        }
        if let Some(m) = &map {
            let (up, why) = guess_up(&clip, Some(m));
            if up != UpAxis::Y && why.starts_with("head above pelvis") {
                clip.up = up;
                clip.up_reason =
                    format!("glTF is Y up (glTF 2.0 §3.4), but the body is not: {why}");
            }
        }
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

/// Per joint, the length of the bone from its parent to it, in file units:
/// the median over up to 32 frames of its local translation (the offset,
/// or the position channels that replace it), so a file whose rest
/// offsets are zero and whose frames carry them measures alike.
pub fn bone_lengths(clip: &Clip) -> Vec<f64> {
    let n = clip.joint_count();
    let frames = clip.frame_count();
    let step = (frames / 32).max(1);
    (0..n)
        .map(|j| {
            let mut v: Vec<f64> = (0..frames)
                .step_by(step)
                .filter_map(|f| clip.translations.get(f * n + j))
                .map(|t| t.length())
                .filter(|l| l.is_finite())
                .collect();
            if v.is_empty() {
                return clip.joints[j].offset.length();
            }
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        })
        .collect()
}

/// The stature of a humanoid clip in file units, from the limb bones the
/// map names ([`stature_from_limbs`]: thigh + shin and upper arm + forearm,
/// each the sum of the bone lengths along the hierarchy, [`bone_lengths`]),
/// with what it was measured from. `None` when a limb joint is missing or
/// derived, or one is not below the other.
pub fn stature(clip: &Clip, map: &RigMap) -> Option<(f64, String)> {
    let len = bone_lengths(clip);
    let id = |c: Canonical| {
        map.joints
            .get(&c)
            .and_then(|n| clip.joint(n))
            .map(|j| j.idx())
    };
    // Bone lengths summed from `top` down to `below` (a descendant).
    let arc = |top: Canonical, below: Canonical| -> Option<f64> {
        let (a, mut k) = (id(top)?, id(below)?);
        let mut sum = 0.0;
        for _ in 0..clip.joint_count() {
            if k == a {
                return Some(sum);
            }
            sum += len[k];
            k = clip.joints[k].parent?.idx();
        }
        None
    };
    use Canonical as C;
    let limb = |a: C, b: C, c: C| Some(arc(a, b)? + arc(b, c)?);
    let leg = 0.5 * (limb(C::LHip, C::LKnee, C::LAnkle)? + limb(C::RHip, C::RKnee, C::RAnkle)?);
    let arm = 0.5
        * (limb(C::LShoulder, C::LElbow, C::LWrist)? + limb(C::RShoulder, C::RElbow, C::RWrist)?);
    let h = stature_from_limbs(leg, arm)?;
    Some((
        h,
        format!(
            "legs {leg:.3} and arms {arm:.3} long: thigh + shin 0.491 H, upper arm + forearm 0.332 H"
        ),
    ))
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

/// Reads a rigged character for its skin, as `mesh::io::read_rigged`
/// does, an FBX at the unit its own clip reads at ([`load_clip`]: the
/// file's `UnitScaleFactor` checked against the stature its limbs give),
/// so a character and a clip of one file come out at one scale: Kenney's
/// character declares cm and its limbs give a 2.59 m stature, so the body
/// decides (a 2.47 m mesh, not the declared 3.76 m), the unit named in the
/// asset's problems. The unit is decided here, not in the mesh reader,
/// because it needs the rig detector (`mesh` does not import `rig`). An
/// FBX whose takes do not read as a clip keeps its file's unit; a glTF
/// is read as it is.
pub fn read_rigged_character(
    path: &Path,
) -> Result<crate::mesh::io::gltf::GltfAsset, crate::mesh::MeshError> {
    use crate::mesh::io::format::MeshFormat;
    if MeshFormat::of(path) != Some(MeshFormat::Fbx) {
        return crate::mesh::io::read_rigged(path);
    }
    let units = load_clip(path, &LoadOptions::default())
        .ok()
        .map(|c| c.units);
    crate::mesh::io::fbx::read_fbx_character_in(path, units.as_ref())
}

/// Maps a glTF skin onto the canonical skeleton with no rig map, as
/// [`detect_clip`] maps a BVH: names when a known convention matches (its
/// left/right checked against the geometry), else the structure of the
/// hierarchy and the bind pose (the rest skeleton, from the inverse bind
/// matrices), with the first animation's frames as the motion.
pub fn detect_skin(
    asset: &crate::mesh::io::gltf::GltfAsset,
) -> Result<super::Detection, super::RigError> {
    // The bind pose is the rest skeleton (the space the mesh was bound in);
    // the animation frames (world space) add the motion.
    let rest = skin_bind_positions(asset).ok_or_else(|| super::RigError::Degenerate {
        reason: "the glTF has no skin".into(),
    })?;
    let (clip, _) = asset
        .skin_clip(&rest, true)
        .map_err(|reason| super::RigError::Degenerate { reason })?;
    detect_clip(&clip)
}

/// Bind-pose positions of the skin's joints (translations of the inverse of
/// each inverse bind matrix), in skin order.
pub fn skin_bind_positions(asset: &crate::mesh::io::gltf::GltfAsset) -> Option<Vec<glam::DVec3>> {
    let skin = asset.skin.as_ref()?;
    Some(
        (0..skin.joint_names.len())
            .map(|k| {
                skin.inverse_bind
                    .get(k)
                    .map(|m| {
                        let t = glam::Mat4::from_cols_array_2d(m).inverse().w_axis;
                        glam::DVec3::new(t.x as f64, t.y as f64, t.z as f64)
                    })
                    .unwrap_or_default()
            })
            .collect(),
    )
}
