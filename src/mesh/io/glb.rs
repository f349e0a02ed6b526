//! Binary glTF (`.glb`) writer for mesh sequences: the rest mesh, one morph
//! target per frame (displacement from the rest positions) and a LINEAR
//! morph-weights animation whose key `k` at time `k / fps` has weight 1 on
//! target `k`, so playback shows frame `k` at its time and blends linearly
//! between frames. Valid per the glTF 2.0 spec (POSITION min/max on the base
//! and on every target, animation input min/max, 4-byte aligned views,
//! `byteStride` on the shared target view), checked with the Khronos
//! glTF-Validator in the test suite.

use crate::mesh::{MeshError, MeshSequence};
use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use std::collections::BTreeMap;
use std::path::Path;

struct Bin {
    data: Vec<u8>,
}

impl Bin {
    fn align(&mut self) {
        while self.data.len() % 4 != 0 {
            self.data.push(0);
        }
    }
    fn push_f32s(&mut self, v: impl Iterator<Item = f32>) -> (usize, usize) {
        self.align();
        let start = self.data.len();
        for x in v {
            self.data.extend_from_slice(&x.to_le_bytes());
        }
        (start, self.data.len() - start)
    }
    fn push_u32s(&mut self, v: impl Iterator<Item = u32>) -> (usize, usize) {
        self.align();
        let start = self.data.len();
        for x in v {
            self.data.extend_from_slice(&x.to_le_bytes());
        }
        (start, self.data.len() - start)
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

#[allow(clippy::too_many_arguments)]
fn accessor(
    root: &mut json::Root,
    view: json::Index<json::buffer::View>,
    offset: usize,
    count: usize,
    ct: json::accessor::ComponentType,
    ty: json::accessor::Type,
    minmax: Option<(Vec<f32>, Vec<f32>)>,
) -> json::Index<json::Accessor> {
    let (min, max) = match minmax {
        Some((a, b)) => (Some(json::Value::from(a)), Some(json::Value::from(b))),
        None => (None, None),
    };
    root.push(json::Accessor {
        buffer_view: Some(view),
        byte_offset: Some(USize64(offset as u64)),
        count: USize64(count as u64),
        component_type: Valid(json::accessor::GenericComponentType(ct)),
        extensions: None,
        extras: Default::default(),
        type_: Valid(ty),
        min,
        max,
        name: None,
        normalized: false,
        sparse: None,
    })
}

fn bounds3(p: impl Iterator<Item = [f64; 3]>) -> (Vec<f32>, Vec<f32>) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    let mut any = false;
    for v in p {
        any = true;
        for k in 0..3 {
            lo[k] = lo[k].min(v[k] as f32);
            hi[k] = hi[k].max(v[k] as f32);
        }
    }
    if !any {
        return (vec![0.0; 3], vec![0.0; 3]);
    }
    (lo.to_vec(), hi.to_vec())
}

/// Encodes a sequence as GLB bytes. `fps` is used when the sequence has none
/// (default 30).
pub fn encode_glb(seq: &MeshSequence, fps: Option<f64>) -> Result<Vec<u8>, MeshError> {
    use json::accessor::{ComponentType as C, Type as T};
    let mesh = seq.mesh();
    let base = mesh.positions();
    let nv = base.len();
    let frames = seq.frame_count();
    let fps = seq
        .fps
        .or(fps)
        .filter(|f| f.is_finite() && *f > 0.0)
        .unwrap_or(30.0);
    let mut root = json::Root {
        asset: json::Asset {
            generator: Some("surfmotion".into()),
            ..Default::default()
        },
        ..Default::default()
    };
    let mut bin = Bin { data: Vec::new() };

    let idx = bin.push_u32s(mesh.triangles().iter().flatten().copied());
    let idx_view = view(
        &mut root,
        idx,
        Some(json::buffer::Target::ElementArrayBuffer),
        None,
    );
    let idx_acc = accessor(
        &mut root,
        idx_view,
        0,
        mesh.triangle_count() * 3,
        C::U32,
        T::Scalar,
        None,
    );

    let pos = bin.push_f32s(base.iter().flatten().map(|&v| v as f32));
    let pos_view = view(
        &mut root,
        pos,
        Some(json::buffer::Target::ArrayBuffer),
        None,
    );
    let pos_acc = accessor(
        &mut root,
        pos_view,
        0,
        nv,
        C::F32,
        T::Vec3,
        Some(bounds3(base.iter().copied())),
    );

    let mut attributes = BTreeMap::new();
    attributes.insert(Valid(json::mesh::Semantic::Positions), pos_acc);
    if let Some(c) = mesh.colors() {
        let cv = bin.push_f32s(c.iter().flatten().map(|&v| v as f32));
        let cview = view(&mut root, cv, Some(json::buffer::Target::ArrayBuffer), None);
        let cacc = accessor(&mut root, cview, 0, nv, C::F32, T::Vec3, None);
        attributes.insert(Valid(json::mesh::Semantic::Colors(0)), cacc);
    }

    let animate = frames > 1 || (frames == 1 && seq.frame(0) != base);
    let mut targets = None;
    let mut weights = None;
    if animate {
        let disp = |f: usize| {
            seq.frame(f)
                .iter()
                .zip(base)
                .map(|(p, b)| [p[0] - b[0], p[1] - b[1], p[2] - b[2]])
        };
        let (start, _) = bin.push_f32s(std::iter::empty());
        for f in 0..frames {
            bin.push_f32s(disp(f).flatten().map(|v| v as f32));
        }
        let len = bin.data.len() - start;
        let tview = view(
            &mut root,
            (start, len),
            Some(json::buffer::Target::ArrayBuffer),
            Some(12),
        );
        let mut t = Vec::with_capacity(frames);
        for f in 0..frames {
            let acc = accessor(
                &mut root,
                tview,
                f * nv * 12,
                nv,
                C::F32,
                T::Vec3,
                Some(bounds3(disp(f))),
            );
            t.push(json::mesh::MorphTarget {
                positions: Some(acc),
                normals: None,
                tangents: None,
            });
        }
        targets = Some(t);
        weights = Some(vec![0.0f32; frames]);
    }
    let primitive = json::mesh::Primitive {
        attributes,
        extensions: None,
        extras: Default::default(),
        indices: Some(idx_acc),
        material: None,
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
        ..Default::default()
    });
    let scene = root.push(json::Scene {
        extensions: None,
        extras: Default::default(),
        name: None,
        nodes: vec![node],
    });
    root.scene = Some(scene);

    if animate {
        let times: Vec<f32> = (0..frames).map(|k| (k as f64 / fps) as f32).collect();
        let tv = bin.push_f32s(times.iter().copied());
        let tview = view(&mut root, tv, None, None);
        let last = *times.last().unwrap_or(&0.0);
        let tacc = accessor(
            &mut root,
            tview,
            0,
            frames,
            C::F32,
            T::Scalar,
            Some((vec![0.0], vec![last])),
        );
        let wv = bin.push_f32s(
            (0..frames * frames).map(|i| if i / frames == i % frames { 1.0 } else { 0.0 }),
        );
        let wview = view(&mut root, wv, None, None);
        let wacc = accessor(
            &mut root,
            wview,
            0,
            frames * frames,
            C::F32,
            T::Scalar,
            None,
        );
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
            format!("{total} bytes: too large for GLB (4 GiB)"),
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

/// Writes a sequence as GLB, atomically.
pub fn write_glb(seq: &MeshSequence, fps: Option<f64>, path: &Path) -> Result<(), MeshError> {
    let bytes = encode_glb(seq, fps).map_err(|e| match e {
        MeshError::Invalid { msg, .. } => MeshError::invalid(path, msg),
        e => e,
    })?;
    crate::fsutil::write_bytes_atomic(path, &bytes)?;
    Ok(())
}
