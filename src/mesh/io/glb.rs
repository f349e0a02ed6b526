//! Binary glTF (`.glb`) writer for mesh sequences: the rest mesh with
//! area-weighted vertex normals and a plain PBR material, one morph target
//! per frame (POSITION and NORMAL displacements from the rest mesh) and a
//! LINEAR morph-weights animation whose key `k` at time `k / fps` has weight
//! `w` on target `k` (1, or 2 in quantised files, see below), so playback
//! shows frame `k` at its time and blends linearly between frames.
//!
//! Valid per the glTF 2.0 spec (POSITION min/max on the base and on every
//! target, animation input min/max, 4-byte aligned views and elements,
//! `byteStride` on the shared target views, unit base normals), checked with
//! the Khronos glTF-Validator in the test suite. The weights animation's
//! output is a sparse accessor (one non-zero per key), so it costs `8·F`
//! bytes instead of `4·F²` for `F` frames.
//!
//! **Quantised files** ([`GlbOptions::quantize`], `KHR_mesh_quantization`,
//! listed in `extensionsRequired`): positions and position displacements are
//! `SHORT` integers on one uniform grid of step `s`, dequantised by the
//! node's transform `p = t + s·q` (uniform scale, so normals keep their
//! direction; the extension's recommendation); the base normals are
//! normalized `SHORT`, the per-frame normal displacements normalized `BYTE`
//! (4-byte stride). A normal displacement lies in `[-2, 2]` per component (a
//! normal can turn over) while normalized types hold `[-1, 1]`, so every
//! target stores half its displacement and the animation uses weight 2:
//! `base + 2·(Δ/2)` is the frame. The grid step is chosen so that the rest
//! mesh and every halved displacement fit in 16 bits: the error of a vertex
//! is at most `s` per axis. 12 bytes per vertex and frame instead of 24.

use crate::mesh::normals::vertex_normals_into;
use crate::mesh::{MeshError, MeshSequence};
use crate::util::fsutil::FileError;
use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use std::collections::BTreeMap;
use std::path::Path;

/// Options of the GLB writer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GlbOptions {
    /// Write vertex normals: the rest mesh's `NORMAL` and, per frame, morph
    /// target `NORMAL` displacements, so viewers shade smoothly.
    /// Default value: `true`.
    pub normals: bool,
    /// Quantise with `KHR_mesh_quantization` (a required extension: viewers
    /// without it refuse the file): 16-bit positions and displacements on a
    /// uniform grid, 8-bit normal displacements; half the size, error at most
    /// one grid step per axis (see the module docs). Default value: `false`.
    pub quantize: bool,
}

impl GlbOptions {
    /// Normals on, floats (the most widely readable file).
    pub const DEFAULT: GlbOptions = GlbOptions {
        normals: true,
        quantize: false,
    };
}

impl Default for GlbOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The most frames one GLB holds: the weights animation has `F²` values,
/// addressed by 32-bit sparse indices.
pub(crate) const MAX_FRAMES: usize = 65_535;

/// The `extensionsRequired` entry of quantised files.
pub(crate) const KHR_MESH_QUANTIZATION: &str = "KHR_mesh_quantization";

struct Bin {
    data: Vec<u8>,
}

impl Bin {
    fn align(&mut self) {
        while self.data.len() % 4 != 0 {
            self.data.push(0);
        }
    }
    /// Aligns and returns the start of the next region.
    fn start(&mut self) -> usize {
        self.align();
        self.data.len()
    }
    fn region(&self, start: usize) -> (usize, usize) {
        (start, self.data.len() - start)
    }
    fn f32s(&mut self, v: impl Iterator<Item = f32>) {
        for x in v {
            self.data.extend_from_slice(&x.to_le_bytes());
        }
    }
    fn push_f32s(&mut self, v: impl Iterator<Item = f32>) -> (usize, usize) {
        let s = self.start();
        self.f32s(v);
        self.region(s)
    }
    fn push_u32s(&mut self, v: impl Iterator<Item = u32>) -> (usize, usize) {
        let s = self.start();
        for x in v {
            self.data.extend_from_slice(&x.to_le_bytes());
        }
        self.region(s)
    }
    /// Three i16 and two bytes of padding (an 8-byte element).
    fn i16x3(&mut self, v: [i16; 3]) {
        for x in v {
            self.data.extend_from_slice(&x.to_le_bytes());
        }
        self.data.extend_from_slice(&[0, 0]);
    }
    /// Three i8 and one byte of padding (a 4-byte element).
    fn i8x3(&mut self, v: [i8; 3]) {
        self.data
            .extend_from_slice(&[v[0] as u8, v[1] as u8, v[2] as u8, 0]);
    }
}

fn view(
    root: &mut json::Root,
    (offset, len): (usize, usize),
    target: Option<json::buffer::Target>,
    stride: Option<usize>,
) -> json::Index<json::buffer::View> {
    root.push(json::buffer::View {
        buffer: json::Index::new(0),
        byte_length: USize64(len as u64),
        byte_offset: Some(USize64(offset as u64)),
        byte_stride: stride.map(json::buffer::Stride),
        name: None,
        target: target.map(Valid),
        extensions: None,
        extras: Default::default(),
    })
}

/// How an accessor's components are stored.
#[derive(Clone, Copy)]
struct Storage {
    ct: json::accessor::ComponentType,
    normalized: bool,
}

const fn storage(ct: json::accessor::ComponentType, normalized: bool) -> Storage {
    Storage { ct, normalized }
}

const F32: Storage = storage(json::accessor::ComponentType::F32, false);
const U32: Storage = storage(json::accessor::ComponentType::U32, false);
const I16: Storage = storage(json::accessor::ComponentType::I16, false);
const I16_NORM: Storage = storage(json::accessor::ComponentType::I16, true);
const I8_NORM: Storage = storage(json::accessor::ComponentType::I8, true);

#[allow(clippy::too_many_arguments)]
fn accessor(
    root: &mut json::Root,
    view: Option<json::Index<json::buffer::View>>,
    offset: usize,
    count: usize,
    storage: Storage,
    ty: json::accessor::Type,
    minmax: Option<(json::Value, json::Value)>,
) -> json::Index<json::Accessor> {
    let (min, max) = match minmax {
        Some((a, b)) => (Some(a), Some(b)),
        None => (None, None),
    };
    root.push(json::Accessor {
        buffer_view: view,
        byte_offset: view.map(|_| USize64(offset as u64)),
        count: USize64(count as u64),
        component_type: Valid(json::accessor::GenericComponentType(storage.ct)),
        extensions: None,
        extras: Default::default(),
        type_: Valid(ty),
        min,
        max,
        name: None,
        normalized: storage.normalized,
        sparse: None,
    })
}

/// Per-axis bounds of float values, as JSON (zeros when empty).
fn bounds_f32(p: impl Iterator<Item = [f32; 3]>) -> (json::Value, json::Value) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let mut any = false;
    for v in p {
        any = true;
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    if !any {
        return (
            json::Value::from(vec![0.0f32; 3]),
            json::Value::from(vec![0.0f32; 3]),
        );
    }
    (
        json::Value::from(lo.to_vec()),
        json::Value::from(hi.to_vec()),
    )
}

/// Per-axis bounds of integer values, as JSON integers (zeros when empty).
fn bounds_i16(p: impl Iterator<Item = [i16; 3]>) -> (json::Value, json::Value) {
    let mut lo = [i16::MAX; 3];
    let mut hi = [i16::MIN; 3];
    let mut any = false;
    for v in p {
        any = true;
        for k in 0..3 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    if !any {
        (lo, hi) = ([0; 3], [0; 3]);
    }
    (
        json::Value::from(lo.to_vec()),
        json::Value::from(hi.to_vec()),
    )
}

fn f32x3(v: [f64; 3]) -> [f32; 3] {
    v.map(|x| x as f32)
}

/// The uniform grid of a quantised file: world `p = t + s·q`.
#[derive(Debug, Clone, Copy)]
struct Grid {
    /// Translation (the centre of the rest mesh's box).
    t: [f32; 3],
    /// Step (uniform scale).
    s: f32,
    /// Weight of every key; displacements are stored divided by it.
    w: f64,
}

impl Grid {
    fn new(seq: &MeshSequence, w: f64) -> Grid {
        let base = seq.mesh().positions();
        let b = seq.mesh().bounds();
        let t = f32x3(std::array::from_fn(|k| 0.5 * (b.min[k] + b.max[k])));
        let mut reach = 0.0f64;
        for p in base {
            for k in 0..3 {
                reach = reach.max((p[k] - t[k] as f64).abs());
            }
        }
        let mut disp = 0.0f64;
        for f in 0..seq.frame_count() {
            for (p, q) in seq.frame(f).iter().zip(base) {
                for k in 0..3 {
                    disp = disp.max((p[k] - q[k]).abs());
                }
            }
        }
        // Headroom for the rounding of the base and of `s` to f32.
        let need = reach.max(disp / w) / (32767.0 - 1.0);
        let s = if need.is_finite() && need > 0.0 {
            need as f32 * (1.0 + 1e-6)
        } else {
            1.0
        };
        Grid { t, s, w }
    }

    fn q(x: f64) -> i16 {
        x.round().clamp(-32767.0, 32767.0) as i16
    }

    /// Rest position on the grid.
    fn base(&self, p: [f64; 3]) -> [i16; 3] {
        std::array::from_fn(|k| Self::q((p[k] - self.t[k] as f64) / self.s as f64))
    }

    /// Stored displacement of a frame position from its quantised rest
    /// position (rounded against the quantised base, so errors do not add).
    fn disp(&self, p: [f64; 3], qb: [i16; 3]) -> [i16; 3] {
        std::array::from_fn(|k| {
            let u = (p[k] - self.t[k] as f64) / self.s as f64;
            Self::q((u - qb[k] as f64) / self.w)
        })
    }
}

fn snorm16(x: f64) -> i16 {
    (x.clamp(-1.0, 1.0) * 32767.0).round() as i16
}

fn snorm8(x: f64) -> i8 {
    (x.clamp(-1.0, 1.0) * 127.0).round() as i8
}

/// Vertex normals of `p` with a fallback where undefined.
pub(super) fn normals_or(
    p: &[[f64; 3]],
    tris: &[[u32; 3]],
    fallback: &[[f64; 3]],
    out: &mut Vec<[f64; 3]>,
) {
    vertex_normals_into(p, tris, out);
    for (n, f) in out.iter_mut().zip(fallback) {
        if *n == [0.0; 3] {
            *n = *f;
        }
    }
}

/// Encodes a sequence as GLB bytes with the default options. `fps` is used
/// when the sequence has none (default 30).
pub fn encode_glb(seq: &MeshSequence, fps: Option<f64>) -> Result<Vec<u8>, MeshError> {
    encode_glb_with(seq, fps, &GlbOptions::DEFAULT)
}

/// Encodes a sequence as GLB bytes. `fps` is used when the sequence has none
/// (default 30). Memory: the output plus one frame of normals.
pub fn encode_glb_with(
    seq: &MeshSequence,
    fps: Option<f64>,
    opts: &GlbOptions,
) -> Result<Vec<u8>, MeshError> {
    let mesh = seq.mesh();
    let frames = seq.frame_count();
    let fps = seq
        .fps
        .or(fps)
        .filter(|f| f.is_finite() && *f > 0.0)
        .unwrap_or(30.0);
    let animate = frames > 1 || (frames == 1 && seq.frame(0) != mesh.positions());
    refuse_unencodable(mesh.vertex_count(), mesh.triangles().is_empty(), frames)?;
    let grid = opts
        .quantize
        .then(|| Grid::new(seq, if opts.normals && animate { 2.0 } else { 1.0 }));
    let key_weight = grid.map_or(1.0, |g| g.w) as f32;
    let mut e = Encoder::new(grid.is_some());
    let indices = e.indices(mesh);
    let rest = e.rest_attributes(mesh, grid, opts.normals);
    let targets = animate.then(|| e.morph_targets(seq, grid, &rest, opts.normals));
    let node = e.scene(mesh, rest.attributes, indices, targets, grid);
    if animate {
        e.weights_animation(frames, fps, key_weight, node);
    }
    e.finish()
}

/// Step 1 of [`encode_glb_with`]: what no GLB can hold, refused (glTF has
/// no empty accessor, count ≥ 1: a mesh without triangles was written and
/// the validator rejected it; more than [`MAX_FRAMES`] morph targets).
fn refuse_unencodable(vertices: usize, no_triangles: bool, frames: usize) -> Result<(), MeshError> {
    if no_triangles {
        return Err(MeshError::invalid(
            Path::new("<glb>"),
            format!(
                "a mesh of {vertices} vertices and no triangles: a GLB needs triangles (write .ply or .obj for points)"
            ),
        ));
    }
    if frames > MAX_FRAMES {
        return Err(MeshError::invalid(
            Path::new("<glb>"),
            format!("{frames} frames: a GLB holds at most {MAX_FRAMES} (one morph target each)"),
        ));
    }
    Ok(())
}

/// A GLB being built: the JSON document and the binary chunk, pushed to in
/// the order the file lays them out.
struct Encoder {
    root: json::Root,
    bin: Bin,
}

/// The rest mesh's vertex attributes, with what the morph targets are
/// displacements from: the quantised rest positions (empty without a grid)
/// and the rest normals (empty without normals).
struct RestAttributes {
    attributes:
        BTreeMap<json::validation::Checked<json::mesh::Semantic>, json::Index<json::Accessor>>,
    qbase: Vec<[i16; 3]>,
    normals: Vec<[f64; 3]>,
}

const ARRAY: Option<json::buffer::Target> = Some(json::buffer::Target::ArrayBuffer);

impl Encoder {
    fn new(quantized: bool) -> Encoder {
        let mut root = json::Root {
            asset: json::Asset {
                generator: Some("surfmotion".into()),
                ..Default::default()
            },
            ..Default::default()
        };
        if quantized {
            root.extensions_used = vec![KHR_MESH_QUANTIZATION.into()];
            root.extensions_required = vec![KHR_MESH_QUANTIZATION.into()];
        }
        Encoder {
            root,
            bin: Bin { data: Vec::new() },
        }
    }

    /// Step 2: the triangle indices.
    fn indices(&mut self, mesh: &crate::mesh::Mesh) -> json::Index<json::Accessor> {
        use json::accessor::Type as T;
        let idx = self
            .bin
            .push_u32s(mesh.triangles().iter().flatten().copied());
        let idx_view = view(
            &mut self.root,
            idx,
            Some(json::buffer::Target::ElementArrayBuffer),
            None,
        );
        accessor(
            &mut self.root,
            Some(idx_view),
            0,
            mesh.triangle_count() * 3,
            U32,
            T::Scalar,
            None,
        )
    }

    /// Step 3: rest positions (on the grid when quantised), rest normals
    /// (unit; +z where a vertex has no area) and vertex colours.
    fn rest_attributes(
        &mut self,
        mesh: &crate::mesh::Mesh,
        grid: Option<Grid>,
        normals: bool,
    ) -> RestAttributes {
        use json::accessor::Type as T;
        let (root, bin) = (&mut self.root, &mut self.bin);
        let base = mesh.positions();
        let nv = base.len();
        let qbase: Vec<[i16; 3]> =
            grid.map_or_else(Vec::new, |g| base.iter().map(|p| g.base(*p)).collect());
        let pos_acc = match grid {
            Some(_) => {
                let s = bin.start();
                qbase.iter().for_each(|q| bin.i16x3(*q));
                let v = view(root, bin.region(s), ARRAY, Some(8));
                let mm = bounds_i16(qbase.iter().copied());
                accessor(root, Some(v), 0, nv, I16, T::Vec3, Some(mm))
            }
            None => {
                let r = bin.push_f32s(base.iter().flatten().map(|&v| v as f32));
                let v = view(root, r, ARRAY, None);
                let mm = bounds_f32(base.iter().map(|p| f32x3(*p)));
                accessor(root, Some(v), 0, nv, F32, T::Vec3, Some(mm))
            }
        };
        let mut attributes = BTreeMap::new();
        attributes.insert(Valid(json::mesh::Semantic::Positions), pos_acc);
        let mut base_normals = Vec::new();
        if normals {
            normals_or(
                base,
                mesh.triangles(),
                &vec![[0.0, 0.0, 1.0]; nv],
                &mut base_normals,
            );
            let acc = match grid {
                Some(_) => {
                    let s = bin.start();
                    base_normals.iter().for_each(|n| bin.i16x3(n.map(snorm16)));
                    let v = view(root, bin.region(s), ARRAY, Some(8));
                    accessor(root, Some(v), 0, nv, I16_NORM, T::Vec3, None)
                }
                None => {
                    let r = bin.push_f32s(base_normals.iter().flatten().map(|&v| v as f32));
                    let v = view(root, r, ARRAY, None);
                    accessor(root, Some(v), 0, nv, F32, T::Vec3, None)
                }
            };
            attributes.insert(Valid(json::mesh::Semantic::Normals), acc);
        }
        if let Some(c) = mesh.colors() {
            let cv = bin.push_f32s(c.iter().flatten().map(|&v| v as f32));
            let cview = view(root, cv, ARRAY, None);
            let cacc = accessor(root, Some(cview), 0, nv, F32, T::Vec3, None);
            attributes.insert(Valid(json::mesh::Semantic::Colors(0)), cacc);
        }
        RestAttributes {
            attributes,
            qbase,
            normals: base_normals,
        }
    }

    /// Step 4: one morph target per frame: the position displacements of
    /// every frame in one view, the normal displacements in another, an
    /// accessor pair per frame into them.
    fn morph_targets(
        &mut self,
        seq: &MeshSequence,
        grid: Option<Grid>,
        rest: &RestAttributes,
        normals: bool,
    ) -> Vec<json::mesh::MorphTarget> {
        use json::accessor::Type as T;
        let (root, bin) = (&mut self.root, &mut self.bin);
        let base = seq.mesh().positions();
        let tris = seq.mesh().triangles();
        let nv = base.len();
        let frames = seq.frame_count();
        let disp = |f: usize| {
            seq.frame(f)
                .iter()
                .zip(base)
                .map(|(p, b)| [p[0] - b[0], p[1] - b[1], p[2] - b[2]])
        };
        let s = bin.start();
        let mut pos_bounds = Vec::with_capacity(frames);
        for f in 0..frames {
            match grid {
                Some(g) => {
                    let start = bin.data.len();
                    for (p, qb) in seq.frame(f).iter().zip(&rest.qbase) {
                        bin.i16x3(g.disp(*p, *qb));
                    }
                    let q = bin.data[start..]
                        .chunks_exact(8)
                        .map(|c| [0, 2, 4].map(|o| i16::from_le_bytes([c[o], c[o + 1]])));
                    pos_bounds.push(bounds_i16(q));
                }
                None => {
                    bin.f32s(disp(f).flatten().map(|v| v as f32));
                    pos_bounds.push(bounds_f32(disp(f).map(f32x3)));
                }
            }
        }
        let (pstride, pstorage) = if grid.is_some() { (8, I16) } else { (12, F32) };
        let pview = view(root, bin.region(s), ARRAY, Some(pstride));
        let nview = if normals {
            let s = bin.start();
            let mut n = Vec::new();
            for f in 0..frames {
                normals_or(seq.frame(f), tris, &rest.normals, &mut n);
                for (a, b) in n.iter().zip(&rest.normals) {
                    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
                    match grid {
                        Some(g) => bin.i8x3(d.map(|x| snorm8(x / g.w))),
                        None => bin.f32s(d.iter().map(|&x| x as f32)),
                    }
                }
            }
            let stride = if grid.is_some() { 4 } else { 12 };
            Some(view(root, bin.region(s), ARRAY, Some(stride)))
        } else {
            None
        };
        let nstorage = if grid.is_some() { I8_NORM } else { F32 };
        let nstride = if grid.is_some() { 4 } else { 12 };
        let mut t = Vec::with_capacity(frames);
        for (f, mm) in pos_bounds.into_iter().enumerate() {
            let positions = accessor(
                root,
                Some(pview),
                f * nv * pstride,
                nv,
                pstorage,
                T::Vec3,
                Some(mm),
            );
            let normals = nview
                .map(|v| accessor(root, Some(v), f * nv * nstride, nv, nstorage, T::Vec3, None));
            t.push(json::mesh::MorphTarget {
                positions: Some(positions),
                normals,
                tangents: None,
            });
        }
        t
    }

    /// Step 5: the material, the mesh (with zero weights when animated),
    /// its node (the grid's transform when quantised) and the scene.
    /// Returns the node.
    fn scene(
        &mut self,
        mesh: &crate::mesh::Mesh,
        attributes: BTreeMap<
            json::validation::Checked<json::mesh::Semantic>,
            json::Index<json::Accessor>,
        >,
        indices: json::Index<json::Accessor>,
        targets: Option<Vec<json::mesh::MorphTarget>>,
        grid: Option<Grid>,
    ) -> json::Index<json::Node> {
        let root = &mut self.root;
        let material = root.push(json::Material {
            name: Some("surfmotion".into()),
            pbr_metallic_roughness: json::material::PbrMetallicRoughness {
                // Vertex colours multiply the base colour: keep them as they are.
                base_color_factor: json::material::PbrBaseColorFactor(if mesh.colors().is_some() {
                    [1.0; 4]
                } else {
                    [0.8, 0.8, 0.8, 1.0]
                }),
                metallic_factor: json::material::StrengthFactor(0.0),
                roughness_factor: json::material::StrengthFactor(0.6),
                ..Default::default()
            },
            ..Default::default()
        });
        let weights = targets.as_ref().map(|t| vec![0.0f32; t.len()]);
        let primitive = json::mesh::Primitive {
            attributes,
            extensions: None,
            extras: Default::default(),
            indices: Some(indices),
            material: Some(material),
            mode: Valid(json::mesh::Mode::Triangles),
            targets,
        };
        let mesh_idx = root.push(json::Mesh {
            extensions: None,
            extras: Default::default(),
            name: Some("surfmotion".into()),
            primitives: vec![primitive],
            weights,
        });
        let node = root.push(json::Node {
            mesh: Some(mesh_idx),
            name: Some("character".into()),
            translation: grid.map(|g| g.t),
            scale: grid.map(|g| [g.s; 3]),
            ..Default::default()
        });
        let scene = root.push(json::Scene {
            extensions: None,
            extras: Default::default(),
            name: None,
            nodes: vec![node],
        });
        root.scene = Some(scene);
        node
    }

    /// Step 6: the morph-weights animation: key `k` at `k / fps`, its
    /// output F keys of F weights, zero but for `key_weight` at (k, k): a
    /// sparse accessor without a view (zeros) and F substitutions.
    fn weights_animation(
        &mut self,
        frames: usize,
        fps: f64,
        key_weight: f32,
        node: json::Index<json::Node>,
    ) {
        use json::accessor::Type as T;
        let (root, bin) = (&mut self.root, &mut self.bin);
        let times: Vec<f32> = (0..frames).map(|k| (k as f64 / fps) as f32).collect();
        let tv = bin.push_f32s(times.iter().copied());
        let tview = view(root, tv, None, None);
        let last = *times.last().unwrap_or(&0.0);
        let tacc = accessor(
            root,
            Some(tview),
            0,
            frames,
            F32,
            T::Scalar,
            Some((
                json::Value::from(vec![0.0f32]),
                json::Value::from(vec![last]),
            )),
        );
        let iv = bin.push_u32s((0..frames).map(|k| (k * frames + k) as u32));
        let iview = view(root, iv, None, None);
        let vv = bin.push_f32s(std::iter::repeat_n(key_weight, frames));
        let vview = view(root, vv, None, None);
        let wacc = accessor(root, None, 0, frames * frames, F32, T::Scalar, None);
        root.accessors[wacc.value()].sparse = Some(json::accessor::sparse::Sparse {
            count: USize64(frames as u64),
            indices: json::accessor::sparse::Indices {
                buffer_view: iview,
                byte_offset: USize64(0),
                component_type: Valid(json::accessor::IndexComponentType(
                    json::accessor::ComponentType::U32,
                )),
                extensions: None,
                extras: Default::default(),
            },
            values: json::accessor::sparse::Values {
                buffer_view: vview,
                byte_offset: USize64(0),
                extensions: None,
                extras: Default::default(),
            },
            extensions: None,
            extras: Default::default(),
        });
        let sampler = json::animation::Sampler {
            extensions: None,
            extras: Default::default(),
            input: tacc,
            interpolation: Valid(json::animation::Interpolation::Linear),
            output: wacc,
        };
        root.push(json::Animation {
            extensions: None,
            extras: Default::default(),
            channels: vec![json::animation::Channel {
                sampler: json::Index::new(0),
                target: json::animation::Target {
                    extensions: None,
                    extras: Default::default(),
                    node,
                    path: Valid(json::animation::Property::MorphTargetWeights),
                },
                extensions: None,
                extras: Default::default(),
            }],
            name: Some("sequence".into()),
            samplers: vec![sampler],
        });
    }

    /// Step 7: the buffer, then the container: header, JSON chunk (padded
    /// with spaces), binary chunk; refused beyond GLB's 4 GiB.
    fn finish(mut self) -> Result<Vec<u8>, MeshError> {
        let (root, bin) = (&mut self.root, &mut self.bin);
        bin.align();
        root.push(json::Buffer {
            byte_length: USize64(bin.data.len() as u64),
            name: None,
            uri: None,
            extensions: None,
            extras: Default::default(),
        });
        let mut js = json::serialize::to_vec(&root)
            .map_err(|e| MeshError::invalid(Path::new("<glb>"), e.to_string()))?;
        while js.len() % 4 != 0 {
            js.push(b' ');
        }
        let total = 12 + 8 + js.len() + 8 + bin.data.len();
        if total > u32::MAX as usize {
            return Err(MeshError::invalid(
                Path::new("<glb>"),
                format!(
                    "{total} bytes: too large for GLB (4 GiB); quantise (`GlbOptions::quantize`), \
                     leave out normals (--glb-no-normals) or split the sequence"
                ),
            ));
        }
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(js.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&js);
        out.extend_from_slice(&(bin.data.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin.data);
        Ok(out)
    }
}

/// Writes a sequence as GLB with the default options, atomically.
pub fn write_glb(seq: &MeshSequence, fps: Option<f64>, path: &Path) -> Result<(), MeshError> {
    write_glb_with(seq, fps, &GlbOptions::DEFAULT, path)
}

/// Writes a sequence as GLB, atomically.
pub fn write_glb_with(
    seq: &MeshSequence,
    fps: Option<f64>,
    opts: &GlbOptions,
    path: &Path,
) -> Result<(), MeshError> {
    let bytes = encode_glb_with(seq, fps, opts).map_err(|e| match e {
        MeshError::File(FileError::Invalid { msg, .. }) => MeshError::invalid(path, msg),
        e => e,
    })?;
    crate::util::fsutil::write_bytes_atomic(path, &bytes)?;
    Ok(())
}
