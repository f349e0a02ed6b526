//! Automatic joint mapping of any humanoid (names, then structure and
//! geometry): renamed, re-ordered, helper-padded, toe-less, head-less and
//! mirrored variants of procedural and real clips, written out as BVH and
//! read back, map to the same canonical joints; non-humanoids are refused;
//! weird hierarchies never panic.

mod common;

use glam::{DQuat, DVec3};
use proptest::prelude::*;
use surfmotion::mocap::bvh::{BvhOptions, format_bvh, parse_bvh};
use surfmotion::mocap::{Channel, Clip, Joint, JointId, PointConvention, Units, UpAxis};
use surfmotion::rig::load_clip;
use surfmotion::rig::{Canonical, RigError, RigMap, Source, detect_clip};
use surfmotion::skeleton::Pose;

/// A joint of an edited hierarchy: where its per-frame data comes from.
#[derive(Clone)]
struct Node {
    name: String,
    parent: Option<usize>,
    offset: DVec3,
    channels: Vec<Channel>,
    tail: Option<DVec3>,
    /// Old joint whose rotation/translation it takes; `None`: identity and
    /// the offset (an inserted pass-through or leaf).
    src: Option<usize>,
    /// Fraction of the source's translation to use (split bones).
    scale: f64,
}

fn nodes_of(c: &Clip) -> Vec<Node> {
    c.joints
        .iter()
        .enumerate()
        .map(|(i, j)| Node {
            name: j.name.clone(),
            parent: j.parent.map(|p| p.idx()),
            offset: j.offset,
            channels: j.channels.clone(),
            tail: j.tail,
            src: Some(i),
            scale: 1.0,
        })
        .collect()
}

/// Rebuilds a clip from nodes (any order with parents known), depth first
/// with children in `order` (reversed when `reverse`).
fn build(c: &Clip, nodes: &[Node], reverse: bool) -> Clip {
    let n = nodes.len();
    let mut ch = vec![Vec::new(); n];
    let mut root = 0;
    for (i, x) in nodes.iter().enumerate() {
        match x.parent {
            Some(p) => ch[p].push(i),
            None => root = i,
        }
    }
    let mut order = Vec::new();
    let mut stack = vec![root];
    while let Some(i) = stack.pop() {
        order.push(i);
        let mut k = ch[i].clone();
        if !reverse {
            k.reverse();
        }
        stack.extend(k);
    }
    let mut new_of = vec![0usize; n];
    for (k, &i) in order.iter().enumerate() {
        new_of[i] = k;
    }
    let joints: Vec<Joint> = order
        .iter()
        .map(|&i| Joint {
            name: nodes[i].name.clone(),
            parent: nodes[i].parent.map(|p| JointId(new_of[p] as u32)),
            offset: nodes[i].offset,
            channels: nodes[i].channels.clone(),
            tail: nodes[i].tail,
        })
        .collect();
    let frames = c.frame_count();
    let mut rot = Vec::with_capacity(frames * n);
    let mut tr = Vec::with_capacity(frames * n);
    for f in 0..frames {
        let (q, t) = (c.frame_rotations(f), c.frame_translations(f));
        for &i in &order {
            match nodes[i].src {
                Some(s) => {
                    rot.push(q[s]);
                    tr.push(if c.joints[s].parent.is_none() {
                        t[s]
                    } else if c.joints[s].has_position_channels() {
                        t[s] * nodes[i].scale
                    } else {
                        nodes[i].offset
                    });
                }
                None => {
                    rot.push(DQuat::IDENTITY);
                    // A split bone's upper part follows the child's animated
                    // translation when it has one (Bandai: 6 channels).
                    let child = nodes
                        .iter()
                        .find(|m| m.parent == Some(i) && m.src.is_some() && m.scale < 1.0);
                    tr.push(match child.and_then(|m| m.src.map(|s| (s, m.scale))) {
                        Some((s, k)) if c.joints[s].has_position_channels() => t[s] * (1.0 - k),
                        _ => nodes[i].offset,
                    });
                }
            }
        }
    }
    let mut out = Clip::new(
        joints,
        c.frame_time,
        rot,
        tr,
        c.units.clone(),
        c.up,
        PointConvention::JointOrigins,
    )
    .unwrap();
    out.up_reason = c.up_reason.clone();
    out
}

/// Through the BVH writer and reader.
fn via_bvh(c: &Clip) -> Clip {
    let text = format_bvh(c);
    parse_bvh(
        &text,
        std::path::Path::new("variant.bvh"),
        &BvhOptions::default(),
    )
    .unwrap()
}

/// At most ~60 frames of a clip (keeps the tests fast).
fn short(c: &Clip) -> Clip {
    let n = c.joint_count();
    let frames = c.frame_count();
    let step = (frames / 60).max(1);
    let mut rot = Vec::new();
    let mut tr = Vec::new();
    for f in (0..frames).step_by(step) {
        rot.extend_from_slice(c.frame_rotations(f));
        tr.extend_from_slice(c.frame_translations(f));
    }
    let _ = n;
    let mut out = c.clone();
    out.rotations = rot;
    out.translations = tr;
    out
}

fn poses(c: &Clip) -> (RigMap, Pose, Vec<Pose>) {
    let d = detect_clip(c).unwrap_or_else(|e| panic!("{e}: {:?}", c.point_names()));
    assert!(d.missing.is_empty(), "{:?}", d.missing);
    let rest = d.map.rest_pose(c).unwrap();
    let p = d.map.poses(c).unwrap();
    (d.map, rest, p)
}

fn scale(p: &Pose) -> f64 {
    p[Canonical::Head.index()].distance(p[Canonical::LAnkle.index()])
}

fn assert_same(what: &str, a: &(RigMap, Pose, Vec<Pose>), b: &(RigMap, Pose, Vec<Pose>)) {
    let tol = 1e-6 * scale(&a.1).max(1.0);
    assert_eq!(a.2.len(), b.2.len(), "{what}");
    for (f, (pa, pb)) in std::iter::once((&a.1, &b.1))
        .chain(a.2.iter().zip(&b.2))
        .enumerate()
    {
        for c in Canonical::ALL {
            let e = pa[c.index()].distance(pb[c.index()]);
            assert!(
                e <= tol * 10.0 + 1e-4 * scale(pa),
                "{what}: pose {f} {} differs by {e} (original map {:?}, variant map {:?} derived {:?})",
                c.name(),
                a.0.joints.get(&c),
                b.0.joints.get(&c),
                b.0.derived.get(&c)
            );
        }
    }
}

/// Canonical joint → original joint index, from the original's detection.
fn canonical_index(c: &Clip, map: &RigMap) -> Vec<Option<Canonical>> {
    let mut out = vec![None; c.joint_count()];
    for (k, name) in &map.joints {
        if let Some(j) = c.joint(name) {
            out[j.idx()] = Some(*k);
        }
    }
    out
}

/// Name families: canonical joint → name (left side; the right is made by
/// `side`).
struct Family {
    name: &'static str,
    torso: [&'static str; 5],
    limbs: [&'static str; 7],
    side: fn(&str, bool) -> String,
}

fn left_prefix(s: &str, l: bool) -> String {
    format!("{}{s}", if l { "Left" } else { "Right" })
}
fn l_prefix(s: &str, l: bool) -> String {
    format!("{}{s}", if l { "l" } else { "r" })
}
fn l_under(s: &str, l: bool) -> String {
    format!("{}_{s}", if l { "L" } else { "R" })
}
fn left_under(s: &str, l: bool) -> String {
    format!("{}_{s}", if l { "left" } else { "right" })
}
fn suffix_left(s: &str, l: bool) -> String {
    format!("{s}{}", if l { "Left" } else { "Right" })
}
fn biped(s: &str, l: bool) -> String {
    format!("Bip01 {} {s}", if l { "L" } else { "R" })
}
fn dot_l(s: &str, l: bool) -> String {
    format!("{s}.{}", if l { "L" } else { "R" })
}

const FAMILIES: &[Family] = &[
    Family {
        name: "daz",
        torso: ["hip", "abdomen", "chest", "neck", "head"],
        limbs: ["Shldr", "ForeArm", "Hand", "Thigh", "Shin", "Foot", "Toe"],
        side: l_prefix,
    },
    Family {
        name: "smpl",
        torso: ["Pelvis", "Spine1", "Spine3", "Neck", "Head"],
        limbs: ["Shoulder", "Elbow", "Wrist", "Hip", "Knee", "Ankle", "Foot"],
        side: l_under,
    },
    Family {
        name: "smpl lower-case",
        torso: ["pelvis", "spine1", "spine3", "neck", "head"],
        limbs: ["shoulder", "elbow", "wrist", "hip", "knee", "ankle", "foot"],
        side: left_under,
    },
    Family {
        name: "kinect",
        torso: ["SpineBase", "SpineMid", "SpineShoulder", "Neck", "Head"],
        limbs: ["Shoulder", "Elbow", "Wrist", "Hip", "Knee", "Ankle", "Foot"],
        side: suffix_left,
    },
    Family {
        name: "xsens",
        torso: ["Pelvis", "L3", "T8", "Neck", "Head"],
        limbs: [
            "UpperArm", "ForeArm", "Hand", "UpperLeg", "LowerLeg", "Foot", "Toe",
        ],
        side: left_prefix,
    },
    Family {
        name: "unity",
        torso: ["Hips", "Spine", "Chest", "Neck", "Head"],
        limbs: [
            "UpperArm", "LowerArm", "Hand", "UpperLeg", "LowerLeg", "Foot", "Toes",
        ],
        side: left_prefix,
    },
    Family {
        name: "biped",
        torso: [
            "Bip01 Pelvis",
            "Bip01 Spine",
            "Bip01 Spine2",
            "Bip01 Neck",
            "Bip01 Head",
        ],
        limbs: [
            "UpperArm", "Forearm", "Hand", "Thigh", "Calf", "Foot", "Toe0",
        ],
        side: biped,
    },
    Family {
        name: "blender",
        torso: ["hips", "spine", "chest", "neck", "head"],
        limbs: [
            "upper_arm",
            "forearm",
            "hand",
            "thigh",
            "shin",
            "foot",
            "toe",
        ],
        side: dot_l,
    },
];

fn family_name(f: &Family, c: Canonical) -> String {
    use Canonical::*;
    let (k, l) = match c {
        Pelvis | Spine | Chest | Neck | Head => return f.torso[c.index()].to_string(),
        LShoulder => (0, true),
        LElbow => (1, true),
        LWrist => (2, true),
        RShoulder => (0, false),
        RElbow => (1, false),
        RWrist => (2, false),
        LHip => (3, true),
        LKnee => (4, true),
        LAnkle => (5, true),
        LToe => (6, true),
        RHip => (3, false),
        RKnee => (4, false),
        RAnkle => (5, false),
        RToe => (6, false),
    };
    (f.side)(f.limbs[k], l)
}

/// Canonical joints renamed to the family; helper-named joints keep their
/// name; every other joint becomes a neutral `x<i>`.
fn rename(c: &Clip, map: &RigMap, f: &Family, prefix: &str) -> Vec<Node> {
    let canon = canonical_index(c, map);
    let mut nodes = nodes_of(c);
    for (i, n) in nodes.iter_mut().enumerate() {
        let toks = surfmotion::rig::names::tokens(surfmotion::rig::names::strip_namespace(&n.name));
        n.name = match canon[i] {
            Some(k) => format!("{prefix}{}", family_name(f, k)),
            None if surfmotion::rig::names::is_helper(&toks) => format!("{prefix}{}", n.name),
            None => format!("{prefix}x{i}"),
        };
    }
    nodes
}

/// Inserts a helper between `child` and its parent: a pass-through bone of
/// `frac` of the child's offset (the child keeps the rest).
fn split(nodes: &mut Vec<Node>, child: usize, frac: f64, name: &str) {
    let p = nodes[child].parent;
    let off = nodes[child].offset;
    let rot_ch: Vec<Channel> = nodes[child]
        .channels
        .iter()
        .copied()
        .filter(|c| c.is_rotation())
        .collect();
    nodes.push(Node {
        name: name.to_string(),
        parent: p,
        offset: off * frac,
        channels: rot_ch,
        tail: None,
        src: None,
        scale: 1.0,
    });
    let k = nodes.len() - 1;
    nodes[child].parent = Some(k);
    nodes[child].offset = off * (1.0 - frac);
    nodes[child].scale = 1.0 - frac;
}

fn leaf(nodes: &mut Vec<Node>, parent: usize, offset: DVec3, name: &str) {
    let ch = nodes[parent]
        .channels
        .iter()
        .copied()
        .filter(|c| c.is_rotation())
        .collect();
    nodes.push(Node {
        name: name.to_string(),
        parent: Some(parent),
        offset,
        channels: ch,
        tail: Some(offset * 0.5),
        src: None,
        scale: 1.0,
    });
}

/// Removes `j` and its subtree; its parent gets `tail` as End Site.
fn remove(nodes: &[Node], j: usize, tail: Option<DVec3>) -> Vec<Node> {
    let mut gone = vec![false; nodes.len()];
    for (i, g) in gone.iter_mut().enumerate() {
        let mut k = Some(i);
        while let Some(x) = k {
            if x == j {
                *g = true;
                break;
            }
            k = nodes[x].parent;
        }
    }
    let mut idx = vec![usize::MAX; nodes.len()];
    let mut out = Vec::new();
    for (i, n) in nodes.iter().enumerate() {
        if !gone[i] {
            idx[i] = out.len();
            out.push(n.clone());
        }
    }
    for n in &mut out {
        n.parent = n.parent.map(|p| idx[p]);
    }
    if let Some(p) = nodes[j].parent {
        out[idx[p]].tail = tail;
    }
    out
}

/// The clips under test: procedural walk and run, and short copies of real
/// clips of every family in the shared data.
fn originals() -> Vec<(String, Clip)> {
    let mut out = vec![
        (
            "procedural walk".to_string(),
            surfmotion::synth::gait_clip(surfmotion::synth::Gait::Walk, 2.0, 30.0),
        ),
        (
            "procedural run".to_string(),
            surfmotion::synth::gait_clip(surfmotion::synth::Gait::Run, 2.0, 30.0),
        ),
    ];
    if let Some(d) = common::optional_data_dir() {
        for rel in [
            "mocap/cmu-bvh/01_01.bvh",
            "mocap/cmu-bvh/131_01.bvh",
            "mocap/cmu-bvh-ccrig/005_01.bvh",
            "mocap/bandai-namco/dataset-1_walk_normal_001.bvh",
            "mocap/bandai-namco/dataset-1_dash_normal_001.bvh",
            "mocap/cmu-amc/02/02_01.amc",
        ] {
            let c = load_clip(&d.join(rel), &Default::default()).unwrap();
            out.push((rel.to_string(), short(&c)));
        }
    }
    out
}

#[test]
fn renamed_reordered_and_padded_variants_map_like_the_original() {
    for (what, c) in originals() {
        let c = via_bvh(&c);
        let orig = poses(&c);
        for (k, f) in FAMILIES.iter().enumerate() {
            let prefix = ["", "Character1_", "mixamorig7:", "Armature|"][k % 4];
            let nodes = rename(&c, &orig.0, f, prefix);
            let v = via_bvh(&build(&c, &nodes, k % 2 == 1));
            let got = poses(&v);
            assert!(
                !surfmotion::rig::CONVENTIONS
                    .iter()
                    .any(|cv| cv.name == got.0.convention),
                "{what} as {}: claims {}",
                f.name,
                got.0.convention
            );
            assert_same(&format!("{what} as {}", f.name), &orig, &got);
        }
        // Helpers: a twist bone halfway down each upper arm, a zero-length
        // pass-through above each knee, mesh-attachment leaves on the elbows.
        let canon = canonical_index(&c, &orig.0);
        let at = |k: Canonical| canon.iter().position(|x| *x == Some(k)).unwrap();
        let mut nodes = nodes_of(&c);
        for (e, s) in [(Canonical::LElbow, "L"), (Canonical::RElbow, "R")] {
            split(&mut nodes, at(e), 0.5, &format!("{s}_UpperArmTwist01"));
        }
        for k in [Canonical::LKnee, Canonical::RKnee] {
            split(&mut nodes, at(k), 0.0, &format!("pass{}", k.index()));
        }
        for e in [Canonical::LElbow, Canonical::RElbow] {
            let o = nodes[at(e)].offset;
            leaf(
                &mut nodes,
                at(e),
                DVec3::new(o.y, o.z, o.x) * 0.2,
                &format!("Arm{}_RIGMESH", e.index()),
            );
        }
        let v = via_bvh(&build(&c, &nodes, true));
        assert_same(&format!("{what} with helpers"), &orig, &poses(&v));
        // Neutral-named twist bones (geometry alone must skip them).
        let mut nodes = rename(&c, &orig.0, &FAMILIES[5], "");
        for e in [Canonical::LElbow, Canonical::RElbow] {
            split(&mut nodes, at(e), 0.4, &format!("seg{}", e.index()));
        }
        let v = via_bvh(&build(&c, &nodes, false));
        assert_same(
            &format!("{what} with neutral pass-through bones"),
            &orig,
            &poses(&v),
        );
    }
}

#[test]
fn toeless_and_headless_skeletons_derive_the_missing_joints() {
    for (what, c) in originals() {
        let c = via_bvh(&c);
        let orig = poses(&c);
        let canon = canonical_index(&c, &orig.0);
        let at = |k: Canonical| canon.iter().position(|x| *x == Some(k)).unwrap();
        let nodes = rename(&c, &orig.0, &FAMILIES[0], "");
        // Toes and head removed; their offsets become End Sites, so the
        // derived points are exactly the removed joints.
        let mut n2 = nodes.clone();
        for (toe, ankle) in [
            (Canonical::LToe, Canonical::LAnkle),
            (Canonical::RToe, Canonical::RAnkle),
        ] {
            let off = nodes[at(toe)].offset;
            let a = &nodes[at(ankle)].name;
            // Every child of the ankle goes (toes and helper bones beside them).
            while let Some(j) = n2
                .iter()
                .position(|n| n.parent.is_some_and(|p| n2[p].name == *a))
            {
                n2 = remove(&n2, j, Some(off));
            }
        }
        // The head goes when it hangs off the neck (or a helper bone after
        // it); with a real joint in between (ASF upperneck) that joint is
        // the head found.
        let hp = nodes[at(Canonical::Head)].parent.unwrap();
        let hp_toks = surfmotion::rig::names::tokens(&nodes[hp].name);
        let headless = hp == at(Canonical::Neck) || surfmotion::rig::names::is_helper(&hp_toks);
        if headless {
            let j = n2
                .iter()
                .position(|n| n.name == nodes[at(Canonical::Head)].name)
                .unwrap();
            let off = n2[j].offset;
            n2 = remove(&n2, j, Some(off));
        }
        let v = via_bvh(&build(&c, &n2, false));
        let d = detect_clip(&v).unwrap_or_else(|e| panic!("{what}: {e}"));
        for k in [Canonical::LToe, Canonical::RToe, Canonical::Head] {
            if k == Canonical::Head && !headless {
                continue;
            }
            assert!(d.derived.contains(&k), "{what}: {k:?} not derived");
            let r = d.joints.iter().find(|j| j.canonical == k).unwrap();
            assert_eq!(r.source, Source::Derived);
            assert!((0.0..=1.0).contains(&r.confidence));
        }
        let got = (
            d.map.clone(),
            d.map.rest_pose(&v).unwrap(),
            d.map.poses(&v).unwrap(),
        );
        assert_same(&format!("{what} toe-less, head-less"), &orig, &got);
        // The map (with its rules) round-trips through JSON.
        let s = serde_json::to_string(&d.map).unwrap();
        let back: RigMap = serde_json::from_str(&s).unwrap();
        assert_eq!(back, d.map);
        // No End Sites at all: toes forward of and below the ankle, head
        // above the neck.
        let mut n3 = n2.clone();
        for (i, n) in n3.iter_mut().enumerate() {
            if !n2.iter().any(|m| m.parent == Some(i)) {
                n.tail = Some(DVec3::ZERO);
            }
        }
        let v = via_bvh(&build(&c, &n3, false));
        let d = detect_clip(&v).unwrap_or_else(|e| panic!("{what} without End Sites: {e}"));
        let ps = d.map.poses(&v).unwrap();
        for p in ps.iter().step_by(7) {
            use Canonical as C;
            let up = (p[C::Neck.index()] - p[C::Pelvis.index()]).normalize();
            let head = p[C::Head.index()] - p[C::Neck.index()];
            assert!(head.dot(up) > 0.0, "{what}: head below the neck");
            for (t, a, kn) in [
                (C::LToe, C::LAnkle, C::LKnee),
                (C::RToe, C::RAnkle, C::RKnee),
            ] {
                let shin = p[kn.index()].distance(p[a.index()]);
                let toe = p[t.index()] - p[a.index()];
                assert!(toe.is_finite() && toe.length() < shin, "{what}: toe {toe}");
                assert!(toe.dot(up) < 0.0, "{what}: toe above the ankle");
            }
        }
    }
}

fn swap_side(c: Canonical) -> Canonical {
    let n = c.name();
    let o = if let Some(r) = n.strip_prefix("l_") {
        format!("r_{r}")
    } else if let Some(r) = n.strip_prefix("r_") {
        format!("l_{r}")
    } else {
        n.to_string()
    };
    Canonical::from_name(&o).unwrap_or(c)
}

fn mirror(c: &Clip) -> Clip {
    let m = DVec3::new(-1.0, 1.0, 1.0);
    let mut out = c.clone();
    for j in &mut out.joints {
        j.offset *= m;
        if let Some(t) = &mut j.tail {
            *t *= m;
        }
    }
    for t in &mut out.translations {
        *t *= m;
    }
    for q in &mut out.rotations {
        *q = DQuat::from_xyzw(q.x, -q.y, -q.z, q.w);
    }
    out
}

#[test]
fn a_mirrored_rig_maps_left_and_right_from_geometry() {
    for (what, c) in originals() {
        let c = via_bvh(&c);
        let orig = poses(&c);
        // x negated, names kept: every "Left" name is now on the right.
        let v = via_bvh(&mirror(&c));
        let got = poses(&v);
        let m = DVec3::new(-1.0, 1.0, 1.0);
        for c2 in Canonical::ALL {
            let other = swap_side(c2);
            let (a, b) = (orig.1[other.index()] * m, got.1[c2.index()]);
            assert!(
                a.distance(b) < 1e-4 * scale(&orig.1),
                "{what}: mirrored {} at {b}, expected the original {} mirrored {a}",
                c2.name(),
                other.name()
            );
        }
        assert!(
            !surfmotion::rig::CONVENTIONS
                .iter()
                .any(|cv| cv.name == got.0.convention),
            "{what}"
        );
    }
}

/// Left = up × forward with up = pelvis→neck and forward = ankles→toes
/// (worked out on CMU 01_01, whose names we trust: Y-up, feet along +Z,
/// LeftUpLeg at +X, and Y × Z = +X).
fn left_is_left(p: &Pose) -> f64 {
    use Canonical as C;
    let up = (p[C::Neck.index()] - p[C::Pelvis.index()]).normalize_or_zero();
    let fw =
        (p[C::LToe.index()] - p[C::LAnkle.index()]) + (p[C::RToe.index()] - p[C::RAnkle.index()]);
    let fw = (fw - up * fw.dot(up)).normalize_or_zero();
    let left = up.cross(fw);
    (p[C::LHip.index()] - p[C::RHip.index()])
        .normalize_or_zero()
        .dot(left)
        + (p[C::LShoulder.index()] - p[C::RShoulder.index()])
            .normalize_or_zero()
            .dot(left)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_sign_of_left_is_checked_on_trusted_names() {
    let Some(d) = common::data_dir() else { return };
    let c = load_clip(&d.join("mocap/cmu-bvh/01_01.bvh"), &Default::default()).unwrap();
    let (rest, _) = c.rest_positions();
    let l = rest[c.joint("LeftUpLeg").unwrap().idx()];
    let r = rest[c.joint("RightUpLeg").unwrap().idx()];
    let toe =
        rest[c.joint("LeftToeBase").unwrap().idx()] - rest[c.joint("LeftFoot").unwrap().idx()];
    assert!(
        l.x > r.x && toe.z > 0.0,
        "CMU 01_01 rest: left at +X, feet along +Z"
    );
    assert!(DVec3::Y.cross(DVec3::Z).x > 0.0);
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn every_humanoid_clip_in_the_data_maps_with_left_on_the_left() {
    let Some(d) = common::data_dir() else { return };
    let mut files = common::files_with_ext(&d.join("mocap"), "bvh");
    files.extend(common::files_with_ext(&d.join("mocap"), "amc"));
    assert!(files.len() >= 30);
    for f in files {
        let c = load_clip(&f, &Default::default()).unwrap();
        let det = detect_clip(&c).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert!(det.missing.is_empty(), "{}", f.display());
        let ps = det.map.poses(&c).unwrap();
        let good = ps.iter().filter(|p| left_is_left(p) > 0.0).count();
        assert!(
            good * 4 >= ps.len() * 3,
            "{}: left on the body's left in {good} of {} frames",
            f.display(),
            ps.len()
        );
        for j in &det.joints {
            assert!((0.0..=1.0).contains(&j.confidence), "{}", f.display());
        }
    }
}

// ---------------------------------------------------------------- non-humanoids

fn joint(name: &str, parent: Option<usize>, offset: [f64; 3], tail: Option<[f64; 3]>) -> Joint {
    Joint {
        name: name.into(),
        parent: parent.map(|p| JointId(p as u32)),
        offset: DVec3::from_array(offset),
        channels: if parent.is_none() {
            vec![
                Channel::Xposition,
                Channel::Yposition,
                Channel::Zposition,
                Channel::Zrotation,
                Channel::Xrotation,
                Channel::Yrotation,
            ]
        } else {
            vec![Channel::Zrotation, Channel::Xrotation, Channel::Yrotation]
        },
        tail: tail.map(DVec3::from_array),
    }
}

/// A clip of `joints` with `frames` frames of a small sway (rotations about
/// X of every joint), root moving along +Z.
fn clip_of(joints: Vec<Joint>, frames: usize) -> Clip {
    let n = joints.len();
    let mut rot = Vec::new();
    let mut tr = Vec::new();
    for f in 0..frames {
        for (i, j) in joints.iter().enumerate() {
            rot.push(DQuat::from_rotation_x(0.3 * ((f + i) as f64 * 0.4).sin()));
            tr.push(if i == 0 {
                j.offset + DVec3::Z * 0.05 * f as f64
            } else {
                j.offset
            });
        }
    }
    let _ = n;
    Clip::new(
        joints,
        1.0 / 30.0,
        rot,
        tr,
        Units {
            metres_per_unit: 1.0,
            name: "m".into(),
            reason: "test".into(),
        },
        UpAxis::Y,
        PointConvention::JointOrigins,
    )
    .unwrap()
}

/// A four-legged animal with a tail: spine along +Z, legs down.
fn quadruped(tail_name: &str) -> Clip {
    let mut j = vec![joint("Hips", None, [0.0, 1.0, 0.0], None)];
    let leg = |j: &mut Vec<Joint>, side: &str, at: usize, x: f64, what: &str| {
        let b = j.len();
        j.push(joint(
            &format!("{side}{what}UpLeg"),
            Some(at),
            [x, -0.1, 0.0],
            None,
        ));
        j.push(joint(
            &format!("{side}{what}Leg"),
            Some(b),
            [0.0, -0.45, 0.05],
            None,
        ));
        j.push(joint(
            &format!("{side}{what}Foot"),
            Some(b + 1),
            [0.0, -0.4, -0.05],
            None,
        ));
        j.push(joint(
            &format!("{side}{what}ToeBase"),
            Some(b + 2),
            [0.0, -0.05, 0.1],
            Some([0.0, 0.0, 0.05]),
        ));
    };
    leg(&mut j, "Left", 0, 0.15, "");
    leg(&mut j, "Right", 0, -0.15, "");
    j.push(joint(tail_name, Some(0), [0.0, 0.05, -0.2], None));
    let t = j.len() - 1;
    j.push(joint(
        &format!("{tail_name}1"),
        Some(t),
        [0.0, 0.0, -0.4],
        Some([0.0, 0.0, -0.3]),
    ));
    j.push(joint("Spine", Some(0), [0.0, 0.0, 0.5], None));
    j.push(joint("Spine1", Some(j.len() - 1), [0.0, 0.0, 0.5], None));
    let chest = j.len() - 1;
    leg(&mut j, "Left", chest, 0.15, "Front");
    leg(&mut j, "Right", chest, -0.15, "Front");
    j.push(joint("Neck", Some(chest), [0.0, 0.2, 0.2], None));
    j.push(joint(
        "Head",
        Some(j.len() - 1),
        [0.0, 0.2, 0.2],
        Some([0.0, 0.0, 0.25]),
    ));
    clip_of(j, 40)
}

fn crab() -> Clip {
    let mut j = vec![joint("Body", None, [0.0, 0.3, 0.0], None)];
    for k in 0..8 {
        let a = std::f64::consts::TAU * (k as f64 + 0.5) / 8.0;
        let (s, c) = a.sin_cos();
        let b = j.len();
        let side = if c > 0.0 { "Left" } else { "Right" };
        j.push(joint(
            &format!("{side}Leg{k}"),
            Some(0),
            [0.1 * c, 0.0, 0.1 * s],
            None,
        ));
        j.push(joint(
            &format!("{side}Knee{k}"),
            Some(b),
            [0.3 * c, 0.1, 0.3 * s],
            None,
        ));
        j.push(joint(
            &format!("{side}Foot{k}"),
            Some(b + 1),
            [0.2 * c, -0.4, 0.2 * s],
            Some([0.0, -0.05, 0.0]),
        ));
    }
    clip_of(j, 20)
}

#[test]
fn non_humanoids_are_refused_with_a_reason() {
    for (what, c) in [
        ("quadruped with a Tail", quadruped("Tail")),
        ("quadruped with an unnamed tail", quadruped("bone")),
        ("crab", crab()),
    ] {
        let c = via_bvh(&c);
        match detect_clip(&c) {
            Err(RigError::NotHumanoid { reason }) => {
                assert!(!reason.is_empty(), "{what}");
                let msg = RigError::NotHumanoid { reason }.to_string();
                assert!(msg.starts_with("not a humanoid: "), "{msg}");
            }
            Ok(d) => panic!("{what} mapped as {}: {:?}", d.map.convention, d.map.joints),
            Err(e) => panic!("{what}: {e}"),
        }
    }
}

#[test]
fn cli_refuses_a_quadruped_with_exit_1_and_inspect_says_not_a_humanoid() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("quad.bvh");
    std::fs::write(&p, format_bvh(&quadruped("Tail"))).unwrap();
    let o = std::process::Command::new(common::bin())
        .args(["mocap", "rigmap"])
        .arg(&p)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("not a humanoid") && e.contains("quad.bvh"),
        "{e}"
    );
    let o = std::process::Command::new(common::bin())
        .args(["inspect", "--json"])
        .arg(&p)
        .output()
        .unwrap();
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(
        v["convention"]
            .as_str()
            .unwrap()
            .starts_with("not a humanoid"),
        "{v}"
    );
    // A humanoid: the per-joint report in text and JSON.
    let h = dir.path().join("walk.bvh");
    std::fs::write(
        &h,
        format_bvh(&surfmotion::synth::gait_clip(
            surfmotion::synth::Gait::Walk,
            1.0,
            30.0,
        )),
    )
    .unwrap();
    let o = std::process::Command::new(common::bin())
        .args(["mocap", "rigmap", "--json"])
        .arg(&h)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["joints"].as_array().unwrap().len(), Canonical::COUNT);
    assert!(v["joints"][0]["source"].is_string() && v["joints"][0]["confidence"].is_number());
    let o = std::process::Command::new(common::bin())
        .args(["inspect"])
        .arg(&h)
        .output()
        .unwrap();
    let t = String::from_utf8_lossy(&o.stdout);
    assert!(t.contains("left/right") && t.contains("l_knee"), "{t}");
}

#[test]
fn weird_hierarchies_never_panic() {
    let one = clip_of(vec![joint("a", None, [0.0; 3], None)], 3);
    let mut chain = vec![joint("c0", None, [0.0; 3], None)];
    for i in 1..500 {
        chain.push(joint(&format!("c{i}"), Some(i - 1), [0.0, 0.01, 0.0], None));
    }
    let mut star = vec![joint("s", None, [0.0; 3], None)];
    for i in 1..500 {
        let a = i as f64;
        star.push(joint(
            &format!("s{i}"),
            Some(0),
            [a.sin(), a.cos(), (a * 0.3).sin()],
            Some([0.0, 0.1, 0.0]),
        ));
    }
    let mut tree = vec![joint("t", None, [0.0; 3], None)];
    let mut seed = 12345u64;
    for i in 1..500 {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let p = (seed >> 33) as usize % i;
        let o = [
            ((seed >> 3) % 7) as f64 - 3.0,
            ((seed >> 7) % 5) as f64 - 2.0,
            ((seed >> 11) % 3) as f64 - 1.0,
        ];
        tree.push(joint(&format!("Left{i}"), Some(p), o, None));
    }
    let zero = clip_of(
        (0..20)
            .map(|i| {
                joint(
                    &format!("Hips{i}"),
                    if i == 0 { None } else { Some(i - 1) },
                    [0.0; 3],
                    None,
                )
            })
            .collect(),
        2,
    );
    for (what, c) in [
        ("one joint", one),
        ("chain", clip_of(chain, 3)),
        ("star", clip_of(star, 3)),
        ("random tree", clip_of(tree, 3)),
        ("zero lengths", zero),
        (
            "no frames",
            clip_of(
                vec![
                    joint("a", None, [0.0; 3], None),
                    joint("b", Some(0), [0.0, 1.0, 0.0], None),
                ],
                0,
            ),
        ),
    ] {
        let r = std::panic::catch_unwind(|| detect_clip(&c).map(|d| d.map.convention));
        assert!(r.is_ok(), "{what} panicked");
        assert!(r.unwrap().is_err(), "{what} mapped as a humanoid");
    }
}

#[test]
fn old_map_files_load_and_explicit_maps_keep_working() {
    let c = surfmotion::synth::gait_clip(surfmotion::synth::Gait::Walk, 1.0, 30.0);
    let mut text = String::from("{\"convention\": \"mine\", \"joints\": {");
    let names = c.point_names();
    let parts: Vec<String> = Canonical::ALL
        .iter()
        .zip(&names)
        .map(|(k, n)| format!("\"{}\": \"{n}\"", k.name()))
        .collect();
    text.push_str(&parts.join(", "));
    text.push_str("}}");
    let m: RigMap = serde_json::from_str(&text).unwrap();
    assert!(m.derived.is_empty());
    let p = m.poses(&c).unwrap();
    let w = c.world_positions(5);
    assert_eq!(p[5][0], w[0]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    #[test]
    fn random_renamings_and_orders_map_the_same(fam in 0usize..FAMILIES.len(), pre in 0usize..4, rev: bool, gait in 0usize..3) {
        let g = [surfmotion::synth::Gait::Walk, surfmotion::synth::Gait::Run, surfmotion::synth::Gait::Turn][gait];
        let c = via_bvh(&surfmotion::synth::gait_clip(g, 1.0, 30.0));
        let orig = poses(&c);
        let prefix = ["", "Rig_", "ns:", "a|b|"][pre];
        let nodes = rename(&c, &orig.0, &FAMILIES[fam], prefix);
        let v = via_bvh(&build(&c, &nodes, rev));
        assert_same(FAMILIES[fam].name, &orig, &poses(&v));
    }
}

/// Structure alone: every non-helper joint renamed `x<i>` (no name hints).
/// Prints, per clip, the canonical joints whose position differs from the
/// name-based map; asserts that the pelvis, hips, knees, shoulders and
/// elbows agree (so left/right is right). Known differences: the spine/neck
/// choice where a rig has more spine joints than the canonical skeleton (CC),
/// and the ankle/toe height rule on one Bandai dash frame.
#[test]
fn structure_alone_agrees_with_the_names_on_limbs() {
    for (what, c) in originals() {
        let c = via_bvh(&c);
        let orig = poses(&c);
        let mut nodes = nodes_of(&c);
        for (i, n) in nodes.iter_mut().enumerate() {
            let toks =
                surfmotion::rig::names::tokens(surfmotion::rig::names::strip_namespace(&n.name));
            if !surfmotion::rig::names::is_helper(&toks) {
                n.name = format!("x{i}");
            }
        }
        let v = via_bvh(&build(&c, &nodes, false));
        let got = poses(&v);
        assert_eq!(got.0.convention, surfmotion::rig::BY_STRUCTURE, "{what}");
        let tol = 1e-4 * scale(&orig.1);
        let differ: Vec<&str> = Canonical::ALL
            .iter()
            .filter(|k| {
                std::iter::once((&orig.1, &got.1))
                    .chain(orig.2.iter().zip(&got.2))
                    .any(|(a, b)| a[k.index()].distance(b[k.index()]) > tol)
            })
            .map(|k| k.name())
            .collect();
        eprintln!("structure alone on {what}: differs at {differ:?}");
        if !differ.is_empty() {
            eprintln!(
                "  names: {:?}\n  structure: {:?}",
                orig.0.joints, got.0.joints
            );
        }
        for k in differ {
            assert!(
                !matches!(
                    k,
                    "pelvis"
                        | "l_hip"
                        | "r_hip"
                        | "l_knee"
                        | "r_knee"
                        | "l_shoulder"
                        | "r_shoulder"
                        | "l_elbow"
                        | "r_elbow"
                ),
                "{what}: structure alone differs at {k}"
            );
        }
    }
}

// ------------------------------------------------ structure alone (issue 17)

/// Adds a joint under `parent` with `offset` and End Site `tail`; static
/// (identity rotation) relative to its parent.
fn add(
    nodes: &mut Vec<Node>,
    parent: usize,
    name: &str,
    offset: DVec3,
    tail: Option<DVec3>,
) -> usize {
    let ch = nodes[parent]
        .channels
        .iter()
        .copied()
        .filter(|c| c.is_rotation())
        .collect();
    nodes.push(Node {
        name: name.to_string(),
        parent: Some(parent),
        offset,
        channels: ch,
        tail,
        src: None,
        scale: 1.0,
    });
    nodes.len() - 1
}

/// Inserts a zero-length joint between `kids` (siblings) and their parent.
fn insert_above(nodes: &mut Vec<Node>, kids: &[usize], name: &str) -> usize {
    let p = nodes[kids[0]].parent;
    let ch = nodes[kids[0]]
        .channels
        .iter()
        .copied()
        .filter(|c| c.is_rotation())
        .collect();
    nodes.push(Node {
        name: name.to_string(),
        parent: p,
        offset: DVec3::ZERO,
        channels: ch,
        tail: None,
        src: None,
        scale: 1.0,
    });
    let k = nodes.len() - 1;
    for &c in kids {
        nodes[c].parent = Some(k);
    }
    k
}

fn idx(nodes: &[Node], name: &str) -> usize {
    nodes.iter().position(|n| n.name == name).unwrap()
}

/// The procedural walk as a Character Creator rig: `CC_Base_` names, a
/// zero-length Pelvis under Hip holding the thighs, Waist below Spine01,
/// clavicles, a neck of two NeckTwist bones, twist and share bones beside
/// every limb bone, five three-joint fingers, toes, face bones, rib bones.
fn cc_like(c: &Clip) -> Vec<Node> {
    let mut n = nodes_of(c);
    let names = [
        ("Hips", "Hip"),
        ("Spine", "Spine01"),
        ("Spine1", "Spine02"),
        ("Neck", "NeckTwist01"),
        ("Head", "Head"),
    ];
    for (a, b) in names {
        let i = idx(&n, a);
        n[i].name = format!("CC_Base_{b}");
    }
    for (side, s) in [("Left", "L"), ("Right", "R")] {
        for (a, b) in [
            ("Arm", "Upperarm"),
            ("ForeArm", "Forearm"),
            ("Hand", "Hand"),
            ("UpLeg", "Thigh"),
            ("Leg", "Calf"),
            ("Foot", "Foot"),
            ("ToeBase", "ToeBase"),
        ] {
            let i = idx(&n, &format!("{side}{a}"));
            n[i].name = format!("CC_Base_{s}_{b}");
        }
    }
    let cc = |s: &str| format!("CC_Base_{s}");
    let thighs = [idx(&n, &cc("L_Thigh")), idx(&n, &cc("R_Thigh"))];
    insert_above(&mut n, &thighs, &cc("Pelvis"));
    let s1 = idx(&n, &cc("Spine01"));
    split(&mut n, s1, 0.6, &cc("Waist"));
    let h = idx(&n, &cc("Head"));
    split(&mut n, h, 0.5, &cc("NeckTwist02"));
    let h = idx(&n, &cc("Head"));
    let face = add(&mut n, h, &cc("FacialBone"), DVec3::ZERO, None);
    let jaw = add(
        &mut n,
        face,
        &cc("JawRoot"),
        DVec3::new(0.0, 0.01, 0.03),
        None,
    );
    add(
        &mut n,
        jaw,
        &cc("Tongue01"),
        DVec3::new(0.0, 0.0, 0.03),
        Some(DVec3::ZERO),
    );
    add(
        &mut n,
        face,
        &cc("L_Eye"),
        DVec3::new(0.03, 0.07, 0.08),
        Some(DVec3::ZERO),
    );
    add(
        &mut n,
        face,
        &cc("R_Eye"),
        DVec3::new(-0.03, 0.07, 0.08),
        Some(DVec3::ZERO),
    );
    add(
        &mut n,
        face,
        &cc("UpperJaw"),
        DVec3::new(0.0, 0.04, 0.06),
        Some(DVec3::ZERO),
    );
    let chest = idx(&n, &cc("Spine02"));
    for (s, x) in [("L", 1.0), ("R", -1.0)] {
        let r = add(
            &mut n,
            chest,
            &cc(&format!("{s}_RibsTwist")),
            DVec3::new(0.1 * x, 0.05, 0.09),
            None,
        );
        add(
            &mut n,
            r,
            &cc(&format!("{s}_Breast")),
            DVec3::new(0.0, 0.0, 0.03),
            Some(DVec3::ZERO),
        );
        let up = idx(&n, &cc(&format!("{s}_Upperarm")));
        split(&mut n, up, 0.25, &cc(&format!("{s}_Clavicle")));
        // Twist and share bones beside each limb bone, along it.
        for (bone, next, twist) in [
            ("Upperarm", "Forearm", "UpperarmTwist"),
            ("Forearm", "Hand", "ForearmTwist"),
            ("Thigh", "Calf", "ThighTwist"),
            ("Calf", "Foot", "CalfTwist"),
        ] {
            let b = idx(&n, &cc(&format!("{s}_{bone}")));
            let o = n[idx(&n, &cc(&format!("{s}_{next}")))].offset;
            let t1 = add(&mut n, b, &cc(&format!("{s}_{twist}01")), DVec3::ZERO, None);
            add(
                &mut n,
                t1,
                &cc(&format!("{s}_{twist}02")),
                o * 0.5,
                Some(DVec3::ZERO),
            );
        }
        let fa = idx(&n, &cc(&format!("{s}_Forearm")));
        add(
            &mut n,
            fa,
            &cc(&format!("{s}_ElbowShareBone")),
            DVec3::ZERO,
            Some(DVec3::ZERO),
        );
        let calf = idx(&n, &cc(&format!("{s}_Calf")));
        add(
            &mut n,
            calf,
            &cc(&format!("{s}_KneeShareBone")),
            DVec3::ZERO,
            Some(DVec3::ZERO),
        );
        let foot = idx(&n, &cc(&format!("{s}_Foot")));
        let toe = idx(&n, &cc(&format!("{s}_ToeBase")));
        let to = n[toe].offset;
        add(
            &mut n,
            foot,
            &cc(&format!("{s}_ToeBaseShareBone")),
            to,
            Some(DVec3::ZERO),
        );
        n[toe].tail = None;
        for (k, t) in ["BigToe1", "IndexToe1", "MidToe1"].iter().enumerate() {
            let dx = x * (0.02 - 0.015 * k as f64);
            add(
                &mut n,
                toe,
                &cc(&format!("{s}_{t}")),
                DVec3::new(dx, 0.0, 0.04),
                Some(DVec3::ZERO),
            );
        }
        let hand = idx(&n, &cc(&format!("{s}_Hand")));
        n[hand].tail = None;
        for (k, f) in ["Thumb", "Index", "Mid", "Ring", "Pinky"]
            .iter()
            .enumerate()
        {
            let base = if k == 0 {
                DVec3::new(0.0, -0.03, 0.025)
            } else {
                DVec3::new(0.0, -0.085, 0.02 * (2.5 - k as f64))
            };
            let f1 = add(&mut n, hand, &cc(&format!("{s}_{f}1")), base, None);
            let f2 = add(
                &mut n,
                f1,
                &cc(&format!("{s}_{f}2")),
                DVec3::new(0.0, -0.035, 0.0),
                None,
            );
            add(
                &mut n,
                f2,
                &cc(&format!("{s}_{f}3")),
                DVec3::new(0.0, -0.025, 0.0),
                Some(DVec3::ZERO),
            );
        }
    }
    n
}

/// The procedural walk as a CMU ASF skeleton (joints at bone starts, as
/// the AMC reader makes them): zero-length lowerback and hip joints,
/// clavicles, lowerneck/upperneck/head, lwrist → lhand → lfingers with
/// lthumb beside lhand.
fn asf_like(c: &Clip) -> Vec<Node> {
    let mut n = nodes_of(c);
    for (a, b) in [
        ("Hips", "root"),
        ("Spine", "upperback"),
        ("Spine1", "thorax"),
        ("Neck", "lowerneck"),
        ("Head", "head"),
    ] {
        let i = idx(&n, a);
        n[i].name = b.into();
    }
    for (side, s) in [("Left", "l"), ("Right", "r")] {
        for (a, b) in [
            ("Arm", "humerus"),
            ("ForeArm", "radius"),
            ("Hand", "wrist"),
            ("UpLeg", "femur"),
            ("Leg", "tibia"),
            ("Foot", "foot"),
            ("ToeBase", "toes"),
        ] {
            let i = idx(&n, &format!("{side}{a}"));
            n[i].name = format!("{s}{b}");
        }
    }
    let ub = idx(&n, "upperback");
    insert_above(&mut n, &[ub], "lowerback");
    let h = idx(&n, "head");
    split(&mut n, h, 0.5, "upperneck");
    for (s, x) in [("l", 1.0), ("r", -1.0)] {
        let f = idx(&n, &format!("{s}femur"));
        insert_above(&mut n, &[f], &format!("{s}hipjoint"));
        let hu = idx(&n, &format!("{s}humerus"));
        split(&mut n, hu, 0.25, &format!("{s}clavicle"));
        let w = idx(&n, &format!("{s}wrist"));
        n[w].tail = None;
        let hand = add(
            &mut n,
            w,
            &format!("{s}hand"),
            DVec3::new(0.0, -0.04, 0.0),
            None,
        );
        add(
            &mut n,
            hand,
            &format!("{s}fingers"),
            DVec3::new(0.0, -0.03, 0.0),
            Some(DVec3::new(0.0, -0.025, 0.0)),
        );
        add(
            &mut n,
            w,
            &format!("{s}thumb"),
            DVec3::new(0.0, -0.04, 0.0),
            Some(DVec3::new(0.02 * x, -0.02, 0.02)),
        );
    }
    n
}

/// Every joint renamed `{prefix}J{k}` (helpers too: no name hints at all).
fn meaningless(nodes: &[Node], prefix: &str) -> Vec<Node> {
    let mut out = nodes.to_vec();
    for (k, n) in out.iter_mut().enumerate() {
        n.name = format!("{prefix}J{k}");
    }
    out
}

/// Positions of every canonical joint, the rest pose and every frame: the
/// largest difference, relative to the body's size.
fn worst(
    a: &(RigMap, Pose, Vec<Pose>),
    b: &(RigMap, Pose, Vec<Pose>),
    swap: bool,
) -> Vec<(f64, Canonical)> {
    let m = if swap {
        DVec3::new(-1.0, 1.0, 1.0)
    } else {
        DVec3::ONE
    };
    let s = scale(&a.1);
    Canonical::ALL
        .iter()
        .map(|&k| {
            let other = if swap { swap_side(k) } else { k };
            let e = std::iter::once((&a.1, &b.1))
                .chain(a.2.iter().zip(&b.2))
                .map(|(pa, pb)| (pa[other.index()] * m).distance(pb[k.index()]))
                .fold(0.0, f64::max);
            (e / s, k)
        })
        .collect()
}

/// Structure alone, on rigs whose helper bones carry no telling name: every
/// joint of CC-like and ASF-like rigs (generated, and the real CC and
/// ASF/AMC files, plus every other family in the data) renamed `J0, J1, …`,
/// also prefixed, re-ordered, mirrored and with extra neutral pass-through
/// and attachment bones, maps every canonical joint where the names do.
/// (CC: the names pick CC_Base_Pelvis, the structure its parent CC_Base_Hip,
/// at the same place: equal positions are what later stages read.)
#[test]
fn structure_alone_picks_the_named_joints_on_cc_and_asf_rigs() {
    let walk = via_bvh(&surfmotion::synth::gait_clip(
        surfmotion::synth::Gait::Walk,
        2.0,
        30.0,
    ));
    let mut rigs: Vec<(String, Vec<Node>, Clip)> = vec![
        ("generated CC rig".into(), cc_like(&walk), walk.clone()),
        ("generated ASF rig".into(), asf_like(&walk), walk.clone()),
    ];
    for (what, c) in originals() {
        let c = via_bvh(&c);
        rigs.push((what, nodes_of(&c), c));
    }
    let mut report = Vec::new();
    for (what, nodes, src) in rigs {
        let named = via_bvh(&build(&src, &nodes, false));
        let orig = poses(&named);
        if what.starts_with("generated") {
            assert!(
                surfmotion::rig::CONVENTIONS
                    .iter()
                    .any(|cv| cv.name == orig.0.convention),
                "{what}: names not detected as a convention ({})",
                orig.0.convention
            );
        }
        let canon = canonical_index(&named, &orig.0);
        let at = |k: Canonical| canon.iter().position(|x| *x == Some(k)).unwrap();
        let named_nodes = nodes_of(&named);
        // Extra neutral bones: a pass-through 40% down each upper arm and
        // each shin, a mesh-attachment leaf on each elbow.
        let mut laden = named_nodes.clone();
        for k in [
            Canonical::LElbow,
            Canonical::RElbow,
            Canonical::LAnkle,
            Canonical::RAnkle,
        ] {
            split(&mut laden, at(k), 0.4, "x");
        }
        for e in [Canonical::LElbow, Canonical::RElbow] {
            let o = laden[at(e)].offset;
            add(
                &mut laden,
                at(e),
                "x",
                DVec3::new(o.y, o.z, o.x) * 0.2,
                Some(DVec3::ZERO),
            );
        }
        let variants: Vec<(&str, Clip, bool)> = vec![
            (
                "J-named",
                via_bvh(&build(&named, &meaningless(&named_nodes, ""), false)),
                false,
            ),
            (
                "J-named, namespaced, re-ordered",
                via_bvh(&build(&named, &meaningless(&named_nodes, "rig7:"), true)),
                false,
            ),
            (
                "J-named, mirrored",
                via_bvh(&mirror(&build(
                    &named,
                    &meaningless(&named_nodes, ""),
                    false,
                ))),
                true,
            ),
            (
                "J-named, extra bones",
                via_bvh(&build(&named, &meaningless(&laden, ""), true)),
                false,
            ),
        ];
        for (how, v, swap) in variants {
            let got = poses(&v);
            assert_eq!(
                got.0.convention,
                surfmotion::rig::BY_STRUCTURE,
                "{what} {how}"
            );
            let w = worst(&orig, &got, swap);
            let bad: Vec<String> = w
                .iter()
                .filter(|(e, _)| *e > 1e-4)
                .map(|(e, k)| format!("{} ({e:.3})", k.name()))
                .collect();
            report.push(format!(
                "{what}, {how}: {}",
                if bad.is_empty() {
                    "all 19 equal".into()
                } else {
                    bad.join(", ")
                }
            ));
            assert!(
                bad.is_empty(),
                "{what}, {how}: structure differs from the names at {bad:?}\n  names: {:?}\n  structure: {:?}",
                orig.0.joints,
                got.0.joints
            );
        }
    }
    eprintln!("{}", report.join("\n"));
}

// ------------------------------------------------------------ glTF skins

/// Canonical poses of a skin mapped with no rig map: the bind pose and the
/// first animation's frames (world space).
fn skin_poses(a: &surfmotion::mesh::io::gltf::GltfAsset) -> Result<(RigMap, Vec<Pose>), RigError> {
    let d = surfmotion::rig::load::detect_skin(a)?;
    assert!(d.missing.is_empty(), "{:?}", d.missing);
    let bind = surfmotion::rig::load::skin_bind_positions(a).unwrap();
    let (clip, _) = surfmotion::rig::load::skin_clip(a, &bind, true).unwrap();
    let p = d.map.poses(&clip)?;
    Ok((d.map, p))
}

/// Every rigged glTF in the data: the humanoids (CesiumMan, RiggedFigure:
/// joints named `joint_N`, so by structure alone) map with no rig map and
/// left on the left (glTF assets face +Z with +Y up, so left is +X: the
/// spec's convention, independent of the mapping); the fox and the
/// two-bone cylinder are not humanoids. Names given to a humanoid skin map
/// to the same joints, and mirrored names are corrected by the geometry.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn rigged_gltf_skins_map_by_structure_like_clips() {
    let Some(d) = common::data_dir() else { return };
    let mut files = common::files_with_ext(&d.join("gltf"), "glb");
    files.sort();
    assert!(files.len() >= 4);
    let mut humanoids = 0;
    for f in files {
        let a = surfmotion::mesh::io::gltf::read_gltf(&f).unwrap();
        let humanoid = ["CesiumMan", "RiggedFigure"]
            .iter()
            .any(|n| f.to_string_lossy().contains(n));
        let got = skin_poses(&a);
        if !humanoid {
            match got {
                Err(RigError::NotHumanoid { reason }) => {
                    eprintln!("{}: not a humanoid: {reason}", f.display())
                }
                Ok((m, _)) => panic!("{} mapped as {}: {:?}", f.display(), m.convention, m.joints),
                Err(e) => panic!("{}: {e}", f.display()),
            }
            continue;
        }
        humanoids += 1;
        if f.to_string_lossy().contains("CesiumMan") {
            // Its left and right are undecided by geometry (it faces +X in
            // bind space; see tests/rig.rs): the mapping must say so, and
            // the rig embedding refuses it without a rig map.
            let d = surfmotion::rig::load::detect_skin(&a).unwrap();
            let c = d.side_confidence.unwrap();
            assert!(
                c < surfmotion::rig::embed::skin::MIN_SIDE_CONFIDENCE,
                "CesiumMan: side confidence {c}"
            );
            continue;
        }
        let (map, ps) = got.unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_eq!(
            map.convention,
            surfmotion::rig::BY_STRUCTURE,
            "{}",
            f.display()
        );
        let ps = &ps[1..]; // the animation frames, in world space
        use Canonical as C;
        let x = |p: &Pose, l: C, r: C| p[l.index()].x - p[r.index()].x;
        let good = ps
            .iter()
            .filter(|p| x(p, C::LHip, C::RHip) > 0.0 && x(p, C::LShoulder, C::RShoulder) > 0.0)
            .count();
        eprintln!(
            "{}: left at +X in {good} of {} frames",
            f.display(),
            ps.len()
        );
        assert!(
            good * 4 >= ps.len() * 3,
            "{}: left at +X in {good} of {} frames",
            f.display(),
            ps.len()
        );
        // The same skin with Mixamo names on the joints found, then with the
        // names' left and right swapped.
        for mirrored in [false, true] {
            let mut b = a.clone();
            let skin = b.skin.as_mut().unwrap();
            for (k, name) in &map.joints {
                let k = if mirrored { swap_side(*k) } else { *k };
                let mixamo = surfmotion::rig::CONVENTIONS
                    .iter()
                    .find(|c| c.name == "Mixamo")
                    .unwrap()
                    .candidates[k.index()][0];
                let i = skin.joint_names.iter().position(|n| n == name).unwrap();
                skin.joint_names[i] = format!("mixamorig:{mixamo}");
            }
            let (m2, p2) = skin_poses(&b).unwrap();
            for (pa, pb) in ps.iter().zip(&p2[1..]) {
                for c in Canonical::ALL {
                    assert!(
                        pa[c.index()].distance(pb[c.index()]) < 1e-9,
                        "{} named (mirrored {mirrored}): {} moved ({})",
                        f.display(),
                        c.name(),
                        m2.convention
                    );
                }
            }
        }
    }
    assert_eq!(humanoids, 2);
}
