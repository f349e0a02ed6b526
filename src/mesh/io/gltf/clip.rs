//! glTF 2.0 skin animation as a [`Clip`]: the first skin's joints (the
//! skeleton) driven by one of the file's animations, read with the
//! project's glTF reader (`mesh::io::gltf`: the `gltf` crate's validation,
//! accessors read by bounds-checked code).
//!
//! Each frame composes every node's TRS down the node hierarchy (glTF 2.0
//! §3.5.3, `GltfAsset::node_worlds_at`: nodes above the skeleton, a Z-up
//! root's matrix, a scale, all included) and expresses the joints' world
//! frames as the FBX reader does ([`crate::mocap::fbx`]): world rotations relative
//! to the unanimated pose (every node at its rest TRS, so that pose is the
//! clip's rest, every local rotation the identity), local translations in
//! the parent's rotated frame. Forward kinematics of the clip reproduces
//! the joints' world positions (checked against a second evaluation, the
//! `gltf` crate's own reader and node matrices, in
//! `tests/it/mocap/gltf_clip.rs`).
//!
//! glTF is in metres, Y up, front +Z (glTF 2.0 §3.4): the clip says so, and
//! `rig::load_clip` checks the metre against the body's stature and the up
//! axis against head above pelvis, as it does for FBX and BVH. Joints are
//! named by their nodes (`joint_N`, N the node index, where a node has no
//! name; a `namespace:` prefix dropped as for FBX). The animation is the
//! first that drives the skeleton unless one is named (by name, else by
//! index: `take`); it is sampled from its first key to its last at the
//! keys' rate when they are evenly spaced at 10 to 1000 per second (24 for
//! the Khronos samples and the Fox), else at 30 fps, unless `fps` is given. Linear keys are interpolated, rotations by slerp, step keys held;
//! cubic-spline keys by glTF 2.0's cubic Hermite spline (Appendix C: the
//! keys' in- and out-tangents; a rotation normalised).

use super::{GltfAsset, NodeAnimation, parse_gltf};
use crate::mesh::MeshError;
use crate::mocap::MocapError;
use crate::mocap::fbx::{
    MAX_SAMPLES, Rest, Skeleton, joints_of, largest_subtree, names_without_namespaces, push_local,
};
use crate::mocap::{Clip, PointConvention, Units, UpAxis};
use crate::util::fsutil::{raise_warning, read_bytes};
use crate::util::numfmt::Short;
use glam::{DMat3, DMat4, DQuat, DVec3};
use std::path::Path;

/// Options of [`read_gltf_clip`].
#[derive(Debug, Clone, Default)]
pub struct GltfClipOptions {
    /// Sampling rate in frames per second (default: the keys' rate when
    /// they are evenly spaced, else 30).
    pub fps: Option<f64>,
    /// The animation to read: its name, else its index (`0`, `1`, ...).
    /// Default: the first that drives the skeleton, else the first.
    pub take: Option<String>,
}

/// One animation of a glTF file.
#[derive(Debug, Clone, PartialEq)]
pub struct GltfTake {
    /// Its index in the file.
    pub index: usize,
    /// Its name (may be empty).
    pub name: String,
    /// First key time in seconds.
    pub start: f64,
    /// Last key time in seconds.
    pub stop: f64,
    /// Channels that drive a joint of the skin or a node above one.
    pub skeleton_channels: usize,
    /// The keys' rate when they are evenly spaced at 10 to 1000 per second.
    pub key_fps: Option<f64>,
    /// The median gap between its distinct key times, in seconds.
    pub key_gap: Option<f64>,
}

/// The key rates taken as the default sampling rate; sparser keys (two keys
/// a second apart) are sampled at 30 fps between them, denser ones too.
const KEY_FPS: std::ops::RangeInclusive<f64> = 10.0..=1000.0;

/// True when `bytes` start like a binary glTF (`glTF` magic).
/// Reads a `.gltf` or `.glb` file's skin and one animation as a clip (see
/// the module documentation).
pub fn read_gltf_clip(path: &Path, opts: &GltfClipOptions) -> Result<Clip, MocapError> {
    let bytes = read_bytes(path)?;
    parse_gltf_clip(&bytes, path, opts)
}

/// [`read_gltf_clip`] of bytes already in memory; `path` names them in
/// errors and locates a `.gltf`'s external buffers.
pub fn parse_gltf_clip(
    bytes: &[u8],
    path: &Path,
    opts: &GltfClipOptions,
) -> Result<Clip, MocapError> {
    let asset = parse_gltf(bytes, path).map_err(|e| mesh_error(path, e))?;
    clip_of_asset(&asset, path, opts)
}

/// A glTF reader error as a mocap error naming the file once.
fn mesh_error(path: &Path, e: MeshError) -> MocapError {
    match e {
        MeshError::File(f) => f,
        other => {
            let s = other.to_string();
            let prefix = format!("{}: ", path.display());
            MocapError::invalid(path, s.strip_prefix(&prefix).unwrap_or(&s).to_string())
        }
    }
}

/// The file's animations, in file order.
pub fn gltf_takes(asset: &GltfAsset) -> Vec<GltfTake> {
    // Nodes whose motion moves the skeleton: its joints and their ancestors.
    let g = &asset.graph;
    let mut moves = vec![false; g.parent.len()];
    for &j in &g.skin_joints {
        let mut n = Some(j);
        let mut steps = 0;
        while let Some(k) = n {
            if k >= moves.len() || moves[k] || steps > moves.len() {
                break;
            }
            moves[k] = true;
            n = g.parent[k];
            steps += 1;
        }
    }
    asset
        .node_animations
        .iter()
        .enumerate()
        .map(|(index, a)| {
            let (mut start, mut stop) = (f64::INFINITY, f64::NEG_INFINITY);
            for ch in &a.channels {
                if let (Some(&f), Some(&l)) = (ch.times.first(), ch.times.last()) {
                    start = start.min(f as f64);
                    stop = stop.max(l as f64);
                }
            }
            if !(start.is_finite() && stop.is_finite()) {
                (start, stop) = (0.0, 0.0);
            }
            let (key_fps, key_gap) = key_rate(a);
            GltfTake {
                index,
                name: a.name.clone(),
                start,
                stop,
                skeleton_channels: a
                    .channels
                    .iter()
                    .filter(|c| moves.get(c.node).copied().unwrap_or(false))
                    .count(),
                key_fps,
                key_gap,
            }
        })
        .collect()
}

/// The rate of an animation's keys when all of them (every channel's) lie
/// on one grid `start + k·dt` (within 1 % of `dt`), `dt` the median gap
/// between distinct key times, and it is in [`KEY_FPS`]; rounded to a whole
/// number within 1e-4 of it. Also `dt`.
fn key_rate(a: &NodeAnimation) -> (Option<f64>, Option<f64>) {
    let mut t: Vec<f64> = a
        .channels
        .iter()
        .flat_map(|c| c.times.iter().map(|&x| x as f64))
        .filter(|x| x.is_finite())
        .collect();
    t.sort_by(f64::total_cmp);
    t.dedup_by(|b, a| (*b - *a).abs() < 1e-6);
    if t.len() < 2 {
        return (None, None);
    }
    let mut gaps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    gaps.sort_by(f64::total_cmp);
    let dt = gaps[gaps.len() / 2];
    if dt.is_nan() || dt <= 0.0 {
        return (None, None);
    }
    let on_grid = t.iter().all(|&x| {
        let k = (x - t[0]) / dt;
        (k - k.round()).abs() <= 0.01
    });
    let fps = 1.0 / dt;
    if !on_grid || !KEY_FPS.contains(&fps) {
        return (None, Some(dt));
    }
    let r = fps.round();
    (
        Some(if (fps - r).abs() <= 1e-4 * fps {
            r
        } else {
            fps
        }),
        Some(dt),
    )
}

fn take_list(takes: &[GltfTake]) -> String {
    if takes.is_empty() {
        return "none".into();
    }
    takes
        .iter()
        .map(|t| format!("{} '{}'", t.index, t.name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The animation asked for (by name, else by index), else the first that
/// drives the skeleton, else the first.
fn choose_take(takes: &[GltfTake], want: Option<&str>, path: &Path) -> Result<usize, MocapError> {
    if takes.is_empty() {
        return Err(MocapError::invalid(
            path,
            "the glTF has no animation: nothing to read as a clip (a glTF clip is a skin driven by an animation)",
        ));
    }
    let Some(w) = want else {
        return Ok(takes
            .iter()
            .position(|t| t.skeleton_channels > 0)
            .unwrap_or(0));
    };
    if let Some(i) = takes.iter().position(|t| t.name == w) {
        return Ok(i);
    }
    match w.trim().parse::<usize>() {
        Ok(i) if i < takes.len() => Ok(i),
        _ => Err(MocapError::invalid(
            path,
            format!(
                "no animation named or numbered '{w}'; the file's animations: {}",
                take_list(takes)
            ),
        )),
    }
}

/// Rotation part (orthonormalised: scale and shear removed; a mirrored
/// frame keeps its positions, its rotation is the nearest proper one) and
/// translation of a node's world matrix.
fn split(m: &DMat4) -> (DMat3, DVec3) {
    let x = m.x_axis.truncate().try_normalize().unwrap_or(DVec3::X);
    let y = m.y_axis.truncate();
    let y = (y - x * x.dot(y))
        .try_normalize()
        .unwrap_or_else(|| x.any_orthonormal_vector());
    (DMat3::from_cols(x, y, x.cross(y)), m.w_axis.truncate())
}

/// The skeleton: the skin's joints (the subtree of the root joint with the
/// most joints when there are several, a warning naming the others), in
/// depth-first order, parents first.
fn skeleton(
    asset: &GltfAsset,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<Skeleton, MocapError> {
    let Some(skin) = asset.skin.as_ref() else {
        return Err(MocapError::invalid(
            path,
            "the glTF has no skin: no skeleton to read as a clip (a glTF clip is a skin driven by an animation)",
        ));
    };
    let nodes = &asset.graph.skin_joints;
    let n = nodes.len().min(skin.joint_names.len());
    if n == 0 {
        return Err(MocapError::invalid(path, "the glTF's skin has no joints"));
    }
    let parent_of = |k: usize| {
        skin.parents
            .get(k)
            .copied()
            .flatten()
            .map(|p| p as usize)
            .filter(|&p| p < n && p != k)
    };
    let mut children = vec![Vec::new(); n];
    let mut roots = Vec::new();
    for k in 0..n {
        match parent_of(k) {
            Some(p) => children[p].push(k),
            None => roots.push(k),
        }
    }
    let best = largest_subtree(&children, &roots, n);
    if best.is_empty() || best.len() > n {
        return Err(MocapError::invalid(
            path,
            "the glTF skin's joint hierarchy has no root or a cycle",
        ));
    }
    if roots.len() > 1 {
        let dropped: Vec<String> = roots
            .iter()
            .filter(|&&r| r != best[0])
            .map(|&r| format!("'{}'", skin.joint_names[r]))
            .collect();
        raise_warning(
            warnings,
            path,
            format!(
                "the skin has {} root joints; reading the largest skeleton, under '{}' ({} joints), and not {}",
                roots.len(),
                skin.joint_names[best[0]],
                best.len(),
                dropped.join(", ")
            ),
        );
    }
    let mut slot = vec![usize::MAX; n];
    for (i, &k) in best.iter().enumerate() {
        slot[k] = i;
    }
    let parent = best
        .iter()
        .map(|&k| parent_of(k).map(|p| slot[p]).filter(|&s| s != usize::MAX))
        .collect();
    let mut names =
        names_without_namespaces(best.iter().map(|&k| skin.joint_names[k].clone()).collect());
    // A node listed twice in the skin (or two nodes of one name): later
    // ones take their skin index, so the rig map names each once.
    let mut seen = std::collections::HashSet::new();
    for (i, name) in names.iter_mut().enumerate() {
        if !seen.insert(name.clone()) {
            *name = format!("{name}#{}", best[i]);
            seen.insert(name.clone());
        }
    }
    Ok(Skeleton {
        order: best.iter().map(|&k| nodes[k]).collect(),
        parent,
        names,
    })
}

/// The frame rate (asked for, else the keys', else 30), first key time and
/// frame count of take `t`, bounded by [`MAX_SAMPLES`] for `joints` joints.
fn sampling(
    take: &GltfTake,
    opts: &GltfClipOptions,
    joints: usize,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<(f64, f64, usize), MocapError> {
    let fps = match (opts.fps, take.key_fps) {
        (Some(f), _) => f,
        (None, Some(f)) => f,
        (None, None) => {
            // Keys denser than the sampling and off one grid: said.
            if take.key_gap.is_some_and(|g| g < 1.0 / 30.0 * 0.99) {
                raise_warning(
                    warnings,
                    path,
                    format!(
                        "animation {} '{}': its keys are not evenly spaced (median gap {} s); sampled at 30 fps",
                        take.index,
                        take.name,
                        Short(take.key_gap.unwrap_or(0.0))
                    ),
                );
            }
            30.0
        }
    };
    if !(fps.is_finite() && fps > 0.0) {
        return Err(MocapError::invalid(
            path,
            format!("frame rate {} is not a positive number", Short(fps)),
        ));
    }
    let span = (take.stop - take.start).max(0.0);
    let count = (span * fps).round() + 1.0;
    if !count.is_finite() || count * joints as f64 > MAX_SAMPLES {
        return Err(MocapError::invalid(
            path,
            format!(
                "animation {} '{}' is {} s long: {} frames of {joints} joints is more than the {} samples a clip may hold",
                take.index,
                take.name,
                Short(span),
                Short(count),
                Short(MAX_SAMPLES)
            ),
        ));
    }
    Ok((fps, take.start, count as usize))
}

/// The clip of an asset already read (see the module documentation).
pub fn clip_of_asset(
    asset: &GltfAsset,
    path: &Path,
    opts: &GltfClipOptions,
) -> Result<Clip, MocapError> {
    let mut warnings = Vec::new();
    let skel = skeleton(asset, path, &mut warnings)?;
    let takes = gltf_takes(asset);
    let a = choose_take(&takes, opts.take.as_deref(), path)?;
    let take = &takes[a];
    if take.skeleton_channels == 0 {
        raise_warning(
            &mut warnings,
            path,
            format!(
                "animation {} '{}' drives no joint of the skin: the clip does not move",
                take.index, take.name
            ),
        );
    }
    let n = skel.order.len();
    let (fps, start, frames) = sampling(take, opts, n, path, &mut warnings)?;
    let (mut trs, mut world) = (Vec::new(), Vec::new());
    // The rest: every node at its rest TRS.
    asset.node_worlds_at(None, 0.0, &mut trs, &mut world);
    let frame_of = |world: &[DMat4], k: usize| -> (DMat3, DVec3) {
        split(world.get(skel.order[k]).unwrap_or(&DMat4::IDENTITY))
    };
    let rest_frames: Vec<(DMat3, DVec3)> = (0..n).map(|k| frame_of(&world, k)).collect();
    if let Some(k) = rest_frames
        .iter()
        .position(|(r, p)| !(r.is_finite() && p.is_finite()))
    {
        return Err(MocapError::invalid(
            path,
            format!(
                "joint '{}' has a rest transform that is not finite",
                skel.names[k]
            ),
        ));
    }
    let pos: Vec<DVec3> = rest_frames.iter().map(|(_, p)| *p).collect();
    let rest = Rest {
        rot_inv: rest_frames.iter().map(|(r, _)| r.transpose()).collect(),
        offsets: (0..n)
            .map(|k| match skel.parent[k] {
                Some(p) => pos[k] - pos[p],
                None => pos[k],
            })
            .collect(),
        pos,
    };
    let mut rotations = Vec::with_capacity(frames * n);
    let mut translations = Vec::with_capacity(frames * n);
    let mut world_q = vec![DQuat::IDENTITY; n];
    let mut world_p = vec![DVec3::ZERO; n];
    for f in 0..frames {
        let t = start + f as f64 / fps;
        asset.node_worlds_at(Some(a), t as f32, &mut trs, &mut world);
        for k in 0..n {
            let (r, p) = frame_of(&world, k);
            let q = DQuat::from_mat3(&(r * rest.rot_inv[k])).normalize();
            if !(q.is_finite() && p.is_finite()) {
                return Err(MocapError::invalid(
                    path,
                    format!(
                        "animation {} '{}': joint '{}' is not finite at frame {f} ({} s): a key is NaN or infinite",
                        take.index,
                        take.name,
                        skel.names[k],
                        Short(t)
                    ),
                ));
            }
            push_local(
                k,
                skel.parent[k],
                (q, p),
                (&mut world_q, &mut world_p),
                (&mut rotations, &mut translations),
            );
        }
    }
    let joints = joints_of(&skel, &rest, &translations, frames);
    let mut clip = Clip::new(
        joints,
        1.0 / fps,
        rotations,
        translations,
        Units {
            metres_per_unit: 1.0,
            name: "m".into(),
            reason: "glTF is in metres (glTF 2.0 §3.4)".into(),
        },
        UpAxis::Y,
        PointConvention::JointOrigins,
    )
    .map_err(|e| MocapError::invalid(path, e.to_string()))?;
    clip.up_reason = "glTF is Y up (glTF 2.0 §3.4)".into();
    clip.warnings = warnings;
    Ok(clip)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn garbage_is_an_error_naming_the_file() {
        let p = Path::new("x.glb");
        for bytes in [&b""[..], b"garbage", b"glTF\x02\0\0\0\xff\xff\0\0"] {
            let e = parse_gltf_clip(bytes, p, &GltfClipOptions::default()).unwrap_err();
            let s = e.to_string();
            assert!(s.starts_with("x.glb: "), "{s}");
            assert!(!s.contains('\n'), "{s}");
            assert!(!s.starts_with("x.glb: x.glb"), "{s}");
        }
    }
}
