//! FBX skeletal animation as a [`Clip`], read with the ufbx C reader (the
//! `ufbx` crate): binary FBX 6.1 to 7.7 and ASCII FBX.
//!
//! The skeleton is the file's `LimbNode` models (the subtree of the root
//! bone with the most joints when there are several, e.g. IK controls
//! beside the body); the Null above it (Blender's `Armature`, a take's
//! group) is folded into the root's transform. Joint names lose their
//! namespace (`mixamorig:Hips` → `Hips`).
//!
//! Each frame samples the reader's own scene evaluator (every node's world
//! matrix at the frame's time: pre/post rotations, pivots, rotation orders
//! and inherit modes applied by ufbx), then expresses it in the project's
//! form: world rotations relative to the unanimated pose (so that pose is
//! the clip's rest, every local rotation the identity, as in BVH), local
//! translations in the parent's rotated frame, and the file's axis system
//! (`UpAxis`, `FrontAxis`, `CoordAxis` with their signs) turned into Y up,
//! front +Z. Lengths stay in file units; [`Clip::units`] carries
//! `UnitScaleFactor`. Forward kinematics of the clip reproduces the
//! evaluator's joint positions (checked in `tests/it/mocap/reference.rs`).
//!
//! The take is the first animation stack with keyed curves (Mixamo files
//! carry an empty `Take 001` before the real one) unless one is named.

use super::clip::{Channel, Clip, Joint, JointId, PointConvention, Units, UpAxis};
use super::error::MocapError;
use super::units::{HUMAN_STATURE_M, UnitFamily, units_from_stature};
use crate::util::fsutil::{raise_warning, read_bytes};
use crate::util::numfmt::Short;
use glam::{DMat3, DQuat, DVec3};
use std::path::Path;

/// Options of [`read_fbx`].
#[derive(Debug, Clone, Default)]
pub struct FbxOptions {
    /// Sampling rate in frames per second (default: the file's `TimeMode`).
    pub fps: Option<f64>,
    /// The animation stack (take) to read, by name. Default: the first one
    /// with keyed curves, else the first.
    pub take: Option<String>,
}

/// Largest `frames × joints` a clip may hold (a corrupt take length must not
/// allocate without bound): 200 million samples, about 10 GB of clip.
pub(crate) const MAX_SAMPLES: f64 = 2e8;

/// True when `bytes` start like an FBX file: the binary magic
/// `Kaydara FBX Binary` or an ASCII file's `; FBX` header comment (after an
/// optional UTF-8 byte-order mark and blank space).
pub(crate) fn is_fbx(bytes: &[u8]) -> bool {
    if bytes.starts_with(b"Kaydara FBX Binary") {
        return true;
    }
    let b = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let start = b
        .iter()
        .position(|c| !c.is_ascii_whitespace())
        .unwrap_or(b.len());
    b[start..].starts_with(b"; FBX")
}

/// One animation stack (take) of an FBX file.
#[derive(Debug, Clone, PartialEq)]
pub struct FbxTake {
    /// Its name.
    pub name: String,
    /// Start and stop time in seconds (`LocalStart`/`LocalStop`).
    pub start: f64,
    /// Stop time in seconds.
    pub stop: f64,
    /// Keyed animation curves in it.
    pub curves: usize,
}

/// What an FBX file holds, for `inspect`.
#[derive(Debug, Clone)]
pub struct FbxInfo {
    /// FBX version (6100, 7400, ...).
    pub version: u32,
    /// ASCII rather than binary.
    pub ascii: bool,
    /// Creator string of the header.
    pub creator: String,
    /// Metres per file unit (`UnitScaleFactor` / 100; 0.01 without one).
    pub metres_per_unit: f64,
    /// False when the file has no `UnitScaleFactor` (the unit is then
    /// judged from the body: [`units_with_stature`]).
    pub unit_declared: bool,
    /// The file's axes, e.g. `right +X, up +Y, front +Z`.
    pub axes: String,
    /// Frames per second of the file's `TimeMode`.
    pub fps: f64,
    /// Its takes, in file order.
    pub takes: Vec<FbxTake>,
    /// Index of the take read by default.
    pub default_take: Option<usize>,
    /// Skeleton joints (`LimbNode` models).
    pub joints: usize,
}

/// Reads an FBX file's skeleton and one take as a clip (see the module
/// documentation).
pub(crate) fn read_fbx(path: &Path, opts: &FbxOptions) -> Result<Clip, MocapError> {
    let bytes = read_bytes(path)?;
    parse_fbx(&bytes, path, opts)
}

/// [`read_fbx`] of bytes already in memory; `path` names them in errors.
pub fn parse_fbx(bytes: &[u8], path: &Path, opts: &FbxOptions) -> Result<Clip, MocapError> {
    let scene = load_scene(bytes, path, false)?;
    clip_of_scene(&scene, path, opts)
}

/// Lists what an FBX file holds: version, units, axes, takes.
pub(crate) fn fbx_info(path: &Path) -> Result<FbxInfo, MocapError> {
    let bytes = read_bytes(path)?;
    let scene = load_scene(&bytes, path, false)?;
    let takes = takes(&scene);
    Ok(FbxInfo {
        version: scene.metadata.version,
        ascii: scene.metadata.ascii,
        creator: scene.metadata.creator.to_string(),
        metres_per_unit: scene.settings.unit_meters,
        unit_declared: ufbx::find_prop(&scene.settings.props, "UnitScaleFactor").is_some(),
        axes: axes_name(&scene.settings.axes),
        fps: scene.settings.frames_per_second,
        default_take: default_take(&takes),
        takes,
        joints: scene
            .nodes
            .iter()
            .filter(|n| n.attrib_type == ufbx::ElementType::Bone)
            .count(),
    })
}

/// Parses the bytes with ufbx (FBX only; geometry skipped unless
/// `geometry`), after checking the magic bytes.
pub(crate) fn load_scene(
    bytes: &[u8],
    path: &Path,
    geometry: bool,
) -> Result<ufbx::SceneRoot, MocapError> {
    if bytes.is_empty() {
        return Err(MocapError::invalid(path, "empty file, not an FBX file"));
    }
    if !is_fbx(bytes) {
        return Err(MocapError::invalid(
            path,
            "not an FBX file: it starts with neither 'Kaydara FBX Binary' nor '; FBX'",
        ));
    }
    // Allocation bounded by the input: a count in a corrupt header cannot
    // make the reader ask for more than this.
    let limit = (bytes.len().saturating_mul(64)).clamp(256 << 20, 8 << 30);
    let alloc = || ufbx::AllocatorOpts {
        memory_limit: limit,
        ..Default::default()
    };
    let opts = ufbx::LoadOpts {
        ignore_geometry: !geometry,
        ignore_embedded: true,
        file_format: ufbx::FileFormat::Fbx,
        no_format_from_extension: true,
        temp_allocator: alloc(),
        result_allocator: alloc(),
        ..Default::default()
    };
    ufbx::load_memory(bytes, opts).map_err(|e| {
        let what = e.description.to_string();
        let what = what.trim();
        MocapError::invalid(
            path,
            format!(
                "not a readable FBX file: {}",
                if what.is_empty() {
                    "ufbx refused it"
                } else {
                    what
                }
            ),
        )
    })
}

fn axis_name(a: ufbx::CoordinateAxis) -> &'static str {
    use ufbx::CoordinateAxis as A;
    match a {
        A::PositiveX => "+X",
        A::NegativeX => "-X",
        A::PositiveY => "+Y",
        A::NegativeY => "-Y",
        A::PositiveZ => "+Z",
        A::NegativeZ => "-Z",
        A::Unknown => "?",
    }
}

fn axes_name(a: &ufbx::CoordinateAxes) -> String {
    format!(
        "right {}, up {}, front {}",
        axis_name(a.right),
        axis_name(a.up),
        axis_name(a.front)
    )
}

/// The unit vector of an axis, `None` when unknown.
fn axis_vec(a: ufbx::CoordinateAxis) -> Option<DVec3> {
    use ufbx::CoordinateAxis as A;
    Some(match a {
        A::PositiveX => DVec3::X,
        A::NegativeX => -DVec3::X,
        A::PositiveY => DVec3::Y,
        A::NegativeY => -DVec3::Y,
        A::PositiveZ => DVec3::Z,
        A::NegativeZ => -DVec3::Z,
        A::Unknown => return None,
    })
}

/// The linear map from the file's axes to the project's (right +X, up +Y,
/// front +Z), and a description. A left-handed file gives a reflection:
/// positions are mirrored, rotations conjugated (still rotations).
pub(crate) fn basis(axes: &ufbx::CoordinateAxes) -> (DMat3, String) {
    let (r, u, f) = (
        axis_vec(axes.right),
        axis_vec(axes.up),
        axis_vec(axes.front),
    );
    match (r, u, f) {
        (Some(r), Some(u), Some(f)) if r.dot(u) == 0.0 && r.dot(f) == 0.0 && u.dot(f) == 0.0 => {
            // Rows: the new x, y, z are the file's right, up, front.
            let m = DMat3::from_cols(r, u, f).transpose();
            let what = if m == DMat3::IDENTITY {
                format!("FBX GlobalSettings: {}", axes_name(axes))
            } else {
                format!(
                    "FBX GlobalSettings: {} (converted to up +Y, front +Z)",
                    axes_name(axes)
                )
            };
            (m, what)
        }
        _ => (
            DMat3::IDENTITY,
            format!(
                "FBX GlobalSettings axes unknown or inconsistent ({}): taken as Y up",
                axes_name(axes)
            ),
        ),
    }
}

fn curve_count(stack: &ufbx::AnimStack) -> usize {
    stack
        .layers
        .iter()
        .flat_map(|l| l.anim_values.iter())
        .flat_map(|v| v.curves.iter().flatten())
        .filter(|c| !c.keyframes.is_empty())
        .count()
}

fn takes(scene: &ufbx::Scene) -> Vec<FbxTake> {
    scene
        .anim_stacks
        .iter()
        .map(|s| FbxTake {
            name: s.element.name.to_string(),
            start: s.time_begin,
            stop: s.time_end,
            curves: curve_count(s),
        })
        .collect()
}

/// The first take with keyed curves, else the first take.
fn default_take(takes: &[FbxTake]) -> Option<usize> {
    takes
        .iter()
        .position(|t| t.curves > 0)
        .or(if takes.is_empty() { None } else { Some(0) })
}

/// Strips a `namespace:` prefix (`mixamorig:Hips` → `Hips`).
fn strip_namespace(s: &str) -> &str {
    s.rsplit(':').next().unwrap_or(s)
}

/// Rotation part and translation of a ufbx matrix, the rotation
/// orthonormalised (scale and shear removed; a mirrored frame keeps its
/// positions, its rotation is the nearest proper one).
fn split(m: &ufbx::Matrix) -> (DMat3, DVec3) {
    let x = DVec3::new(m.m00, m.m10, m.m20);
    let y = DVec3::new(m.m01, m.m11, m.m21);
    let t = DVec3::new(m.m03, m.m13, m.m23);
    let x = x.try_normalize().unwrap_or(DVec3::X);
    let y = (y - x * x.dot(y))
        .try_normalize()
        .unwrap_or_else(|| x.any_orthonormal_vector());
    (DMat3::from_cols(x, y, x.cross(y)), t)
}

/// The bones read as the clip's skeleton: scene node indices in depth-first
/// order (parents first), each one's parent among them, and joint names.
pub(crate) struct Skeleton {
    /// Scene node index of each joint.
    pub(crate) order: Vec<usize>,
    /// Parent joint of each joint (an index into `order`).
    pub(crate) parent: Vec<Option<usize>>,
    /// Joint names without namespaces (unless that makes two alike).
    pub(crate) names: Vec<String>,
}

/// How the take is sampled: its animation (`None`: the rest pose), the
/// first frame's time, the frame count and rate.
struct Sampling<'a> {
    anim: Option<&'a ufbx::Anim>,
    start: f64,
    frames: usize,
    fps: f64,
}

/// The rest (unanimated) skeleton in the project's axes: each joint's
/// world rotation inverted (the motion is expressed relative to it), its
/// world position and its offset from its parent.
pub(crate) struct Rest {
    pub(crate) rot_inv: Vec<DMat3>,
    pub(crate) pos: Vec<DVec3>,
    pub(crate) offsets: Vec<DVec3>,
}

fn clip_of_scene(scene: &ufbx::Scene, path: &Path, opts: &FbxOptions) -> Result<Clip, MocapError> {
    let mut warnings = Vec::new();
    let skel = skeleton(scene, path, &mut warnings)?;
    let n = skel.order.len();
    let sampling = sampling(scene, path, opts, n, &mut warnings)?;
    let (m, up_reason) = basis(&scene.settings.axes);
    let rest = rest_skeleton(scene, &skel, m);
    let (rotations, translations) = sample_motion(scene, path, &skel, &rest, &sampling, m)?;
    let joints = joints_of(&skel, &rest, &translations, sampling.frames);
    let mut clip = Clip::new(
        joints,
        1.0 / sampling.fps,
        rotations,
        translations,
        file_units(&scene.settings),
        UpAxis::Y,
        PointConvention::JointOrigins,
    )
    .map_err(|e| MocapError::invalid(path, e.to_string()))?;
    clip.up_reason = up_reason;
    clip.warnings = warnings;
    Ok(clip)
}

/// Step 1 of [`clip_of_scene`]: the skeleton, the subtree of the root bone
/// with the most joints (a warning names the others).
fn skeleton(
    scene: &ufbx::Scene,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<Skeleton, MocapError> {
    let nodes: Vec<&ufbx::Node> = scene.nodes.iter().map(|n| &**n).collect();
    let is_bone = |n: &ufbx::Node| n.attrib_type == ufbx::ElementType::Bone;
    let index_of = |n: &ufbx::Node| nodes.iter().position(|m| std::ptr::eq(*m, n));
    let parent_bone = |n: &ufbx::Node| -> Option<usize> {
        n.parent
            .as_ref()
            .filter(|p| is_bone(p))
            .and_then(|p| index_of(p))
    };
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); nodes.len()];
    let mut roots = Vec::new();
    for (i, n) in nodes.iter().enumerate() {
        if !is_bone(n) {
            continue;
        }
        match parent_bone(n) {
            Some(p) => children[p].push(i),
            None => roots.push(i),
        }
    }
    if roots.is_empty() {
        return Err(MocapError::invalid(
            path,
            "the FBX file has no skeleton (no LimbNode models)",
        ));
    }
    let best = largest_subtree(&children, &roots, nodes.len());
    if roots.len() > 1 {
        let dropped: Vec<String> = roots
            .iter()
            .filter(|&&r| r != best[0])
            .map(|&r| format!("'{}'", nodes[r].element.name))
            .collect();
        raise_warning(
            warnings,
            path,
            format!(
                "{} root bones; reading the largest skeleton, under '{}' ({} joints), and not {}",
                roots.len(),
                nodes[best[0]].element.name,
                best.len(),
                dropped.join(", ")
            ),
        );
    }
    let order = best;
    let mut slot = vec![usize::MAX; nodes.len()];
    for (k, &i) in order.iter().enumerate() {
        slot[i] = k;
    }
    let parent = order
        .iter()
        .map(|&i| parent_bone(nodes[i]).map(|p| slot[p]))
        .collect();
    let full: Vec<String> = order
        .iter()
        .map(|&i| nodes[i].element.name.to_string())
        .collect();
    Ok(Skeleton {
        order,
        parent,
        names: names_without_namespaces(full),
    })
}

/// Names without namespaces, unless that makes two alike (then the full
/// names).
pub(crate) fn names_without_namespaces(full: Vec<String>) -> Vec<String> {
    let names: Vec<String> = full
        .iter()
        .map(|s| strip_namespace(s).to_string())
        .collect();
    let mut seen = std::collections::HashSet::new();
    if names.iter().all(|s| seen.insert(s.clone())) {
        names
    } else {
        full
    }
}

/// Step 2 of [`clip_of_scene`]: the take (named, else the reader's
/// default), the frame rate (asked for, else the file's, else 30) and the
/// frame count, bounded by [`MAX_SAMPLES`] for `joints` joints.
fn sampling<'a>(
    scene: &'a ufbx::Scene,
    path: &Path,
    opts: &FbxOptions,
    joints: usize,
    warnings: &mut Vec<String>,
) -> Result<Sampling<'a>, MocapError> {
    let all = takes(scene);
    let take = match &opts.take {
        Some(want) => Some(all.iter().position(|t| &t.name == want).ok_or_else(|| {
            let list: Vec<String> = all.iter().map(|t| format!("'{}'", t.name)).collect();
            MocapError::invalid(
                path,
                format!(
                    "no take named '{want}'; the file's takes: {}",
                    if list.is_empty() {
                        "none".to_string()
                    } else {
                        list.join(", ")
                    }
                ),
            )
        })?),
        None => default_take(&all),
    };
    let file_fps = scene.settings.frames_per_second;
    let fps = match opts.fps {
        Some(f) => f,
        None if file_fps.is_finite() && file_fps > 0.0 => file_fps,
        None => {
            raise_warning(
                warnings,
                path,
                format!(
                    "the file's frame rate ({}) is not usable; sampling at 30 fps",
                    Short(file_fps)
                ),
            );
            30.0
        }
    };
    if !(fps.is_finite() && fps > 0.0) {
        return Err(MocapError::invalid(
            path,
            format!("frame rate {} is not a positive number", Short(fps)),
        ));
    }
    let Some(t) = take else {
        raise_warning(
            warnings,
            path,
            "the file has no takes: one frame of its rest pose read".to_string(),
        );
        return Ok(Sampling {
            anim: None,
            start: 0.0,
            frames: 1,
            fps,
        });
    };
    let stack = &scene.anim_stacks[t];
    let (a, b) = (stack.time_begin, stack.time_end);
    let span = if a.is_finite() && b.is_finite() && b >= a {
        b - a
    } else {
        raise_warning(
            warnings,
            path,
            format!(
                "take '{}' has no usable time range ({} to {} s); one frame read",
                all[t].name,
                Short(a),
                Short(b)
            ),
        );
        0.0
    };
    let count = (span * fps).round() + 1.0;
    if count * joints as f64 > MAX_SAMPLES {
        return Err(MocapError::invalid(
            path,
            format!(
                "take '{}' is {} s long: {} frames of {joints} joints is more than the {} samples a clip may hold",
                all[t].name,
                Short(span),
                Short(count),
                Short(MAX_SAMPLES)
            ),
        ));
    }
    if all[t].curves == 0 {
        raise_warning(
            warnings,
            path,
            format!(
                "take '{}' has no keyed curves: the clip does not move",
                all[t].name
            ),
        );
    }
    Ok(Sampling {
        anim: Some(&*stack.anim),
        start: if a.is_finite() { a } else { 0.0 },
        frames: count as usize,
        fps,
    })
}

/// Step 3 of [`clip_of_scene`]: the unanimated scene's world frames of the
/// skeleton, positions in the project's axes (`m`).
fn rest_skeleton(scene: &ufbx::Scene, skel: &Skeleton, m: DMat3) -> Rest {
    let rest: Vec<(DMat3, DVec3)> = skel
        .order
        .iter()
        .map(|&i| split(&scene.nodes[i].node_to_world))
        .collect();
    let rot_inv = rest.iter().map(|(r, _)| r.transpose()).collect();
    let pos: Vec<DVec3> = rest.iter().map(|(_, p)| m * *p).collect();
    let offsets = skel
        .parent
        .iter()
        .enumerate()
        .map(|(k, p)| match p {
            Some(p) => pos[k] - pos[*p],
            None => pos[k],
        })
        .collect();
    Rest {
        rot_inv,
        pos,
        offsets,
    }
}

/// Step 4 of [`clip_of_scene`]: every frame through ufbx's evaluator, as
/// local rotations (relative to the rest) and translations in the parent's
/// rotated frame, frame-major.
fn sample_motion(
    scene: &ufbx::Scene,
    path: &Path,
    skel: &Skeleton,
    rest: &Rest,
    s: &Sampling,
    m: DMat3,
) -> Result<(Vec<DQuat>, Vec<DVec3>), MocapError> {
    let n = skel.order.len();
    let m_inv = m.inverse();
    let to_project = |r: DMat3, p: DVec3| -> (DQuat, DVec3) {
        (DQuat::from_mat3(&(m * r * m_inv)).normalize(), m * p)
    };
    let mut rotations = Vec::with_capacity(s.frames * n);
    let mut translations = Vec::with_capacity(s.frames * n);
    let mut world_q = vec![DQuat::IDENTITY; n];
    let mut world_p = vec![DVec3::ZERO; n];
    for f in 0..s.frames {
        let t = s.start + f as f64 / s.fps;
        let evaluated;
        let frame_nodes: &ufbx::Scene = match s.anim {
            Some(a) => {
                evaluated = ufbx::evaluate_scene(scene, a, t, ufbx::EvaluateOpts::default())
                    .map_err(|e| {
                        MocapError::invalid(
                            path,
                            format!(
                                "ufbx could not evaluate frame {f} ({} s): {}",
                                Short(t),
                                e.description
                            ),
                        )
                    })?;
                &evaluated
            }
            None => scene,
        };
        for (k, &i) in skel.order.iter().enumerate() {
            let node = frame_nodes
                .nodes
                .get(i)
                .ok_or_else(|| MocapError::invalid(path, "the evaluated scene lost a node"))?;
            let (r, p) = split(&node.node_to_world);
            // World rotation relative to the rest frame.
            let (q, p) = to_project(r * rest.rot_inv[k], p);
            push_local(
                k,
                skel.parent[k],
                (q, p),
                (&mut world_q, &mut world_p),
                (&mut rotations, &mut translations),
            );
        }
    }
    Ok((rotations, translations))
}

/// Joint `k`'s world rotation and position `(q, p)` kept in `world` and
/// pushed onto `out` as local to its `parent` (whose world transform is
/// already in `world`): the clip's local rotations and translations, shared
/// by the FBX and glTF readers.
pub(crate) fn push_local(
    k: usize,
    parent: Option<usize>,
    (q, p): (DQuat, DVec3),
    world: (&mut [DQuat], &mut [DVec3]),
    out: (&mut Vec<DQuat>, &mut Vec<DVec3>),
) {
    world.0[k] = q;
    world.1[k] = p;
    match parent {
        None => {
            out.0.push(q);
            out.1.push(p);
        }
        Some(pk) => {
            let pinv = world.0[pk].inverse();
            out.0.push((pinv * q).normalize());
            out.1.push(pinv * (p - world.1[pk]));
        }
    }
}

/// The largest of the `roots`' subtrees under `children`, in depth-first
/// order (parents first); a walk that passes `limit` nodes (a cycle in a
/// malformed file) stops there, one past it, so the caller can tell. Shared
/// by the FBX and glTF skeleton readers; empty without roots.
pub(crate) fn largest_subtree(
    children: &[Vec<usize>],
    roots: &[usize],
    limit: usize,
) -> Vec<usize> {
    let subtree = |r: usize| -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = vec![r];
        while let Some(i) = stack.pop() {
            if out.len() > limit {
                break;
            }
            out.push(i);
            stack.extend(children[i].iter().rev());
        }
        out
    };
    let mut best: Vec<usize> = Vec::new();
    for &r in roots {
        let s = subtree(r);
        if s.len() > best.len() {
            best = s;
        }
    }
    best
}

/// Step 5 of [`clip_of_scene`]: the joints, with six channels for the root
/// and for every joint whose translation moves away from its offset, three
/// rotations for the rest.
pub(crate) fn joints_of(
    skel: &Skeleton,
    rest: &Rest,
    translations: &[DVec3],
    frames: usize,
) -> Vec<Joint> {
    let n = skel.order.len();
    let extent = rest
        .pos
        .iter()
        .fold(0.0f64, |a, p| a.max(p.abs().max_element()))
        .max(1e-9);
    (0..n)
        .map(|k| {
            let moves = skel.parent[k].is_none()
                || (0..frames)
                    .any(|f| (translations[f * n + k] - rest.offsets[k]).length() > 1e-6 * extent);
            Joint {
                name: skel.names[k].clone(),
                parent: skel.parent[k].map(|p| JointId(p as u32)),
                offset: rest.offsets[k],
                channels: if moves {
                    Channel::ROOT6.to_vec()
                } else {
                    Channel::ROT_ZYX.to_vec()
                },
                tail: None,
            }
        })
        .collect()
}

/// Step 6 of [`clip_of_scene`]: the file's unit, `UnitScaleFactor` (cm
/// when missing, FBX's default, or unusable). [`units_with_stature`] then
/// checks it against the body.
pub(crate) fn file_units(settings: &ufbx::SceneSettings) -> Units {
    let mpu = settings.unit_meters;
    let mpu_ok = mpu.is_finite() && mpu > 0.0;
    let declared = ufbx::find_prop(&settings.props, "UnitScaleFactor").is_some();
    Units {
        metres_per_unit: if mpu_ok && declared { mpu } else { 0.01 },
        name: unit_name(if mpu_ok && declared { mpu } else { 0.01 }),
        reason: if !declared {
            format!("{NO_UNIT_SCALE}; centimetres (FBX's default) assumed")
        } else if mpu_ok {
            format!("FBX GlobalSettings UnitScaleFactor {}", Short(mpu * 100.0))
        } else {
            format!(
                "FBX UnitScaleFactor unusable ({}); centimetres assumed",
                Short(mpu * 100.0)
            )
        },
    }
}

/// How [`file_units`] says the file has no `UnitScaleFactor`.
const NO_UNIT_SCALE: &str = "no UnitScaleFactor in the FBX GlobalSettings";

/// The unit of an FBX clip judged with its body, the rule BVH files get
/// ([`units_from_stature`]) where the file's own unit is missing or
/// contradicts the body. `file` is the clip's unit as read
/// ([`file_units`]); `stature` the humanoid's stature in file units and
/// what it was measured from (`rig::load::stature`), `None` without a
/// humanoid. The file's `UnitScaleFactor` stands when it gives a human
/// stature ([`HUMAN_STATURE_M`]); a body of 170 m (an actor in cm
/// declared as m) or one without the factor is measured instead.
pub fn units_with_stature(file: &Units, stature: Option<(f64, String)>) -> Units {
    let Some((h, basis)) = stature.filter(|(h, _)| h.is_finite() && *h > 0.0) else {
        return Units {
            reason: format!("{}; no humanoid limbs to check it against", file.reason),
            ..file.clone()
        };
    };
    let declared = !file.reason.starts_with(NO_UNIT_SCALE);
    let metres = h * file.metres_per_unit;
    let (lo, hi) = HUMAN_STATURE_M;
    if declared && (lo..=hi).contains(&metres) {
        return Units {
            reason: format!(
                "{}; the body agrees (stature {metres:.2} m from {basis})",
                file.reason
            ),
            ..file.clone()
        };
    }
    let mut u = units_from_stature(h, &basis, UnitFamily::Other);
    u.reason = if declared {
        format!(
            "{} gives a stature of {} m, not a human one ({lo}-{hi} m), so the body decides: {}",
            file.reason,
            Short(metres),
            u.reason
        )
    } else {
        format!("{NO_UNIT_SCALE}, so the body decides: {}", u.reason)
    };
    u
}

fn unit_name(mpu: f64) -> String {
    for (v, name) in [
        (0.01, "cm"),
        (1.0, "m"),
        (0.001, "mm"),
        (0.1, "dm"),
        (0.0254, "inch"),
        (0.3048, "ft"),
    ] {
        if (mpu - v).abs() <= 1e-9 * v {
            return name.into();
        }
    }
    format!("{mpu} m")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn magic_bytes_are_recognised() {
        assert!(is_fbx(b"Kaydara FBX Binary  \0\x1a\0"));
        assert!(is_fbx(b"; FBX 7.5.0 project file\n"));
        assert!(is_fbx(b"\xEF\xBB\xBF\n; FBX 6.1.0 project file"));
        assert!(!is_fbx(b"HIERARCHY\nROOT Hips"));
        assert!(!is_fbx(b""));
    }

    #[test]
    fn max_axes_become_y_up() {
        use ufbx::CoordinateAxis as A;
        let (m, _) = basis(&ufbx::CoordinateAxes {
            right: A::PositiveX,
            up: A::PositiveZ,
            front: A::NegativeY,
        });
        // The project's Z-up rule: (x, y, z) → (x, z, −y).
        assert_eq!(m * DVec3::new(1.0, 2.0, 3.0), DVec3::new(1.0, 3.0, -2.0));
    }

    #[test]
    fn garbage_is_an_error_naming_the_file() {
        let p = Path::new("x.fbx");
        for bytes in [
            &b""[..],
            b"garbage",
            b"Kaydara FBX Binary  \0\x1a\0\xff\xff",
        ] {
            let e = parse_fbx(bytes, p, &FbxOptions::default()).unwrap_err();
            let s = e.to_string();
            assert!(s.starts_with("x.fbx: "), "{s}");
            assert!(!s.contains('\n'), "{s}");
        }
    }
}
