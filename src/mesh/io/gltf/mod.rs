//! glTF 2.0 reader (`.gltf` with external or data-URI buffers, `.glb`):
//! triangle primitives of every mesh node merged into one [`Mesh`] (node
//! transforms applied, except to skinned meshes, which stay in bind space),
//! vertex colours and normals, the first skin (joints, parents, inverse bind
//! matrices, per-vertex joints and weights), morph targets (POSITION and
//! NORMAL displacements, through the node transform like the base), and a
//! morph-weights animation sampled at its key times as a mesh sequence.
//! Quantised attributes (`KHR_mesh_quantization`: integer and normalized
//! integer component types, dequantised by the node transform) are read;
//! the `gltf` crate's validation, which refuses that required extension,
//! runs with it taken out of `extensionsRequired`.
//!
//! Accessors are read by our own bounds-checked code rather than
//! `gltf::Reader`, so a malformed file gives an error, never a panic.

use crate::mesh::{Mesh, MeshError, MeshSequence};
use base64::Engine as _;
use glam::{DVec3, Mat4};
use gltf::accessor::{DataType, Dimensions};
use std::path::Path;

/// The non-zero morph weights of one animation key: `(target, weight)`.
pub type KeyWeights = Vec<(u32, f32)>;

/// Indices and values of a sparse accessor's substitutions.
type Substitutions = (Vec<usize>, Vec<f32>);

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

/// One sampled channel of a node animation (CUBICSPLINE keys keep their values only).
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
    /// STEP interpolation (else linear / slerp).
    pub step: bool,
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

struct Ctx<'a> {
    path: &'a Path,
    buffers: Vec<Vec<u8>>,
}

impl Ctx<'_> {
    fn err(&self, msg: impl Into<String>) -> MeshError {
        MeshError::invalid(self.path, msg)
    }

    /// Reads a view's bytes region `[offset, offset + len)`, checked.
    fn view_bytes(&self, view: &gltf::buffer::View) -> Result<&[u8], MeshError> {
        let b = self.buffers.get(view.buffer().index()).ok_or_else(|| {
            self.err(format!(
                "bufferView {} names a missing buffer",
                view.index()
            ))
        })?;
        let (o, l) = (view.offset(), view.length());
        o.checked_add(l).and_then(|e| b.get(o..e)).ok_or_else(|| {
            self.err(format!(
                "bufferView {} (offset {o}, length {l}) exceeds its buffer ({} bytes)",
                view.index(),
                b.len()
            ))
        })
    }

    /// Reads `count` elements of `comps` scalars of type `dt` from a view.
    #[allow(clippy::too_many_arguments)]
    fn read_elements(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        count: usize,
        comps: usize,
        dt: DataType,
        normalized: bool,
        what: &str,
    ) -> Result<Vec<f32>, MeshError> {
        let bytes = self.view_bytes(view)?;
        let cs = dt.size();
        let elem = cs * comps;
        let stride = view.stride().unwrap_or(elem).max(elem);
        if count > 0 {
            let last = (count - 1)
                .checked_mul(stride)
                .and_then(|v| v.checked_add(offset))
                .and_then(|v| v.checked_add(elem));
            if last.is_none_or(|e| e > bytes.len()) {
                return Err(self.err(format!(
                    "{what}: {count} elements do not fit in bufferView {}",
                    view.index()
                )));
            }
        }
        let mut out = Vec::with_capacity(count * comps);
        for i in 0..count {
            let base = offset + i * stride;
            for c in 0..comps {
                let o = base + c * cs;
                let b = &bytes[o..o + cs];
                let v = match dt {
                    DataType::I8 => {
                        let x = b[0] as i8 as f32;
                        if normalized { (x / 127.0).max(-1.0) } else { x }
                    }
                    DataType::U8 => {
                        let x = b[0] as f32;
                        if normalized { x / 255.0 } else { x }
                    }
                    DataType::I16 => {
                        let x = i16::from_le_bytes([b[0], b[1]]) as f32;
                        if normalized {
                            (x / 32767.0).max(-1.0)
                        } else {
                            x
                        }
                    }
                    DataType::U16 => {
                        let x = u16::from_le_bytes([b[0], b[1]]) as f32;
                        if normalized { x / 65535.0 } else { x }
                    }
                    DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
                    DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                };
                out.push(v);
            }
        }
        Ok(out)
    }

    /// Reads an accessor as f32 scalars (integers converted), with sparse
    /// substitution. Returns (values, components per element).
    fn read_f32(&self, acc: &gltf::Accessor, what: &str) -> Result<(Vec<f32>, usize), MeshError> {
        let comps = acc.dimensions().multiplicity();
        let count = acc.count();
        let dt = acc.data_type();
        let mut out = match acc.view() {
            Some(view) => self.read_elements(
                &view,
                acc.offset(),
                count,
                comps,
                dt,
                acc.normalized(),
                what,
            )?,
            None => {
                if count > 100_000_000 {
                    return Err(self.err(format!("{what}: absurd count {count}")));
                }
                // Zeros that no byte of the file backs: a few bytes of JSON
                // declared 6.4 GB (issue 46, item 5).
                crate::util::budget::check(
                    || format!("{what}: {count} elements of {comps} zeros (no bufferView)"),
                    count as u128 * comps as u128 * 4,
                )
                .map_err(|e| self.err(e.to_string()))?;
                vec![0.0; count * comps]
            }
        };
        if let Some(sp) = acc.sparse() {
            let (idx, vals) = self.read_sparse(&sp, comps, dt, acc.normalized(), what)?;
            for (k, &i) in idx.iter().enumerate() {
                if i >= count {
                    return Err(self.err(format!("{what}: sparse index {i} ≥ count {count}")));
                }
                out[i * comps..(i + 1) * comps].copy_from_slice(&vals[k * comps..(k + 1) * comps]);
            }
        }
        Ok((out, comps))
    }

    /// A sparse accessor's substitutions: its indices and its values
    /// (`comps` components of type `dt` each), indices read first.
    fn read_sparse(
        &self,
        sp: &gltf::accessor::sparse::Sparse,
        comps: usize,
        dt: DataType,
        normalized: bool,
        what: &str,
    ) -> Result<(Vec<usize>, Vec<f32>), MeshError> {
        let n = sp.count();
        let iv = sp.indices();
        let it = match iv.index_type() {
            gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let idx = self.read_indices(&iv.view(), iv.offset(), n, it, what)?;
        let vals = self.read_elements(
            &sp.values().view(),
            sp.values().offset(),
            n,
            comps,
            dt,
            normalized,
            what,
        )?;
        Ok((idx, vals))
    }

    /// `count` unsigned integers of type `it` (exact: an f32 holds
    /// integers only up to 2²⁴, and sparse indices into an F×F weight table
    /// exceed that).
    fn read_indices(
        &self,
        view: &gltf::buffer::View,
        offset: usize,
        count: usize,
        it: DataType,
        what: &str,
    ) -> Result<Vec<usize>, MeshError> {
        let bytes = self.view_bytes(view)?;
        let cs = it.size();
        let stride = view.stride().unwrap_or(cs).max(cs);
        let fits = count == 0
            || (count - 1)
                .checked_mul(stride)
                .and_then(|v| v.checked_add(offset + cs))
                .is_some_and(|e| e <= bytes.len());
        if !fits {
            return Err(self.err(format!(
                "{what}: {count} indices do not fit in bufferView {}",
                view.index()
            )));
        }
        Ok((0..count)
            .map(|i| {
                let b = &bytes[offset + i * stride..offset + i * stride + cs];
                match cs {
                    1 => b[0] as usize,
                    2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                    _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
                }
            })
            .collect())
    }

    /// A scalar sparse accessor without a view (zeros but for its
    /// substitutions) as its (index, value) pairs, in O(substitutions)
    /// whatever its count; `None` for any other accessor.
    fn read_sparse_zeros(
        &self,
        acc: &gltf::Accessor,
        what: &str,
    ) -> Result<Option<Substitutions>, MeshError> {
        let (None, Some(sp), Dimensions::Scalar) = (acc.view(), acc.sparse(), acc.dimensions())
        else {
            return Ok(None);
        };
        let (idx, vals) = self.read_sparse(&sp, 1, acc.data_type(), acc.normalized(), what)?;
        if idx.windows(2).any(|w| w[1] <= w[0]) || idx.last().is_some_and(|&i| i >= acc.count()) {
            return Err(self.err(format!(
                "{what}: sparse indices must increase and stay under the count {}",
                acc.count()
            )));
        }
        Ok(Some((idx, vals)))
    }

    fn read_vec3(&self, acc: &gltf::Accessor, what: &str) -> Result<Vec<[f64; 3]>, MeshError> {
        if acc.dimensions() != Dimensions::Vec3 {
            return Err(self.err(format!("{what}: expected VEC3")));
        }
        let (v, _) = self.read_f32(acc, what)?;
        Ok(v.chunks_exact(3)
            .map(|c| [c[0] as f64, c[1] as f64, c[2] as f64])
            .collect())
    }
}

fn load_buffers(
    doc: &gltf::Document,
    blob: Option<Vec<u8>>,
    path: &Path,
) -> Result<Vec<Vec<u8>>, MeshError> {
    let mut blob = blob;
    let mut out = Vec::new();
    for b in doc.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                MeshError::invalid(path, "buffer refers to a missing GLB BIN chunk")
            })?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let b64 = rest.split_once(";base64,").map(|x| x.1).ok_or_else(|| {
                        MeshError::invalid(
                            path,
                            format!("buffer {}: only base64 data URIs are supported", b.index()),
                        )
                    })?;
                    base64::engine::general_purpose::STANDARD
                        .decode(b64)
                        .map_err(|e| {
                            MeshError::invalid(
                                path,
                                format!("buffer {}: bad base64: {e}", b.index()),
                            )
                        })?
                } else {
                    let p = buffer_path(path, b.index(), uri)?;
                    // Named with the glTF that refers to it ("missing.bin:
                    // No such file" named neither the .gltf nor the buffer).
                    crate::util::fsutil::read_bytes(&p).map_err(|e| {
                        MeshError::invalid(path, format!("buffer {}: {e}", b.index()))
                    })?
                }
            }
        };
        if data.len() < b.length() {
            return Err(MeshError::invalid(
                path,
                format!(
                    "buffer {} has {} bytes, declares {}",
                    b.index(),
                    data.len(),
                    b.length()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The file a buffer's external URI names, or why it is not followed.
///
/// The rule (README, "Mesh formats"): a buffer URI is a relative reference
/// (glTF 2.0 spec, 2.8 "URIs"), percent-decoded and resolved against the
/// glTF's own folder. It may name a file in that folder, below it, or in a
/// sibling folder (`../buffers/x.bin`: one `..` above the glTF's folder at
/// most, counted after `a/../` pairs cancel). Refused, with the glTF, the
/// buffer and the URI named: an absolute path (`/x.bin`, `C:\x.bin`,
/// `\\server\x`), any scheme but `data:` (`file://`, `http://`), and a
/// path climbing two or more folders above the glTF's (`../../x.bin`). A
/// downloaded glTF thus cannot make a conversion read, and write into its
/// output, a file elsewhere on the disk.
fn buffer_path(gltf: &Path, buffer: usize, uri: &str) -> Result<std::path::PathBuf, MeshError> {
    use std::path::PathBuf;
    let refuse = |why: &str| MeshError::BufferUri {
        gltf: gltf.to_path_buf(),
        buffer,
        uri: uri.to_string(),
        why: why.to_string(),
    };
    // A scheme: letters, digits, '+', '-', '.' before the first ':',
    // starting with a letter (RFC 3986, 3.1). One letter is a drive.
    if let Some((scheme, _)) = uri.split_once(':')
        && scheme.starts_with(|c: char| c.is_ascii_alphabetic())
        && scheme
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
    {
        return Err(if scheme.len() == 1 {
            refuse("is an absolute path (a drive letter); name the file relative to the glTF")
        } else {
            refuse("has a scheme; only data: URIs and paths relative to the glTF are read")
        });
    }
    let decoded = crate::util::fsutil::percent_decode(uri)
        .ok_or_else(|| refuse("has a bad percent escape (expected %XX of UTF-8 bytes)"))?;
    if decoded.starts_with(['/', '\\']) {
        return Err(refuse(
            "is an absolute path; name the file relative to the glTF",
        ));
    }
    // The path with `a/..` pairs cancelled (lexically, as the URI reads:
    // `a/c/../x.bin` needs no folder `c`), and how many `..` lead it.
    let mut parts: Vec<&str> = Vec::new();
    for part in decoded.split(['/', '\\']) {
        match part {
            "" | "." => {}
            ".." if parts.last().is_some_and(|p| *p != "..") => {
                parts.pop();
            }
            p => parts.push(p),
        }
    }
    let up = parts.iter().take_while(|p| **p == "..").count();
    let rel: PathBuf = parts.iter().collect();
    if up > 1 {
        return Err(refuse(
            "climbs more than one folder above the glTF's folder; \
             copy the buffer beside the glTF, or into a folder next to it",
        ));
    }
    Ok(gltf.parent().unwrap_or(Path::new(".")).join(rel))
}

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

/// Rejects enum-valued fields the `gltf` crate would unwrap (and panic on)
/// when they hold an unknown value: its validation lets some through (an
/// animation target `path` of `"weigh9s"` panics in `Target::property`).
fn check_enums(root: &gltf::json::Root, path: &Path) -> Result<(), MeshError> {
    use gltf::json::validation::Checked;
    let bad = |what: String| Err(MeshError::invalid(path, format!("glTF: invalid {what}")));
    for (i, a) in root.accessors.iter().enumerate() {
        if matches!(a.component_type, Checked::Invalid) || matches!(a.type_, Checked::Invalid) {
            return bad(format!("componentType or type of accessor {i}"));
        }
        if let Some(sp) = &a.sparse
            && matches!(sp.indices.component_type, Checked::Invalid)
        {
            return bad(format!("sparse index type of accessor {i}"));
        }
    }
    for (i, a) in root.animations.iter().enumerate() {
        if a.channels
            .iter()
            .any(|c| matches!(c.target.path, Checked::Invalid))
        {
            return bad(format!("channel target path in animation {i}"));
        }
        if a.samplers
            .iter()
            .any(|s| matches!(s.interpolation, Checked::Invalid))
        {
            return bad(format!("sampler interpolation in animation {i}"));
        }
    }
    for (i, m) in root.meshes.iter().enumerate() {
        for p in &m.primitives {
            if matches!(p.mode, Checked::Invalid)
                || p.attributes.keys().any(|k| matches!(k, Checked::Invalid))
            {
                return bad(format!("primitive mode or attribute name in mesh {i}"));
            }
        }
    }
    Ok(())
}

/// Rejects mesh attributes naming an accessor that does not exist: the
/// `gltf` crate's validation indexes the POSITION accessor unchecked (a
/// panic; found by `tests/it/hostile/malformed.rs` on a bit-flipped GLB).
fn check_attribute_indices(root: &gltf::json::Root, path: &Path) -> Result<(), MeshError> {
    let n = root.accessors.len();
    for (i, m) in root.meshes.iter().enumerate() {
        for p in &m.primitives {
            let targets = p.targets.iter().flatten();
            let named = p.attributes.values().copied().chain(
                targets.flat_map(|t| [t.positions, t.normals, t.tangents].into_iter().flatten()),
            );
            for a in named.chain(p.indices) {
                if a.value() >= n {
                    return Err(MeshError::invalid(
                        path,
                        format!(
                            "glTF: mesh {i} names accessor {}, the file has {n}",
                            a.value()
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Checks a GLB container's header and chunk lengths before the `gltf` crate
/// sees them: its parser subtracts the header size from the declared length
/// unchecked (a declared length under 12 overflows; found by cargo-fuzz).
/// Returns the bytes the header declares. Non-GLB input passes through.
fn check_glb_layout<'a>(bytes: &'a [u8], path: &Path) -> Result<&'a [u8], MeshError> {
    if !bytes.starts_with(b"glTF") {
        return Ok(bytes);
    }
    let bad = |msg: String| Err(MeshError::invalid(path, format!("GLB: {msg}")));
    if bytes.len() < 20 {
        return bad(format!(
            "{} bytes: too short for a header and a chunk",
            bytes.len()
        ));
    }
    let u32_at = |o: usize| {
        u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]) as usize
    };
    let (version, total) = (u32_at(4), u32_at(8));
    if version != 2 {
        return bad(format!("version {version}, expected 2"));
    }
    if total < 20 || total > bytes.len() {
        return bad(format!(
            "header declares {total} bytes, the file has {}",
            bytes.len()
        ));
    }
    let mut off = 12;
    let mut first = true;
    while off + 8 <= total {
        let (len, kind) = (u32_at(off), &bytes[off + 4..off + 8]);
        if first && kind != b"JSON" {
            return bad("the first chunk is not JSON".into());
        }
        first = false;
        match (off + 8).checked_add(len) {
            Some(end) if end <= total => off = end,
            _ => {
                return bad(format!(
                    "chunk at byte {off} declares {len} bytes, past the end ({total})"
                ));
            }
        }
    }
    Ok(&bytes[..total])
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
        .retain(|e| e != super::glb::KHR_MESH_QUANTIZATION);
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

/// World transforms of every node reachable from the scene(s), cycle-safe.
struct SceneNodes {
    /// World matrix per node (`None` for unreachable nodes).
    world: Vec<Option<Mat4>>,
    /// Parent per node.
    parent: Vec<Option<usize>>,
    /// Reachable nodes, parents first.
    order: Vec<usize>,
}

impl SceneNodes {
    /// Step 2 of [`parse_gltf`]: walks the default scene (else the first,
    /// else every node that is nobody's child) depth first.
    fn walk(doc: &gltf::Document) -> SceneNodes {
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
struct Geometry {
    positions: Vec<[f64; 3]>,
    colors: Vec<[f64; 3]>,
    any_color: bool,
    tris: Vec<[u32; 3]>,
    targets: Vec<Vec<[f64; 3]>>,
    normals: Vec<[f64; 3]>,
    any_normal: bool,
    target_normals: Vec<Vec<[f64; 3]>>,
    morph_node: Option<usize>,
    skin_joints: Vec<[u16; 4]>,
    skin_weights: Vec<[f32; 4]>,
    skin_idx: Option<usize>,
}

/// What [`Geometry::into_mesh`] hands on besides the mesh.
struct GeometryParts {
    targets: Vec<Vec<[f64; 3]>>,
    normals: Option<Vec<[f64; 3]>>,
    target_normals: Vec<Vec<[f64; 3]>>,
    skin_joints: Vec<[u16; 4]>,
    skin_weights: Vec<[f32; 4]>,
}

impl Geometry {
    /// Step 3 of [`parse_gltf`]: the triangle primitives of node `ni` (if
    /// it has a mesh and is reachable, `world` its matrix), through the
    /// node transform unless skinned. Only the first skin is read.
    fn add_node(
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

    /// Step 4 of [`parse_gltf`]: the merged mesh (with colours when any
    /// primitive has them), morph targets padded to every vertex.
    fn into_mesh(self, ctx: &Ctx) -> Result<(Mesh, GeometryParts), MeshError> {
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
        super::format::refuse_huge_coordinates(&positions, path)?;
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

/// Step 5 of [`parse_gltf`]: skin `skin_idx` (joints, their parents within
/// the skin, inverse bind matrices) with the per-vertex influences of the
/// `nv` vertices; weights not summing to 1 are normalised (and said in
/// `problems`).
fn read_skin(
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

/// The animations of an asset (see [`GltfAsset`]).
struct Animations {
    names: Vec<(String, f32)>,
    nodes: Vec<NodeAnimation>,
    weights: Option<(Vec<f32>, Vec<KeyWeights>)>,
}

/// Step 6 of [`parse_gltf`]: every animation's name and duration, its node
/// (TRS) channels, and the first morph-weights channel that drives
/// `morph_node` (with `nt` targets).
fn read_animations(
    ctx: &Ctx,
    doc: &gltf::Document,
    morph_node: Option<usize>,
    nt: usize,
) -> Result<Animations, MeshError> {
    let mut names = Vec::new();
    let mut nodes = Vec::new();
    let mut weights = None;
    for a in doc.animations() {
        let mut dur = 0.0f32;
        for ch in a.channels() {
            let input = ch.sampler().input();
            let (t, _) = ctx.read_f32(&input, "animation input")?;
            dur = t.iter().copied().fold(dur, f32::max);
            if weights.is_none()
                && ch.target().property() == gltf::animation::Property::MorphTargetWeights
                && Some(ch.target().node().index()) == morph_node
                && nt > 0
            {
                weights = Some(read_weights_channel(ctx, &ch, t, nt)?);
            }
        }
        names.push((a.name().unwrap_or("").to_string(), dur));
        let mut channels = Vec::new();
        for ch in a.channels() {
            if let Some(c) = read_trs_channel(ctx, &a, &ch)? {
                channels.push(c);
            }
        }
        nodes.push(NodeAnimation {
            name: a.name().unwrap_or("").to_string(),
            duration: dur,
            channels,
        });
    }
    Ok(Animations {
        names,
        nodes,
        weights,
    })
}

/// A morph-weights channel with key times `t` as sparse keys: the non-zero
/// weights of each key (the value part of a cubic-spline key).
fn read_weights_channel(
    ctx: &Ctx,
    ch: &gltf::animation::Channel,
    t: Vec<f32>,
    nt: usize,
) -> Result<(Vec<f32>, Vec<KeyWeights>), MeshError> {
    let out = ch.sampler().output();
    let per_key = match ch.sampler().interpolation() {
        gltf::animation::Interpolation::CubicSpline => 3 * nt,
        _ => nt,
    };
    if out.dimensions() != Dimensions::Scalar || Some(out.count()) != t.len().checked_mul(per_key) {
        return Err(ctx.err("morph weights animation output has the wrong size"));
    }
    // Element i is weight i % per_key (of which the value part
    // of a cubic key, off..off + nt) at key i / per_key.
    let off = if per_key == 3 * nt { nt } else { 0 };
    let mut keys = vec![Vec::new(); t.len()];
    let mut put = |i: usize, w: f32| {
        let j = i % per_key;
        if w != 0.0 && (off..off + nt).contains(&j) {
            keys[i / per_key].push(((j - off) as u32, w));
        }
    };
    match ctx.read_sparse_zeros(&out, "animation output")? {
        Some((idx, vals)) => idx.into_iter().zip(vals).for_each(|(i, w)| put(i, w)),
        None => {
            let (w, _) = ctx.read_f32(&out, "animation output")?;
            w.into_iter().enumerate().for_each(|(i, w)| put(i, w));
        }
    }
    Ok((t, keys))
}

/// A translation, rotation or scale channel of animation `a` (`None` for a
/// morph-weights channel); cubic-spline keys keep their values only.
fn read_trs_channel(
    ctx: &Ctx,
    a: &gltf::Animation,
    ch: &gltf::animation::Channel,
) -> Result<Option<NodeChannel>, MeshError> {
    use gltf::animation::Property as P;
    let path = match ch.target().property() {
        P::Translation => TrsPath::Translation,
        P::Rotation => TrsPath::Rotation,
        P::Scale => TrsPath::Scale,
        P::MorphTargetWeights => return Ok(None),
    };
    let (times, _) = ctx.read_f32(&ch.sampler().input(), "animation input")?;
    let (vals, comps) = ctx.read_f32(&ch.sampler().output(), "animation output")?;
    let want = if path == TrsPath::Rotation { 4 } else { 3 };
    let cubic = ch.sampler().interpolation() == gltf::animation::Interpolation::CubicSpline;
    let per_key = if cubic { 3 } else { 1 };
    if comps != want || vals.len() != times.len() * per_key * comps {
        return Err(ctx.err(format!(
            "animation '{}': a channel's output has the wrong size",
            a.name().unwrap_or("")
        )));
    }
    if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
        return Err(ctx.err(format!(
            "animation '{}': key times are not ascending",
            a.name().unwrap_or("")
        )));
    }
    let values = (0..times.len())
        .map(|k| {
            let o = (k * per_key + if cubic { 1 } else { 0 }) * comps;
            let mut v = [0.0f32; 4];
            v[..comps].copy_from_slice(&vals[o..o + comps]);
            v
        })
        .collect();
    let step = ch.sampler().interpolation() == gltf::animation::Interpolation::Step;
    Ok(Some(NodeChannel {
        node: ch.target().node().index(),
        path,
        times,
        values,
        step,
    }))
}

/// Step 7 of [`parse_gltf`]: the scene graph (parents, rest TRS, order,
/// the skin's joint nodes).
fn node_graph(
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

/// Reads a `.gltf` or `.glb` file.
pub fn read_gltf(path: &Path) -> Result<GltfAsset, MeshError> {
    parse_gltf(&crate::util::fsutil::read_bytes(path)?, path)
}

/// Samples one channel at time `t`.
fn sample(ch: &NodeChannel, t: f32) -> [f32; 4] {
    let n = ch.times.len();
    if n == 0 {
        return [0.0, 0.0, 0.0, 1.0];
    }
    let k = ch.times.partition_point(|&x| x <= t);
    if k == 0 {
        return ch.values[0];
    }
    if k >= n || ch.step {
        return ch.values[(k - 1).min(n - 1)];
    }
    let (t0, t1) = (ch.times[k - 1], ch.times[k]);
    let a = if t1 > t0 {
        ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (v0, v1) = (ch.values[k - 1], ch.values[k]);
    if ch.path == TrsPath::Rotation {
        let q0 = glam::Quat::from_array(v0).normalize();
        let q1 = glam::Quat::from_array(v1).normalize();
        q0.slerp(q1, a).to_array()
    } else {
        std::array::from_fn(|i| v0[i] + (v1[i] - v0[i]) * a)
    }
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
    pub fn skinned_sequence(&self, index: usize, fps: f64) -> Result<MeshSequence, MeshError> {
        use glam::{DMat4, DQuat, DVec3};
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
            trs.clone_from(&g.rest);
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
            for &n in &g.order {
                let local = DMat4::from_scale_rotation_translation(trs[n].2, trs[n].1, trs[n].0);
                world[n] = match g.parent[n] {
                    Some(p) => world[p] * local,
                    None => local,
                };
            }
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

    /// World positions of the skin's joints (in skin order) at time `t` of
    /// node animation `index` (linear, slerp or step keys; the rest TRS of
    /// nodes the animation does not drive). `None` without a skin or that
    /// animation. For the joint mapping of rigged characters
    /// (`rig::load::skin_clip`).
    pub fn joint_positions_at(&self, index: usize, t: f32) -> Option<Vec<glam::DVec3>> {
        use glam::{DMat4, DQuat, DVec3};
        self.skin.as_ref()?;
        let anim = self.node_animations.get(index)?;
        let g = &self.graph;
        let mut trs = g.rest.clone();
        for ch in &anim.channels {
            let Some(slot) = trs.get_mut(ch.node) else {
                continue;
            };
            let v = sample(ch, t);
            match ch.path {
                TrsPath::Translation => slot.0 = DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64),
                TrsPath::Rotation => {
                    slot.1 = DQuat::from_xyzw(v[0] as f64, v[1] as f64, v[2] as f64, v[3] as f64)
                        .normalize()
                }
                TrsPath::Scale => slot.2 = DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64),
            }
        }
        let mut world = vec![DMat4::IDENTITY; trs.len()];
        for &n in &g.order {
            let local = DMat4::from_scale_rotation_translation(trs[n].2, trs[n].1, trs[n].0);
            world[n] = match g.parent[n] {
                Some(p) => world[p] * local,
                None => local,
            };
        }
        Some(
            g.skin_joints
                .iter()
                .map(|&jn| world.get(jn).map_or(DVec3::ZERO, |m| m.w_axis.truncate()))
                .collect(),
        )
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
