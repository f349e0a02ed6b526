//! Mesh readers on real data, and every writer round-tripped through its reader.

use crate::common;

use std::path::Path;
use surfmotion::mesh::io::{LoadOptions, glb, load_sequence, obj, objseq, pc2, save_sequence};
use surfmotion::mesh::{Mesh, MeshSequence};

fn samba(d: &Path, frames: usize) -> MeshSequence {
    let s = load_sequence(
        d.join("4d/samba/samba.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    let n = s.mesh().vertex_count();
    MeshSequence::new(
        s.mesh().clone(),
        s.all_positions()[..frames * n].to_vec(),
        Some(30.0),
    )
    .unwrap()
}

fn max_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn samba_cache_obj_frames_and_topology_agree() {
    let Some(d) = common::data_dir() else { return };
    let seq = load_sequence(
        d.join("4d/samba/samba.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(seq.frame_count(), 175);
    assert_eq!(seq.mesh().vertex_count(), 9971);
    assert_eq!(seq.mesh().triangle_count(), 19938);
    assert!(
        seq.mesh().problems().is_empty(),
        "{:?}",
        seq.mesh().problems()
    );
    let folder = load_sequence(
        d.join("4d/samba/frames").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(folder.frame_count(), 20);
    assert_eq!(folder.mesh().triangles(), seq.mesh().triangles());
    for f in 0..20 {
        assert!(max_diff(folder.frame(f), seq.frame(f)) < 1e-5, "frame {f}");
    }
    // PATH:FRAME picks one frame.
    let one = load_sequence(
        &format!("{}:12", d.join("4d/samba/samba.pc2").display()),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(one.frame_count(), 1);
    assert_eq!(one.frame(0), seq.frame(12));
    let crane = load_sequence(
        d.join("4d/crane/crane.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(
        (crane.mesh().vertex_count(), crane.frame_count()),
        (10002, 175)
    );
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn every_writer_round_trips_through_its_reader() {
    let Some(d) = common::data_dir() else { return };
    let seq = samba(&d, 8);
    let diag = seq.bounds().diagonal();
    let dir = tempfile::tempdir().unwrap();
    for name in ["s.glb", "s.pc2", "s.mdd", "folder"] {
        let out = dir.path().join(name);
        let files = save_sequence(&seq, &out, Some(30.0)).unwrap();
        assert!(!files.is_empty());
        let back = load_sequence(out.to_str().unwrap(), &LoadOptions::default()).unwrap();
        assert_eq!(back.frame_count(), 8, "{name}");
        assert_eq!(back.mesh().triangles(), seq.mesh().triangles(), "{name}");
        let tol = if name.ends_with("glb") {
            1e-6 * diag
        } else {
            0.0
        };
        let e = max_diff(back.all_positions(), seq.all_positions());
        assert!(e <= tol, "{name}: max error {e}");
        assert!(
            (back.fps.unwrap_or(30.0) - 30.0).abs() < 1e-3,
            "{name}: fps {:?}",
            back.fps
        );
    }
    for name in ["one.obj", "one.ply"] {
        let single = seq.select_frame(3).unwrap();
        let out = dir.path().join(name);
        save_sequence(&single, &out, None).unwrap();
        let back = load_sequence(out.to_str().unwrap(), &LoadOptions::default()).unwrap();
        assert_eq!(back.frame(0), single.frame(0), "{name}");
        assert_eq!(back.mesh().triangles(), single.mesh().triangles(), "{name}");
    }
    // A multi-frame sequence does not fit one OBJ: a clear error, no file.
    assert!(save_sequence(&seq, &dir.path().join("many.obj"), None).is_err());
    assert!(!dir.path().join("many.obj").exists());
}

#[test]
fn obj_groups_colours_and_polygons() {
    let text = "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\ng quad\nf 1/1/1 2/2/2 3/3/3 4/4/4\ng tri\nf -4 -3 -1\n";
    let m = obj::parse_obj(text, Path::new("t.obj")).unwrap();
    assert_eq!(m.triangle_count(), 3);
    assert_eq!(m.groups().len(), 2);
    assert_eq!(
        (
            m.groups()[0].end - m.groups()[0].start,
            m.groups()[1].name.as_str()
        ),
        (2, "tri")
    );
    assert_eq!(m.colors().unwrap()[2], [0.0, 0.0, 1.0]);
    let back = obj::parse_obj(&obj::format_obj(&m, None), Path::new("w.obj")).unwrap();
    assert_eq!(back, m);
    let e = obj::parse_obj("v 0 0 0\nv 1 0 0\nf 1 2 3\n", Path::new("bad.obj"))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("bad.obj:3:"), "{e}");
}

/// Regression (session 6 review): a `\` at the end of an OBJ line (the
/// format's line continuation, written by some exporters for long faces)
/// was read as a coordinate or face index and the file refused
/// ("bad face index '\'"). Statements now join across the break; an error
/// names the statement's first line.
#[test]
fn obj_line_continuations_join_statements() {
    let plain = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    let want = obj::parse_obj(plain, Path::new("plain.obj")).unwrap();
    for text in [
        // A face split over two lines, one with a CRLF ending.
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 \\\r\n 3 4\n",
        // A vertex split after its keyword, a backslash with no space
        // before it, trailing blanks after it, and a comment after it.
        "v \\\n0 0 0\nv 1 0\\\n 0\nv 1 1 0\nv 0 1 0\nf 1 \\  \n2 \\ # more\n3 4\n",
        // A face split three times, the last line ending the file.
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf \\\n1 \\\n2 \\\n3 4",
        // A continuation on the last line.
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4 \\\n",
    ] {
        let m = obj::parse_obj(text, Path::new("c.obj")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m, want, "{text:?}");
    }
    // The error of a joined statement names its first line, and the
    // lines after it keep their own numbers.
    let e = obj::parse_obj(
        "v 0 0 0\nv 1 0 0\nf 1 \\\n2 \\\n9\nv 0 1 0\n",
        Path::new("c.obj"),
    )
    .unwrap_err()
    .to_string();
    assert!(e.starts_with("c.obj:3:"), "{e}");
    let e = obj::parse_obj("v 0 0 \\\n0\nv 1 0 0\nf 1 2 x\n", Path::new("c.obj"))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("c.obj:4:"), "{e}");
    // A comment line is not continued into: its `\` is part of the comment.
    let m = obj::parse_obj(&format!("# C:\\path\\\n{plain}"), Path::new("c.obj")).unwrap();
    assert_eq!(m, want);
}

#[test]
fn ply_ascii_and_big_endian() {
    let ascii = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 0 0 0 0\n4 0 1 2 3\n";
    let m = surfmotion::mesh::io::ply::parse_ply(ascii.as_bytes(), Path::new("a.ply")).unwrap();
    assert_eq!((m.vertex_count(), m.triangle_count()), (4, 2));
    assert_eq!(m.colors().unwrap()[1], [0.0, 1.0, 0.0]);
    let mut be = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n".to_vec();
    for v in [[0.0f64, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]] {
        for c in v {
            be.extend_from_slice(&c.to_be_bytes());
        }
    }
    be.push(3);
    for i in [0u32, 1, 2] {
        be.extend_from_slice(&i.to_be_bytes());
    }
    let m = surfmotion::mesh::io::ply::parse_ply(&be, Path::new("b.ply")).unwrap();
    assert_eq!(m.positions()[2], [0.0, 3.0, 0.0]);
}

#[test]
fn obj_folder_names_the_frame_that_breaks_connectivity() {
    let dir = tempfile::tempdir().unwrap();
    let m = Mesh::new(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
        vec![[0, 1, 2], [1, 3, 2]],
    )
    .unwrap();
    for k in 0..3 {
        obj::write_obj(&m, None, &dir.path().join(format!("f_{k}.obj"))).unwrap();
    }
    let other = Mesh::new(m.positions().to_vec(), vec![[0, 1, 2], [1, 2, 3]]).unwrap();
    obj::write_obj(&other, None, &dir.path().join("f_10.obj")).unwrap();
    let e = objseq::read_obj_folder(dir.path()).unwrap_err().to_string();
    assert!(e.contains("f_10.obj") && e.contains("triangle 1"), "{e}");
    // Natural order: f_2 before f_10.
    let files = objseq::list_obj_frames(dir.path()).unwrap();
    assert!(files[3].ends_with("f_10.obj"));
}

#[test]
fn pc2_header_lies_are_errors_not_allocations() {
    let mut b = pc2::encode_pc2(3, &[[0.0; 3]; 6]);
    b[16..20].copy_from_slice(&(i32::MAX).to_le_bytes());
    let e = pc2::parse_pc2(&b, Path::new("x.pc2"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("truncated"), "{e}");
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn gltf_samples_read_with_skins() {
    let Some(d) = common::data_dir() else { return };
    for (f, joints, verts) in [
        ("gltf/Fox/Fox.glb", 24, 1728),
        ("gltf/CesiumMan/CesiumMan.glb", 19, 3273),
        ("gltf/RiggedFigure/RiggedFigure.glb", 19, 370),
        ("gltf/RiggedSimple/RiggedSimple.glb", 2, 96),
    ] {
        let a = surfmotion::mesh::io::gltf::read_gltf(&d.join(f)).unwrap();
        let s = a.skin.as_ref().unwrap();
        assert_eq!(
            (s.joint_names.len(), a.mesh.vertex_count()),
            (joints, verts),
            "{f}"
        );
        assert_eq!(
            s.parents.iter().filter(|p| p.is_none()).count(),
            1,
            "{f}: one top joint"
        );
        for w in &s.weights {
            let sum: f32 = w.iter().sum();
            assert!(
                (sum - 1.0).abs() < 1e-3 || sum == 0.0,
                "{f}: weights sum {sum}"
            );
        }
        assert!(!a.animations.is_empty());
    }
}

/// Runs the Khronos glTF-Validator (installed by .ci/run from npm) on GLBs we
/// write. Required under CI=true; skipped with a message elsewhere if absent.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn written_glb_passes_the_khronos_validator() {
    let Some(d) = common::data_dir() else { return };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let script = root.join(".ci/validate-gltf.mjs");
    if !common::npm_package("gltf-validator", "validate GLB output") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let seq = samba(&d, 12);
    let a = dir.path().join("anim.glb");
    glb::write_glb(&seq, Some(30.0), &a).unwrap();
    let b = dir.path().join("static.glb");
    glb::write_glb(&seq.select_frame(0).unwrap(), None, &b).unwrap();
    // A coloured mesh too.
    let m = Mesh::new(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        vec![[0, 1, 2]],
    )
    .unwrap()
    .with_colors(vec![[1.0, 0.0, 0.0]; 3])
    .unwrap();
    let c = dir.path().join("colour.glb");
    glb::write_glb(&MeshSequence::single(m), None, &c).unwrap();
    // Quantised (KHR_mesh_quantization), with and without normals.
    let q = dir.path().join("quantised.glb");
    let quantised = glb::GlbOptions {
        quantize: true,
        ..Default::default()
    };
    glb::write_glb_with(&seq, Some(30.0), &quantised, &q).unwrap();
    let qn = dir.path().join("quantised-no-normals.glb");
    let bare = glb::GlbOptions {
        quantize: true,
        normals: false,
    };
    glb::write_glb_with(&seq, Some(30.0), &bare, &qn).unwrap();
    let qs = dir.path().join("quantised-static.glb");
    glb::write_glb_with(&seq.select_frame(0).unwrap(), None, &quantised, &qs).unwrap();
    let out = std::process::Command::new("node")
        .arg(&script)
        .args([&a, &b, &c, &q, &qn, &qs])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "validator reported errors:\n{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(text.lines().count(), 6, "{text}");
    for line in text.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        assert_eq!(v["errors"], 0, "{line}");
        assert_eq!(v["warnings"], 0, "{line}");
    }
}

/// Issue 18, item 6 on real data: the samba capture as a quantised GLB
/// comes back through our reader within 0.1 mm (metres in, 16-bit grid),
/// with normals within 2 degrees of the normals of the input frames, at
/// about half the size of the float file.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn quantised_samba_glb_is_half_the_size_within_a_tenth_of_a_millimetre() {
    let Some(d) = common::data_dir() else { return };
    let seq = samba(&d, 175);
    let float = glb::encode_glb(&seq, None).unwrap();
    let opts = glb::GlbOptions {
        quantize: true,
        ..Default::default()
    };
    let q = glb::encode_glb_with(&seq, None, &opts).unwrap();
    let asset = surfmotion::mesh::io::gltf::parse_gltf(&q, Path::new("q.glb")).unwrap();
    let back = asset.to_sequence().unwrap();
    let e = back
        .all_positions()
        .iter()
        .zip(seq.all_positions())
        .map(|(p, q)| glam::DVec3::from_array(*p).distance(glam::DVec3::from_array(*q)))
        .fold(0.0, f64::max);
    assert!(e < 1e-4, "max vertex error {e} m");
    for k in [0, 60, 174] {
        let n = asset.key_normals(k).unwrap();
        let r = surfmotion::mesh::normals::vertex_normals(seq.frame(k), seq.mesh().triangles());
        let worst = n
            .iter()
            .zip(&r)
            .map(|(a, b)| {
                glam::DVec3::from_array(*a)
                    .dot(glam::DVec3::from_array(*b))
                    .clamp(-1.0, 1.0)
                    .acos()
            })
            .fold(0.0, f64::max);
        eprintln!("frame {k}: normals within {:.2} deg", worst.to_degrees());
        assert!(
            worst < 2f64.to_radians(),
            "frame {k}: normals off by {worst} rad"
        );
    }
    let ratio = q.len() as f64 / float.len() as f64;
    eprintln!("samba, 175 frames: quantised max vertex error {e:.2e} m, size ratio {ratio:.3}");
    assert!(ratio < 0.55, "size ratio {ratio}");
}

/// A skinned glTF with a node animation becomes a mesh sequence by linear
/// blend skinning: it moves, stays finite, and keeps its edge lengths roughly.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn skinned_gltf_animation_becomes_a_sequence() {
    let Some(d) = common::data_dir() else { return };
    for (f, frames) in [
        ("gltf/CesiumMan/CesiumMan.glb", 61),
        ("gltf/Fox/Fox.glb", 103),
    ] {
        let s = load_sequence(d.join(f).to_str().unwrap(), &LoadOptions::default()).unwrap();
        assert_eq!(s.frame_count(), frames, "{f}");
        let m = s.mesh();
        let e = surfmotion::mesh::measure::edges(m);
        let l0 = surfmotion::mesh::measure::edge_lengths(s.frame(0), &e);
        let mut moved = 0.0f64;
        for k in 1..s.frame_count() {
            let lk = surfmotion::mesh::measure::edge_lengths(s.frame(k), &e);
            let change: f64 = l0
                .iter()
                .zip(&lk)
                .map(|(a, b)| (a - b).abs() / a.max(1e-12))
                .sum::<f64>()
                / e.len() as f64;
            assert!(
                change < 0.1,
                "{f} frame {k}: mean edge length change {change}"
            );
            moved = moved.max(max_diff(s.frame(0), s.frame(k)));
        }
        assert!(moved > 1e-3 * s.bounds().diagonal(), "{f}: nothing moves");
    }
}

/// A Python with Pixar's `usd-core` (`pxr`): `.ci/usd-venv` (made by
/// .ci/run), else `python3` if it imports `pxr`. Required under CI=true;
/// elsewhere the test is skipped with a message when absent.
fn usd_python() -> Option<std::path::PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let venv = root.join(".ci/usd-venv/bin/python");
    for py in [venv, "python3".into()] {
        let ok = std::process::Command::new(&py)
            .args(["-c", "import pxr.Usd, pxr.UsdValidation"])
            .output()
            .is_ok_and(|o| o.status.success());
        if ok {
            return Some(py);
        }
    }
    assert!(
        !std::env::var("CI").is_ok_and(|v| v == "true"),
        "CI=true but Pixar's usd-core is not installed (.ci/run installs it into .ci/usd-venv)"
    );
    eprintln!("SKIPPED: no python3 with usd-core; run .ci/run or `pip install usd-core`");
    None
}

/// Runs `.ci/usdcheck.py --dump` on `file`: the validators must pass; the
/// dump's JSON.
fn usd_dump(py: &Path, file: &Path) -> serde_json::Value {
    let o = std::process::Command::new(py)
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join(".ci/usdcheck.py"))
        .arg("--dump")
        .arg(file)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "usd-core validation failed:\n{err}");
    serde_json::from_slice(&o.stdout).unwrap()
}

/// `v` (a JSON array of xyz arrays) as f32 triples.
fn f32x3s(v: &serde_json::Value) -> Vec<[f32; 3]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|q| [0, 1, 2].map(|a| q[a].as_f64().unwrap() as f32))
        .collect()
}

/// Issue 44: a `.usda` sequence, written frame by frame through the
/// sequence writer as every verb writes, passes Pixar's validators (what
/// `usdchecker` runs) and reads back through `pxr.Usd` with our topology,
/// metadata (metres, Y up, the frame rate, time codes 0..frames-1) and,
/// per time code, our points, extent and vertex normals to the stored f32
/// precision: the normals are the area-weighted ones the GLB writer
/// stores, unit length, each on the side its triangles wind
/// counter-clockwise around (this tetrahedron's face inward) in every
/// frame, and a frame collapsed to a point takes the rest normals. With
/// `UsdOptions::normals` off the file has none and still passes.
#[test]
fn usda_output_passes_usd_core_and_reads_back_equal() {
    let Some(py) = usd_python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("wave seq.usda");
    let mesh = Mesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0 / 3.0, 0.0, 0.0],
            [0.0, 2.0e-7, 0.0],
            [0.0, 0.0, 1234.5678],
        ],
        vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]],
    )
    .unwrap();
    let frames = 7;
    let collapsed = 3;
    let frame = |k: usize| -> Vec<[f64; 3]> {
        if k == collapsed {
            return vec![[0.25, -0.5, 2.0]; 4];
        }
        mesh.positions()
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let s = (k as f64 * 0.7 + i as f64).sin() * 0.123_456_789;
                [p[0] + s, p[1] - s * 1e-3, p[2] * (1.0 + s)]
            })
            .collect()
    };
    let mut w = surfmotion::mesh::io::stream::SequenceWriter::create(
        &mesh,
        &out,
        frames,
        &surfmotion::mesh::io::SaveOptions {
            fps: Some(24.0),
            ..Default::default()
        },
    )
    .unwrap();
    assert!(w.streams());
    for k in 0..frames {
        w.push(&frame(k)).unwrap();
    }
    assert_eq!(w.finish().unwrap(), vec![out.clone()]);
    let v = usd_dump(&py, &out);
    assert_eq!(v["metersPerUnit"], 1.0);
    assert_eq!(v["upAxis"], "Y");
    assert_eq!(v["timeCodesPerSecond"], 24.0);
    assert_eq!(v["startTimeCode"], 0.0);
    assert_eq!(v["endTimeCode"], (frames - 1) as f64);
    assert_eq!(v["prim"], "/wave_seq");
    assert_eq!(v["faceVertexCounts"], serde_json::json!([3, 3, 3, 3]));
    assert_eq!(
        v["faceVertexIndices"],
        serde_json::json!([0, 1, 2, 0, 2, 3, 0, 3, 1, 1, 3, 2])
    );
    let pts = v["points"].as_array().unwrap();
    let ext = v["extent"].as_array().unwrap();
    assert_eq!(pts.len(), frames);
    assert_eq!(ext.len(), frames);
    for (k, (p, e)) in pts.iter().zip(ext).enumerate() {
        let ours = frame(k);
        let mut lo = [f32::MAX; 3];
        let mut hi = [f32::MIN; 3];
        for (i, q) in p.as_array().unwrap().iter().enumerate() {
            for a in 0..3 {
                // Exactly our value rounded to f32 (the stored precision).
                let theirs = q[a].as_f64().unwrap() as f32;
                assert_eq!(theirs, ours[i][a] as f32, "frame {k} vertex {i} axis {a}");
                lo[a] = lo[a].min(theirs);
                hi[a] = hi[a].max(theirs);
            }
        }
        for a in 0..3 {
            assert_eq!(e[0][a].as_f64().unwrap() as f32, lo[a]);
            assert_eq!(e[1][a].as_f64().unwrap() as f32, hi[a]);
        }
    }
    usda_normals_read_back_equal(&v, &mesh, frames, collapsed, &frame);
    // Normals off: none written, the validators still pass.
    let seq = MeshSequence::new(
        mesh.clone(),
        (0..frames).flat_map(&frame).collect(),
        Some(24.0),
    )
    .unwrap();
    let bare = dir.path().join("bare.usda");
    surfmotion::mesh::io::usd::write_usda_with(
        &seq,
        24.0,
        &bare,
        surfmotion::mesh::io::usd::UsdOptions { normals: false },
    )
    .unwrap();
    let b = usd_dump(&py, &bare);
    assert_eq!(b["normalTimes"], serde_json::json!([]));
    assert_eq!(b["restNormals"], serde_json::json!([]));
    assert_eq!(b["points"], v["points"]);
}

/// The normals of [`usda_output_passes_usd_core_and_reads_back_equal`]'s
/// dump `v`: vertex interpolation, one sample per frame, each equal (as
/// f32) to the area-weighted normals of our frame (the rest's for the
/// `collapsed` frame), unit length, and on the side the winding faces.
fn usda_normals_read_back_equal(
    v: &serde_json::Value,
    mesh: &Mesh,
    frames: usize,
    collapsed: usize,
    frame: &dyn Fn(usize) -> Vec<[f64; 3]>,
) {
    use surfmotion::mesh::normals::vertex_normals;
    assert_eq!(v["normalsInterpolation"], "vertex");
    let times: Vec<f64> = (0..frames).map(|k| k as f64).collect();
    assert_eq!(v["normalTimes"], serde_json::json!(times));
    let rest = vertex_normals(mesh.positions(), mesh.triangles());
    let as_f32 =
        |n: &[[f64; 3]]| -> Vec<[f32; 3]> { n.iter().map(|q| q.map(|x| x as f32)).collect() };
    assert_eq!(f32x3s(&v["restNormals"]), as_f32(&rest));
    let normals = v["normals"].as_array().unwrap();
    assert_eq!(normals.len(), frames);
    for (k, n) in normals.iter().enumerate() {
        let p = frame(k);
        let ours = match k == collapsed {
            true => rest.clone(),
            false => vertex_normals(&p, mesh.triangles()),
        };
        let theirs = f32x3s(n);
        assert_eq!(theirs, as_f32(&ours), "frame {k}");
        let c = p
            .iter()
            .fold([0.0; 3], |s, q| [0, 1, 2].map(|a| s[a] + q[a] / 4.0));
        // Triangle 0 (0, 1, 2) faces away from vertex 3 when the winding
        // faces out: `side` < 0 then, and each normal points away from
        // the centroid.
        let d = |i: usize| [0, 1, 2].map(|a| p[i][a] - p[0][a]);
        let (e1, e2, e3) = (d(1), d(2), d(3));
        let side = (e1[1] * e2[2] - e1[2] * e2[1]) * e3[0]
            + (e1[2] * e2[0] - e1[0] * e2[2]) * e3[1]
            + (e1[0] * e2[1] - e1[1] * e2[0]) * e3[2];
        for (i, t) in theirs.iter().enumerate() {
            let len = t.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>().sqrt();
            assert!(
                (len - 1.0).abs() < 1e-6,
                "frame {k} vertex {i}: length {len}"
            );
            let out: f64 = (0..3).map(|a| f64::from(t[a]) * (p[i][a] - c[a])).sum();
            assert!(
                k == collapsed || out * side < 0.0,
                "frame {k} vertex {i}: the normal is on the wrong side ({out}, {side})"
            );
        }
    }
}

/// Issue 44: `--usd-no-normals`, the command line's switch for
/// `UsdOptions::normals`. `mesh convert` of a generated sequence (a
/// tetrahedron breathing, and the same sequence turned and shifted: each
/// frame's normals differ) to `.usda` with and without it: both pass
/// Pixar's validators and read back the same points; the default file has
/// one normal sample per frame, the other none and is the library's
/// `write_usda_with(.., UsdOptions { normals: false })` byte for byte,
/// smaller. Given with a non-USD output the flag is refused in one line
/// naming it and the output, and nothing is written.
#[test]
fn usd_no_normals_on_the_command_line_leaves_the_normals_out() {
    let Some(py) = usd_python() else { return };
    let dir = tempfile::tempdir().unwrap();
    let tetra = Mesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    )
    .unwrap();
    for (v, (turn, shift)) in [(0.0_f64, 0.0), (0.7, 2.5)].into_iter().enumerate() {
        let frames = 6;
        let all: Vec<[f64; 3]> = (0..frames)
            .flat_map(|k| {
                let s = 1.0 + 0.2 * (k as f64).sin();
                let (c, sn) = (turn.cos(), turn.sin());
                tetra.positions().iter().enumerate().map(move |(i, p)| {
                    let q = [p[0] * s, p[1] * (2.0 - s), p[2] + 0.1 * (i * k) as f64];
                    [c * q[0] - sn * q[2] + shift, q[1], sn * q[0] + c * q[2]]
                })
            })
            .collect();
        let seq = MeshSequence::new(tetra.clone(), all, Some(25.0)).unwrap();
        let src = dir.path().join(format!("breath{v}.pc2"));
        save_sequence(&seq, &src, Some(25.0)).unwrap();
        let convert = |out: &Path, extra: &[&str]| {
            common::run_ok(
                std::process::Command::new(common::bin())
                    .args(["mesh", "convert"])
                    .arg(&src)
                    .arg(out)
                    .args(["--fps", "25"])
                    .args(extra),
            )
        };
        let with = dir.path().join(format!("with{v}.usda"));
        let without = dir.path().join(format!("without{v}.usda"));
        convert(&with, &[]);
        convert(&without, &["--usd-no-normals"]);
        let (a, b) = (usd_dump(&py, &with), usd_dump(&py, &without));
        assert_eq!(a["points"], b["points"], "variant {v}");
        assert_eq!(a["points"].as_array().unwrap().len(), frames);
        assert_eq!(
            a["normals"].as_array().unwrap().len(),
            frames,
            "variant {v}"
        );
        assert_eq!(b["normalTimes"], serde_json::json!([]), "variant {v}");
        assert_eq!(b["restNormals"], serde_json::json!([]), "variant {v}");
        let lib = dir.path().join(format!("lib{v}.usda"));
        let back = load_sequence(src.to_str().unwrap(), &LoadOptions::default()).unwrap();
        surfmotion::mesh::io::usd::write_usda_with(
            &back,
            25.0,
            &lib,
            surfmotion::mesh::io::usd::UsdOptions { normals: false },
        )
        .unwrap();
        let bytes = |p: &Path| std::fs::read(p).unwrap();
        // The prim is named after the file: compare past the names.
        let body = |p: &Path| {
            String::from_utf8(bytes(p))
                .unwrap()
                .replace(p.file_stem().unwrap().to_str().unwrap(), "PRIM")
        };
        assert_eq!(body(&without), body(&lib), "variant {v}");
        assert!(bytes(&without).len() < bytes(&with).len());
    }
    for out in ["x.glb", "x.pc2", "frames"] {
        let r = common::run_cli(
            &["mesh", "convert", "breath0.pc2", out, "--usd-no-normals"],
            Some(dir.path()),
            &[],
        );
        let problems = r.bad_input_problems(&["--usd-no-normals", out, ".usda"]);
        assert!(problems.is_empty(), "{out}: {problems:?}: {}", r.stderr);
        assert!(!dir.path().join(out).exists(), "{out} written");
    }
}

/// `--usd-no-normals` on every other verb that writes a sequence is
/// refused for a non-USD output before any work (the database and clips
/// named here do not exist: the refusal comes first), in one line naming
/// the flag and the output, as the `--glb-*` flags are for a non-GLB one;
/// `live` without `--record` names `--record`.
#[test]
fn usd_no_normals_is_refused_for_other_outputs_on_every_verb() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir_all(d.join("clips")).unwrap();
    for (args, words) in [
        (
            "retarget --db db --mocap w.bvh -o out.glb --usd-no-normals",
            &["--usd-no-normals", "out.glb", ".usda"][..],
        ),
        (
            "transfer --scan s.obj --landmarks l.json --mocap w.bvh -o out.pc2 --usd-no-normals",
            &["--usd-no-normals", "out.pc2", ".usda"][..],
        ),
        (
            "batch --db db --mocap-dir clips -o outs --format glb --usd-no-normals",
            &["--usd-no-normals", "--format glb", ".usda"][..],
        ),
        (
            "live --db db --replay w.bvh --record rec.mdd --usd-no-normals",
            &["--usd-no-normals", "rec.mdd", ".usda"][..],
        ),
        (
            "live --db db --replay w.bvh --usd-no-normals",
            &["--usd-no-normals", "--record"][..],
        ),
        (
            "play --db db --script s.json -o out.pc2 --usd-no-normals",
            &["--usd-no-normals", "out.pc2", ".usda"][..],
        ),
        (
            "play --db db --script s.json -o out.usda --glb-quantize",
            &["--glb-quantize", "out.usda", ".glb"][..],
        ),
        (
            "keyframe --db db --from a:0 --to a:1 --distance 1 --time 1 -o out.glb --usd-no-normals",
            &["--usd-no-normals", "out.glb", ".usda"][..],
        ),
    ] {
        let args: Vec<&str> = args.split(' ').collect();
        let r = common::run_cli(&args, Some(d), &[]);
        let problems = r.bad_input_problems(words);
        assert!(problems.is_empty(), "{args:?}: {problems:?}: {}", r.stderr);
    }
    let left: Vec<_> = std::fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left, vec![std::ffi::OsString::from("clips")], "{left:?}");
}
