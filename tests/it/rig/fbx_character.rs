//! Kenney's skinned FBX character (Maya 2023, `ufbx/maya_kenney_character_7700_binary.fbx`)
//! through `rig embed --skin` (issue 44). Its first skin cluster binds a
//! foot IK control that the scene as loaded poses away from its bind; the
//! mesh was placed by that cluster's posed matrix, came out lying on its
//! back beside the skeleton, and the embedding refused it ("joint spine:
//! no vertices around it span a volume"). The mesh is now placed by the
//! clusters' bind matrices.

use crate::common;
use glam::DVec3;
use surfmotion::embed::skin::from_skin;
use surfmotion::mesh::io::fbx::read_fbx_character;
use surfmotion::rig::Canonical;

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
    let a = read_fbx_character(&f).unwrap();
    assert_eq!(a.mesh.vertex_count(), 804);
    let b = surfmotion::mesh::Bounds::of(a.mesh.positions());
    let tall = b.max[1] - b.min[1];
    // cm as declared (UnitScaleFactor 1): a 3.76 m cartoon with a big head
    // (the mesh 1.05 m deep at it).
    assert!((3.5..4.0).contains(&tall), "height {tall} m");
    assert!(b.min[1].abs() < 0.02, "feet at {}", b.min[1]);
    let width = b.max[0] - b.min[0];
    let depth = b.max[2] - b.min[2];
    assert!(
        depth < 0.35 * tall && width > 0.8 * tall,
        "T-pose bounds {b:?}"
    );
    let e = from_skin(&a.mesh, &a, None, &f).unwrap();
    assert!(e.facing[2] > 0.99, "facing {:?}", e.facing);
    let j = |c: C| DVec3::from_array(e.joints[c.index()]);
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
