//! GLB output (issue 18, item 6): per-frame normals, a material, the
//! quantised (`KHR_mesh_quantization`) option, a sparse weights animation,
//! and the project's reader reading all of it back. Synthetic sequences, so
//! these run without `../shared`; the Khronos validator and the real-data
//! figures are in `tests/mesh_io.rs`.

use crate::common;

use glam::{DQuat, DVec3};
use std::path::Path;
use surfmotion::mesh::io::glb::{GlbOptions, encode_glb_with};
use surfmotion::mesh::io::gltf::{GltfAsset, parse_gltf};
use surfmotion::mesh::normals::vertex_normals;
use surfmotion::mesh::{Mesh, MeshSequence};

/// A closed ellipsoid (semi-axes 0.3, 0.9, 0.2 m: a body-sized blob),
/// triangles counter-clockwise from outside.
fn ellipsoid(rings: u32, segments: u32) -> Mesh {
    let mut p = vec![[0.0, 0.9, 0.0]];
    for i in 1..rings {
        let th = std::f64::consts::PI * i as f64 / rings as f64;
        for j in 0..segments {
            let ph = std::f64::consts::TAU * j as f64 / segments as f64;
            p.push([
                0.3 * th.sin() * ph.cos(),
                0.9 * th.cos(),
                0.2 * th.sin() * ph.sin(),
            ]);
        }
    }
    p.push([0.0, -0.9, 0.0]);
    let south = p.len() as u32 - 1;
    let at = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let mut t = Vec::new();
    for j in 0..segments {
        t.push([0, at(1, j + 1), at(1, j)]);
        t.push([south, at(rings - 1, j), at(rings - 1, j + 1)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            t.push([a, b, d]);
            t.push([a, d, c]);
        }
    }
    let m = Mesh::new(p, t).unwrap();
    assert!(
        surfmotion::mesh::measure::volume(m.positions(), m.triangles()) > 0.0,
        "the fixture must face outward"
    );
    m
}

/// The ellipsoid turning a full circle about +y and about +x while it
/// travels `travel` metres along x: every normal turns over at some frame
/// (normal changes of length 2, the case 8-bit normalized storage cannot
/// hold without the halving), and the displacements exceed the mesh.
fn tumbling(frames: usize, travel: f64) -> MeshSequence {
    let m = ellipsoid(16, 24);
    let mut all = Vec::new();
    for f in 0..frames {
        let a = std::f64::consts::TAU * f as f64 / frames as f64;
        let q = DQuat::from_rotation_y(a) * DQuat::from_rotation_x(0.5 * a);
        let shift = DVec3::new(travel * f as f64 / frames as f64, 0.1, 0.0);
        all.extend(
            m.positions()
                .iter()
                .map(|p| (q * DVec3::from_array(*p) + shift).to_array()),
        );
    }
    MeshSequence::new(m, all, Some(30.0)).unwrap()
}

fn encode(seq: &MeshSequence, quantize: bool) -> (Vec<u8>, GltfAsset) {
    let bytes = encode_glb_with(
        seq,
        None,
        &GlbOptions {
            quantize,
            ..Default::default()
        },
    )
    .unwrap();
    let asset = parse_gltf(&bytes, Path::new("t.glb")).unwrap();
    (bytes, asset)
}

/// The JSON chunk of a GLB.
fn json_of(glb: &[u8]) -> serde_json::Value {
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&glb[20..20 + len]).unwrap()
}

fn max_error(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| DVec3::from_array(*p).distance(DVec3::from_array(*q)))
        .fold(0.0, f64::max)
}

/// Largest angle (radians) between the normals a reader gets for each key
/// and the normals of the positions it gets for that key.
fn normal_disagreement(asset: &GltfAsset) -> f64 {
    let seq = asset.to_sequence().unwrap();
    let mut worst = 0.0f64;
    for k in 0..seq.frame_count() {
        let got = asset.key_normals(k).unwrap();
        let want = vertex_normals(seq.frame(k), seq.mesh().triangles());
        for (g, w) in got.iter().zip(&want) {
            let c = DVec3::from_array(*g)
                .dot(DVec3::from_array(*w))
                .clamp(-1.0, 1.0);
            worst = worst.max(c.acos());
        }
    }
    worst
}

#[test]
fn glb_has_per_frame_normals_and_a_pbr_material() {
    let seq = tumbling(12, 0.5);
    let (bytes, asset) = encode(&seq, false);
    let js = json_of(&bytes);
    let prim = &js["meshes"][0]["primitives"][0];
    assert!(prim["attributes"]["NORMAL"].is_u64(), "{prim}");
    assert_eq!(prim["material"], 0);
    let pbr = &js["materials"][0]["pbrMetallicRoughness"];
    assert_eq!(pbr["metallicFactor"], 0.0, "{pbr}");
    for t in prim["targets"].as_array().unwrap() {
        assert!(t["NORMAL"].is_u64() && t["POSITION"].is_u64(), "{t}");
    }
    assert_eq!(asset.morph_normals.len(), 12);
    // Float normals: what the reader gets is the normals of the frame.
    let e = normal_disagreement(&asset);
    assert!(e < 1e-4, "normals off by {e} rad");
}

/// On a closed mesh the normal at the extreme vertex along each axis points
/// away from the centroid and along that axis, at every frame, in both
/// storages.
#[test]
fn glb_normals_point_outward_at_extreme_vertices() {
    let seq = tumbling(10, 2.0);
    for quantize in [false, true] {
        let (_, asset) = encode(&seq, quantize);
        let back = asset.to_sequence().unwrap();
        for k in 0..back.frame_count() {
            let p = back.frame(k);
            let n = asset.key_normals(k).unwrap();
            let c = p.iter().map(|v| DVec3::from_array(*v)).sum::<DVec3>() / p.len() as f64;
            for axis in 0..3 {
                for sign in [-1.0, 1.0] {
                    let v = (0..p.len())
                        .max_by(|&a, &b| (sign * p[a][axis]).total_cmp(&(sign * p[b][axis])))
                        .unwrap();
                    let nv = DVec3::from_array(n[v]);
                    let out = (DVec3::from_array(p[v]) - c).normalize();
                    let mut dir = DVec3::ZERO;
                    dir[axis] = sign;
                    let (d, e) = (nv.dot(out), nv.dot(dir));
                    assert!(
                        d > 0.0 && e > 0.5,
                        "quantize {quantize}, frame {k}, axis {axis}{sign}: n·out {d}, n·axis {e}"
                    );
                }
            }
        }
    }
}

/// Quantised files: the required extension is declared, the reader (which
/// the `gltf` crate alone would refuse) reads them, positions come back
/// within one grid step per axis (the step is what the rest mesh and the
/// halved displacements need in 16 bits), normals within a few degrees
/// although every normal turns over, and the file is half the float one.
#[test]
fn quantised_glb_round_trips_within_one_grid_step() {
    let seq = tumbling(24, 6.0);
    let (fbytes, _) = encode(&seq, false);
    let (qbytes, asset) = encode(&seq, true);
    let js = json_of(&qbytes);
    assert_eq!(js["extensionsRequired"][0], "KHR_mesh_quantization");
    assert_eq!(
        js["accessors"][js["meshes"][0]["primitives"][0]["attributes"]["POSITION"]
            .as_u64()
            .unwrap() as usize]["componentType"],
        5122
    );
    let back = asset.to_sequence().unwrap();
    assert_eq!(back.frame_count(), 24);
    assert_eq!(back.mesh().triangles(), seq.mesh().triangles());
    // The grid step the writer documents.
    let base = seq.mesh().positions();
    let b = seq.mesh().bounds();
    let reach = base
        .iter()
        .flat_map(|p| (0..3).map(move |k| (p[k] - 0.5 * (b.min[k] + b.max[k])).abs()))
        .fold(0.0, f64::max);
    let disp = (0..24)
        .flat_map(|f| seq.frame(f).iter().zip(base))
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max);
    assert!(
        disp > 2.0 * reach,
        "the fixture must travel further than it is big"
    );
    let step = reach.max(disp / 2.0) / 32766.0;
    let per_axis = seq
        .all_positions()
        .iter()
        .zip(back.all_positions())
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max);
    assert!(per_axis <= 1.01 * step, "error {per_axis} > step {step}");
    assert!(per_axis > 0.0);
    let e = normal_disagreement(&asset);
    assert!(
        e < 3f64.to_radians(),
        "normals off by {} deg",
        e.to_degrees()
    );
    let ratio = qbytes.len() as f64 / fbytes.len() as f64;
    assert!(ratio < 0.55, "quantised/float size {ratio}");
}

/// The weights animation is sparse: a long clip of a tiny mesh costs bytes
/// linear in the frames, not the `4·F²` of a dense F×F weight table (576 MB
/// here), and the reader reads it without densifying (its guard against
/// absurd counts refused 10⁸ weights, i.e. more than 10,000 frames).
#[test]
fn glb_weights_animation_is_sparse_for_long_clips() {
    let m = Mesh::new(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let frames = 12_000;
    let all = (0..frames)
        .flat_map(|f| {
            m.positions()
                .iter()
                .map(move |p| [p[0], p[1], p[2] + f as f64 * 1e-3])
        })
        .collect();
    let seq = MeshSequence::new(m, all, Some(30.0)).unwrap();
    let (bytes, asset) = encode(&seq, false);
    assert!(bytes.len() < 10_000_000, "{} bytes", bytes.len());
    let back = asset.to_sequence().unwrap();
    assert_eq!(back.frame_count(), frames);
    assert!(max_error(back.all_positions(), seq.all_positions()) < 1e-6);
}

/// `mesh convert --glb-quantize`: a quantised file, and the measured error
/// of what the reader gets back is printed.
#[test]
fn mesh_convert_glb_quantize_writes_a_quantised_file_and_reports_its_error() {
    let dir = tempfile::tempdir().unwrap();
    let seq = tumbling(6, 1.0);
    let pc2 = dir.path().join("t.pc2");
    surfmotion::mesh::io::save_sequence(&seq, &pc2, Some(30.0)).unwrap();
    let out = dir.path().join("t.glb");
    let o = std::process::Command::new(common::bin())
        .args(["mesh", "convert"])
        .arg(&pc2)
        .arg(&out)
        .arg("--glb-quantize")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("quantised: max vertex error"), "{err}");
    let bytes = std::fs::read(&out).unwrap();
    assert_eq!(
        json_of(&bytes)["extensionsRequired"][0],
        "KHR_mesh_quantization"
    );
}

/// A GLB whose POSITION names a missing accessor made the `gltf` crate's
/// validation index out of bounds (a panic, found by `tests/malformed.rs`
/// once GLBs carried normals): now an error naming the accessor.
#[test]
fn regression_position_accessor_out_of_range_is_an_error_not_a_panic() {
    let (bytes, _) = encode(&tumbling(3, 0.0), false);
    let mut js = json_of(&bytes);
    js["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 999.into();
    let mut text = serde_json::to_vec(&js).unwrap();
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let old = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let bin = &bytes[20 + old..];
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    glb.extend(((12 + 8 + text.len() + bin.len()) as u32).to_le_bytes());
    glb.extend((text.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&text);
    glb.extend(bin);
    let r = std::panic::catch_unwind(|| parse_gltf(&glb, Path::new("bad.glb")));
    let e = r.expect("no panic").unwrap_err().to_string();
    assert!(e.contains("accessor 999"), "{e}");
}

/// A GLB as glTF Transform decodes it: every frame's positions
/// (frame-major), the node's scale, the frame count.
type Decoded = (Vec<[f64; 3]>, f64, usize);

/// The positions of every frame as glTF Transform decodes a GLB (a reader
/// independent of ours, `.ci/decode-gltf.mjs`), and the node's scale (the
/// grid step of a quantised file); `None` (skipped with a message) when
/// node or the package is absent, which fails under CI=true.
fn decode_in_gltf_transform(files: &[&Path]) -> Option<Vec<Decoded>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    if !common::npm_package(
        "@gltf-transform/core",
        "decode GLB output in glTF Transform",
    ) {
        return None;
    }
    let out = common::run_ok(
        std::process::Command::new("node")
            .arg(root.join(".ci/decode-gltf.mjs"))
            .args(files),
    );
    let text = String::from_utf8(out.stdout).unwrap();
    Some(
        text.lines()
            .map(|l| {
                let v: serde_json::Value = serde_json::from_str(l).unwrap();
                let n = v["vertices"].as_u64().unwrap() as usize;
                let frames = v["positions"].as_array().unwrap();
                let p: Vec<[f64; 3]> = frames
                    .iter()
                    .flat_map(|f| {
                        let f: Vec<f64> = f
                            .as_array()
                            .unwrap()
                            .iter()
                            .map(|x| x.as_f64().unwrap())
                            .collect();
                        assert_eq!(f.len(), 3 * n);
                        f.chunks_exact(3)
                            .map(|c| [c[0], c[1], c[2]])
                            .collect::<Vec<_>>()
                    })
                    .collect();
                (p, v["scale"].as_f64().unwrap(), frames.len())
            })
            .collect(),
    )
}

/// Issue 18, item 6: quantised GLB (`KHR_mesh_quantization`) was checked
/// only by the Khronos validator (which checks structure, not values) and
/// our own reader. glTF Transform decodes every frame of the quantised file
/// within the documented bound, one grid step (the node's scale) per axis,
/// of the positions written, and the float file within f32 rounding.
#[test]
fn quantised_glb_decodes_within_one_grid_step_in_gltf_transform() {
    let dir = tempfile::tempdir().unwrap();
    let seq = tumbling(24, 6.0);
    let (fbytes, _) = encode(&seq, false);
    let (qbytes, qasset) = encode(&seq, true);
    let (f, q) = (dir.path().join("f.glb"), dir.path().join("q.glb"));
    std::fs::write(&f, fbytes).unwrap();
    std::fs::write(&q, qbytes).unwrap();
    let Some(d) = decode_in_gltf_transform(&[&f, &q]) else {
        return;
    };
    let per_axis = |a: &[[f64; 3]], b: &[[f64; 3]]| {
        assert_eq!(a.len(), b.len());
        a.iter()
            .zip(b)
            .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
            .fold(0.0, f64::max)
    };
    let want = seq.all_positions();
    let (fp, fscale, fframes) = &d[0];
    assert_eq!((*fframes, *fscale), (24, 1.0));
    assert!(per_axis(fp, want) < 1e-5, "float: {}", per_axis(fp, want));
    let (qp, step, qframes) = &d[1];
    assert_eq!(*qframes, 24);
    assert!(*step > 0.0 && *step < 1e-3, "grid step {step}");
    let e = per_axis(qp, want);
    // One grid step, plus the f32 rounding of the dequantising transform.
    assert!(e <= 1.01 * step + 1e-6, "quantised: {e} > step {step}");
    assert!(e > 0.1 * step, "{e}: not quantised?");
    // Both readers agree on what the file holds.
    let ours = qasset.to_sequence().unwrap();
    assert!(per_axis(qp, ours.all_positions()) < 1e-5);
}
