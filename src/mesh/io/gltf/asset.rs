//! The asset a glTF file holds and the reading of it: [`parse_gltf`] runs the
//! steps of the sibling files in order ([`super::validate`], [`super::buffers`],
//! [`super::geometry`], [`super::skin`], [`super::animation`]).

use super::animation::{KeyWeights, NodeAnimation, read_animations};
use super::buffers::{Ctx, load_buffers};
use super::geometry::{Geometry, SceneNodes};
use super::skin::{NodeGraph, Skin, node_graph, read_skin};
use super::validate::{check_attribute_indices, check_enums, check_glb_layout};
use crate::mesh::{Mesh, MeshError, MeshSequence};
use std::path::Path;

/// What a glTF file holds.
#[derive(Debug, Clone)]
pub struct GltfAsset {
    /// All triangle primitives merged.
    pub mesh: Mesh,
    /// The first skin, if any mesh is skinned.
    pub skin: Option<Skin>,
    /// Morph target displacements (per target, one per vertex of `mesh`).
    pub morph_targets: Vec<Vec<[f64; 3]>>,
    /// Vertex normals (`NORMAL`) through the normal matrix of their node
    /// (cofactor of its linear part), not renormalised; zero for the vertices
    /// of primitives without normals. `None` when no primitive has them.
    pub normals: Option<Vec<[f64; 3]>>,
    /// Morph target normal displacements, transformed like [`Self::normals`]
    /// (per target, one per vertex; zero where a target has none). Empty when
    /// the asset has no normals.
    pub morph_normals: Vec<Vec<[f64; 3]>>,
    /// Key times and, per key, the non-zero weights `(target, weight)` of the
    /// first morph-weights animation (sparse: a clip of `F` frames written as
    /// one target per frame has `F` weights, not `F²`).
    pub weights_animation: Option<(Vec<f32>, Vec<KeyWeights>)>,
    /// Animation names and durations (seconds).
    pub animations: Vec<(String, f32)>,
    /// Node count, for `inspect`.
    pub nodes: usize,
    /// Node transform animations (translation, rotation, scale channels).
    pub node_animations: Vec<NodeAnimation>,
    /// Scene graph: parent of each node, rest TRS, and an order with parents first.
    pub graph: NodeGraph,
    /// Non-fatal problems.
    pub problems: Vec<String>,
}

/// Parses glTF or GLB bytes. `path` locates external buffers and names errors.
///
/// The steps, in order (each names the file in its errors): `open_document`
/// (GLB layout, JSON, validation, buffers), `SceneNodes::walk` (world
/// transforms, parents, order), `Geometry::add_node` per mesh node
/// (positions, normals, colours, triangles, skin attributes, morph targets),
/// `Geometry::into_mesh`, `read_skin`, `read_animations` and
/// `node_graph`.
pub fn parse_gltf(bytes: &[u8], path: &Path) -> Result<GltfAsset, MeshError> {
    let (doc, ctx) = open_document(bytes, path)?;
    let mut problems = Vec::new();
    let scene = SceneNodes::walk(&doc);
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut geo = Geometry::default();
    for (ni, node) in nodes.iter().enumerate() {
        geo.add_node(&ctx, ni, node, scene.world[ni], &mut problems)?;
    }
    let skin_idx = geo.skin_idx;
    let morph_node = geo.morph_node;
    let (mesh, parts) = geo.into_mesh(&ctx)?;
    let skin = read_skin(
        &ctx,
        &doc,
        skin_idx,
        &scene.parent,
        mesh.vertex_count(),
        (parts.skin_joints, parts.skin_weights),
        &mut problems,
    )?;
    let anims = read_animations(&ctx, &doc, morph_node, parts.targets.len())?;
    let graph = node_graph(&doc, &nodes, scene, skin_idx);
    Ok(GltfAsset {
        mesh,
        skin,
        morph_targets: parts.targets,
        normals: parts.normals,
        morph_normals: parts.target_normals,
        weights_animation: anims.weights,
        animations: anims.names,
        nodes: nodes.len(),
        node_animations: anims.nodes,
        graph,
        problems,
    })
}

/// Step 1 of [`parse_gltf`]: checks the GLB layout, parses the JSON (with
/// `KHR_mesh_quantization` taken out of `extensionsRequired`, since
/// quantisation only widens the component types of attributes, which
/// `Ctx::read_f32` reads whatever they are), validates it, and loads the
/// buffers.
fn open_document<'a>(bytes: &[u8], path: &'a Path) -> Result<(gltf::Document, Ctx<'a>), MeshError> {
    let bytes = check_glb_layout(bytes, path)?;
    let g = gltf::Gltf::from_slice_without_validation(bytes)
        .map_err(|e| MeshError::invalid(path, format!("glTF: {e}")))?;
    let mut json = g.document.into_json();
    json.extensions_required
        .retain(|e| e != crate::mesh::io::glb::KHR_MESH_QUANTIZATION);
    check_attribute_indices(&json, path)?;
    let doc = gltf::Document::from_json(json)
        .map_err(|e| MeshError::invalid(path, format!("glTF: {e}")))?;
    check_enums(doc.as_json(), path)?;
    let ctx = Ctx {
        path,
        buffers: load_buffers(&doc, g.blob, path)?,
    };
    Ok((doc, ctx))
}

/// Reads a `.gltf` or `.glb` file.
pub fn read_gltf(path: &Path) -> Result<GltfAsset, MeshError> {
    parse_gltf(&crate::util::fsutil::read_bytes(path)?, path)
}

impl GltfAsset {
    /// Unit vertex normals at key `key` of the morph-weights animation,
    /// `normalize(N + Σ_j w_j ΔN_j)` (zero where that vanishes); the rest
    /// normals when there is no such animation. `None` without normals or
    /// past the last key.
    pub fn key_normals(&self, key: usize) -> Option<Vec<[f64; 3]>> {
        use glam::DVec3;
        let base = self.normals.as_ref()?;
        let mut n: Vec<DVec3> = base.iter().map(|v| DVec3::from_array(*v)).collect();
        if let Some((_, keys)) = &self.weights_animation {
            for &(j, w) in keys.get(key)? {
                let Some(d) = self.morph_normals.get(j as usize) else {
                    continue;
                };
                for (a, b) in n.iter_mut().zip(d) {
                    *a += w as f64 * DVec3::from_array(*b);
                }
            }
        }
        Some(n.iter().map(|v| v.normalize_or_zero().to_array()).collect())
    }

    /// The asset as a mesh sequence: one frame per key of the morph-weights
    /// animation (`base + Σ w_k · target_k`), or the single rest frame.
    pub fn to_sequence(&self) -> Result<MeshSequence, MeshError> {
        let Some((times, keys)) = &self.weights_animation else {
            if self.skin.is_some() && !self.node_animations.is_empty() {
                return self.skinned_sequence(0, 30.0);
            }
            return Ok(MeshSequence::single(self.mesh.clone()));
        };
        let base = self.mesh.positions();
        // A key per frame of the whole mesh: a small weights accessor
        // declares many frames (issue 46, item 5).
        crate::util::budget::check_frames(
            "a glTF morph-weights animation",
            keys.len(),
            base.len(),
            1,
        )
        .map_err(|e| MeshError::invalid(std::path::Path::new("<gltf>"), e.to_string()))?;
        let mut frames = Vec::with_capacity(keys.len() * base.len());
        for w in keys {
            let start = frames.len();
            frames.extend_from_slice(base);
            for &(k, wk) in w {
                let Some(target) = self.morph_targets.get(k as usize) else {
                    continue;
                };
                for (p, d) in frames[start..].iter_mut().zip(target) {
                    p[0] += wk as f64 * d[0];
                    p[1] += wk as f64 * d[1];
                    p[2] += wk as f64 * d[2];
                }
            }
        }
        let fps = if times.len() > 1 {
            let dt = (times[times.len() - 1] - times[0]) as f64 / (times.len() - 1) as f64;
            (dt > 0.0).then(|| 1.0 / dt)
        } else {
            None
        };
        Ok(MeshSequence::new(self.mesh.clone(), frames, fps)?)
    }
}
