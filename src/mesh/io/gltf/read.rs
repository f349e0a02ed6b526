//! Reading a glTF file: [`parse_gltf`] runs the steps of the sibling files in
//! order ([`super::validate`], [`super::buffers`], [`super::geometry`],
//! [`super::skin`], [`super::animation`]).

use super::animation::read_animations;
use super::asset::GltfAsset;
use super::buffers::{Ctx, load_buffers};
use super::geometry::{Geometry, SceneNodes};
use super::skin::{node_graph, read_skin};
use super::validate::{check_attribute_indices, check_enums, check_glb_layout};
use crate::mesh::MeshError;
use std::path::Path;

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
