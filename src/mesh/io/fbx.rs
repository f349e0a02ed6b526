//! A rigged FBX character (mesh, skin clusters, bones) read with the ufbx C
//! reader, in the form the glTF reader gives a skinned glTF
//! ([`GltfAsset`] with its [`Skin`]), so `rig embed --skin` and a
//! database's `gltf_skin` take it the same way (`embed::skin::from_skin`).
//!
//! - **Mesh**: every mesh node, merged in scene order, in its bind pose in
//!   world space (a skinned mesh through a cluster's bind matrix times its
//!   mesh-to-bone matrix, a rigid one through its node), polygons
//!   triangulated by ufbx.
//! - **Joints**: every bone (`LimbNode`) and every node a skin cluster
//!   binds, parents the nearest such ancestor, names without their
//!   namespace (`mixamorig:Hips` → `Hips`, as the FBX clip reader does).
//!   Bind matrices: a cluster's `TransformLink` (bind to world); a bone no
//!   cluster binds takes its rest offset from the nearest bound ancestor.
//! - **Weights**: each vertex's four largest cluster weights, normalised to
//!   sum to 1; a rigid mesh under a bone is weighted 1 to that bone.
//! - **Units and axes**: converted to the project's (metres by
//!   `UnitScaleFactor`, Y up, front +Z), like glTF; or metres by a unit the
//!   caller decided ([`parse_fbx_character_in`]: `rig::read_rigged_character`
//!   passes the unit the file's clip reads at, so a character and its clip
//!   come out at one scale), named in the asset's problems when it is not
//!   the file's.
//!
//! Not read: animation (the clip reader, `mocap::fbx`, reads the takes),
//! blend shapes, materials.

use super::gltf::{GltfAsset, NodeGraph, Skin};
use crate::mesh::{Mesh, MeshError};
use crate::mocap::Units;
use crate::mocap::fbx::{basis, file_units, load_scene, names_without_namespaces};
use glam::{DMat4, DVec3};
use std::path::Path;

/// Reads a rigged FBX character: its meshes in their bind pose and its skin
/// (see the module documentation), in metres, Y up.
pub fn read_fbx_character(path: &Path) -> Result<GltfAsset, MeshError> {
    let bytes = crate::util::fsutil::read_bytes(path)?;
    parse_fbx_character(&bytes, path)
}

/// [`read_fbx_character`] of bytes in memory; `path` names them in errors.
pub fn parse_fbx_character(bytes: &[u8], path: &Path) -> Result<GltfAsset, MeshError> {
    parse_fbx_character_in(bytes, path, None)
}

/// [`read_fbx_character`] at a unit the caller decided (`None`: the file's
/// `UnitScaleFactor`). A unit other than the file's is named in the asset's
/// problems with its reason. The reader decides no unit itself: the unit a
/// body's stature gives needs the rig detector, above the mesh readers
/// (`rig::read_rigged_character` passes its clip's).
pub(crate) fn read_fbx_character_in(
    path: &Path,
    units: Option<&Units>,
) -> Result<GltfAsset, MeshError> {
    let bytes = crate::util::fsutil::read_bytes(path)?;
    parse_fbx_character_in(&bytes, path, units)
}

/// [`read_fbx_character_in`] of bytes in memory; `path` names them in errors.
pub(crate) fn parse_fbx_character_in(
    bytes: &[u8],
    path: &Path,
    units: Option<&Units>,
) -> Result<GltfAsset, MeshError> {
    let scene = load_scene(bytes, path, true)?;
    let (m, _) = basis(&scene.settings.axes);
    let file = file_units(&scene.settings);
    let units = units.unwrap_or(&file);
    // File world → project world: axes, then metres.
    let conv = DMat4::from_mat3(m * units.metres_per_unit);
    let joints = joints(&scene, conv);
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let mut influence: Vec<[(u16, f32); 4]> = Vec::new();
    let mut problems = Vec::new();
    if units.metres_per_unit != file.metres_per_unit {
        problems.push(format!(
            "units: {} m per file unit ({}), not the file's {} m",
            units.metres_per_unit, units.reason, file.metres_per_unit
        ));
    }
    for node in scene.nodes.iter() {
        let Some(mesh) = node.mesh.as_ref() else {
            continue;
        };
        let first = positions.len();
        let skin = mesh.skin_deformers.first();
        if mesh.skin_deformers.len() > 1 {
            problems.push(format!(
                "mesh '{}' has {} skins; the first is read",
                node.element.name,
                mesh.skin_deformers.len()
            ));
        }
        // A cluster's bind (`TransformLink`) times its mesh-to-bone
        // (`Transform`): the mesh at bind time. Not ufbx's cluster
        // `geometry_to_world`, which carries the bone's pose in the scene
        // as loaded: Kenney's character (Maya) has its first cluster on a
        // foot IK control posed away from the bind, and the mesh came out
        // turned on its back beside its skeleton.
        let to_world = match skin.and_then(|s| s.clusters.first()) {
            Some(c) => matrix(&c.bind_to_world) * matrix(&c.geometry_to_bone),
            None => matrix(&node.geometry_to_world),
        };
        let to_world = conv * to_world;
        for v in mesh.vertices.iter() {
            let p = to_world.transform_point3(DVec3::new(v.x, v.y, v.z));
            positions.push(p.to_array());
        }
        let rigid = bone_above(&scene, &joints, node.element.typed_id as usize);
        for (v, row) in (0..mesh.vertices.len()).map(|v| (v, [(0u16, 0f32); 4])) {
            let row = match skin {
                Some(s) => skin_row(s, v, &joints).unwrap_or(row),
                None => rigid.map_or(row, |j| [(j as u16, 1.0), (0, 0.0), (0, 0.0), (0, 0.0)]),
            };
            influence.push(row);
        }
        if skin.is_none() && rigid.is_none() {
            problems.push(format!(
                "mesh '{}' is neither skinned nor under a bone: its vertices follow the root",
                node.element.name
            ));
        }
        let mut tri = vec![0u32; mesh.max_face_triangles * 3];
        for face in mesh.faces.iter() {
            if face.num_indices < 3 {
                continue;
            }
            let n = ufbx::triangulate_face(&mut tri, mesh, *face) as usize;
            for t in tri[..(3 * n).min(tri.len())].chunks_exact(3) {
                let Some(v) = t
                    .iter()
                    .map(|&i| {
                        let x = *mesh.vertex_indices.get(i as usize)? as usize;
                        u32::try_from(first + x).ok()
                    })
                    .collect::<Option<Vec<u32>>>()
                else {
                    return Err(MeshError::invalid(
                        path,
                        format!("mesh '{}': a face index out of range", node.element.name),
                    ));
                };
                triangles.push([v[0], v[1], v[2]]);
            }
        }
    }
    if positions.is_empty() {
        return Err(MeshError::invalid(path, "the FBX file has no mesh"));
    }
    if joints.nodes.is_empty() {
        return Err(MeshError::invalid(
            path,
            "the FBX file has no skeleton (no LimbNode models and no skin clusters)",
        ));
    }
    if joints.nodes.len() > usize::from(u16::MAX) {
        return Err(MeshError::invalid(
            path,
            format!("{} joints: more than a skin holds", joints.nodes.len()),
        ));
    }
    super::format::refuse_huge_coordinates(&positions, path)?;
    let mesh = Mesh::new(positions, triangles).map_err(|e| MeshError::from(e).in_file(path))?;
    let weights: Vec<[f32; 4]> = influence.iter().map(|r| r.map(|(_, w)| w)).collect();
    let skin = Skin {
        joint_names: joints.names.clone(),
        parents: joints.parent.iter().map(|p| p.map(|p| p as u32)).collect(),
        inverse_bind: joints
            .bind
            .iter()
            .map(|b| b.inverse().as_mat4().to_cols_array_2d())
            .collect(),
        joints: influence.iter().map(|r| r.map(|(j, _)| j)).collect(),
        weights,
    };
    Ok(GltfAsset {
        mesh,
        skin: Some(skin),
        morph_targets: Vec::new(),
        normals: None,
        morph_normals: Vec::new(),
        weights_animation: None,
        animations: Vec::new(),
        nodes: scene.nodes.len(),
        node_animations: Vec::new(),
        graph: graph(&joints),
        problems,
    })
}

/// The skin's joints: scene node indices, parents (indices into them),
/// names and bind matrices (joint to world, in the project's axes and
/// metres).
struct Joints {
    nodes: Vec<usize>,
    parent: Vec<Option<usize>>,
    names: Vec<String>,
    bind: Vec<DMat4>,
    /// Joint of each scene node, if it is one.
    of_node: Vec<Option<usize>>,
}

fn joints(scene: &ufbx::Scene, conv: DMat4) -> Joints {
    let count = scene.nodes.len();
    // Bind (joint to world) of every node a cluster binds.
    let mut bound: Vec<Option<DMat4>> = vec![None; count];
    for skin in scene.skin_deformers.iter() {
        for c in skin.clusters.iter() {
            if let Some(b) = c.bone_node.as_ref() {
                let i = b.element.typed_id as usize;
                if i < count && bound[i].is_none() {
                    bound[i] = Some(matrix(&c.bind_to_world));
                }
            }
        }
    }
    let is_joint =
        |i: usize| bound[i].is_some() || scene.nodes[i].attrib_type == ufbx::ElementType::Bone;
    let mut of_node = vec![None; count];
    let mut nodes = Vec::new();
    // ufbx lists nodes parents first.
    for (i, slot) in of_node.iter_mut().enumerate() {
        if is_joint(i) {
            *slot = Some(nodes.len());
            nodes.push(i);
        }
    }
    let parent_joint = |i: usize| -> Option<usize> {
        let mut p = scene.nodes[i].parent.as_ref();
        for _ in 0..count {
            let n = p?;
            let k = n.element.typed_id as usize;
            if let Some(j) = of_node.get(k).copied().flatten() {
                return Some(j);
            }
            p = n.parent.as_ref();
        }
        None
    };
    let parent: Vec<Option<usize>> = nodes.iter().map(|&i| parent_joint(i)).collect();
    // In the file's space: a bound joint's cluster bind; an unbound one
    // the parent's bind times its rest offset from the parent.
    let mut file_bind: Vec<DMat4> = Vec::with_capacity(nodes.len());
    for (k, &i) in nodes.iter().enumerate() {
        let rest = matrix(&scene.nodes[i].node_to_world);
        let b = match (bound[i], parent[k]) {
            (Some(b), _) => b,
            (None, Some(p)) => {
                let prest = matrix(&scene.nodes[nodes[p]].node_to_world);
                file_bind[p] * prest.inverse() * rest
            }
            (None, None) => rest,
        };
        file_bind.push(b);
    }
    // Joint to project world, the joint's axes turned alike.
    let conv_inv = conv.inverse();
    let bind = file_bind.iter().map(|b| conv * *b * conv_inv).collect();
    let names = names_without_namespaces(
        nodes
            .iter()
            .map(|&i| scene.nodes[i].element.name.to_string())
            .collect(),
    );
    Joints {
        nodes,
        parent,
        names,
        bind,
        of_node,
    }
}

/// The joint at or above scene node `i` (a rigid mesh's bone).
fn bone_above(scene: &ufbx::Scene, joints: &Joints, i: usize) -> Option<usize> {
    let mut node = scene.nodes.get(i)?.parent.as_ref();
    for _ in 0..scene.nodes.len() {
        let n = node?;
        if let Some(j) = joints
            .of_node
            .get(n.element.typed_id as usize)
            .copied()
            .flatten()
        {
            return Some(j);
        }
        node = n.parent.as_ref();
    }
    None
}

/// The four largest weights of vertex `v` (joint, weight), normalised to
/// sum to 1; `None` when it has none.
fn skin_row(skin: &ufbx::SkinDeformer, v: usize, joints: &Joints) -> Option<[(u16, f32); 4]> {
    let sv = skin.vertices.get(v)?;
    let (b, n) = (sv.weight_begin as usize, sv.num_weights as usize);
    let mut all: Vec<(u16, f64)> = (b..b + n)
        .filter_map(|k| {
            let w = skin.weights.get(k)?;
            let c = skin.clusters.get(w.cluster_index as usize)?;
            let node = c.bone_node.as_ref()?;
            let j = joints
                .of_node
                .get(node.element.typed_id as usize)
                .copied()
                .flatten()?;
            (w.weight.is_finite() && w.weight > 0.0).then_some((j as u16, w.weight))
        })
        .collect();
    all.sort_by(|a, b| b.1.total_cmp(&a.1));
    all.truncate(4);
    let sum: f64 = all.iter().map(|x| x.1).sum();
    if sum <= 0.0 {
        return None;
    }
    let mut row = [(0u16, 0f32); 4];
    for (slot, (j, w)) in row.iter_mut().zip(all) {
        *slot = (j, (w / sum) as f32);
    }
    Some(row)
}

/// The joints as a node graph (the bind pose as the rest), so
/// [`GltfAsset::rest_pose`] gives the bind pose back.
fn graph(j: &Joints) -> NodeGraph {
    let rest = j
        .bind
        .iter()
        .zip(&j.parent)
        .map(|(b, p)| {
            let local = match p {
                Some(p) => j.bind[*p].inverse() * *b,
                None => *b,
            };
            let (s, r, t) = local.to_scale_rotation_translation();
            (t, r, s)
        })
        .collect();
    let n = j.nodes.len();
    NodeGraph {
        parent: j.parent.clone(),
        rest,
        order: (0..n).collect(),
        skin_joints: (0..n).collect(),
    }
}

/// A ufbx affine matrix as a glam one.
fn matrix(m: &ufbx::Matrix) -> DMat4 {
    DMat4::from_cols(
        DVec3::new(m.m00, m.m10, m.m20).extend(0.0),
        DVec3::new(m.m01, m.m11, m.m21).extend(0.0),
        DVec3::new(m.m02, m.m12, m.m22).extend(0.0),
        DVec3::new(m.m03, m.m13, m.m23).extend(1.0),
    )
}
