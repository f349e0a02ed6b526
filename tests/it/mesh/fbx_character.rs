//! A rigged FBX character as `rig embed --skin` takes a skinned glTF
//! (`mesh::io::fbx`, issue 44): mesh in its bind pose, skin clusters as
//! joints and weights, the same embedding downstream.

use crate::common;
use std::path::Path;
use surfmotion::embed::skin::from_skin;
use surfmotion::mesh::io::fbx::{parse_fbx_character, read_fbx_character};
use surfmotion::rig::Canonical;

/// Mixamo's dancer (two skinned meshes, 65 `mixamorig:` bones, cm): read
/// in metres, Y up, its joints named without the namespace, and embedded
/// with no rig map: upright, facing +Z (Mixamo's front), left at +X, the
/// pelvis at the `Hips` bind position, every vertex weighted.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn mixamo_fbx_character_embeds_as_a_gltf_skin_does() {
    let Some(d) = common::data_dir() else { return };
    let f = d.join("fbx/threejs/Samba Dancing.fbx");
    let a = read_fbx_character(&f).unwrap();
    // Beta_Surface + Beta_Joints.
    assert_eq!(a.mesh.vertex_count(), 24_746);
    let skin = a.skin.as_ref().unwrap();
    assert_eq!(skin.joint_names.len(), 65);
    assert_eq!(skin.joint_names[0], "Hips");
    for (v, w) in skin.weights.iter().enumerate() {
        let s: f32 = w.iter().sum();
        assert!((s - 1.0).abs() < 1e-5, "vertex {v}: weights sum to {s}");
    }
    let b = surfmotion::mesh::Bounds::of(a.mesh.positions());
    let tall = b.max[1] - b.min[1];
    assert!((1.7..1.9).contains(&tall), "height {tall} m");
    assert!(b.min[1].abs() < 0.01, "feet at {}", b.min[1]);
    let e = from_skin(&a.mesh, &a, None, &f).unwrap();
    assert!(
        e.notes().iter().any(|n| n.contains("HumanIK")),
        "{:?}",
        e.notes()
    );
    assert!(e.facing()[2] > 0.99, "facing {:?}", e.facing());
    let j = |c: Canonical| glam::DVec3::from_array(e.joints()[c.index()]);
    assert!(j(Canonical::LWrist).x > 0.5 && j(Canonical::RWrist).x < -0.5);
    assert!(j(Canonical::Head).y > j(Canonical::Chest).y);
    assert!(j(Canonical::Chest).y > j(Canonical::Pelvis).y);
    assert!(j(Canonical::LKnee).y < j(Canonical::LHip).y);
    let hips = glam::Mat4::from_cols_array_2d(&skin.inverse_bind[0])
        .inverse()
        .w_axis;
    assert!((j(Canonical::Pelvis) - hips.truncate().as_dvec3()).length() < 1e-6);
    // The regressors reproduce the joints on the rest frame.
    let sk = e.frame_joints(a.mesh.positions());
    for c in Canonical::ALL {
        assert!((sk[c.index()] - j(c)).length() < 1e-6, "{}", c.name());
    }
}

/// The verb: `rig embed CHAR.fbx --skin CHAR.fbx` writes the embedding and
/// its picture; a truncated FBX and an FBX without a mesh are refused in
/// one line naming the file.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn rig_embed_takes_an_fbx_skin_and_refuses_broken_ones_in_one_line() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let f = d.join("fbx/threejs/Samba Dancing.fbx");
    let out = tmp.path().join("rig.json");
    let png = tmp.path().join("rig.png");
    let o = common::run_ok(
        std::process::Command::new(common::bin())
            .args(["rig", "embed"])
            .arg(&f)
            .arg("--skin")
            .arg(&f)
            .arg("-o")
            .arg(&out)
            .arg("--png")
            .arg(&png)
            .arg("--json"),
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let h = v["height"].as_f64().unwrap();
    assert!((1.7..1.9).contains(&h), "{v}");
    assert!(out.is_file() && png.is_file());
    let bytes = std::fs::read(&f).unwrap();
    let cut = tmp.path().join("cut.fbx");
    std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
    let no_mesh = d.join("fbx/isaacgymenvs/01_01_cmu.fbx");
    for (bad, why) in [(&cut, "FBX"), (&no_mesh, "no mesh")] {
        let o = std::process::Command::new(common::bin())
            .args(["rig", "embed"])
            .arg(bad)
            .arg("--skin")
            .arg(bad)
            .arg("-o")
            .arg(tmp.path().join("x.json"))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1));
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(e.trim().lines().count(), 1, "{e}");
        assert!(
            e.contains(&*bad.file_name().unwrap().to_string_lossy()) && e.contains(why),
            "{e}"
        );
    }
}

/// Garbage, a header alone and a truncated file: one-line errors naming
/// the file, no panic.
#[test]
fn malformed_fbx_characters_are_one_line_errors() {
    let p = Path::new("char.fbx");
    for bytes in [
        &b""[..],
        b"garbage",
        b"Kaydara FBX Binary  \0\x1a\0\xff\xff",
        b"; FBX 7.5.0 project file\nObjects: {",
    ] {
        let e = parse_fbx_character(bytes, p).unwrap_err().to_string();
        assert!(e.starts_with("char.fbx: "), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }
}
