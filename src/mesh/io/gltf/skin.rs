//! The first skin (joints, parents, inverse bind matrices, per-vertex
//! influences), the node hierarchy with rest transforms, and the skinned
//! mesh posed by a node animation.

use super::animation::sample;
use super::asset::{GltfAsset, NodeGraph, Skin, TrsPath};
use super::buffers::Ctx;
use super::geometry::SceneNodes;
use crate::mesh::{MeshError, MeshSequence};
use crate::mocap::Clip;
use glam::Mat4;

/// Step 5 of [`parse_gltf`](super::parse_gltf): skin `skin_idx` (joints, their parents within
/// the skin, inverse bind matrices) with the per-vertex influences of the
/// `nv` vertices; weights not summing to 1 are normalised (and said in
/// `problems`).
pub(super) fn read_skin(
    ctx: &Ctx,
    doc: &gltf::Document,
    skin_idx: Option<usize>,
    parent: &[Option<usize>],
    nv: usize,
    (mut skin_joints, mut skin_weights): (Vec<[u16; 4]>, Vec<[f32; 4]>),
    problems: &mut Vec<String>,
) -> Result<Option<Skin>, MeshError> {
    let Some(s) = skin_idx.and_then(|i| doc.skins().nth(i)) else {
        return Ok(None);
    };
    let joint_nodes: Vec<usize> = s.joints().map(|j| j.index()).collect();
    let joint_names = s
        .joints()
        .map(|j| {
            j.name()
                .map(str::to_string)
                .unwrap_or_else(|| format!("joint_{}", j.index()))
        })
        .collect();
    let parents = joint_nodes
        .iter()
        .map(|&n| {
            let mut p = parent[n];
            while let Some(pi) = p {
                if let Some(k) = joint_nodes.iter().position(|&x| x == pi) {
                    return Some(k as u32);
                }
                p = parent[pi];
            }
            None
        })
        .collect();
    let inverse_bind = match s.inverse_bind_matrices() {
        Some(a) => {
            let (v, c) = ctx.read_f32(&a, "inverseBindMatrices")?;
            if c != 16 || v.len() != joint_nodes.len() * 16 {
                return Err(ctx.err("inverseBindMatrices must be one MAT4 per joint"));
            }
            v.chunks_exact(16)
                .map(|m| Mat4::from_cols_slice(m).to_cols_array_2d())
                .collect()
        }
        None => vec![Mat4::IDENTITY.to_cols_array_2d(); joint_nodes.len()],
    };
    skin_joints.resize(nv, [0; 4]);
    skin_weights.resize(nv, [0.0; 4]);
    let mut renorm = 0usize;
    for (w, j) in skin_weights.iter_mut().zip(&skin_joints) {
        if j.iter().any(|&k| k as usize >= joint_nodes.len()) {
            return Err(ctx.err("JOINTS_0 refers to a joint the skin does not have"));
        }
        let s: f32 = w.iter().sum();
        if (s - 1.0).abs() > 1e-3 {
            renorm += 1;
            if s > 0.0 {
                w.iter_mut().for_each(|x| *x /= s);
            }
        }
    }
    if renorm > 0 {
        problems.push(format!(
            "{renorm} vertices had skin weights not summing to 1; normalised"
        ));
    }
    Ok(Some(Skin {
        joint_names,
        parents,
        inverse_bind,
        joints: skin_joints,
        weights: skin_weights,
    }))
}

/// Step 7 of [`parse_gltf`](super::parse_gltf): the scene graph (parents, rest TRS, order,
/// the skin's joint nodes).
pub(super) fn node_graph(
    doc: &gltf::Document,
    nodes: &[gltf::Node],
    scene: SceneNodes,
    skin_idx: Option<usize>,
) -> NodeGraph {
    NodeGraph {
        parent: scene.parent,
        rest: nodes
            .iter()
            .map(|n| {
                let (t, r, sc) = n.transform().decomposed();
                (
                    glam::DVec3::from_array(t.map(f64::from)),
                    glam::DQuat::from_array(r.map(f64::from)).normalize(),
                    glam::DVec3::from_array(sc.map(f64::from)),
                )
            })
            .collect(),
        order: scene.order,
        skin_joints: skin_idx
            .and_then(|i| doc.skins().nth(i))
            .map(|s| s.joints().map(|j| j.index()).collect())
            .unwrap_or_default(),
    }
}

impl GltfAsset {
    /// The skinned mesh in its rest pose in world space (every node at its
    /// rest TRS, no animation), with the world position of each skin joint.
    /// `None` without a skin.
    pub fn rest_pose(&self) -> Option<(Vec<[f64; 3]>, Vec<glam::DVec3>)> {
        use glam::{DMat4, DVec3};
        let skin = self.skin.as_ref()?;
        let g = &self.graph;
        let mut world = vec![DMat4::IDENTITY; g.rest.len()];
        for &n in &g.order {
            let (t, r, sc) = g.rest[n];
            let local = DMat4::from_scale_rotation_translation(sc, r, t);
            world[n] = match g.parent[n] {
                Some(p) => world[p] * local,
                None => local,
            };
        }
        let skinning: Vec<DMat4> = g
            .skin_joints
            .iter()
            .enumerate()
            .map(|(k, &jn)| {
                let ibm = skin.inverse_bind.get(k).map_or(DMat4::IDENTITY, |m| {
                    DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from)))
                });
                world.get(jn).copied().unwrap_or(DMat4::IDENTITY) * ibm
            })
            .collect();
        let verts = self
            .mesh
            .positions()
            .iter()
            .enumerate()
            .map(|(v, p)| {
                let src = DVec3::from_array(*p);
                let mut acc = DVec3::ZERO;
                for (j, w) in skin.joints[v].iter().zip(skin.weights[v]) {
                    if let Some(m) = skinning.get(*j as usize) {
                        acc += m.transform_point3(src) * w as f64;
                    }
                }
                acc.to_array()
            })
            .collect();
        let joints = g
            .skin_joints
            .iter()
            .map(|&jn| world.get(jn).map_or(DVec3::ZERO, |m| m.w_axis.truncate()))
            .collect();
        Some((verts, joints))
    }

    /// Animation `index` of a skinned asset as a mesh sequence sampled at
    /// `fps`: node transforms are sampled (linear, slerp or step), composed
    /// down the hierarchy, and the mesh is skinned with linear blend skinning
    /// `v' = Σ w_j (W_j · IBM_j) v` (glTF 2.0 §3.7.3; the mesh node's own
    /// transform is ignored, as the spec says).
    pub(crate) fn skinned_sequence(
        &self,
        index: usize,
        fps: f64,
    ) -> Result<MeshSequence, MeshError> {
        use glam::{DMat4, DVec3};
        let bad = |m: String| MeshError::invalid(std::path::Path::new("<gltf>"), m);
        let skin = self.skin.as_ref().ok_or_else(|| bad("no skin".into()))?;
        let anim = self
            .node_animations
            .get(index)
            .ok_or_else(|| bad(format!("no animation {index}")))?;
        let g = &self.graph;
        let frames = ((anim.duration as f64 * fps).floor() as usize + 1).min(100_000);
        let nv = self.mesh.vertex_count();
        // 100,000 frames of a mesh the file declares: checked before held.
        crate::util::budget::check_frames("a skinned glTF animation", frames, nv, 1)
            .map_err(|e| bad(e.to_string()))?;
        let mut out = Vec::with_capacity(frames * nv);
        let mut trs = g.rest.clone();
        let mut world = vec![DMat4::IDENTITY; trs.len()];
        let mut skinning = vec![DMat4::IDENTITY; g.skin_joints.len()];
        for f in 0..frames {
            let t = (f as f64 / fps) as f32;
            // The animation was found above: every frame composes.
            self.node_worlds_at(Some(index), t, &mut trs, &mut world);
            for (k, &jn) in g.skin_joints.iter().enumerate() {
                let ibm =
                    DMat4::from_cols_array_2d(&skin.inverse_bind[k].map(|c| c.map(f64::from)));
                skinning[k] = world[jn] * ibm;
            }
            for (v, p) in self.mesh.positions().iter().enumerate() {
                let (js, ws) = (skin.joints[v], skin.weights[v]);
                let src = DVec3::from_array(*p);
                let mut acc = DVec3::ZERO;
                let mut wsum = 0.0;
                for i in 0..4 {
                    let w = ws[i] as f64;
                    if w != 0.0 {
                        acc += skinning[js[i] as usize].transform_point3(src) * w;
                        wsum += w;
                    }
                }
                out.push(if wsum > 0.0 {
                    (acc / wsum).to_array()
                } else {
                    *p
                });
            }
        }
        MeshSequence::new(self.mesh.clone(), out, Some(fps)).map_err(MeshError::from)
    }

    /// World matrices of every node at time `t` of node animation `anim`
    /// (`None`: every node at its rest TRS) into `world`, with `trs` as
    /// scratch: channels sampled (linear, slerp, step or cubic-spline
    /// keys), the rest TRS of nodes the animation does not
    /// drive, composed down the hierarchy (glTF 2.0 §3.5.3: `T · R · S`).
    /// Both vectors are resized to the node count, so a caller that keeps
    /// them allocates once. Nodes outside the scene keep the identity.
    /// Returns false when there is no animation `anim`.
    pub fn node_worlds_at(
        &self,
        anim: Option<usize>,
        t: f32,
        trs: &mut Vec<(glam::DVec3, glam::DQuat, glam::DVec3)>,
        world: &mut Vec<glam::DMat4>,
    ) -> bool {
        use glam::{DMat4, DQuat, DVec3};
        let g = &self.graph;
        trs.clone_from(&g.rest);
        if let Some(a) = anim {
            let Some(anim) = self.node_animations.get(a) else {
                return false;
            };
            for ch in &anim.channels {
                let Some(slot) = trs.get_mut(ch.node) else {
                    continue;
                };
                let v = sample(ch, t);
                match ch.path {
                    TrsPath::Translation => {
                        slot.0 = DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64)
                    }
                    TrsPath::Rotation => {
                        slot.1 =
                            DQuat::from_xyzw(v[0] as f64, v[1] as f64, v[2] as f64, v[3] as f64)
                                .normalize()
                    }
                    TrsPath::Scale => slot.2 = DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64),
                }
            }
        }
        world.clear();
        world.resize(trs.len(), DMat4::IDENTITY);
        for &n in &g.order {
            let Some(&(tr, r, sc)) = trs.get(n) else {
                continue;
            };
            let local = DMat4::from_scale_rotation_translation(sc, r, tr);
            world[n] = match g.parent[n].and_then(|p| world.get(p)) {
                Some(pw) => *pw * local,
                None => local,
            };
        }
        true
    }

    /// World positions of the skin's joints (in skin order) at time `t` of
    /// node animation `index` ([`GltfAsset::node_worlds_at`]). `None`
    /// without a skin or that animation. For the joint mapping of rigged
    /// characters ([`GltfAsset::skin_clip`]).
    pub(crate) fn joint_positions_at(&self, index: usize, t: f32) -> Option<Vec<glam::DVec3>> {
        use glam::DVec3;
        self.skin.as_ref()?;
        let (mut trs, mut world) = (Vec::new(), Vec::new());
        if !self.node_worlds_at(Some(index), t, &mut trs, &mut world) {
            return None;
        }
        Some(
            self.graph
                .skin_joints
                .iter()
                .map(|&jn| world.get(jn).map_or(DVec3::ZERO, |m| m.w_axis.truncate()))
                .collect(),
        )
    }

    /// The skin as a clip ([`crate::mocap::skin::skin_clip`]), so rigged
    /// characters go through the same joint mapping as BVH and ASF
    /// (`rig::detect_skin`): the rest at `pose` (skin order: bind or rest
    /// positions); the frames, with `animate`, up to 48 samples of the first
    /// node animation (world space, which may differ from bind space by the
    /// root node's transform), else `pose` alone. Also returns, per clip joint, its skin joint
    /// (`None` for `skin_root`).
    pub fn skin_clip(
        &self,
        pose: &[glam::DVec3],
        animate: bool,
    ) -> Result<(Clip, Vec<Option<usize>>), String> {
        let skin = self.skin.as_ref().ok_or("the glTF has no skin")?;
        let n = skin.joint_names.len();
        let mut frames: Vec<Vec<glam::DVec3>> = Vec::new();
        if animate && let Some(a) = self.node_animations.first() {
            let count = 48usize;
            for f in 0..count {
                let t = a.duration * f as f32 / (count - 1) as f32;
                match self.joint_positions_at(0, t) {
                    Some(p) if p.len() == n => frames.push(p),
                    _ => break,
                }
            }
        }
        crate::mocap::skin::skin_clip(&skin.joint_names, &skin.parents, pose, frames)
    }
}
