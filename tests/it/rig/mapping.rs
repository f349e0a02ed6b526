//! Automatic joint mapping of any humanoid (names, then structure and
//! geometry): renamed, re-ordered, helper-padded, toe-less, head-less and
//! mirrored variants of procedural and real clips, written out as BVH and
//! read back, map to the same canonical joints; non-humanoids are refused;
//! weird hierarchies never panic.

use crate::common;

use common::skel::{Suite, expected, map_errors, mirror, scaled, skel_to_bvh, swap_side};

use glam::{DQuat, DVec3};
use proptest::prelude::*;
use surfmotion::mocap::bvh::{BvhOptions, format_bvh, parse_bvh};
use surfmotion::mocap::{Channel, Clip, Joint, JointId, PointConvention, Units, UpAxis};
use surfmotion::pose::Pose;
use surfmotion::rig::load_clip;
use surfmotion::rig::{Canonical, Provenance, RigError, RigMap, detect_clip};

/// A joint of an edited hierarchy: where its per-frame data comes from.
#[derive(Clone)]
pub(super) struct Node {
    pub(super) name: String,
    pub(super) parent: Option<usize>,
    pub(super) offset: DVec3,
    pub(super) channels: Vec<Channel>,
    pub(super) tail: Option<DVec3>,
    /// Old joint whose rotation/translation it takes; `None`: identity and
    /// the offset (an inserted pass-through or leaf).
    pub(super) src: Option<usize>,
    /// Fraction of the source's translation to use (split bones).
    pub(super) scale: f64,
}

pub(super) fn nodes_of(c: &Clip) -> Vec<Node> {
    c.joints()
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
pub(super) fn build(c: &Clip, nodes: &[Node], reverse: bool) -> Clip {
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
                    tr.push(if c.joints()[s].parent.is_none() {
                        t[s]
                    } else if c.joints()[s].has_position_channels() {
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
                        Some((s, k)) if c.joints()[s].has_position_channels() => t[s] * (1.0 - k),
                        _ => nodes[i].offset,
                    });
                }
            }
        }
    }
    Clip::new(
        joints,
        c.frame_time(),
        rot,
        tr,
        c.units().clone(),
        c.up(),
        PointConvention::JointOrigins,
    )
    .unwrap()
    .edited(|p| p.up_reason = c.up_reason().to_string())
    .unwrap()
}

/// Through the BVH writer and reader.
pub(super) fn via_bvh(c: &Clip) -> Clip {
    let text = format_bvh(c);
    parse_bvh(
        &text,
        std::path::Path::new("variant.bvh"),
        &BvhOptions::default(),
    )
    .unwrap()
}

/// At most ~60 frames of a clip (keeps the tests fast).
pub(super) fn short(c: &Clip) -> Clip {
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
    c.clone()
        .edited(|p| {
            p.rotations = rot;
            p.translations = tr;
        })
        .unwrap()
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
pub(super) fn canonical_index(c: &Clip, map: &RigMap) -> Vec<Option<Canonical>> {
    let mut out = vec![None; c.joint_count()];
    for (k, name) in &map.joints {
        if let Some(j) = c.joint(name) {
            out[j.idx()] = Some(*k);
        }
    }
    out
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
fn under_l(s: &str, l: bool) -> String {
    format!("{s}_{}", if l { "l" } else { "r" })
}
fn dot_l(s: &str, l: bool) -> String {
    format!("{s}.{}", if l { "L" } else { "R" })
}

/// Name families (names only, on any clip: see [`rename`]): canonical joint
/// → name, the side made by `side`.
const FAMILIES: &[RigShape] = &[
    named_shape(
        "daz",
        ["hip", "abdomen", "chest", "neck", "head"],
        ["Shldr", "ForeArm", "Hand", "Thigh", "Shin", "Foot", "Toe"],
        l_prefix,
    ),
    named_shape(
        "smpl",
        ["Pelvis", "Spine1", "Spine3", "Neck", "Head"],
        ["Shoulder", "Elbow", "Wrist", "Hip", "Knee", "Ankle", "Foot"],
        l_under,
    ),
    named_shape(
        "smpl lower-case",
        ["pelvis", "spine1", "spine3", "neck", "head"],
        ["shoulder", "elbow", "wrist", "hip", "knee", "ankle", "foot"],
        left_under,
    ),
    named_shape(
        "kinect",
        ["SpineBase", "SpineMid", "SpineShoulder", "Neck", "Head"],
        ["Shoulder", "Elbow", "Wrist", "Hip", "Knee", "Ankle", "Foot"],
        suffix_left,
    ),
    named_shape(
        "xsens",
        ["Pelvis", "L3", "T8", "Neck", "Head"],
        [
            "UpperArm", "ForeArm", "Hand", "UpperLeg", "LowerLeg", "Foot", "Toe",
        ],
        left_prefix,
    ),
    named_shape(
        "unity",
        ["Hips", "Spine", "Chest", "Neck", "Head"],
        [
            "UpperArm", "LowerArm", "Hand", "UpperLeg", "LowerLeg", "Foot", "Toes",
        ],
        left_prefix,
    ),
    named_shape(
        "biped",
        [
            "Bip01 Pelvis",
            "Bip01 Spine",
            "Bip01 Spine2",
            "Bip01 Neck",
            "Bip01 Head",
        ],
        [
            "UpperArm", "Forearm", "Hand", "Thigh", "Calf", "Foot", "Toe0",
        ],
        biped,
    ),
    named_shape(
        "unreal",
        ["pelvis", "spine_01", "spine_03", "neck_01", "head"],
        [
            "upperarm", "lowerarm", "hand", "thigh", "calf", "foot", "ball",
        ],
        under_l,
    ),
    named_shape(
        "blender",
        ["hips", "spine", "chest", "neck", "head"],
        [
            "upper_arm",
            "forearm",
            "hand",
            "thigh",
            "shin",
            "foot",
            "toe",
        ],
        dot_l,
    ),
];

fn family_name(f: &RigShape, c: Canonical) -> String {
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
fn rename(c: &Clip, map: &RigMap, f: &RigShape, prefix: &str) -> Vec<Node> {
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
            // Only the family's own convention, when it is a known one
            // (Unity's and Unreal's names are).
            let own = match f.name {
                "unity" => "Unity Humanoid",
                "unreal" => "Unreal Engine mannequin",
                _ => "",
            };
            assert!(
                got.0.convention == own
                    || !surfmotion::rig::CONVENTIONS
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
            assert_eq!(r.source, Provenance::Derived);
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
        // The names' left and right are checked on the body's geometry
        // (never taken on trust; Bandai dataset-2's walk was once left
        // unchecked: its static root joint, metres from the walking body,
        // made every limb look small).
        eprintln!("{}: {} | {}", f.display(), det.map.convention, det.sides);
        assert!(
            det.sides.contains("confirmed by geometry"),
            "{}: {}",
            f.display(),
            det.sides
        );
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

/// A snake: one chain of 30 bones along +Z, named as a spine, a head at
/// its end.
fn snake() -> Clip {
    let mut j = vec![joint("Hips", None, [0.0, 0.1, 0.0], None)];
    for i in 1..30 {
        j.push(joint(
            &format!("Spine{i}"),
            Some(i - 1),
            [0.0, 0.0, 0.08],
            None,
        ));
    }
    j.push(joint(
        "Head",
        Some(29),
        [0.0, 0.02, 0.1],
        Some([0.0, 0.0, 0.08]),
    ));
    clip_of(j, 20)
}

#[test]
fn non_humanoids_are_refused_with_a_reason() {
    for (what, c) in [
        ("quadruped with a Tail", quadruped("Tail")),
        ("quadruped with an unnamed tail", quadruped("bone")),
        ("crab", crab()),
        ("snake", snake()),
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

/// `mocap rigmap FILE [--json]` and `inspect FILE [--json]` on a clip.
fn run_cli(args: &[&str], file: &std::path::Path) -> std::process::Output {
    std::process::Command::new(common::bin())
        .args(args)
        .arg(file)
        .output()
        .unwrap()
}

#[test]
fn cli_refuses_a_quadruped_with_exit_1_and_inspect_says_not_a_humanoid() {
    let dir = tempfile::tempdir().unwrap();
    for (name, c) in [
        ("quad.bvh", quadruped("Tail")),
        ("crab.bvh", crab()),
        ("snake.bvh", snake()),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, format_bvh(&c)).unwrap();
        let o = run_cli(&["mocap", "rigmap"], &p);
        assert_eq!(o.status.code(), Some(1), "{name}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("not a humanoid") && e.contains(name), "{e}");
        // inspect describes the file (exit 0) and names no convention.
        let o = run_cli(&["inspect", "--json"], &p);
        assert!(o.status.success(), "{name}");
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert!(
            v["convention"]
                .as_str()
                .unwrap()
                .starts_with("not a humanoid: "),
            "{name}: {v}"
        );
    }
    // A humanoid with no telling names: "unknown convention, mapped by
    // structure", never a known convention's name; half its names kept:
    // the report says which joints came from names and which from
    // structure, each with a confidence. A chest-less one: the chest is
    // derived, and the report says so.
    let walk = via_bvh(&surfmotion::synth::gait_clip(
        surfmotion::synth::Gait::Walk,
        1.0,
        30.0,
    ));
    let mut half = nodes_of(&walk);
    for (i, n) in half.iter_mut().enumerate() {
        if n.name.starts_with("Right") || n.name.starts_with("Spine") {
            n.name = format!("J{i}");
        }
    }
    // Spine and Spine1 made one joint: the arms leave the spine's only
    // joint above the hips.
    let mut chestless = nodes_of(&walk);
    let (sp, sp1) = (idx(&chestless, "Spine"), idx(&chestless, "Spine1"));
    let below = chestless[sp].offset;
    chestless[sp1].offset += below;
    chestless[sp1].src = None;
    chestless[sp1].parent = chestless[sp].parent;
    let chestless = remove(&chestless, sp, None);
    for (name, nodes) in [
        ("nonames.bvh", meaningless(&nodes_of(&walk), "")),
        ("half.bvh", half),
        ("chestless.bvh", chestless),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, format_bvh(&build(&walk, &nodes, false))).unwrap();
        let o = run_cli(&["inspect", "--json"], &p);
        assert!(o.status.success(), "{name}");
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(
            v["convention"].as_str(),
            Some(surfmotion::rig::BY_STRUCTURE),
            "{name}: {v}"
        );
        let o = run_cli(&["mocap", "rigmap", "--json"], &p);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let rows = v["joints"].as_array().unwrap();
        assert_eq!(rows.len(), Canonical::COUNT, "{name}");
        let source = |c: Canonical| rows[c.index()]["source"].as_str().unwrap().to_string();
        for r in rows {
            let c = r["confidence"].as_f64().unwrap();
            assert!(c > 0.0 && c <= 1.0, "{name}: {r}");
        }
        match name {
            "nonames.bvh" => assert!(
                Canonical::ALL.iter().all(|&c| source(c) == "structure"),
                "{name}: {v}"
            ),
            "half.bvh" => {
                assert_eq!(source(Canonical::LKnee), "names", "{v}");
                assert_eq!(source(Canonical::RKnee), "structure", "{v}");
                assert_eq!(source(Canonical::Spine), "structure", "{v}");
            }
            _ => {
                assert_eq!(source(Canonical::Chest), "derived", "{v}");
                assert_eq!(
                    rows[Canonical::Chest.index()]["joint"],
                    serde_json::Value::Null
                );
                let t = String::from_utf8_lossy(&run_cli(&["inspect"], &p).stdout).to_string();
                assert!(
                    t.lines().any(|l| l.contains("chest")
                        && l.contains("(derived)")
                        && l.contains("derived")),
                    "{t}"
                );
            }
        }
    }
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
pub(super) fn add(
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

/// A family of real rigs, as a re-shaping of the procedural skeleton
/// (`Hips`, `Spine`, `Spine1` (the chest), `Neck`, `Head`; `Left`/`Right`
/// followed by `Arm`, `ForeArm`, `Hand`, `UpLeg`, `Leg`, `Foot`, `ToeBase`): names,
/// pass-through joints along the torso and limbs, a joint carrying both
/// thighs, and helper bones beside the body joints. [`shaped`] builds it.
struct RigShape {
    name: &'static str,
    /// Put before every name (`CC_Base_`).
    prefix: &'static str,
    /// Names of Hips, Spine, Spine1, Neck, Head.
    torso: [&'static str; 5],
    /// Names (before `side`) of Arm, ForeArm, Hand, UpLeg, Leg, Foot, ToeBase.
    limbs: [&'static str; 7],
    side: fn(&str, bool) -> String,
    /// Pass-through joints along the torso, in order: (torso joint whose
    /// offset is split, fraction of it above the new joint, name). A
    /// fraction 0 puts a zero-length joint above it (ASF `lowerback`).
    torso_splits: &'static [(usize, f64, &'static str)],
    /// The same along each limb (`side` applied to the name): collars,
    /// twist bones in the chain (Daz `lShldrTwist`), metatarsals, ASF
    /// `lhipjoint`.
    limb_splits: &'static [(usize, f64, &'static str)],
    /// A joint between the hips and both thighs, at this offset from the
    /// hips (the thighs keep their place): CC `Pelvis`, Daz `pelvis`.
    leg_holder: Option<(&'static str, [f64; 3])>,
    /// Three-joint fingers (`Thumb` first) under each hand, through
    /// `Carpal<k>` joints when `carpals`.
    fingers: &'static [&'static str],
    carpals: bool,
    /// Toe joints under each toe.
    toes: &'static [&'static str],
    /// Face bones (a jaw, a tongue, eyes) under the head.
    face: bool,
    /// CC: rib and breast bones off the chest; `Twist01`/`Twist02` bones
    /// beside every limb bone, along it; elbow, knee and toe share bones.
    cc_helpers: bool,
    /// Daz: a pectoral leaf off the chest on each side.
    pectorals: bool,
    /// ASF: `hand` → `fingers` and `thumb` under the wrist.
    asf_hand: bool,
}

const SRC_TORSO: [&str; 5] = ["Hips", "Spine", "Spine1", "Neck", "Head"];
const SRC_LIMBS: [&str; 7] = ["Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "ToeBase"];

/// A shape with only names (no extra joints).
const fn named_shape(
    name: &'static str,
    torso: [&'static str; 5],
    limbs: [&'static str; 7],
    side: fn(&str, bool) -> String,
) -> RigShape {
    RigShape {
        name,
        prefix: "",
        torso,
        limbs,
        side,
        torso_splits: &[],
        limb_splits: &[],
        leg_holder: None,
        fingers: &[],
        carpals: false,
        toes: &[],
        face: false,
        cc_helpers: false,
        pectorals: false,
        asf_hand: false,
    }
}

/// Character Creator: `CC_Base_` names, a zero-length Pelvis under Hip
/// holding the thighs, Waist below Spine01, clavicles, a neck of two
/// NeckTwist bones, twist and share bones beside every limb bone, five
/// three-joint fingers, toes, face and rib bones.
const CC: RigShape = RigShape {
    prefix: "CC_Base_",
    torso_splits: &[(1, 0.6, "Waist"), (4, 0.5, "NeckTwist02")],
    limb_splits: &[(0, 0.25, "Clavicle")],
    leg_holder: Some(("Pelvis", [0.0; 3])),
    fingers: &["Thumb", "Index", "Mid", "Ring", "Pinky"],
    toes: &["BigToe1", "IndexToe1", "MidToe1"],
    face: true,
    cc_helpers: true,
    ..named_shape(
        "generated CC rig",
        ["Hip", "Spine01", "Spine02", "NeckTwist01", "Head"],
        [
            "Upperarm", "Forearm", "Hand", "Thigh", "Calf", "Foot", "ToeBase",
        ],
        l_under,
    )
};

/// CMU ASF (joints at bone starts, as the AMC reader makes them):
/// zero-length lowerback and hip joints, clavicles,
/// lowerneck/upperneck/head, lwrist → lhand → lfingers with lthumb beside
/// lhand.
const ASF: RigShape = RigShape {
    torso_splits: &[(1, 0.0, "lowerback"), (4, 0.5, "upperneck")],
    limb_splits: &[(3, 0.0, "hipjoint"), (0, 0.25, "clavicle")],
    asf_hand: true,
    ..named_shape(
        "generated ASF rig",
        ["root", "upperback", "thorax", "lowerneck", "head"],
        [
            "humerus", "radius", "wrist", "femur", "tibia", "foot", "toes",
        ],
        l_prefix,
    )
};

/// Daz Genesis 1 and 2: `hip` (the root) carries `abdomen` → `abdomen2` →
/// `chest` and, `pelvis` beside it, the thighs; `lCollar` → `lShldr` →
/// `lForeArm` → `lHand`; `lThigh` → `lShin` → `lFoot` → `lToe`.
const GENESIS_1: RigShape = RigShape {
    torso_splits: &[(2, 0.4, "abdomen2")],
    limb_splits: &[(0, 0.3, "Collar")],
    leg_holder: Some(("pelvis", [0.0; 3])),
    fingers: &["Thumb", "Index", "Mid", "Ring", "Pinky"],
    toes: &["BigToe", "SmallToe1", "SmallToe2"],
    face: true,
    pectorals: true,
    ..named_shape(
        "generated Daz Genesis 1 rig",
        ["hip", "abdomen", "chest", "neck", "head"],
        ["Shldr", "ForeArm", "Hand", "Thigh", "Shin", "Foot", "Toe"],
        l_prefix,
    )
};

/// Daz Genesis 3 and 8: `hip` → `abdomenLower` → `abdomenUpper` →
/// `chestLower` → `chestUpper` → `neckLower` → `neckUpper` → `head`,
/// `pelvis` beside the abdomen carrying `lThighBend` → `lThighTwist` →
/// `lShin` → `lFoot` → `lMetatarsals` → `lToe`; `lCollar` → `lShldrBend`
/// → `lShldrTwist` → `lForearmBend` → `lForearmTwist` → `lHand` →
/// `lCarpal<k>` → fingers (twist bones in the chain, not beside it).
const GENESIS_3: RigShape = RigShape {
    torso_splits: &[
        (2, 0.3, "abdomenUpper"),
        (2, 0.45, "chestLower"),
        (4, 0.5, "neckUpper"),
    ],
    limb_splits: &[
        (0, 0.3, "Collar"),
        (1, 0.5, "ShldrTwist"),
        (2, 0.5, "ForearmTwist"),
        (4, 0.5, "ThighTwist"),
        (6, 0.5, "Metatarsals"),
    ],
    leg_holder: Some(("pelvis", [0.0; 3])),
    fingers: &["Thumb", "Index", "Mid", "Ring", "Pinky"],
    carpals: true,
    toes: &["BigToe", "SmallToe1", "SmallToe2", "SmallToe3"],
    face: true,
    pectorals: true,
    ..named_shape(
        "generated Daz Genesis 3/8 rig",
        ["hip", "abdomenLower", "chestUpper", "neckLower", "head"],
        [
            "ShldrBend",
            "ForearmBend",
            "Hand",
            "ThighBend",
            "Shin",
            "Foot",
            "Toe",
        ],
        l_prefix,
    )
};

/// The procedural walk (or any clip with its joint names) re-shaped as `s`.
fn shaped(c: &Clip, s: &RigShape) -> Vec<Node> {
    let mut n = nodes_of(c);
    let name = |x: &str| format!("{}{x}", s.prefix);
    let sided = |x: &str, l: bool| name(&(s.side)(x, l));
    for (a, b) in SRC_TORSO.iter().zip(s.torso) {
        let i = idx(&n, a);
        n[i].name = name(b);
    }
    for (l, side) in [(true, "Left"), (false, "Right")] {
        for (a, b) in SRC_LIMBS.iter().zip(s.limbs) {
            let i = idx(&n, &format!("{side}{a}"));
            n[i].name = sided(b, l);
        }
    }
    let torso = |n: &[Node], k: usize| idx(n, &name(s.torso[k]));
    let limb = |n: &[Node], k: usize, l: bool| idx(n, &sided(s.limbs[k], l));
    if let Some((h, off)) = s.leg_holder {
        let thighs = [limb(&n, 3, true), limb(&n, 3, false)];
        let k = insert_above(&mut n, &thighs, &name(h));
        let d = DVec3::from_array(off);
        n[k].offset = d;
        for t in thighs {
            n[t].offset -= d;
        }
    }
    for &(k, frac, x) in s.torso_splits {
        let j = torso(&n, k);
        split(&mut n, j, frac, &name(x));
    }
    for (l, x) in [(true, 1.0), (false, -1.0)] {
        for &(k, frac, what) in s.limb_splits {
            let j = limb(&n, k, l);
            split(&mut n, j, frac, &sided(what, l));
        }
        let chest = torso(&n, 2);
        if s.pectorals {
            add(
                &mut n,
                chest,
                &sided("Pectoral", l),
                DVec3::new(0.08 * x, -0.05, 0.08),
                Some(DVec3::new(0.0, 0.0, 0.02)),
            );
        }
        if s.cc_helpers {
            let r = add(
                &mut n,
                chest,
                &sided("RibsTwist", l),
                DVec3::new(0.1 * x, 0.05, 0.09),
                None,
            );
            add(
                &mut n,
                r,
                &sided("Breast", l),
                DVec3::new(0.0, 0.0, 0.03),
                Some(DVec3::ZERO),
            );
            // Twist bones beside each limb bone, along it.
            for (bone, next) in [(0, 1), (1, 2), (3, 4), (4, 5)] {
                let b = limb(&n, bone, l);
                let o = n[limb(&n, next, l)].offset;
                let t = format!("{}Twist", s.limbs[bone]);
                let t1 = add(&mut n, b, &sided(&format!("{t}01"), l), DVec3::ZERO, None);
                add(
                    &mut n,
                    t1,
                    &sided(&format!("{t}02"), l),
                    o * 0.5,
                    Some(DVec3::ZERO),
                );
            }
            for (at, what) in [(1, "ElbowShareBone"), (4, "KneeShareBone")] {
                let j = limb(&n, at, l);
                add(&mut n, j, &sided(what, l), DVec3::ZERO, Some(DVec3::ZERO));
            }
            let foot = limb(&n, 5, l);
            let to = n[limb(&n, 6, l)].offset;
            let share = format!("{}ShareBone", s.limbs[6]);
            add(&mut n, foot, &sided(&share, l), to, Some(DVec3::ZERO));
        }
        if !s.toes.is_empty() {
            let toe = limb(&n, 6, l);
            n[toe].tail = None;
            for (k, t) in s.toes.iter().enumerate() {
                let dx = x * (0.02 - 0.015 * k as f64);
                add(
                    &mut n,
                    toe,
                    &sided(t, l),
                    DVec3::new(dx, 0.0, 0.04),
                    Some(DVec3::ZERO),
                );
            }
        }
        if !s.fingers.is_empty() {
            let hand = limb(&n, 2, l);
            n[hand].tail = None;
            for (k, f) in s.fingers.iter().enumerate() {
                let base = if k == 0 {
                    DVec3::new(0.0, -0.03, 0.025)
                } else {
                    DVec3::new(0.0, -0.085, 0.02 * (2.5 - k as f64))
                };
                let (from, base) = if s.carpals && k > 0 {
                    let cp = add(
                        &mut n,
                        hand,
                        &sided(&format!("Carpal{k}"), l),
                        base * 0.5,
                        None,
                    );
                    (cp, base * 0.5)
                } else {
                    (hand, base)
                };
                let f1 = add(&mut n, from, &sided(&format!("{f}1"), l), base, None);
                let f2 = add(
                    &mut n,
                    f1,
                    &sided(&format!("{f}2"), l),
                    DVec3::new(0.0, -0.035, 0.0),
                    None,
                );
                add(
                    &mut n,
                    f2,
                    &sided(&format!("{f}3"), l),
                    DVec3::new(0.0, -0.025, 0.0),
                    Some(DVec3::ZERO),
                );
            }
        }
        if s.asf_hand {
            let w = limb(&n, 2, l);
            n[w].tail = None;
            let hand = add(
                &mut n,
                w,
                &sided("hand", l),
                DVec3::new(0.0, -0.04, 0.0),
                None,
            );
            add(
                &mut n,
                hand,
                &sided("fingers", l),
                DVec3::new(0.0, -0.03, 0.0),
                Some(DVec3::new(0.0, -0.025, 0.0)),
            );
            add(
                &mut n,
                w,
                &sided("thumb", l),
                DVec3::new(0.0, -0.04, 0.0),
                Some(DVec3::new(0.02 * x, -0.02, 0.02)),
            );
        }
    }
    if s.face {
        let h = torso(&n, 4);
        let face = add(&mut n, h, &name("FacialBone"), DVec3::ZERO, None);
        let jaw = add(
            &mut n,
            face,
            &name("JawRoot"),
            DVec3::new(0.0, 0.01, 0.03),
            None,
        );
        add(
            &mut n,
            jaw,
            &name("Tongue01"),
            DVec3::new(0.0, 0.0, 0.03),
            Some(DVec3::ZERO),
        );
        for (l, x) in [(true, 1.0), (false, -1.0)] {
            add(
                &mut n,
                face,
                &sided("Eye", l),
                DVec3::new(0.03 * x, 0.07, 0.08),
                Some(DVec3::ZERO),
            );
        }
        add(
            &mut n,
            face,
            &name("UpperJaw"),
            DVec3::new(0.0, 0.04, 0.06),
            Some(DVec3::ZERO),
        );
    }
    n
}

/// The generated rig families.
const SHAPES: [&RigShape; 4] = [&CC, &ASF, &GENESIS_1, &GENESIS_3];

/// Genesis 3/8 with `pelvis` 2.2 cm below and behind `hip` (not at it):
/// the junction of legs and spine is split across two joints.
const GENESIS_3_SPLIT_PELVIS: RigShape = RigShape {
    name: "generated Daz Genesis 3/8 rig, pelvis apart from hip",
    leg_holder: Some(("pelvis", [0.0, -0.02, -0.01])),
    ..GENESIS_3
};

/// Every generated family (CC, ASF, Daz Genesis 1 and 3/8, the latter
/// also with its pelvis apart from the hip), from the procedural walk and
/// run, named, namespaced and re-ordered, maps each canonical joint to the
/// original clip's position (rest pose and every frame): the names and
/// the structure agree on the same body.
#[test]
fn generated_rig_families_map_like_the_original_clip() {
    for gait in [surfmotion::synth::Gait::Walk, surfmotion::synth::Gait::Run] {
        let c = via_bvh(&surfmotion::synth::gait_clip(gait, 1.5, 30.0));
        let orig = poses(&c);
        for s in SHAPES.iter().copied().chain([&GENESIS_3_SPLIT_PELVIS]) {
            for (k, ns) in ["", "Genesis8Female:", "Armature|"].iter().enumerate() {
                let mut nodes = shaped(&c, s);
                for n in &mut nodes {
                    n.name = format!("{ns}{}", n.name);
                }
                let v = via_bvh(&build(&c, &nodes, k == 1));
                let what = format!("{:?} as {}{ns}", gait, s.name);
                let d = detect_clip(&v).unwrap_or_else(|e| panic!("{what}: {e}"));
                assert!(d.missing.is_empty(), "{what}: {:?}", d.missing);
                assert!(d.derived.is_empty(), "{what}: derived {:?}", d.derived);
                let got = (
                    d.map.clone(),
                    d.map.rest_pose(&v).unwrap(),
                    d.map.poses(&v).unwrap(),
                );
                assert_same(&what, &orig, &got);
                // Names decide every joint on these rigs (a convention, or
                // name tokens inside the structure found).
                for j in &d.joints {
                    assert!(
                        matches!(j.source, Provenance::Convention | Provenance::Names),
                        "{what}: {} from {:?}",
                        j.canonical.name(),
                        j.source
                    );
                }
            }
        }
    }
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
/// joint of CC-like, ASF-like and Daz Genesis rigs (generated, and the real CC and
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
    let mut rigs: Vec<(String, Vec<Node>, Clip)> = Vec::new();
    for s in SHAPES.iter().copied().chain([&GENESIS_3_SPLIT_PELVIS]) {
        rigs.push((s.name.into(), shaped(&walk, s), walk.clone()));
    }
    for (what, c) in originals() {
        let c = via_bvh(&c);
        rigs.push((what, nodes_of(&c), c));
    }
    let mut report = Vec::new();
    for (what, nodes, src) in rigs {
        let named = via_bvh(&build(&src, &nodes, false));
        let orig = poses(&named);
        if what == CC.name || what == ASF.name {
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
    let (clip, _) = a.skin_clip(&bind, true).unwrap();
    let p = d.map.poses(&clip)?;
    Ok((d.map, p))
}

/// Every rigged glTF in the data: the humanoids (CesiumMan, RiggedFigure:
/// joints named `joint_N`, so by structure alone) map with no rig map and
/// left on the left (RiggedFigure: glTF assets face +Z with +Y up, so left
/// is +X: the spec's convention, independent of the mapping; CesiumMan:
/// the hand-made map's sides); the fox and the
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
            // It faces +X in its bind space with Z up (left is +Y), walks
            // in place, and its toe joints sit 6 cm below the ankles: the
            // sides come from the soles across the shins. Checked against
            // the hand-made map (whose sides were checked by hand on the
            // inverse bind matrices), joint for joint.
            let d = surfmotion::rig::load::detect_skin(&a).unwrap();
            let c = d.side_confidence.unwrap();
            eprintln!("CesiumMan: {} ({})", d.map.convention, d.sides);
            assert!(
                c >= surfmotion::embed::skin::MIN_SIDE_CONFIDENCE,
                "CesiumMan: side confidence {c}"
            );
            let hand_made = RigMap::load(
                &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("tests/fixtures/cesiumman.rigmap.json"),
            )
            .unwrap();
            assert_eq!(d.map.joints, hand_made.joints, "CesiumMan");
            assert_eq!(d.map.convention, surfmotion::rig::BY_STRUCTURE);
            // And the rig embedding takes it with no rig map.
            let rig = surfmotion::embed::skin::from_skin(&a.mesh, &a, None, &f)
                .unwrap_or_else(|e| panic!("CesiumMan without a map: {e}"));
            let with_map =
                surfmotion::embed::skin::from_skin(&a.mesh, &a, Some(&hand_made), &f).unwrap();
            assert_eq!(rig.joints(), with_map.joints());
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

// ------------------------------------------------------- T- and A-pose rests

/// The same motion over another rest skeleton: the subtree below joint
/// `top` has its rest bones turned by `a` about `top` (offsets, End Sites
/// and per-frame translations of the descendants turned; `top`'s local
/// rotation followed by `a⁻¹` and every descendant's conjugated by `a`), so
/// every frame's world positions are unchanged while the rest pose holds
/// that limb elsewhere (an arm hanging down becomes a T- or an A-pose arm).
pub(super) fn rerest(c: &Clip, top: usize, a: DQuat) -> Clip {
    let n = c.joint_count();
    let below: Vec<bool> = (0..n)
        .map(|i| {
            let mut k = c.joints()[i].parent.map(|p| p.idx());
            while let Some(x) = k {
                if x == top {
                    return true;
                }
                k = c.joints()[x].parent.map(|p| p.idx());
            }
            false
        })
        .collect();
    let mut out = c.clone().into_parts();
    for (i, j) in out.joints.iter_mut().enumerate() {
        if below[i] {
            j.offset = a * j.offset;
            j.tail = j.tail.map(|t| a * t);
        }
    }
    for f in 0..c.frame_count() {
        for (i, &under) in below.iter().enumerate() {
            let k = f * n + i;
            if i == top {
                out.rotations[k] = c.rotations()[k] * a.inverse();
            } else if under {
                out.rotations[k] = a * c.rotations()[k] * a.inverse();
                out.translations[k] = a * c.translations()[k];
            }
        }
    }
    Clip::from_parts(out).unwrap()
}

/// A T-pose and an A-pose version of one clip (the arms' rest bones turned
/// 90° and 45° out from hanging down; the motion identical) map to the same
/// joints by names and by structure alone, and drive a character to the
/// same poses (`pose::retarget`, each version's rest skeleton as its
/// neutral reference) within 1e-6 of its height.
#[test]
fn t_and_a_pose_versions_of_a_clip_map_and_retarget_alike() {
    use surfmotion::pose::retarget::{ClipNeutralSource, clip_poses, retarget};
    let walk = via_bvh(&surfmotion::synth::gait_clip(
        surfmotion::synth::Gait::Walk,
        2.0,
        30.0,
    ));
    let character = poses(&walk).1;
    let height = character[Canonical::Head.index()].y - character[Canonical::LToe.index()].y;
    for (what, nodes) in [
        ("procedural walk", nodes_of(&walk)),
        ("generated CC rig", shaped(&walk, &CC)),
        (
            "generated Daz Genesis 3/8 rig, no names",
            meaningless(&shaped(&walk, &GENESIS_3), ""),
        ),
    ] {
        let base = via_bvh(&build(&walk, &nodes, false));
        // The upper arm: the top joint of each arm that starts off the
        // body's mid-plane (below a collar when there is one).
        let upper = |l: bool| {
            let d = detect_clip(&base).unwrap();
            let k = if l {
                Canonical::LShoulder
            } else {
                Canonical::RShoulder
            };
            base.joint(&d.map.joints[&k]).unwrap().idx()
        };
        let (lu, ru) = (upper(true), upper(false));
        let mut results = Vec::new();
        for deg in [90.0f64, 45.0] {
            let t = deg.to_radians();
            let v = rerest(
                &rerest(&base, lu, DQuat::from_rotation_z(t)),
                ru,
                DQuat::from_rotation_z(-t),
            );
            let v = via_bvh(&v);
            let (rest, _) = v.rest_positions();
            let arm = rest[v.joint(&base.joints()[lu].name).unwrap().idx()];
            let below = (0..v.joint_count())
                .filter(|&j| v.joints()[j].parent.is_some_and(|p| p.idx() == lu))
                .max_by(|&a, &b| {
                    let l = |j: usize| v.joints()[j].offset.length();
                    l(a).total_cmp(&l(b))
                })
                .unwrap();
            let dir = (rest[below] - arm).normalize();
            assert!(
                (dir.dot(DVec3::Y).asin().to_degrees() + 90.0 - deg).abs() < 1.0,
                "{what}: the {deg}° version's upper arm points {dir}"
            );
            let d = detect_clip(&v).unwrap_or_else(|e| panic!("{what} {deg}°: {e}"));
            let base_map = detect_clip(&base).unwrap().map;
            assert_eq!(d.map.joints, base_map.joints, "{what} {deg}°");
            let cp = clip_poses(&v, &d.map).unwrap();
            assert_eq!(
                cp.reference.source,
                ClipNeutralSource::Rest,
                "{what} {deg}°"
            );
            results.push(retarget(&character, &cp.reference, &cp.poses));
        }
        let worst = results[0]
            .iter()
            .zip(&results[1])
            .flat_map(|((p, _), (q, _))| p.iter().zip(q).map(|(a, b)| a.distance(*b)))
            .fold(0.0, f64::max);
        eprintln!(
            "{what}: T- and A-pose results at most {:.2e} of the height apart",
            worst / height
        );
        assert!(
            worst < 1e-6 * height,
            "{what}: T and A versions {worst} m apart"
        );
    }
}

/// CMU 01_01 in its native ASF/AMC and in the third-party cgspeed BVH
/// conversion (frame 0 of the BVH an added T-pose), each mapped with no
/// rig map: the same canonical joints in every one of the 2,751 frames.
/// Pelvis, spine, chest and legs land within 1e-5 m; the conversion's rest
/// skeleton hangs the neck and shoulders 11.7 cm lower on the thorax than
/// the ASF, so the arms are compared by their bone directions (within
/// 0.1°) and the neck and head (on bones of other lengths there) not at
/// all.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn an_amc_clip_and_its_third_party_bvh_conversion_map_alike() {
    let Some(d) = common::data_dir() else { return };
    let mut a = load_clip(&d.join("mocap/cmu-amc/01/01_01.amc"), &Default::default()).unwrap();
    let mut b = load_clip(&d.join("mocap/cmu-bvh/01_01.bvh"), &Default::default()).unwrap();
    a.to_metres_y_up();
    b.to_metres_y_up();
    assert_eq!(a.frame_count() + 1, b.frame_count());
    let n = b.joint_count();
    let b = b
        .edited(|p| {
            p.rotations.drain(..n);
            p.translations.drain(..n);
        })
        .unwrap();
    let (da, db) = (detect_clip(&a).unwrap(), detect_clip(&b).unwrap());
    assert!(da.sides.contains("confirmed by geometry"), "{}", da.sides);
    assert!(db.sides.contains("confirmed by geometry"), "{}", db.sides);
    let (pa, pb) = (da.map.poses(&a).unwrap(), db.map.poses(&b).unwrap());
    use Canonical as C;
    let exact = Canonical::TORSO_AND_LEGS;
    let mut worst = 0.0f64;
    let mut worst_deg = 0.0f64;
    for (x, y) in pa.iter().zip(&pb) {
        for c in exact {
            worst = worst.max(x[c.index()].distance(y[c.index()]));
        }
        for (p, q) in [
            (C::LShoulder, C::LElbow),
            (C::LElbow, C::LWrist),
            (C::RShoulder, C::RElbow),
            (C::RElbow, C::RWrist),
        ] {
            let u = (x[q.index()] - x[p.index()]).normalize();
            let v = (y[q.index()] - y[p.index()]).normalize();
            worst_deg = worst_deg.max(u.dot(v).clamp(-1.0, 1.0).acos().to_degrees());
        }
    }
    eprintln!(
        "01_01 AMC vs cgspeed BVH, {} frames: torso and legs {worst:.1e} m apart, arm bones {worst_deg:.4}°",
        pa.len()
    );
    assert!(worst < 1e-5, "{worst} m");
    assert!(worst_deg < 0.1, "{worst_deg}°");
}

// ------------------------------------------------- real mocap suites (issue 17)

const BY_N: &str = surfmotion::rig::BY_NAMES;
const BY_S: &str = surfmotion::rig::BY_STRUCTURE;

macro_rules! suite {
    ($name:literal, $conv:expr, $sides:literal, $map:literal) => {
        Suite {
            name: $name,
            skel: include_str!(concat!("../../fixtures/suites/", $name, ".skel")),
            convention: $conv,
            sides: $sides,
            map: $map,
        }
    };
}

/// The families (sources in each `.skel` file's comment).
const SUITES: &[Suite] = &[
    suite!(
        "daz_friendly",
        BY_N,
        "from geometry",
        "pelvis=hip;spine=abdomen;chest=chest;neck=neck;head=head;\
         l_shoulder=lShldr;l_elbow=lForeArm;l_wrist=lHand;\
         r_shoulder=rShldr;r_elbow=rForeArm;r_wrist=rHand;\
         l_hip=lThigh;l_knee=lShin;l_ankle=lFoot;l_toe=~;\
         r_hip=rThigh;r_knee=rShin;r_ankle=rFoot;r_toe=~"
    ),
    suite!(
        "mocapdata_com",
        BY_S,
        "from names",
        "pelvis=Hips;spine=Chest;chest=Chest2;neck=Neck;head=Head;\
         l_shoulder=LeftShoulder;l_elbow=LeftElbow;l_wrist=LeftWrist;\
         r_shoulder=RightShoulder;r_elbow=RightElbow;r_wrist=RightWrist;\
         l_hip=LeftHip;l_knee=LeftKnee;l_ankle=LeftAnkle;l_toe=~;\
         r_hip=RightHip;r_knee=RightKnee;r_ankle=RightAnkle;r_toe=~"
    ),
    suite!(
        "biovision_classic",
        BY_S,
        "from names",
        "pelvis=Hips;spine=Chest;chest=~;neck=Neck;head=Head;\
         l_shoulder=LeftUpArm;l_elbow=LeftLowArm;l_wrist=LeftHand;\
         r_shoulder=RightUpArm;r_elbow=RightLowArm;r_wrist=RightHand;\
         l_hip=LeftUpLeg;l_knee=LeftLowLeg;l_ankle=LeftFoot;l_toe=~;\
         r_hip=RightUpLeg;r_knee=RightLowLeg;r_ankle=RightFoot;r_toe=~"
    ),
    suite!(
        "xsens_mvn",
        BY_S,
        "from geometry",
        "pelvis=Hips;spine=Chest2;chest=Chest4;neck=Neck;head=Head;\
         l_shoulder=LeftShoulder;l_elbow=LeftElbow;l_wrist=LeftWrist;\
         r_shoulder=RightShoulder;r_elbow=RightElbow;r_wrist=RightWrist;\
         l_hip=LeftHip;l_knee=LeftKnee;l_ankle=LeftAnkle;l_toe=LeftToe;\
         r_hip=RightHip;r_knee=RightKnee;r_ankle=RightAnkle;r_toe=RightToe"
    ),
    suite!(
        "perception_neuron",
        BY_N,
        "from geometry",
        "pelvis=Hips;spine=Spine;chest=Spine3;neck=Neck;head=Head;\
         l_shoulder=LeftArm;l_elbow=LeftForeArm;l_wrist=LeftHand;\
         r_shoulder=RightArm;r_elbow=RightForeArm;r_wrist=RightHand;\
         l_hip=LeftUpLeg;l_knee=LeftLeg;l_ankle=LeftFoot;l_toe=~;\
         r_hip=RightUpLeg;r_knee=RightLeg;r_ankle=RightFoot;r_toe=~"
    ),
    suite!(
        "louise",
        BY_S,
        "from geometry",
        "pelvis=Hips;spine=Chest;chest=~;neck=Neck;head=Head;\
         l_shoulder=LeftShoulder;l_elbow=LeftElbow;l_wrist=LeftWrist;\
         r_shoulder=RightShoulder;r_elbow=RightElbow;r_wrist=RightWrist;\
         l_hip=LeftHip;l_knee=LeftKnee;l_ankle=LeftAnkle;l_toe=~;\
         r_hip=RightHip;r_knee=RightKnee;r_ankle=RightAnkle;r_toe=~"
    ),
    suite!(
        "mixamo_numbered",
        "Mixamo",
        "from names, confirmed by geometry",
        "pelvis=mixamorig7:Hips;spine=mixamorig7:Spine;chest=mixamorig7:Spine2;\
         neck=mixamorig7:Neck;head=mixamorig7:Head;\
         l_shoulder=mixamorig7:LeftArm;l_elbow=mixamorig7:LeftForeArm;\
         l_wrist=mixamorig7:LeftHand;r_shoulder=mixamorig7:RightArm;\
         r_elbow=mixamorig7:RightForeArm;r_wrist=mixamorig7:RightHand;\
         l_hip=mixamorig7:LeftUpLeg;l_knee=mixamorig7:LeftLeg;\
         l_ankle=mixamorig7:LeftFoot;l_toe=mixamorig7:LeftToeBase;\
         r_hip=mixamorig7:RightUpLeg;r_knee=mixamorig7:RightLeg;\
         r_ankle=mixamorig7:RightFoot;r_toe=mixamorig7:RightToeBase"
    ),
    suite!(
        "humanik_rigmesh",
        "MotionBuilder HumanIK",
        "from names, confirmed by geometry",
        "pelvis=Character1_Hips;spine=Character1_Spine;chest=Character1_Spine2;\
         neck=Character1_Neck;head=Character1_Head;\
         l_shoulder=Character1_LeftArm;l_elbow=Character1_LeftForeArm;\
         l_wrist=Character1_LeftHand;r_shoulder=Character1_RightArm;\
         r_elbow=Character1_RightForeArm;r_wrist=Character1_RightHand;\
         l_hip=Character1_LeftUpLeg;l_knee=Character1_LeftLeg;\
         l_ankle=Character1_LeftFoot;l_toe=Character1_LeftToeBase;\
         r_hip=Character1_RightUpLeg;r_knee=Character1_RightLeg;\
         r_ankle=Character1_RightFoot;r_toe=Character1_RightToeBase"
    ),
    suite!(
        "max_biped",
        BY_N,
        "from geometry",
        "pelvis=Bip01 Pelvis;spine=Bip01 Spine;chest=Bip01 Spine2;\
         neck=Bip01 Neck;head=Bip01 Head;\
         l_shoulder=Bip01 L UpperArm;l_elbow=Bip01 L Forearm;l_wrist=Bip01 L Hand;\
         r_shoulder=Bip01 R UpperArm;r_elbow=Bip01 R Forearm;r_wrist=Bip01 R Hand;\
         l_hip=Bip01 L Thigh;l_knee=Bip01 L Calf;l_ankle=Bip01 L Foot;l_toe=Bip01 L Toe0;\
         r_hip=Bip01 R Thigh;r_knee=Bip01 R Calf;r_ankle=Bip01 R Foot;r_toe=Bip01 R Toe0"
    ),
    suite!(
        "unreal_manny",
        "Unreal Engine mannequin",
        "from names, confirmed by geometry",
        "pelvis=pelvis;spine=spine_01;chest=spine_05;neck=neck_01;head=head;\
         l_shoulder=upperarm_l;l_elbow=lowerarm_l;l_wrist=hand_l;\
         r_shoulder=upperarm_r;r_elbow=lowerarm_r;r_wrist=hand_r;\
         l_hip=thigh_l;l_knee=calf_l;l_ankle=foot_l;l_toe=ball_l;\
         r_hip=thigh_r;r_knee=calf_r;r_ankle=foot_r;r_toe=ball_r"
    ),
    suite!(
        "vroid",
        BY_N,
        "from geometry",
        "pelvis=J_Bip_C_Hips;spine=J_Bip_C_Spine;chest=J_Bip_C_UpperChest;\
         neck=J_Bip_C_Neck;head=J_Bip_C_Head;\
         l_shoulder=J_Bip_L_UpperArm;l_elbow=J_Bip_L_LowerArm;l_wrist=J_Bip_L_Hand;\
         r_shoulder=J_Bip_R_UpperArm;r_elbow=J_Bip_R_LowerArm;r_wrist=J_Bip_R_Hand;\
         l_hip=J_Bip_L_UpperLeg;l_knee=J_Bip_L_LowerLeg;l_ankle=J_Bip_L_Foot;\
         l_toe=J_Bip_L_ToeBase;r_hip=J_Bip_R_UpperLeg;r_knee=J_Bip_R_LowerLeg;\
         r_ankle=J_Bip_R_Foot;r_toe=J_Bip_R_ToeBase"
    ),
    suite!(
        "smpl",
        BY_N,
        "from geometry",
        "pelvis=Pelvis;spine=Spine1;chest=Spine3;neck=Neck;head=Head;\
         l_shoulder=L_Shoulder;l_elbow=L_Elbow;l_wrist=L_Wrist;\
         r_shoulder=R_Shoulder;r_elbow=R_Elbow;r_wrist=R_Wrist;\
         l_hip=L_Hip;l_knee=L_Knee;l_ankle=L_Ankle;l_toe=L_Foot;\
         r_hip=R_Hip;r_knee=R_Knee;r_ankle=R_Ankle;r_toe=R_Foot"
    ),
    suite!(
        "smplx_zup",
        BY_N,
        "from geometry",
        "pelvis=pelvis;spine=spine1;chest=spine3;neck=neck;head=head;\
         l_shoulder=left_shoulder;l_elbow=left_elbow;l_wrist=left_wrist;\
         r_shoulder=right_shoulder;r_elbow=right_elbow;r_wrist=right_wrist;\
         l_hip=left_hip;l_knee=left_knee;l_ankle=left_ankle;l_toe=left_foot;\
         r_hip=right_hip;r_knee=right_knee;r_ankle=right_ankle;r_toe=right_foot"
    ),
    suite!(
        "h36m_video2bvh",
        BY_N,
        "from geometry",
        "pelvis=Hip;spine=Spine;chest=Thorax;neck=Neck;head=~;\
         l_shoulder=LeftShoulder;l_elbow=LeftElbow;l_wrist=LeftWrist;\
         r_shoulder=RightShoulder;r_elbow=RightElbow;r_wrist=RightWrist;\
         l_hip=LeftHip;l_knee=LeftKnee;l_ankle=LeftAnkle;l_toe=~;\
         r_hip=RightHip;r_knee=RightKnee;r_ankle=RightAnkle;r_toe=~"
    ),
    suite!(
        "kinect_v2",
        BY_N,
        "from geometry",
        "pelvis=SpineBase;spine=SpineMid;chest=SpineShoulder;neck=Neck;head=Head;\
         l_shoulder=ShoulderLeft;l_elbow=ElbowLeft;l_wrist=WristLeft;\
         r_shoulder=ShoulderRight;r_elbow=ElbowRight;r_wrist=WristRight;\
         l_hip=HipLeft;l_knee=KneeLeft;l_ankle=AnkleLeft;l_toe=FootLeft;\
         r_hip=HipRight;r_knee=KneeRight;r_ankle=AnkleRight;r_toe=FootRight"
    ),
    suite!(
        "optitrack_motive",
        BY_N,
        "from geometry",
        "pelvis=Skeleton1_Hip;spine=Skeleton1_Ab;chest=Skeleton1_Chest;\
         neck=Skeleton1_Neck;head=Skeleton1_Head;\
         l_shoulder=Skeleton1_LUArm;l_elbow=Skeleton1_LFArm;l_wrist=Skeleton1_LHand;\
         r_shoulder=Skeleton1_RUArm;r_elbow=Skeleton1_RFArm;r_wrist=Skeleton1_RHand;\
         l_hip=Skeleton1_LThigh;l_knee=Skeleton1_LShin;l_ankle=Skeleton1_LFoot;\
         l_toe=Skeleton1_LToe;r_hip=Skeleton1_RThigh;r_knee=Skeleton1_RShin;\
         r_ankle=Skeleton1_RFoot;r_toe=Skeleton1_RToe"
    ),
    suite!(
        "blender_rigify",
        BY_S,
        "from geometry",
        "pelvis=DEF-spine;spine=DEF-spine.001;chest=DEF-spine.003;\
         neck=DEF-spine.004;head=DEF-spine.006;\
         l_shoulder=DEF-upper_arm.L;l_elbow=DEF-forearm.L;l_wrist=DEF-hand.L;\
         r_shoulder=DEF-upper_arm.R;r_elbow=DEF-forearm.R;r_wrist=DEF-hand.R;\
         l_hip=DEF-thigh.L;l_knee=DEF-shin.L;l_ankle=DEF-foot.L;l_toe=DEF-toe.L;\
         r_hip=DEF-thigh.R;r_knee=DEF-shin.R;r_ankle=DEF-foot.R;r_toe=DEF-toe.R"
    ),
    suite!(
        "rokoko",
        BY_N,
        "from geometry",
        "pelvis=Hips;spine=Spine1;chest=Spine4;neck=Neck;head=Head;\
         l_shoulder=LeftArm;l_elbow=LeftForeArm;l_wrist=LeftHand;\
         r_shoulder=RightArm;r_elbow=RightForeArm;r_wrist=RightHand;\
         l_hip=LeftThigh;l_knee=LeftShin;l_ankle=LeftFoot;l_toe=LeftToe;\
         r_hip=RightThigh;r_knee=RightShin;r_ankle=RightFoot;r_toe=RightToe"
    ),
    suite!(
        "second_life_bento",
        BY_N,
        "from geometry",
        "pelvis=hip;spine=abdomen;chest=chest;neck=neck;head=head;\
         l_shoulder=lShldr;l_elbow=lForeArm;l_wrist=lHand;\
         r_shoulder=rShldr;r_elbow=rForeArm;r_wrist=rHand;\
         l_hip=lThigh;l_knee=lShin;l_ankle=lFoot;l_toe=mToeLeft;\
         r_hip=rThigh;r_knee=rShin;r_ankle=rFoot;r_toe=mToeRight"
    ),
    suite!(
        "poser_sl",
        BY_N,
        "from geometry",
        "pelvis=hip;spine=abdomen;chest=chest;neck=neck;head=head;\
         l_shoulder=lShldr;l_elbow=lForeArm;l_wrist=lHand;\
         r_shoulder=rShldr;r_elbow=rForeArm;r_wrist=rHand;\
         l_hip=lThigh;l_knee=lShin;l_ankle=lFoot;l_toe=~;\
         r_hip=rThigh;r_knee=rShin;r_ankle=rFoot;r_toe=~"
    ),
    suite!(
        "lafan1",
        BY_N,
        "from geometry",
        "pelvis=Hips;spine=Spine;chest=Spine2;neck=Neck;head=Head;\
         l_shoulder=LeftArm;l_elbow=LeftForeArm;l_wrist=LeftHand;\
         r_shoulder=RightArm;r_elbow=RightForeArm;r_wrist=RightHand;\
         l_hip=LeftUpLeg;l_knee=LeftLeg;l_ankle=LeftFoot;l_toe=LeftToe;\
         r_hip=RightUpLeg;r_knee=RightLeg;r_ankle=RightFoot;r_toe=RightToe"
    ),
    suite!(
        "hanim_loa1",
        BY_S,
        "from geometry",
        "pelvis=sacroiliac;spine=vl5;chest=~;neck=skullbase;head=~;\
         l_shoulder=l_shoulder;l_elbow=l_elbow;l_wrist=l_radiocarpal;\
         r_shoulder=r_shoulder;r_elbow=r_elbow;r_wrist=r_radiocarpal;\
         l_hip=l_hip;l_knee=l_knee;l_ankle=l_talocrural;l_toe=~;\
         r_hip=r_hip;r_knee=r_knee;r_ankle=r_talocrural;r_toe=~"
    ),
];

/// Non-humanoids in the suites (a Biped-named horse, a bird, a dog carrying
/// every MotionBuilder HumanIK name).
const NOT_HUMANOIDS: &[(&str, &str)] = &[
    (
        "truebones_horse",
        include_str!("../../fixtures/suites/truebones_horse.skel"),
    ),
    ("bird", include_str!("../../fixtures/suites/bird.skel")),
    (
        "dog_humanik_names",
        include_str!("../../fixtures/suites/dog_humanik_names.skel"),
    ),
];

fn suite_clip(name: &str, skel: &str) -> Clip {
    let text = skel_to_bvh(skel);
    parse_bvh(
        &text,
        std::path::Path::new(&format!("{name}.bvh")),
        &BvhOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{name}: {e}\n{text}"))
}

/// Every real-world family maps with no rig map to the full canonical map
/// (left and right included), names the right convention (a known one only
/// when it is one: Xsens MVN's names are not CMU's 3dsMax BVH), says where
/// left and right came from, and places every canonical joint. All
/// families are checked before failing, each failure listed.
#[test]
fn real_suites_map_every_canonical_joint() {
    let mut fails = Vec::new();
    for s in SUITES {
        let c = suite_clip(s.name, s.skel);
        let d = match detect_clip(&c) {
            Ok(d) => d,
            Err(e) => {
                fails.push(format!("{}: {e}", s.name));
                continue;
            }
        };
        if d.map.convention != s.convention {
            fails.push(format!("{}: convention '{}'", s.name, d.map.convention));
        }
        if !d.sides.starts_with(s.sides) {
            fails.push(format!("{}: sides {}", s.name, d.sides));
        }
        for e in map_errors(&d, &expected(s)) {
            fails.push(format!("{}: {e}", s.name));
        }
        let rest = d.map.rest_pose(&c).unwrap();
        assert!(rest.iter().all(|p| p.is_finite()), "{}", s.name);
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// The same bodies mirrored (x negated, names kept): where the geometry
/// says which way the body faces (feet forward), the joints named left are
/// now on the right and map to the right canonical joints; where it cannot
/// (mocapdata.com, the Biovision sample: feet straight down, straight
/// knees, no travel) the names decide.
#[test]
fn real_suites_mirrored_map_left_and_right_from_geometry() {
    let mut fails = Vec::new();
    for s in SUITES {
        let c = suite_clip(s.name, s.skel);
        let m = via_bvh(&mirror(&c));
        let d = match detect_clip(&m) {
            Ok(d) => d,
            Err(e) => {
                fails.push(format!("{} mirrored: {e}", s.name));
                continue;
            }
        };
        let by_names = s.sides == "from names";
        let want: Vec<(Canonical, Vec<String>)> = expected(s)
            .into_iter()
            .map(|(k, v)| (if by_names { k } else { swap_side(k) }, v))
            .collect();
        for e in map_errors(&d, &want) {
            fails.push(format!("{} mirrored: {e}", s.name));
        }
        if !by_names && !d.sides.contains("mirrored") {
            fails.push(format!("{} mirrored: sides {}", s.name, d.sides));
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// Non-humanoids are refused with "not a humanoid: …", whatever their
/// joint names (a dog with every HumanIK name was reported as "MotionBuilder
/// HumanIK" before).
#[test]
fn suite_non_humanoids_are_refused_whatever_their_names() {
    for (name, skel) in NOT_HUMANOIDS {
        let c = suite_clip(name, skel);
        match detect_clip(&c) {
            Err(RigError::NotHumanoid { reason }) => {
                assert!(reason.contains("horizontal"), "{name}: {reason}")
            }
            Ok(d) => panic!("{name} mapped as {}: {:?}", d.map.convention, d.map.joints),
            Err(e) => panic!("{name}: {e}"),
        }
    }
}

/// `mocap rigmap` and `inspect --json` on every suite written as a BVH
/// file: humanoids exit 0 and report the expected convention (never a
/// known convention for a family that is not one); non-humanoids exit 1
/// with "not a humanoid" and `inspect` says so instead of naming one.
#[test]
fn cli_maps_every_suite_and_refuses_the_animals() {
    let dir = tempfile::tempdir().unwrap();
    for s in SUITES {
        let p = dir.path().join(format!("{}.bvh", s.name));
        std::fs::write(&p, skel_to_bvh(s.skel)).unwrap();
        let o = run_cli(&["mocap", "rigmap"], &p);
        let out = String::from_utf8_lossy(&o.stdout);
        assert!(
            o.status.success(),
            "{}: {}",
            s.name,
            String::from_utf8_lossy(&o.stderr)
        );
        assert!(
            out.lines()
                .next()
                .is_some_and(|l| l == format!("convention: {}", s.convention)),
            "{}: {out}",
            s.name
        );
        let o = run_cli(&["inspect", "--json"], &p);
        assert!(o.status.success(), "{}", s.name);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["convention"].as_str(), Some(s.convention), "{}", s.name);
    }
    for (name, skel) in NOT_HUMANOIDS {
        let p = dir.path().join(format!("{name}.bvh"));
        std::fs::write(&p, skel_to_bvh(skel)).unwrap();
        let o = run_cli(&["mocap", "rigmap"], &p);
        assert_eq!(o.status.code(), Some(1), "{name}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains("not a humanoid"), "{name}: {e}");
        let o = run_cli(&["inspect", "--json"], &p);
        assert!(o.status.success(), "{name}");
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert!(
            v["convention"]
                .as_str()
                .is_some_and(|c| c.starts_with("not a humanoid: ")),
            "{name}: {v}"
        );
    }
}

/// Structure alone on the suites: every joint of a few families renamed
/// `J<k>` (no name hints at all) puts the limbs' canonical joints (hips,
/// knees, ankles, shoulders, elbows, wrists, left and right) where the
/// names put them, in the rest pose.
#[test]
fn real_suites_without_names_place_the_limbs_alike() {
    use Canonical as C;
    let limbs = [
        C::LHip,
        C::LKnee,
        C::LAnkle,
        C::LShoulder,
        C::LElbow,
        C::LWrist,
        C::RHip,
        C::RKnee,
        C::RAnkle,
        C::RShoulder,
        C::RElbow,
        C::RWrist,
    ];
    let mut fails = Vec::new();
    for s in SUITES {
        let c = suite_clip(s.name, s.skel);
        if s.sides == "from names" {
            continue; // nothing but the names tells left from right
        }
        let named = detect_clip(&c).unwrap().map.rest_pose(&c).unwrap();
        let bare = common::skel::unnamed(&c);
        let bare = via_bvh(&bare);
        let d = match detect_clip(&bare) {
            Ok(d) => d,
            Err(e) => {
                fails.push(format!("{} without names: {e}", s.name));
                continue;
            }
        };
        let p = d.map.rest_pose(&bare).unwrap();
        let tol = 1e-6 * scale(&named);
        for k in limbs {
            let e = p[k.index()].distance(named[k.index()]);
            if e > tol {
                fails.push(format!(
                    "{} without names: {} {:.3} from the named one ({})",
                    s.name,
                    k.name(),
                    e,
                    d.map.joints.get(&k).map_or("derived", String::as_str)
                ));
            }
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// Every suite drives the procedural humanoid as `retarget` reads a clip
/// (`load_clip`: unit and up axis guessed; metres, Y-up; detected map,
/// reference pose, rotation transfer): a smoke run. Each result is finite
/// and stands: head above the neck above the pelvis, knees well below the
/// hips and ankles well below the knees, on the character's up axis (+Y).
#[test]
fn real_suites_drive_the_procedural_character() {
    use Canonical as C;
    use surfmotion::embed::Embedding;
    use surfmotion::pose::retarget::{clip_poses, retarget};
    use surfmotion::synth::humanoid::{DEMO_GRID, humanoid_landmarks, humanoid_mesh};
    let mesh = humanoid_mesh(DEMO_GRID);
    let rig = Embedding::new(&mesh, &humanoid_landmarks(&mesh), None).unwrap();
    let character: Pose = rig.joints().map(DVec3::from_array);
    let dir = tempfile::tempdir().unwrap();
    let mut fails = Vec::new();
    for s in SUITES {
        let path = dir.path().join(format!("{}.bvh", s.name));
        std::fs::write(&path, skel_to_bvh(s.skel)).unwrap();
        let mut c = load_clip(&path, &Default::default()).unwrap();
        c.to_metres_y_up();
        let d = detect_clip(&c).unwrap();
        let cp = clip_poses(&c, &d.map).unwrap_or_else(|e| panic!("{}: {e}", s.name));
        for (f, (p, _)) in retarget(&character, &cp.reference, &cp.poses)
            .into_iter()
            .enumerate()
        {
            let y = |k: C| p[k.index()].y;
            // A shin or thigh is about a quarter of the height: standing,
            // each knee is over 0.15 H below its hip and each ankle over
            // 0.15 H below its knee (a Z-up clip read as Y-up sits).
            let h = rig.height();
            let stands = p.iter().all(|q| q.is_finite())
                && y(C::Head) > y(C::Neck)
                && y(C::Neck) > y(C::Pelvis)
                && [(C::LHip, C::LKnee), (C::RHip, C::RKnee)]
                    .iter()
                    .chain(&[(C::LKnee, C::LAnkle), (C::RKnee, C::RAnkle)])
                    .all(|&(a, b)| y(b) < y(a) - 0.15 * h);
            if !stands {
                fails.push(format!("{} frame {f}: {p:?}", s.name));
            }
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

// ------------------------------------------- units, and rests that do not stand

/// The unit a suite's `.skel` comment states (`cm,`, `inches,`, `m,` ...),
/// as [`surfmotion::mocap::units::BVH_UNITS`] names it.
fn stated_unit(skel: &str) -> &'static str {
    for line in skel.lines().filter(|l| l.starts_with('#')) {
        for w in line.split_whitespace() {
            match w.trim_end_matches([',', '.']) {
                "mm" => return "mm",
                "cm" => return "cm",
                "inches" | "inch" => return "inch",
                "dm" => return "dm",
                "ft" | "feet" => return "ft",
                "m" => return "m",
                _ => {}
            }
        }
    }
    panic!("no unit stated in {skel}")
}

fn metres_per(unit: &str) -> f64 {
    surfmotion::mocap::units::BVH_UNITS
        .iter()
        .find(|u| u.1 == unit)
        .unwrap_or_else(|| panic!("{unit}"))
        .0
}

/// `load_clip` on a clip written as a BVH file (units and up axis decided
/// as every verb decides them).
fn load_written(dir: &std::path::Path, name: &str, c: &Clip) -> Clip {
    let p = dir.join(format!("{name}.bvh"));
    std::fs::write(&p, format_bvh(c)).unwrap();
    load_clip(&p, &Default::default()).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Every suite is read in the unit its source writes (inches for the
/// Biovision sample, mocapdata.com and Second Life, which were read as
/// centimetres: the Biovision body came out 0.60 m tall), and the same
/// skeleton written in each unit real suites use (mm, cm, inch, dm, ft,
/// m) is read in that unit, its stature the same in metres (within 1e-9)
/// and between 1.4 and 2.0 m; `inspect --json` says which unit and why.
#[test]
fn every_suite_is_read_in_its_unit_and_in_every_unit_it_is_written_in() {
    let dir = tempfile::tempdir().unwrap();
    let mut fails = Vec::new();
    for s in SUITES {
        let c = suite_clip(s.name, s.skel);
        let unit = stated_unit(s.skel);
        let got = load_written(dir.path(), s.name, &c);
        if got.units().name != unit {
            fails.push(format!(
                "{}: read in {} ({}), written in {unit}",
                s.name,
                got.units().name,
                got.units().reason
            ));
        }
        let map = detect_clip(&c).unwrap().map;
        let (h, _) = surfmotion::rig::load::stature(&c, &map).unwrap();
        let h_m = h * metres_per(unit);
        if !(1.4..=2.0).contains(&h_m) {
            fails.push(format!("{}: stature {h_m:.3} m", s.name));
        }
        for (u, uname) in surfmotion::mocap::units::BVH_UNITS {
            let v = scaled(&c, metres_per(unit) / u);
            let got = load_written(dir.path(), &format!("{}_{uname}", s.name), &v);
            let (hv, _) = surfmotion::rig::load::stature(&v, &map).unwrap();
            if got.units().name != uname || (hv * u - h_m).abs() > 1e-9 * h_m {
                fails.push(format!(
                    "{} written in {uname}: read in {} ({})",
                    s.name,
                    got.units().name,
                    got.units().reason
                ));
            }
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
    // The report and the override.
    let p = dir.path().join("biovision_classic.bvh");
    let o = run_cli(&["inspect", "--json"], &p);
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["units"]["name"], "inch", "{v}");
    let why = v["units"]["reason"].as_str().unwrap();
    assert!(
        why.contains("stature 1.") && why.contains("in cm it would be"),
        "{why}"
    );
    let o = run_cli(&["inspect", "--json", "--input-units", "cm"], &p);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["units"]["name"], "cm", "{v}");
    assert_eq!(v["units"]["reason"], "given by the user", "{v}");
}

/// Children and tall adults: the same body scaled to a stature of 0.9 to
/// 2.0 m, written in centimetres and in inches (a factor 2.54 apart, the
/// closest pair of units), is read in the unit it was written in; so are
/// metres and feet (3.28 apart) down to 0.8 m.
#[test]
fn children_and_tall_adults_are_read_in_their_unit() {
    let s = SUITES.iter().find(|s| s.name == "daz_friendly").unwrap();
    let c = suite_clip(s.name, s.skel);
    let map = detect_clip(&c).unwrap().map;
    let (h, _) = surfmotion::rig::load::stature(&c, &map).unwrap();
    let h_m = h * metres_per("cm");
    let dir = tempfile::tempdir().unwrap();
    let mut fails = Vec::new();
    for (stature, units) in [
        (0.9, &["cm", "inch", "m", "ft"][..]),
        (1.1, &["cm", "inch", "mm", "m", "ft", "dm"][..]),
        (1.5, &["cm", "inch", "mm", "m", "ft", "dm"][..]),
        (1.95, &["cm", "inch", "mm", "m", "ft", "dm"][..]),
        (0.8, &["m", "ft"][..]),
    ] {
        for unit in units {
            let v = scaled(&c, stature / h_m * metres_per("cm") / metres_per(unit));
            let got = load_written(dir.path(), &format!("h{stature}_{unit}"), &v);
            if got.units().name != *unit {
                fails.push(format!(
                    "{stature} m in {unit}: read in {} ({})",
                    got.units().name,
                    got.units().reason
                ));
            }
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// The same motion over another rest skeleton: joint `j`'s bone frame
/// turned by `a[j]` (its rest offsets to children, End Site and per-frame
/// child translations expressed in the turned frame: `a[j]⁻¹ · o`; its
/// local rotation `a[parent]⁻¹ · q · a[j]`, the root's `q · a[root]`), so
/// every frame's world positions are unchanged while the rest pose is any
/// other: lying down (one rotation for all), folded (every bone along its
/// parent's +X, as LAFAN1 writes it), or random.
fn rerest_all(c: &Clip, a: &[DQuat]) -> Clip {
    let n = c.joint_count();
    let pa = |j: usize| c.joints()[j].parent.map_or(DQuat::IDENTITY, |p| a[p.idx()]);
    let mut out = c.clone().into_parts();
    for (j, jt) in out.joints.iter_mut().enumerate() {
        if jt.parent.is_some() {
            jt.offset = pa(j).inverse() * jt.offset;
        }
        jt.tail = jt.tail.map(|t| a[j].inverse() * t);
    }
    for f in 0..c.frame_count() {
        for (j, aj) in a.iter().enumerate().take(n) {
            let k = f * n + j;
            out.rotations[k] = pa(j).inverse() * c.rotations()[k] * *aj;
            if c.joints()[j].parent.is_some() {
                out.translations[k] = pa(j).inverse() * c.translations()[k];
            }
        }
    }
    Clip::from_parts(out).unwrap()
}

/// The turn of each joint's frame that lays its longest child bone (or its
/// End Site) along +X: LAFAN1's folded rest.
fn folding(c: &Clip) -> Vec<DQuat> {
    (0..c.joint_count())
        .map(|j| {
            let d = c
                .joints()
                .iter()
                .filter(|k| k.parent.is_some_and(|p| p.idx() == j))
                .map(|k| k.offset)
                .chain(c.joints()[j].tail)
                .max_by(|a, b| a.length().total_cmp(&b.length()))
                .unwrap_or(DVec3::X);
            if d.length() < 1e-12 {
                DQuat::IDENTITY
            } else {
                DQuat::from_rotation_arc(DVec3::X, d.normalize())
            }
        })
        .collect()
}

/// A zero rest: every offset zero and six channels on every joint, the
/// frames' position channels carrying the bones (as some exporters write).
fn zero_rest(c: &Clip) -> Clip {
    let mut out = c.clone().into_parts();
    for j in &mut out.joints {
        if j.parent.is_some() {
            j.offset = DVec3::ZERO;
        }
        let rot: Vec<Channel> = j
            .channels
            .iter()
            .copied()
            .filter(|c| c.is_rotation())
            .collect();
        j.channels = [Channel::Xposition, Channel::Yposition, Channel::Zposition]
            .into_iter()
            .chain(if rot.len() == 3 {
                rot
            } else {
                Channel::ROT_ZYX.to_vec()
            })
            .collect();
    }
    Clip::from_parts(out).unwrap()
}

/// The variants of a clip whose rest does not stand, the motion unchanged:
/// its rest turned 90° about Z and about X (the inverse in the frames),
/// folded (LAFAN1), turned at random per joint, and zero.
fn non_standing_rests(c: &Clip) -> Vec<(&'static str, Clip)> {
    let n = c.joint_count();
    let all = |q: DQuat| vec![q; n];
    let mut seed = 0x9e3779b97f4a7c15u64;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let random: Vec<DQuat> = (0..n)
        .map(|_| {
            let axis = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize_or(DVec3::Y);
            DQuat::from_axis_angle(axis, (rnd() - 0.5) * 2.0 * std::f64::consts::PI)
        })
        .collect();
    let h = std::f64::consts::FRAC_PI_2;
    vec![
        (
            "rest lying along X",
            rerest_all(c, &all(DQuat::from_rotation_z(-h))),
        ),
        (
            "rest lying along Z",
            rerest_all(c, &all(DQuat::from_rotation_x(h))),
        ),
        ("rest folded along X (LAFAN1)", rerest_all(c, &folding(c))),
        ("rest turned at random per joint", rerest_all(c, &random)),
        ("zero rest, offsets in the frames", zero_rest(c)),
    ]
}

/// A rest skeleton that does not stand (lying, folded as LAFAN1's, turned
/// at random, zero) with the inverse in the frames maps every suite
/// exactly as the standing rest does (the structure is read on a frame's
/// pose instead), gives the same stature (so the same unit), and every
/// non-humanoid is still refused.
#[test]
fn rests_that_do_not_stand_map_like_the_standing_one() {
    let mut fails = Vec::new();
    for s in SUITES {
        let c = suite_clip(s.name, s.skel);
        let want = detect_clip(&c).unwrap().map;
        let (h, _) = surfmotion::rig::load::stature(&c, &want).unwrap();
        for (what, v) in non_standing_rests(&c) {
            let v = via_bvh(&v);
            match detect_clip(&v) {
                Ok(d) if d.map == want => {
                    let (hv, _) = surfmotion::rig::load::stature(&v, &d.map).unwrap();
                    if (hv - h).abs() > 1e-6 * h {
                        fails.push(format!("{} {what}: stature {hv} vs {h}", s.name));
                    }
                }
                Ok(d) => fails.push(format!("{} {what}: {:?}\n  want {:?}", s.name, d.map, want)),
                Err(e) => fails.push(format!("{} {what}: {e}", s.name)),
            }
        }
    }
    for (name, skel) in NOT_HUMANOIDS {
        let c = suite_clip(name, skel);
        for (what, v) in non_standing_rests(&c) {
            match detect_clip(&via_bvh(&v)) {
                Err(RigError::NotHumanoid { .. }) => {}
                Ok(d) => fails.push(format!("{name} {what}: mapped as {:?}", d.map)),
                Err(e) => fails.push(format!("{name} {what}: {e}")),
            }
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}
