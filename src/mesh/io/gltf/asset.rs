//! What a glTF file holds: the [`GltfAsset`] and its parts (skin, node
//! graph, animations), and the mesh sequence of its morph-weights animation.

use crate::mesh::{Mesh, MeshError, MeshSequence};

/// The non-zero morph weights of one animation key: `(target, weight)`.
pub type KeyWeights = Vec<(u32, f32)>;

/// A skin: joints with their hierarchy, and per-vertex influences.
#[derive(Debug, Clone)]
pub struct Skin {
    /// Joint node names (`joint_N` where a node has no name).
    pub joint_names: Vec<String>,
    /// Parent joint of each joint within the skin (`None` at the top).
    pub parents: Vec<Option<u32>>,
    /// Inverse bind matrices, column-major.
    pub inverse_bind: Vec<[[f32; 4]; 4]>,
    /// Four joint indices per vertex.
    pub joints: Vec<[u16; 4]>,
    /// Four weights per vertex, normalised to sum to 1 where they did not.
    pub weights: Vec<[f32; 4]>,
}

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

/// Which node property a channel drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrsPath {
    /// Translation (VEC3).
    Translation,
    /// Rotation quaternion xyzw (VEC4).
    Rotation,
    /// Scale (VEC3).
    Scale,
}

/// One sampled channel of a node animation.
#[derive(Debug, Clone)]
pub struct NodeChannel {
    /// Target node.
    pub node: usize,
    /// Property.
    pub path: TrsPath,
    /// Key times (seconds, ascending).
    pub times: Vec<f32>,
    /// Key values (xyz or xyzw).
    pub values: Vec<[f32; 4]>,
    /// STEP interpolation (else linear / slerp, or cubic with tangents).
    pub step: bool,
    /// CUBICSPLINE keys: each key's in- and out-tangent (same layout as
    /// `values`); empty for linear and step keys.
    pub tangents: Vec<[[f32; 4]; 2]>,
}

/// A node animation: its name, duration and channels.
#[derive(Debug, Clone)]
pub struct NodeAnimation {
    /// Name (may be empty).
    pub name: String,
    /// Last key time.
    pub duration: f32,
    /// Channels.
    pub channels: Vec<NodeChannel>,
}

/// The node hierarchy with rest transforms.
#[derive(Debug, Clone, Default)]
pub struct NodeGraph {
    /// Parent per node (`None` at a root or for unreachable nodes).
    pub parent: Vec<Option<usize>>,
    /// Rest translation, rotation, scale per node.
    pub rest: Vec<(glam::DVec3, glam::DQuat, glam::DVec3)>,
    /// Reachable nodes, parents before children.
    pub order: Vec<usize>,
    /// The skin's joint nodes (if any).
    pub skin_joints: Vec<usize>,
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
