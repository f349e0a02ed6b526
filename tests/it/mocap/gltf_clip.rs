//! glTF skin animations read as clips (`mesh::io::gltf::clip`, read by `rig::read_any_clip`): forward kinematics
//! against a second evaluation of the file (the `gltf` crate's own reader
//! and node matrices, composed here from the JSON's `children`), the
//! Khronos samples and the Fox mapped or refused, generated variants of
//! CesiumMan (nodes re-ordered, rescaled, Z-up, an extra root) read alike,
//! and typed errors.

use crate::common;
use glam::{Mat4, Vec3};
use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use surfmotion::mocap::{Clip, UpAxis};
use surfmotion::rig::{Canonical, LoadOptions, detect_clip, load_clip, read_any_clip};

const FILES: [&str; 4] = [
    "gltf/CesiumMan/CesiumMan.glb",
    "gltf/RiggedFigure/RiggedFigure.glb",
    "gltf/Fox/Fox.glb",
    "gltf/RiggedSimple/RiggedSimple.glb",
];

/// Node world matrices at time `t` of animation `a` (`None`: the rest),
/// the second path: the `gltf` crate's reader for the keys (only times
/// that are a key of every channel are asked for), `Transform::matrix` for
/// each node, parents from the JSON's `children`.
fn second_path(doc: &gltf::Gltf, a: Option<usize>, t: f32) -> Vec<Mat4> {
    let blob = doc.blob.as_deref().unwrap();
    let nodes: Vec<gltf::Node> = doc.nodes().collect();
    let mut local: Vec<gltf::scene::Transform> = nodes.iter().map(|n| n.transform()).collect();
    if let Some(a) = a {
        let anim = doc.animations().nth(a).unwrap();
        for ch in anim.channels() {
            let r = ch.reader(|_| Some(blob));
            let times: Vec<f32> = r.read_inputs().unwrap().collect();
            let k = times
                .iter()
                .position(|&x| (x - t).abs() < 1e-5)
                .expect("a key of every channel");
            let cubic = ch.sampler().interpolation() == gltf::animation::Interpolation::CubicSpline;
            let at = |n: usize| if cubic { 3 * k + 1 } else { k }.min(n - 1);
            let node = ch.target().node().index();
            let (mut tr, mut rot, mut sc) = local[node].clone().decomposed();
            use gltf::animation::util::ReadOutputs as O;
            match r.read_outputs().unwrap() {
                O::Translations(v) => {
                    let v: Vec<[f32; 3]> = v.collect();
                    tr = v[at(v.len())];
                }
                O::Rotations(v) => {
                    let v: Vec<[f32; 4]> = v.into_f32().collect();
                    rot = v[at(v.len())];
                }
                O::Scales(v) => {
                    let v: Vec<[f32; 3]> = v.collect();
                    sc = v[at(v.len())];
                }
                O::MorphTargetWeights(_) => {}
            }
            local[node] = gltf::scene::Transform::Decomposed {
                translation: tr,
                rotation: rot,
                scale: sc,
            };
        }
    }
    let mut world = vec![Mat4::IDENTITY; nodes.len()];
    fn walk(n: &gltf::Node, parent: Mat4, local: &[gltf::scene::Transform], world: &mut [Mat4]) {
        let m = parent * Mat4::from_cols_array_2d(&local[n.index()].clone().matrix());
        world[n.index()] = m;
        for c in n.children() {
            walk(&c, m, local, world);
        }
    }
    for s in doc.scenes() {
        for n in s.nodes() {
            walk(&n, Mat4::IDENTITY, &local, &mut world);
        }
    }
    world
}

/// The node of a clip joint: its name, or `joint_N` for unnamed node N.
fn node_of(doc: &gltf::Gltf, name: &str) -> usize {
    doc.nodes()
        .find(|n| n.name() == Some(name) || format!("joint_{}", n.index()) == name)
        .unwrap_or_else(|| panic!("no node for joint '{name}'"))
        .index()
}

/// Times that are a key of every channel of animation `a`, and the first key.
fn common_keys(doc: &gltf::Gltf, a: usize) -> (Vec<f32>, f32) {
    let blob = doc.blob.as_deref().unwrap();
    let anim = doc.animations().nth(a).unwrap();
    let sets: Vec<Vec<f32>> = anim
        .channels()
        .map(|ch| ch.reader(|_| Some(blob)).read_inputs().unwrap().collect())
        .collect();
    let start = sets.iter().flatten().copied().fold(f32::INFINITY, f32::min);
    let keys = sets[0]
        .iter()
        .copied()
        .filter(|t| sets.iter().all(|s| s.iter().any(|x| (x - t).abs() < 1e-6)))
        .collect();
    (keys, start)
}

fn height(clip: &Clip) -> f64 {
    let (lo, hi) = clip.world_positions(0).iter().fold(
        (glam::DVec3::splat(f64::MAX), glam::DVec3::splat(f64::MIN)),
        |(lo, hi), p| (lo.min(*p), hi.max(*p)),
    );
    (hi - lo).max_element()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn gltf_clip_fk_matches_the_files_node_matrices_at_every_key() {
    let Some(d) = common::data_dir() else { return };
    for rel in FILES {
        let path = d.join(rel);
        let doc = gltf::Gltf::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        for a in 0..doc.animations().count() {
            let (keys, start) = common_keys(&doc, a);
            // Sampled at the rate of the common keys, so frames fall on them.
            let gap = keys
                .windows(2)
                .map(|w| (w[1] - w[0]) as f64)
                .fold(f64::INFINITY, f64::min);
            let fps = if gap.is_finite() { 1.0 / gap } else { 30.0 };
            let clip = read_any_clip(&path, Some(fps), None, Some(&a.to_string())).unwrap();
            let h = height(&clip);
            let nodes: Vec<usize> = clip
                .point_names()
                .iter()
                .map(|n| node_of(&doc, n))
                .collect();
            let mut checked = 0;
            let mut worst = 0.0f64;
            for &t in &keys {
                let f = ((t - start) as f64 * clip.fps()).round() as usize;
                if f >= clip.frame_count()
                    || ((start as f64 + f as f64 / clip.fps()) - t as f64).abs() > 1e-5
                {
                    continue;
                }
                let world = second_path(&doc, Some(a), t);
                let ours = clip.world_positions(f);
                for (j, &n) in nodes.iter().enumerate() {
                    let theirs = world[n].w_axis.truncate();
                    let e = (ours[j] - theirs.as_dvec3()).length();
                    worst = worst.max(e / h);
                    assert!(
                        e <= 1e-3 * h,
                        "{rel} animation {a} t {t} joint {}: {} vs {theirs}",
                        clip.joints()[j].name,
                        ours[j]
                    );
                }
                checked += 1;
            }
            assert!(
                checked >= 2,
                "{rel} animation {a}: {checked} keys on frames"
            );
            // The rest (offsets) is the unanimated node tree.
            let rest = second_path(&doc, None, 0.0);
            let (rest_pos, _) = clip.rest_positions();
            for (j, &n) in nodes.iter().enumerate() {
                let e = (rest_pos[j] - rest[n].w_axis.truncate().as_dvec3()).length();
                assert!(e <= 1e-3 * h, "{rel} rest joint {j}: {e}");
            }
            eprintln!(
                "{rel} animation {a}: {} frames at {} fps, {checked} keys checked, max |Δ| = {worst:.1e} of the height",
                clip.frame_count(),
                clip.fps()
            );
        }
    }
}

/// The canonical joints the map names, as clip joint indices.
fn mapped(clip: &Clip) -> Result<Vec<(Canonical, usize)>, String> {
    let d = detect_clip(clip).map_err(|e| e.to_string())?;
    let mut v: Vec<(Canonical, usize)> = d
        .map
        .joints
        .iter()
        .filter_map(|(c, n)| Some((*c, clip.joint(n)?.idx())))
        .collect();
    v.sort_by_key(|(c, _)| c.name());
    Ok(v)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn khronos_figures_map_as_humanoids_and_the_fox_and_the_two_bone_rig_are_refused() {
    let Some(d) = common::data_dir() else { return };
    for rel in FILES {
        let clip = load_clip(&d.join(rel), &LoadOptions::default()).unwrap();
        let got = mapped(&clip);
        eprintln!(
            "{rel}: {} joints, {} frames at {} fps, units {} ({}), up {:?} ({}): {}",
            clip.joint_count(),
            clip.frame_count(),
            clip.fps(),
            clip.units().name,
            clip.units().reason,
            clip.up(),
            clip.up_reason(),
            match &got {
                Ok(m) => format!("{} canonical joints mapped", m.len()),
                Err(e) => format!("refused: {e}"),
            }
        );
        let humanoid = rel.contains("CesiumMan") || rel.contains("RiggedFigure");
        assert_eq!(got.is_ok(), humanoid, "{rel}: {got:?}");
        if humanoid {
            assert_eq!(clip.up(), UpAxis::Y, "{rel}");
            let m = got.unwrap();
            // The clip's joints are the character's (`rig embed --skin`):
            // CesiumMan's hand-written map names the same nodes.
            if rel.contains("CesiumMan") {
                let fixture = surfmotion::rig::RigMap::load(
                    &Path::new(env!("CARGO_MANIFEST_DIR"))
                        .join("tests/fixtures/cesiumman.rigmap.json"),
                )
                .unwrap();
                let names = clip.point_names();
                for (c, j) in &m {
                    assert_eq!(
                        fixture.joints.get(c),
                        Some(&names[*j]),
                        "{rel}: {} mapped to {}",
                        c.name(),
                        names[*j]
                    );
                }
                assert_eq!(m.len(), fixture.joints.len(), "{rel}");
            }
        }
    }
}

/// A GLB's JSON and binary chunk.
fn glb_split(bytes: &[u8]) -> (Value, Vec<u8>) {
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
    let rest = &bytes[20 + len..];
    let bin_len = u32::from_le_bytes(rest[0..4].try_into().unwrap()) as usize;
    (json, rest[8..8 + bin_len].to_vec())
}

fn glb_join(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while b.len() % 4 != 0 {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b);
    out
}

/// Puts a new node with `trs` above the scene's roots.
fn with_root(json: &Value, trs: Value) -> Value {
    let mut j = json.clone();
    let n = j["nodes"].as_array().unwrap().len();
    let scene = j["scene"].as_u64().unwrap_or(0) as usize;
    let roots = j["scenes"][scene]["nodes"].clone();
    let mut node = trs;
    node["children"] = roots;
    j["nodes"].as_array_mut().unwrap().push(node);
    j["scenes"][scene]["nodes"] = json!([n]);
    j
}

/// The nodes in reverse order, every reference renumbered.
fn reversed_nodes(json: &Value) -> Value {
    let mut j = json.clone();
    let n = j["nodes"].as_array().unwrap().len();
    let new = |i: &Value| json!(n - 1 - i.as_u64().unwrap() as usize);
    let renumber = |v: &mut Value| {
        if let Some(a) = v.as_array_mut() {
            a.iter_mut().for_each(|x| *x = new(x));
        }
    };
    let mut nodes = j["nodes"].as_array().unwrap().clone();
    nodes.reverse();
    for node in &mut nodes {
        renumber(&mut node["children"]);
    }
    j["nodes"] = Value::Array(nodes);
    for s in j["scenes"].as_array_mut().unwrap() {
        renumber(&mut s["nodes"]);
    }
    for s in j["skins"].as_array_mut().unwrap() {
        renumber(&mut s["joints"]);
        if s.get("skeleton").is_some() {
            s["skeleton"] = new(&s["skeleton"]);
        }
    }
    for a in j["animations"].as_array_mut().unwrap() {
        for c in a["channels"].as_array_mut().unwrap() {
            c["target"]["node"] = new(&c["target"]["node"]);
        }
    }
    j
}

fn write(dir: &Path, name: &str, json: &Value, bin: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, glb_join(json, bin)).unwrap();
    p
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn generated_variants_of_a_rigged_figure_read_and_map_alike() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    for rel in [FILES[0], FILES[1]] {
        let (json, bin) = glb_split(&std::fs::read(d.join(rel)).unwrap());
        let base_path = write(tmp.path(), "base.glb", &json, &bin);
        let base = load_clip(&base_path, &LoadOptions::default()).unwrap();
        let base_map = mapped(&base).unwrap();
        let h = height(&base);
        let turn = glam::Quat::from_rotation_y(0.52);
        let shift = Vec3::new(3.0, 0.0, -2.0);
        // (name, JSON, the expected world position of a base position, up)
        type Expect = Box<dyn Fn(glam::DVec3) -> glam::DVec3>;
        let mut variants: Vec<(String, Value, Expect, UpAxis)> = vec![
            (
                "reordered".into(),
                reversed_nodes(&json),
                Box::new(|p| p),
                UpAxis::Y,
            ),
            (
                "extra root".into(),
                with_root(
                    &json,
                    json!({"translation": shift.to_array(), "rotation": turn.to_array()}),
                ),
                Box::new(move |p| (turn.as_dquat() * p) + shift.as_dvec3()),
                UpAxis::Y,
            ),
            (
                // The body stands along +Z: R_x(+90°) takes +Y to +Z.
                "z-up".into(),
                with_root(
                    &json,
                    json!({"rotation": glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2).to_array()}),
                ),
                Box::new(|p| glam::DVec3::new(p.x, -p.z, p.y)),
                UpAxis::Z,
            ),
        ];
        for s in [0.6f64, 1.5] {
            variants.push((
                format!("x{s}"),
                with_root(&json, json!({"scale": [s, s, s]})),
                Box::new(move |p| p * s),
                UpAxis::Y,
            ));
        }
        for (name, vj, expect, up) in variants {
            let p = write(tmp.path(), &format!("{name}.glb"), &vj, &bin);
            let raw = read_any_clip(&p, None, None, None).unwrap();
            assert_eq!(raw.frame_count(), base.frame_count(), "{rel} {name}");
            assert_eq!(raw.joint_count(), base.joint_count(), "{rel} {name}");
            let mut worst = 0.0f64;
            for f in [0, base.frame_count() / 2, base.frame_count() - 1] {
                let (a, b) = (raw.world_positions(f), base.world_positions(f));
                for j in 0..a.len() {
                    worst = worst.max((a[j] - expect(b[j])).length() / h);
                }
            }
            assert!(worst < 1e-5, "{rel} {name}: {worst:e} of the height");
            let clip = load_clip(&p, &LoadOptions::default()).unwrap();
            assert_eq!(clip.up(), up, "{rel} {name}: {}", clip.up_reason());
            let m = mapped(&clip).unwrap_or_else(|e| panic!("{rel} {name}: {e}"));
            assert_eq!(m, base_map, "{rel} {name}: another mapping");
            eprintln!(
                "{rel} {name}: positions within {worst:.1e} of the height, same {} joints mapped, up {:?}, units {} ({})",
                m.len(),
                clip.up(),
                clip.units().name,
                clip.units().reason
            );
        }
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_gltf_without_skin_or_animation_or_the_named_one_is_a_one_line_error() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let (json, bin) = glb_split(&std::fs::read(d.join(FILES[0])).unwrap());
    let mut no_anim = json.clone();
    no_anim.as_object_mut().unwrap().remove("animations");
    let mut no_skin = json.clone();
    no_skin.as_object_mut().unwrap().remove("skins");
    for n in no_skin["nodes"].as_array_mut().unwrap() {
        n.as_object_mut().unwrap().remove("skin");
    }
    let cases = [
        ("no-animation.glb", no_anim, None, "has no animation"),
        ("no-skin.glb", no_skin, None, "has no skin"),
        (
            "take.glb",
            json.clone(),
            Some("7"),
            "no animation named or numbered '7'; the file's animations: 0 ''",
        ),
        (
            "take-name.glb",
            json.clone(),
            Some("Walk"),
            "no animation named or numbered 'Walk'",
        ),
    ];
    for (name, j, take, want) in cases {
        let p = write(tmp.path(), name, &j, &bin);
        let e = read_any_clip(&p, None, None, take).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}: ", p.display())), "{name}: {e}");
        assert!(e.contains(want), "{name}: {e}");
        assert_eq!(e.lines().count(), 1, "{name}: {e}");
        eprintln!("{name}: {e}");
    }
    // The Fox's animations by name and by index read the same clip.
    let fox = d.join(FILES[2]);
    let by_name = read_any_clip(&fox, None, None, Some("Walk")).unwrap();
    let by_index = read_any_clip(&fox, None, None, Some("1")).unwrap();
    assert_eq!(by_name.frame_count(), by_index.frame_count());
    assert_eq!(by_name.world_positions(5), by_index.world_positions(5));
    // A frame rate asked for is the clip's.
    let c = read_any_clip(&d.join(FILES[0]), Some(60.0), None, None).unwrap();
    assert_eq!(c.fps(), 60.0);
    assert_eq!(c.frame_count(), 121);
}

/// A cubic in `t` (coefficients per component, lowest first) and its
/// derivative.
fn cubic(c: &[[f64; 4]], t: f64) -> (Vec<f64>, Vec<f64>) {
    c.iter()
        .map(|k| {
            (
                k[0] + t * (k[1] + t * (k[2] + t * k[3])),
                k[1] + t * (2.0 * k[2] + 3.0 * t * k[3]),
            )
        })
        .unzip()
}

/// A GLB of one triangle and two animated nodes, node 1's translation and
/// node 2's rotation keyed CUBICSPLINE at `times` (three keys): on the
/// first interval the curve is the cubic `f`, on the second the cubic `g`
/// (`g(t₁) = f(t₁)`, its own slope there), so key 1's in-tangent is `f′(t₁)`
/// and its out-tangent `g′(t₁)`.
fn cubic_spline_glb(times: [f64; 3], f: &[[f64; 4]], g: &[[f64; 4]]) -> Vec<u8> {
    let mut bin: Vec<u8> = Vec::new();
    let mut push = |v: &[f64]| {
        for x in v {
            bin.extend_from_slice(&(*x as f32).to_le_bytes());
        }
    };
    push(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]);
    push(&times);
    // Per key: in-tangent, value, out-tangent (glTF 2.0 Appendix C).
    let keys = |dims: usize| -> Vec<f64> {
        let (f0, df0) = cubic(&f[..dims], times[0]);
        let (f1, df1) = cubic(&f[..dims], times[1]);
        let (_, dg1) = cubic(&g[..dims], times[1]);
        let (g2, dg2) = cubic(&g[..dims], times[2]);
        [df0.clone(), f0, df0, df1, f1, dg1, dg2.clone(), g2, dg2].concat()
    };
    let (tr, rot) = (keys(3), keys(4));
    push(&tr);
    push(&rot);
    let view =
        |offset: usize, len: usize| json!({"buffer": 0, "byteOffset": offset, "byteLength": len});
    let (t0, t2) = (times[0] as f32, times[2] as f32);
    let j = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0}, {"name": "mover"}, {"name": "turner"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [view(0, 36), view(36, 12), view(48, 4 * tr.len()), view(48 + 4 * tr.len(), 4 * rot.len())],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "SCALAR", "min": [t0], "max": [t2]},
            {"bufferView": 2, "componentType": 5126, "count": 9, "type": "VEC3"},
            {"bufferView": 3, "componentType": 5126, "count": 9, "type": "VEC4"}
        ],
        "animations": [{
            "name": "curve",
            "samplers": [
                {"input": 1, "output": 2, "interpolation": "CUBICSPLINE"},
                {"input": 1, "output": 3, "interpolation": "CUBICSPLINE"}
            ],
            "channels": [
                {"sampler": 0, "target": {"node": 1, "path": "translation"}},
                {"sampler": 1, "target": {"node": 2, "path": "rotation"}}
            ]
        }]
    });
    glb_join(&j, &bin)
}

/// glTF 2.0's CUBICSPLINE keys follow the cubic Hermite spline of their
/// values and tangents (Appendix C), checked against generated curves: a
/// translation whose two intervals are two different cubics (so key 1's
/// in- and out-tangents differ: the spline reproduces each cubic exactly,
/// which a linear reading between the values, or the tangents swapped,
/// does not) and a rotation whose components are cubics (the spline's
/// sum normalised), at uneven key times, through `GltfAsset::node_worlds_at`
/// (what the clip reader samples).
#[test]
fn cubic_spline_keys_follow_the_generated_curves_between_the_keys() {
    let f = [
        [0.1, 1.3, -2.0, 1.7],
        [-0.4, 0.2, 3.1, -2.2],
        [0.9, -1.1, 0.4, 0.8],
        [0.6, 0.5, -0.3, 0.2],
    ];
    let g = [
        [0.0, -0.7, 1.9, -0.6],
        [0.0, 2.4, -1.2, 0.5],
        [0.0, 0.3, 0.9, -1.4],
        [0.0, -0.2, 0.6, 0.1],
    ];
    for times in [[0.0, 0.3, 1.1], [0.5, 0.52, 2.0]] {
        // `g` is written about t₁ and starts where `f` ends.
        let (f1, _) = cubic(&f, times[1]);
        let shift = |t: f64| t - times[1];
        let g_at = |t: f64| -> Vec<f64> {
            let (v, _) = cubic(&g, shift(t));
            v.iter().zip(&f1).map(|(a, b)| a + b).collect()
        };
        // The spline's `g` in absolute time: its coefficients expanded.
        let g_abs: Vec<[f64; 4]> = (0..4)
            .map(|c| {
                let (a, b, cc, d, s) = (g[c][0] + f1[c], g[c][1], g[c][2], g[c][3], times[1]);
                [
                    a - b * s + cc * s * s - d * s * s * s,
                    b - 2.0 * cc * s + 3.0 * d * s * s,
                    cc - 3.0 * d * s,
                    d,
                ]
            })
            .collect();
        let bytes = cubic_spline_glb(times, &f, &g_abs);
        let asset = surfmotion::mesh::io::gltf::parse_gltf(&bytes, Path::new("curve.glb")).unwrap();
        let (mut trs, mut world) = (Vec::new(), Vec::new());
        let (mut worst_t, mut worst_r, mut linear_gap) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..=200 {
            let t = times[0] + (times[2] - times[0]) * f64::from(i) / 200.0;
            let want = if t <= times[1] {
                cubic(&f, t).0
            } else {
                g_at(t)
            };
            assert!(asset.node_worlds_at(Some(0), t as f32, &mut trs, &mut world));
            let (_, _, tr) = world[1].to_scale_rotation_translation();
            for a in 0..3 {
                worst_t = worst_t.max((tr[a] - want[a]).abs());
            }
            let q = glam::DQuat::from_xyzw(want[0], want[1], want[2], want[3]).normalize();
            let (_, got, _) = world[2].to_scale_rotation_translation();
            worst_r = worst_r.max(got.angle_between(q).to_degrees());
            // What a linear reading between the values would give.
            let (k0, k1) = if t <= times[1] { (0, 1) } else { (1, 2) };
            let s = (t - times[k0]) / (times[k1] - times[k0]);
            let at = |k: usize| {
                if k < 2 {
                    cubic(&f, times[k]).0
                } else {
                    g_at(times[2])
                }
            };
            let (v0, v1) = (at(k0), at(k1));
            for a in 0..3 {
                linear_gap = linear_gap.max((v0[a] + s * (v1[a] - v0[a]) - want[a]).abs());
            }
        }
        eprintln!(
            "keys at {times:?}: translation off its curve by at most {worst_t:.2e}, rotation \
             {worst_r:.2e}°; a linear reading would be {linear_gap:.3} off"
        );
        assert!(worst_t < 2e-4, "{times:?}: {worst_t}");
        assert!(worst_r < 0.02, "{times:?}: {worst_r}°");
        assert!(linear_gap > 100.0 * worst_t, "{times:?}: {linear_gap}");
    }
}
