//! Kenney's skinned FBX character (Maya 2023, `ufbx/maya_kenney_character_7700_binary.fbx`)
//! through `rig embed --skin` (issue 44). Its first skin cluster binds a
//! foot IK control that the scene as loaded poses away from its bind; the
//! mesh was placed by that cluster's posed matrix, came out lying on its
//! back beside the skeleton, and the embedding refused it ("joint spine:
//! no vertices around it span a volume"). The mesh is now placed by the
//! clusters' bind matrices. It is read at its clip's unit
//! (`rig::read_rigged_character`), the unit decided in `rig` and passed
//! down to the mesh reader.

use crate::common;
use glam::DVec3;
use surfmotion::embed::skin::from_skin;
use surfmotion::mesh::io::fbx::read_fbx_character;
use surfmotion::rig::{Canonical, read_rigged_character};

use Canonical as C;

/// The mesh stands around its skeleton (feet on the floor, the head's
/// joint inside the mesh's top, the hips inside its width); the embedding
/// is upright, faces +Z (Maya's front), left at +X, and its skeleton is
/// human-proportioned: left and right limbs alike, thigh ≈ shin and upper
/// arm ≈ forearm, the arms out at shoulder height (a T-pose), knees below
/// hips, the trunk above the legs; the regressors give the joints back.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn kenney_fbx_character_embeds_with_a_human_skeleton() {
    let Some(d) = common::data_dir() else { return };
    let f = d.join("fbx/ufbx/maya_kenney_character_7700_binary.fbx");
    let a = read_rigged_character(&f).unwrap();
    assert_eq!(a.mesh.vertex_count(), 804);
    let b = surfmotion::mesh::Bounds::of(a.mesh.positions());
    let tall = b.max[1] - b.min[1];
    // Declared cm (UnitScaleFactor 1) makes a 3.76 m cartoon (the mesh
    // reader alone, below); its limbs give a 2.59 m stature in cm, not a
    // human one, so the body decides as it does for the file's clip (a
    // 1.70 m stature from the limbs): a 2.47 m mesh, the big head on top,
    // the clip's unit named in the asset's problems.
    assert!((2.3..2.6).contains(&tall), "height {tall} m");
    let clip = surfmotion::rig::load_clip(&f, &Default::default()).unwrap();
    let said = format!("units: {} m per file unit", clip.units().metres_per_unit);
    assert!(
        a.problems.iter().any(|p| p.starts_with(&said)),
        "{said} not in {:?}",
        a.problems
    );
    let declared = read_fbx_character(&f).unwrap();
    let bd = surfmotion::mesh::Bounds::of(declared.mesh.positions());
    let tall_declared = bd.max[1] - bd.min[1];
    assert!(
        (3.5..4.0).contains(&tall_declared),
        "declared: height {tall_declared} m"
    );
    assert!(
        !declared.problems.iter().any(|p| p.starts_with("units:")),
        "{:?}",
        declared.problems
    );
    // The same mesh, scaled about the origin by the two units' ratio.
    let k = clip.units().metres_per_unit / 0.01;
    for (p, q) in a.mesh.positions().iter().zip(declared.mesh.positions()) {
        for i in 0..3 {
            assert!((p[i] - k * q[i]).abs() < 1e-9, "{p:?} vs {q:?} × {k}");
        }
    }
    assert!(b.min[1].abs() < 0.02, "feet at {}", b.min[1]);
    let width = b.max[0] - b.min[0];
    let depth = b.max[2] - b.min[2];
    assert!(
        depth < 0.35 * tall && width > 0.8 * tall,
        "T-pose bounds {b:?}"
    );
    let e = from_skin(&a.mesh, &a, None, &f).unwrap();
    assert!(e.facing()[2] > 0.99, "facing {:?}", e.facing());
    let j = |c: C| DVec3::from_array(e.joints()[c.index()]);
    let len = |a: C, b: C| j(a).distance(j(b));
    // Left at +X, mirrored right.
    for (l, r) in [
        (C::LShoulder, C::RShoulder),
        (C::LElbow, C::RElbow),
        (C::LWrist, C::RWrist),
        (C::LHip, C::RHip),
        (C::LKnee, C::RKnee),
        (C::LAnkle, C::RAnkle),
    ] {
        assert!(j(l).x > 0.05 && j(r).x < -0.05, "{} {}", l.name(), r.name());
        let m = j(r) * DVec3::new(-1.0, 1.0, 1.0);
        assert!(j(l).distance(m) < 0.01 * tall, "{} not mirrored", l.name());
    }
    // Vertical order and proportions.
    assert!(j(C::Head).y > j(C::Neck).y && j(C::Neck).y > j(C::Chest).y);
    assert!(j(C::Chest).y > j(C::Pelvis).y && j(C::Pelvis).y > j(C::LKnee).y);
    assert!(j(C::LKnee).y > j(C::LAnkle).y && j(C::LAnkle).y > j(C::LToe).y - 0.01);
    let thigh_shin = len(C::LHip, C::LKnee) / len(C::LKnee, C::LAnkle);
    let arm = len(C::LShoulder, C::LElbow) / len(C::LElbow, C::LWrist);
    assert!(
        (0.75..1.33).contains(&thigh_shin),
        "thigh / shin {thigh_shin}"
    );
    assert!((0.75..1.33).contains(&arm), "upper arm / forearm {arm}");
    let leg = len(C::LHip, C::LKnee) + len(C::LKnee, C::LAnkle);
    let reach = len(C::LShoulder, C::LElbow) + len(C::LElbow, C::LWrist);
    assert!(
        (0.6..1.2).contains(&(reach / leg)),
        "arm / leg {}",
        reach / leg
    );
    assert!((j(C::LWrist).y - j(C::LShoulder).y).abs() < 0.15 * reach);
    // Every joint inside the mesh's bounds.
    for c in Canonical::ALL {
        let p = j(c);
        for k in 0..3 {
            assert!(
                p[k] >= b.min[k] - 1e-6 && p[k] <= b.max[k] + 1e-6,
                "{} at {p} outside {b:?}",
                c.name()
            );
        }
    }
    let sk = e.frame_joints(a.mesh.positions());
    for c in Canonical::ALL {
        assert!((sk[c.index()] - j(c)).length() < 1e-6, "{}", c.name());
    }
}

/// ufbx's barbarian (Blender 2.93, French bone names) has legs of two
/// bones, `jambe` (thigh) and `pied` (the shin, reaching the ground), the
/// second's tail written as a leaf joint `pied …_end`, and no foot bone:
/// "the leg chain from 'jambe gauche' has fewer than three joints". It
/// maps now, the end marker as the ankle and the toe placed by
/// proportion, with a note; left on the left (+X: the character faces
/// +Z), the ankles below the knees below the hips.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_barbarian_maps_with_two_joint_legs() {
    let Some(d) = common::data_dir() else { return };
    let f = d.join("fbx/ufbx/blender_293_barbarian_7400_binary.fbx");
    let mut clip = surfmotion::rig::load_clip(&f, &Default::default()).unwrap();
    clip.to_metres_y_up();
    let det = surfmotion::rig::detect_clip(&clip).unwrap();
    assert!(det.missing.is_empty(), "{:?}", det.missing);
    let name = |c: C| det.map.joints.get(&c).cloned().unwrap_or_default();
    assert_eq!(name(C::LHip), "jambe gauche");
    assert_eq!(name(C::LKnee), "pied gauche");
    assert_eq!(name(C::LAnkle), "pied gauche_end");
    assert_eq!(name(C::RAnkle), "pied droit_end");
    assert!(det.derived.contains(&C::LToe) && det.derived.contains(&C::RToe));
    assert!(
        det.structure_pose.contains("two joints and an end marker"),
        "{}",
        det.structure_pose
    );
    let poses = det.map.poses(&clip).unwrap();
    for p in [&poses[0], &poses[poses.len() / 2]] {
        let y = |c: C| p[c.index()].y;
        assert!(y(C::LHip) > y(C::LKnee) && y(C::LKnee) > y(C::LAnkle));
        assert!(y(C::RHip) > y(C::RKnee) && y(C::RKnee) > y(C::RAnkle));
        assert!(y(C::Head) > y(C::Neck) && y(C::Neck) > y(C::Pelvis));
        // Left of the body: +X, up × forward with the face towards +Z.
        assert!(p[C::LHip.index()].x > p[C::RHip.index()].x);
        assert!(p[C::LShoulder.index()].x > p[C::RShoulder.index()].x);
    }
}
