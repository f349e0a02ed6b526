//! The scene's nodes (world transforms, parents, order) and the merged
//! triangle primitives: positions, normals, colours, triangles, skin
//! attributes and morph targets, through each node's transform.

use super::buffers::Ctx;
use crate::mesh::{Mesh, MeshError};
use glam::{DVec3, Mat4};
use gltf::accessor::{DataType, Dimensions};

/// A point through a node's world matrix (f32 entries, f64 arithmetic; the
/// bottom row is taken as `0 0 0 1`).
fn transform_point(m: &Mat4, p: [f64; 3]) -> [f64; 3] {
    m.as_dmat4()
        .transform_point3(DVec3::from_array(p))
        .to_array()
}

/// The linear part of `m` applied to a displacement.
fn transform_vector(m: &Mat4, d: [f64; 3]) -> [f64; 3] {
    m.as_dmat4()
        .transform_vector3(DVec3::from_array(d))
        .to_array()
}

/// The cofactor matrix of `m`'s linear part (`det · A⁻ᵀ`, defined for any
/// `A`) applied to a normal: directions stay perpendicular to transformed
/// surfaces; renormalise after summing morph displacements.
fn transform_normal(m: &Mat4, n: [f64; 3]) -> [f64; 3] {
    let m = m.as_dmat4();
    let (c0, c1, c2) = (
        m.x_axis.truncate(),
        m.y_axis.truncate(),
        m.z_axis.truncate(),
    );
    (c1.cross(c2) * n[0] + c2.cross(c0) * n[1] + c0.cross(c1) * n[2]).to_array()
}

/// World transforms of every node reachable from the scene(s), cycle-safe.
pub(super) struct SceneNodes {
    /// World matrix per node (`None` for unreachable nodes).
    pub(super) world: Vec<Option<Mat4>>,
    /// Parent per node.
    pub(super) parent: Vec<Option<usize>>,
    /// Reachable nodes, parents first.
    pub(super) order: Vec<usize>,
}

impl SceneNodes {
    /// Step 2 of [`parse_gltf`](super::parse_gltf): walks the default scene (else the first,
    /// else every node that is nobody's child) depth first.
    pub(super) fn walk(doc: &gltf::Document) -> SceneNodes {
        let nn = doc.nodes().len();
        let mut world: Vec<Option<Mat4>> = vec![None; nn];
        let mut parent: Vec<Option<usize>> = vec![None; nn];
        let roots: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(s) => s.nodes().map(|n| n.index()).collect(),
            None => {
                let mut is_child = vec![false; nn];
                for n in doc.nodes() {
                    for c in n.children() {
                        is_child[c.index()] = true;
                    }
                }
                (0..nn).filter(|&i| !is_child[i]).collect()
            }
        };
        let nodes: Vec<gltf::Node> = doc.nodes().collect();
        let mut stack: Vec<(usize, Mat4)> = roots.iter().map(|&r| (r, Mat4::IDENTITY)).collect();
        let mut order = Vec::with_capacity(nn);
        while let Some((i, pm)) = stack.pop() {
            if world[i].is_some() {
                continue;
            }
            let m = pm * Mat4::from_cols_array_2d(&nodes[i].transform().matrix());
            world[i] = Some(m);
            order.push(i);
            for c in nodes[i].children() {
                if world[c.index()].is_none() {
                    parent[c.index()] = Some(i);
                    stack.push((c.index(), m));
                }
            }
        }
        SceneNodes {
            world,
            parent,
            order,
        }
    }
}

/// The merged triangle primitives, as they are read.
#[derive(Default)]
pub(super) struct Geometry {
    positions: Vec<[f64; 3]>,
    colors: Vec<[f64; 3]>,
    any_color: bool,
    tris: Vec<[u32; 3]>,
    targets: Vec<Vec<[f64; 3]>>,
    normals: Vec<[f64; 3]>,
    any_normal: bool,
    target_normals: Vec<Vec<[f64; 3]>>,
    pub(super) morph_node: Option<usize>,
    skin_joints: Vec<[u16; 4]>,
    skin_weights: Vec<[f32; 4]>,
    pub(super) skin_idx: Option<usize>,
}

/// What [`Geometry::into_mesh`] hands on besides the mesh.
pub(super) struct GeometryParts {
    pub(super) targets: Vec<Vec<[f64; 3]>>,
    pub(super) normals: Option<Vec<[f64; 3]>>,
    pub(super) target_normals: Vec<Vec<[f64; 3]>>,
    pub(super) skin_joints: Vec<[u16; 4]>,
    pub(super) skin_weights: Vec<[f32; 4]>,
}

impl Geometry {
    /// Step 3 of [`parse_gltf`](super::parse_gltf): the triangle primitives of node `ni` (if
    /// it has a mesh and is reachable, `world` its matrix), through the
    /// node transform unless skinned. Only the first skin is read.
    pub(super) fn add_node(
        &mut self,
        ctx: &Ctx,
        ni: usize,
        node: &gltf::Node,
        world: Option<Mat4>,
        problems: &mut Vec<String>,
    ) -> Result<(), MeshError> {
        let (Some(mesh), Some(m)) = (node.mesh(), world) else {
            return Ok(());
        };
        let skinned = node.skin().is_some();
        if let Some(s) = node.skin() {
            if self.skin_idx.is_none() {
                self.skin_idx = Some(s.index());
            } else if self.skin_idx != Some(s.index()) {
                problems.push(format!(
                    "node {ni} uses skin {}; only the first skin is read",
                    s.index()
                ));
            }
        }
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                problems.push(format!(
                    "mesh {} has a {:?} primitive; skipped",
                    mesh.index(),
                    prim.mode()
                ));
                continue;
            }
            let Some(pacc) = prim.get(&gltf::Semantic::Positions) else {
                problems.push(format!(
                    "mesh {} has a primitive without POSITION; skipped",
                    mesh.index()
                ));
                continue;
            };
            self.add_primitive(ctx, ni, mesh.index(), &prim, &pacc, &m, skinned)?;
        }
        Ok(())
    }

    /// One triangle primitive: vertices, normals, colours, triangles, skin
    /// attributes, and morph targets (from the first node that has them).
    #[allow(clippy::too_many_arguments)]
    fn add_primitive(
        &mut self,
        ctx: &Ctx,
        ni: usize,
        mesh_index: usize,
        prim: &gltf::Primitive,
        pacc: &gltf::Accessor,
        m: &Mat4,
        skinned: bool,
    ) -> Result<(), MeshError> {
        let base = self.positions.len();
        let mut p = ctx.read_vec3(pacc, "POSITION")?;
        if !skinned {
            p.iter_mut().for_each(|x| *x = transform_point(m, *x));
        }
        let nv = p.len();
        if base + nv > u32::MAX as usize {
            return Err(ctx.err("too many vertices"));
        }
        self.positions.extend(p);
        match prim.get(&gltf::Semantic::Normals) {
            Some(a) => {
                let mut n = ctx.read_vec3(&a, "NORMAL")?;
                if n.len() != nv {
                    return Err(ctx.err("NORMAL has the wrong size"));
                }
                if !skinned {
                    n.iter_mut().for_each(|x| *x = transform_normal(m, *x));
                }
                self.normals.extend(n);
                self.any_normal = true;
            }
            None => self.normals.extend(std::iter::repeat_n([0.0; 3], nv)),
        }
        match prim.get(&gltf::Semantic::Colors(0)) {
            Some(c) => {
                let (v, comps) = ctx.read_f32(&c, "COLOR_0")?;
                if comps < 3 || v.len() != nv * comps {
                    return Err(ctx.err("COLOR_0 has the wrong size"));
                }
                self.colors.extend(
                    v.chunks_exact(comps)
                        .map(|c| [c[0] as f64, c[1] as f64, c[2] as f64]),
                );
                self.any_color = true;
            }
            None => self.colors.extend(std::iter::repeat_n([1.0; 3], nv)),
        }
        let idx: Vec<u32> = match prim.indices() {
            // Unsigned integer scalars only (a FLOAT VEC3 accessor was read
            // as indices, truncated, and the mesh accepted), read exactly
            // (through an f32, indices above 2²⁴ were rounded).
            Some(ia)
                if ia.dimensions() != Dimensions::Scalar
                    || ia.normalized()
                    || !matches!(ia.data_type(), DataType::U8 | DataType::U16 | DataType::U32) =>
            {
                return Err(ctx.err(format!(
                    "mesh {mesh_index}: indices (accessor {}) are {:?} {:?}, expected unsigned integer scalars",
                    ia.index(),
                    ia.data_type(),
                    ia.dimensions()
                )));
            }
            Some(ia) => match (ia.view(), ia.sparse()) {
                (Some(view), None) => ctx
                    .read_indices(&view, ia.offset(), ia.count(), ia.data_type(), "indices")?
                    .into_iter()
                    .map(|v| v.min(u32::MAX as usize) as u32)
                    .collect(),
                _ => ctx
                    .read_f32(&ia, "indices")?
                    .0
                    .into_iter()
                    .map(|v| v as u32)
                    .collect(),
            },
            None => (0..nv as u32).collect(),
        };
        for t in idx.chunks_exact(3) {
            if t.iter().any(|&v| v as usize >= nv) {
                return Err(ctx.err(format!(
                    "mesh {mesh_index}: index out of range ({nv} vertices)"
                )));
            }
            self.tris
                .push([t[0] + base as u32, t[1] + base as u32, t[2] + base as u32]);
        }
        // Skin attributes.
        match (
            prim.get(&gltf::Semantic::Joints(0)),
            prim.get(&gltf::Semantic::Weights(0)),
        ) {
            (Some(ja), Some(wa)) if skinned => {
                let (j, jc) = ctx.read_f32(&ja, "JOINTS_0")?;
                let (w, wc) = ctx.read_f32(&wa, "WEIGHTS_0")?;
                if jc != 4 || wc != 4 || j.len() != nv * 4 || w.len() != nv * 4 {
                    return Err(ctx.err("JOINTS_0/WEIGHTS_0 must be VEC4 with one per vertex"));
                }
                self.skin_joints.resize(base, [0; 4]);
                self.skin_weights.resize(base, [0.0; 4]);
                self.skin_joints.extend(
                    j.chunks_exact(4)
                        .map(|c| [c[0] as u16, c[1] as u16, c[2] as u16, c[3] as u16]),
                );
                self.skin_weights
                    .extend(w.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]));
            }
            _ => {}
        }
        // Morph targets: from the first node that has them.
        let ptargets: Vec<_> = prim.morph_targets().collect();
        if !ptargets.is_empty() && self.morph_node.is_none_or(|n| n == ni) {
            self.morph_node = Some(ni);
            if self.targets.is_empty() {
                self.targets = vec![Vec::new(); ptargets.len()];
                self.target_normals = vec![Vec::new(); ptargets.len()];
            }
            if self.targets.len() != ptargets.len() {
                return Err(ctx.err("primitives of one mesh have different morph target counts"));
            }
            for (k, t) in ptargets.iter().enumerate() {
                let mut d = match t.positions() {
                    Some(a) => ctx.read_vec3(&a, "morph target POSITION")?,
                    None => vec![[0.0; 3]; nv],
                };
                let mut dn = match t.normals() {
                    Some(a) => ctx.read_vec3(&a, "morph target NORMAL")?,
                    None => vec![[0.0; 3]; nv],
                };
                if d.len() != nv || dn.len() != nv {
                    return Err(ctx.err("morph target size differs from its primitive"));
                }
                if !skinned {
                    d.iter_mut().for_each(|x| *x = transform_vector(m, *x));
                    dn.iter_mut().for_each(|x| *x = transform_normal(m, *x));
                }
                self.targets[k].resize(base, [0.0; 3]);
                self.targets[k].extend(d);
                self.target_normals[k].resize(base, [0.0; 3]);
                self.target_normals[k].extend(dn);
            }
        }
        Ok(())
    }

    /// Step 4 of [`parse_gltf`](super::parse_gltf): the merged mesh (with colours when any
    /// primitive has them), morph targets padded to every vertex.
    pub(super) fn into_mesh(self, ctx: &Ctx) -> Result<(Mesh, GeometryParts), MeshError> {
        let Geometry {
            positions,
            colors,
            any_color,
            tris,
            mut targets,
            normals,
            any_normal,
            mut target_normals,
            skin_joints,
            skin_weights,
            ..
        } = self;
        if positions.is_empty() {
            return Err(ctx.err("no triangle mesh in the scene"));
        }
        for t in targets.iter_mut().chain(&mut target_normals) {
            t.resize(positions.len(), [0.0; 3]);
        }
        if !any_normal {
            target_normals.clear();
        }
        let path = ctx.path;
        crate::mesh::io::format::refuse_huge_coordinates(&positions, path)?;
        let mut mesh = Mesh::new(positions, tris).map_err(|e| MeshError::from(e).in_file(path))?;
        if any_color {
            mesh = mesh
                .with_colors(colors)
                .map_err(|e| MeshError::from(e).in_file(path))?;
        }
        let parts = GeometryParts {
            targets,
            normals: any_normal.then_some(normals),
            target_normals,
            skin_joints,
            skin_weights,
        };
        Ok((mesh, parts))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Under a non-uniform scale and a rotation, a transformed normal stays
    /// perpendicular to the transformed tangent plane (where the plain
    /// linear map would tilt it), and a displacement is the linear map.
    #[test]
    fn normals_follow_the_node_transform_through_the_cofactor() {
        let r = glam::Mat4::from_scale_rotation_translation(
            glam::Vec3::new(3.0, 0.5, 1.0),
            glam::Quat::from_rotation_z(0.7),
            glam::Vec3::new(5.0, -2.0, 1.0),
        );
        let m: Mat4 = r;
        let n = DVec3::new(1.0, 1.0, 0.0).normalize();
        let (t1, t2) = (DVec3::new(1.0, -1.0, 0.0), DVec3::Z);
        let tn = DVec3::from_array(transform_normal(&m, n.to_array()));
        for t in [t1, t2] {
            let tt = DVec3::from_array(transform_vector(&m, t.to_array()));
            assert!(
                tn.dot(tt).abs() < 1e-5 * tn.length() * tt.length(),
                "{tn} · {tt}"
            );
        }
        let plain = DVec3::from_array(transform_vector(&m, n.to_array()));
        assert!(
            plain
                .dot(DVec3::from_array(transform_vector(&m, t1.to_array())))
                .abs()
                > 0.1
        );
        let p = DVec3::from_array(transform_point(&m, [0.0; 3]));
        assert!((p - DVec3::new(5.0, -2.0, 1.0)).length() < 1e-6);
        assert!(tn.dot(n) > 0.0, "orientation kept for det > 0");
    }
}
