//! The rig families issue 44 found refused, generated from real clips
//! (CMU cgspeed and 3dsMax-friendly BVH, CMU ASF/AMC, Reallusion CC,
//! Bandai Namco) and the procedural walk by editing their hierarchies, then
//! written as BVH in several units and read back as `retarget` reads a
//! clip (`load_clip`: unit and up axis guessed; metres, Y-up):
//!
//! - (a) **helper leaves**: beside the real child of every bone a leaf
//!   joint (a mesh attachment or a socket: `lhumerus_RIGMESH` beside
//!   `lradius`), 30-70% of that bone long, 35-90° off it, named by several
//!   schemes (helper words or not);
//! - (b) **Rigify-style exports**: `DEF-` names, pelvis controller leaves
//!   (`DEF-pelvis.L/R`) beside the thighs, a tail chain below the hips, a
//!   torso controller leaf up beside the spine;
//! - (c) **depth-sensor skeletons**: Kinect v2 joint names, the legs' rest
//!   bones turned out of line with the trunk (spread sideways, bent forward
//!   as in a seated rest, every bone along the trunk as the sensor's joint
//!   orientations have it), the motion unchanged;
//! - (d) **exact convention names** (HumanIK `Character1_`, Mixamo
//!   `mixamorig:`, Unreal `pelvis`/`spine_01`/`thigh_l`, Unity
//!   `LeftUpperLeg`) on rigs the structure analysis alone cannot read,
//!   and a body whose named legs point the wrong way (still refused).
//!
//! Every variant maps every canonical joint, and its canonical positions in
//! every frame (`mocap positions`) and its retargeted poses (`pose`
//! retargeting onto one character) are the plain rig's within 1e-6 of the
//! height: the same joints, left on the left.

use super::mapping::{Node, add, build, canonical_index, nodes_of, rerest, short};
use crate::common;

use glam::{DQuat, DVec3};
use surfmotion::mocap::Clip;
use surfmotion::mocap::bvh::format_bvh;
use surfmotion::pose::Pose;
use surfmotion::rig::{Canonical, RigMap, detect_clip, load_clip};

use Canonical as C;

/// The plain rigs: the procedural walk and short copies (60 frames) of
/// real clips of every family in the data.
fn sources(d: &std::path::Path) -> Vec<(String, Clip)> {
    let mut out = vec![(
        "procedural walk".to_string(),
        surfmotion::synth::gait_clip(surfmotion::synth::Gait::Walk, 2.0, 30.0),
    )];
    for rel in [
        "cmu-bvh/01_01.bvh",
        "cmu-bvh/131_01.bvh",
        "cmu-amc/02/02_01.amc",
        "cmu-bvh-ccrig/005_01.bvh",
        "bandai-namco/dataset-1_walk_normal_001.bvh",
    ] {
        let c = load_clip(&d.join("mocap").join(rel), &Default::default()).unwrap();
        out.push((rel.to_string(), short(&c)));
    }
    out
}

/// A clip written as BVH (lengths times `k`) and read back as `retarget`
/// reads a clip, in metres, Y-up.
fn reread(dir: &std::path::Path, name: &str, c: &Clip, k: f64) -> Clip {
    let p = dir.join(format!("{}.bvh", name.replace(['/', ' '], "_")));
    std::fs::write(&p, format_bvh(&common::skel::scaled(c, k))).unwrap();
    let mut c = load_clip(&p, &Default::default()).unwrap();
    c.to_metres_y_up();
    c
}

/// The rest positions and the body's axes in the rest (file frame): up
/// (pelvis → chest), left (right hip → left hip, across up), forward
/// (left × up), and the leg's length (hip → ankle).
struct Frame {
    rest: Vec<DVec3>,
    up: DVec3,
    left: DVec3,
    fwd: DVec3,
    leg: f64,
    hips: f64,
}

fn frame(c: &Clip, map: &RigMap) -> Frame {
    let (rest, _) = c.rest_positions();
    let at = |k: C| rest[c.joint(&map.joints[&k]).unwrap().idx()];
    // The rest may hold the body turned (Bandai's lies along +X): the axes
    // are the body's own.
    let top = if map.joints.contains_key(&C::Chest) {
        C::Chest
    } else {
        C::Neck
    };
    let up = (at(top) - at(C::Pelvis)).normalize();
    let lr = at(C::LHip) - at(C::RHip);
    let left = (lr - up * lr.dot(up)).normalize();
    Frame {
        up,
        left,
        fwd: left.cross(up),
        leg: at(C::LHip).distance(at(C::LAnkle)),
        hips: lr.length(),
        rest,
    }
}

fn joint_of(c: &Clip, map: &RigMap, k: C) -> usize {
    c.joint(&map.joints[&k]).unwrap().idx()
}

/// Canonical joints renamed by `name` (others kept, or `x<i>` when
/// `neutral`).
fn renamed(c: &Clip, map: &RigMap, name: &dyn Fn(C) -> String, neutral: bool) -> Vec<Node> {
    let canon = canonical_index(c, map);
    let mut n = nodes_of(c);
    for (i, x) in n.iter_mut().enumerate() {
        match canon[i] {
            Some(k) => x.name = name(k),
            None if neutral => x.name = format!("x{i}"),
            None => {}
        }
    }
    n
}

/// (a) A leaf beside the real child of every bone: 30, 50 or 70% of the
/// longest child's offset (the joint's own bone when that is zero), turned
/// 35, 60 or 90° off it about an axis that goes round the bone from joint
/// to joint; named `{bone}{suffix}`, an End Site or none.
fn helper_leaves(c: &Clip, map: &RigMap, scheme: usize) -> Vec<Node> {
    let mut n = nodes_of(c);
    add_leaves(&mut n, rest_size(c), &torso_of(c, map), scheme);
    n
}

/// The joints from the pelvis up to the head (the head excluded): their
/// leaves are at least 15% of the body's size long × 0.5-0.9 (a mesh
/// attachment beside `Spine1` as long as a limb bone: the structure saw a
/// junction there, "the two chains off 'Spine1' differ in length").
fn torso_of(c: &Clip, map: &RigMap) -> Vec<bool> {
    let mut out = vec![false; c.joint_count()];
    let pelvis = joint_of(c, map, C::Pelvis);
    let mut k = c.joints()[joint_of(c, map, C::Head)]
        .parent
        .map(|p| p.idx());
    while let Some(j) = k {
        out[j] = true;
        if j == pelvis {
            break;
        }
        k = c.joints()[j].parent.map(|p| p.idx());
    }
    out
}

/// The rest skeleton's bounding-box diagonal.
fn rest_size(c: &Clip) -> f64 {
    let (rest, _) = c.rest_positions();
    let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for p in &rest {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    (hi - lo).length()
}

/// The leaves of [`helper_leaves`] added to `n` (a body of `size`, the
/// trunk's joints `torso`).
fn add_leaves(n: &mut Vec<Node>, size: f64, torso: &[bool], scheme: usize) {
    let suffix = ["_RIGMESH", "_geo", "Attach", "_Socket"][scheme % 4];
    let count = n.len();
    for j in 0..count {
        let longest = (0..count)
            .filter(|&k| n[k].parent == Some(j))
            .map(|k| n[k].offset)
            .max_by(|a, b| a.length().total_cmp(&b.length()));
        let Some(longest) = longest else { continue };
        let base = if longest.length() > 1e-2 * size {
            longest
        } else if n[j].offset.length() > 1e-2 * size {
            n[j].offset
        } else {
            continue;
        };
        let k = j + scheme;
        let turn = [35.0f64, 60.0, 90.0][k % 3].to_radians();
        let (frac, base) = if torso.get(j).copied().unwrap_or(false) {
            let floor = 0.15 * size;
            (
                [0.5, 0.7, 0.9][(k / 3) % 3],
                base.normalize() * base.length().max(floor),
            )
        } else {
            ([0.3, 0.5, 0.7][(k / 3) % 3], base)
        };
        let b = base.normalize();
        let axis = DQuat::from_axis_angle(b, 1.1 * k as f64) * b.any_orthonormal_vector();
        let off = DQuat::from_axis_angle(axis, turn) * base * frac;
        let tail = match scheme % 3 {
            0 => Some(off * 0.25),
            1 => Some(DVec3::ZERO),
            _ => None,
        };
        let name = format!("{}{suffix}", n[j].name);
        add(n, j, &name, off, tail);
    }
}

/// Rigify's deform-bone names for the canonical joints (`DEF-spine` the
/// hips … `DEF-spine.006` the head; `.L`/`.R` limbs).
fn rigify_name(k: C) -> String {
    let s = |b: &str, l: bool| format!("DEF-{b}.{}", if l { "L" } else { "R" });
    match k {
        C::Pelvis => "DEF-spine".into(),
        C::Spine => "DEF-spine.001".into(),
        C::Chest => "DEF-spine.003".into(),
        C::Neck => "DEF-spine.004".into(),
        C::Head => "DEF-spine.006".into(),
        C::LShoulder => s("upper_arm", true),
        C::LElbow => s("forearm", true),
        C::LWrist => s("hand", true),
        C::RShoulder => s("upper_arm", false),
        C::RElbow => s("forearm", false),
        C::RWrist => s("hand", false),
        C::LHip => s("thigh", true),
        C::LKnee => s("shin", true),
        C::LAnkle => s("foot", true),
        C::LToe => s("toe", true),
        C::RHip => s("thigh", false),
        C::RKnee => s("shin", false),
        C::RAnkle => s("foot", false),
        C::RToe => s("toe", false),
    }
}

/// (b) A Rigify-style export: `DEF-` names (scheme 2: the source's names),
/// pelvis controller leaves up, out and forward from the hips, a tail of
/// five bones back and down from them (named `DEF-tail…`, or neutral
/// `ORG-chain…` names), and with scheme ≥ 1 a torso controller leaf up
/// beside the spine.
fn rigify(c: &Clip, map: &RigMap, scheme: usize) -> Vec<Node> {
    let mut n = if scheme == 2 {
        nodes_of(c)
    } else {
        renamed(c, map, &rigify_name, true)
    };
    add_extras(&mut n, &frame(c, map), joint_of(c, map, C::Pelvis), scheme);
    n
}

/// The extra chains of [`rigify`] added below the pelvis `p` of `n`.
fn add_extras(n: &mut Vec<Node>, f: &Frame, p: usize, scheme: usize) {
    for (s, sign) in [("L", 1.0), ("R", -1.0)] {
        let off = sign * f.left * 0.6 * f.hips + f.up * 0.2 * f.leg + f.fwd * 0.1 * f.leg;
        add(n, p, &format!("DEF-pelvis.{s}"), off, Some(off * 0.1));
    }
    let word = ["DEF-tail", "ORG-chain", "MCH-dangle"][scheme % 3];
    let mut at = p;
    for i in 0..5 {
        let off = if i == 0 {
            -f.fwd * 0.08 * f.leg - f.up * 0.04 * f.leg
        } else {
            -f.fwd * 0.12 * f.leg - f.up * 0.06 * f.leg
        };
        let name = if i == 0 {
            word.to_string()
        } else {
            format!("{word}.{i:03}")
        };
        at = add(n, at, &name, off, (i == 4).then_some(off * 0.5));
    }
    if scheme >= 1 {
        let off = f.up * 0.35 * f.leg + f.fwd * 0.05 * f.leg;
        add(n, p, "MCH-torso", off, Some(off * 0.2));
    }
}

/// Kinect v2's joint names for the canonical joints (`SpineBase` …
/// `FootLeft`: the sensor's foot joint is the toe).
fn kinect_name(k: C) -> String {
    let s = |b: &str, l: bool| format!("{b}{}", if l { "Left" } else { "Right" });
    match k {
        C::Pelvis => "SpineBase".into(),
        C::Spine => "SpineMid".into(),
        C::Chest => "SpineShoulder".into(),
        C::Neck => "Neck".into(),
        C::Head => "Head".into(),
        C::LShoulder => s("Shoulder", true),
        C::LElbow => s("Elbow", true),
        C::LWrist => s("Wrist", true),
        C::RShoulder => s("Shoulder", false),
        C::RElbow => s("Elbow", false),
        C::RWrist => s("Wrist", false),
        C::LHip => s("Hip", true),
        C::LKnee => s("Knee", true),
        C::LAnkle => s("Ankle", true),
        C::LToe => s("Foot", true),
        C::RHip => s("Hip", false),
        C::RKnee => s("Knee", false),
        C::RAnkle => s("Ankle", false),
        C::RToe => s("Foot", false),
    }
}

/// (c) A depth-sensor skeleton: Kinect names (other joints neutral), and
/// the legs' rest bones turned about the hips out of line with the trunk,
/// the motion unchanged ([`rerest`]): scheme 0 spread 55° sideways, 1 bent
/// 80° forward (a seated rest), 2 every leg bone along the trunk's up (the
/// sensor's joint orientations: each bone along its joint's +Y).
fn depth_sensor(c: &Clip, map: &RigMap, scheme: usize) -> Clip {
    let base = build(c, &renamed(c, map, &kinect_name, true), false);
    legs_rerested(c, map, &base, scheme, &kinect_name)
}

/// `base` (a re-shaping of `c` whose canonical joints are named by `name`)
/// with the legs' rest bones turned as [`depth_sensor`] says.
fn legs_rerested(
    c: &Clip,
    map: &RigMap,
    base: &Clip,
    scheme: usize,
    name: &dyn Fn(C) -> String,
) -> Clip {
    let f = frame(c, map);
    let mut out = base.clone();
    for (k, sign) in [(C::LHip, 1.0), (C::RHip, -1.0)] {
        let hip = joint_of(c, map, k);
        let knee = joint_of(c, map, k.child_leg());
        let a = match scheme % 3 {
            0 => DQuat::from_axis_angle(f.fwd, sign * 55f64.to_radians()),
            1 => DQuat::from_axis_angle(f.left, -80f64.to_radians()),
            _ => {
                let down = (f.rest[knee] - f.rest[hip]).normalize();
                DQuat::from_rotation_arc(down, f.up)
            }
        };
        let here = out.joint(&name(k)).unwrap().idx();
        out = rerest(&out, here, a);
    }
    out
}

trait LegChild {
    fn child_leg(self) -> C;
}

impl LegChild for C {
    fn child_leg(self) -> C {
        match self {
            C::LHip => C::LKnee,
            C::RHip => C::RKnee,
            _ => self,
        }
    }
}

/// A known convention's name for each canonical joint.
fn convention_name(conv: usize, k: C) -> String {
    let hik = |b: &str| -> String {
        match k {
            C::Pelvis => "Hips".into(),
            C::Spine => "Spine".into(),
            C::Chest => "Spine2".into(),
            C::Neck => "Neck".into(),
            C::Head => "Head".into(),
            _ => b.into(),
        }
    };
    let sided = |l: &str, r: &str| -> (String, String) { (l.into(), r.into()) };
    let limb = |names: [&str; 7], left: bool, ue: bool| -> String {
        let i = match k {
            C::LShoulder | C::RShoulder => 0,
            C::LElbow | C::RElbow => 1,
            C::LWrist | C::RWrist => 2,
            C::LHip | C::RHip => 3,
            C::LKnee | C::RKnee => 4,
            C::LAnkle | C::RAnkle => 5,
            _ => 6,
        };
        if ue {
            format!("{}_{}", names[i], if left { "l" } else { "r" })
        } else {
            format!("{}{}", if left { "Left" } else { "Right" }, names[i])
        }
    };
    let _ = sided;
    let left = matches!(
        k,
        C::LShoulder | C::LElbow | C::LWrist | C::LHip | C::LKnee | C::LAnkle | C::LToe
    );
    let torso = matches!(k, C::Pelvis | C::Spine | C::Chest | C::Neck | C::Head);
    const HIK: [&str; 7] = ["Arm", "ForeArm", "Hand", "UpLeg", "Leg", "Foot", "ToeBase"];
    const UE: [&str; 7] = [
        "upperarm", "lowerarm", "hand", "thigh", "calf", "foot", "ball",
    ];
    const UNITY: [&str; 7] = [
        "UpperArm", "LowerArm", "Hand", "UpperLeg", "LowerLeg", "Foot", "Toes",
    ];
    match conv % 4 {
        0 => format!(
            "Character1_{}",
            if torso {
                hik("")
            } else {
                limb(HIK, left, false)
            }
        ),
        1 => format!(
            "mixamorig:{}",
            if torso {
                hik("")
            } else {
                limb(HIK, left, false)
            }
        ),
        2 => match k {
            C::Pelvis => "pelvis".into(),
            C::Spine => "spine_01".into(),
            C::Chest => "spine_03".into(),
            C::Neck => "neck_01".into(),
            C::Head => "head".into(),
            _ => limb(UE, left, true),
        },
        _ => match k {
            C::Pelvis => "Hips".into(),
            C::Spine => "Spine".into(),
            C::Chest => "Chest".into(),
            C::Neck => "Neck".into(),
            C::Head => "Head".into(),
            _ => limb(UNITY, left, false),
        },
    }
}

/// Every joint of `n` carrying the convention's prefix (a HumanIK
/// character's `Character1_`, Mixamo's `mixamorig:` namespace), as their
/// exporters write every joint.
fn with_prefix(mut n: Vec<Node>, conv: usize) -> Vec<Node> {
    let p = ["Character1_", "mixamorig:", "", ""][conv % 4];
    for x in &mut n {
        if !x.name.starts_with(p) {
            x.name = format!("{p}{}", x.name);
        }
    }
    n
}

fn height(p: &Pose) -> f64 {
    p[C::Head.index()].distance(p[C::LAnkle.index()])
}

/// The largest difference of two clips' canonical positions (each
/// relative to its own height: the unit guessed may differ) over every
/// frame and joint, in heights.
fn position_gap(a: &[Pose], b: &[Pose]) -> f64 {
    assert_eq!(a.len(), b.len());
    let (ha, hb) = (height(&a[0]), height(&b[0]));
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..Canonical::COUNT).map(move |k| (p[k] / ha).distance(q[k] / hb)))
        .fold(0.0, f64::max)
}

/// Result of one variant.
struct Outcome {
    what: String,
    error: Option<String>,
    positions: f64,
    retargeted: f64,
}

/// Maps `v` and compares it with the plain rig (`plain`, its poses and
/// retargeted poses). A variant whose rest skeleton was changed (`rest`:
/// the plain rig's reference) is retargeted from the plain rig's
/// reference: the mapping is judged, not the choice of reference (a rest
/// whose legs do not stand gives way to the most neutral frame).
fn judge(
    what: String,
    v: &Clip,
    plain: &(Vec<Pose>, Vec<Pose>),
    character: &Pose,
    rest: Option<&surfmotion::pose::retarget::ClipNeutral>,
) -> Outcome {
    use surfmotion::pose::retarget::{clip_poses, retarget};
    let d = match detect_clip(v) {
        Ok(d) => d,
        Err(e) => {
            return Outcome {
                what,
                error: Some(e.to_string()),
                positions: f64::NAN,
                retargeted: f64::NAN,
            };
        }
    };
    if !d.missing.is_empty() {
        return Outcome {
            what,
            error: Some(format!("unmapped: {:?}", d.missing)),
            positions: f64::NAN,
            retargeted: f64::NAN,
        };
    }
    let mut cp = clip_poses(v, &d.map).unwrap();
    // In the plain rig's metres (the unit guessed for the variant's file
    // may differ: a CMU unit is known by CMU names only).
    let k = height(&plain.0[0]) / height(&cp.poses[0]);
    for p in &mut cp.poses {
        *p = p.map(|q| q * k);
    }
    cp.reference.pose = cp.reference.pose.map(|q| q * k);
    let reference = rest.cloned().unwrap_or(cp.reference);
    let out: Vec<Pose> = retarget(character, &reference, &cp.poses)
        .into_iter()
        .map(|(p, _)| p)
        .collect();
    let h = height(character);
    let retargeted = out
        .iter()
        .zip(&plain.1)
        .flat_map(|(p, q)| p.iter().zip(q).map(|(a, b)| a.distance(*b) / h))
        .fold(0.0, f64::max);
    let positions = position_gap(&plain.0, &cp.poses);
    if positions > 1e-6 {
        // Which joints moved (the plain rig's picks are where its own
        // names put them; here the variant's names).
        let (h0, h1) = (height(&plain.0[0]), height(&cp.poses[0]));
        for k in Canonical::ALL {
            let e = (plain.0[0][k.index()] / h0).distance(cp.poses[0][k.index()] / h1);
            if e > 1e-6 {
                eprintln!(
                    "  {what}: {} at {:?} is {e:.3} H off",
                    k.name(),
                    d.map.joints.get(&k)
                );
            }
        }
    }
    Outcome {
        what,
        error: None,
        positions,
        retargeted,
    }
}

/// Every generated variant of every source, judged (see the module docs).
fn outcomes(d: &std::path::Path, families: &str) -> Vec<Outcome> {
    use surfmotion::pose::retarget::{clip_poses, retarget};
    let walk = surfmotion::synth::gait_clip(surfmotion::synth::Gait::Walk, 2.0, 30.0);
    let wm = detect_clip(&walk).unwrap().map;
    let character = wm.rest_pose(&walk).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let mut out = Vec::new();
    for (s, (name, src)) in sources(d).into_iter().enumerate() {
        let c = reread(dir.path(), &format!("{name}-plain"), &src, 1.0);
        let map = detect_clip(&c).unwrap().map;
        let cp = clip_poses(&c, &map).unwrap();
        let rt: Vec<Pose> = retarget(&character, &cp.reference, &cp.poses)
            .into_iter()
            .map(|(p, _)| p)
            .collect();
        let plain_ref = cp.reference.clone();
        let plain = (cp.poses, rt);
        let units = [1.0, 0.01, 10.0];
        let mut variants: Vec<(String, Clip)> = Vec::new();
        for scheme in 0..4 {
            if families.contains('a') {
                variants.push((
                    format!("(a) helper leaves, scheme {scheme}"),
                    build(&c, &helper_leaves(&c, &map, scheme), scheme % 2 == 1),
                ));
            }
            if families.contains('b') && scheme < 3 {
                variants.push((
                    format!("(b) Rigify, scheme {scheme}"),
                    build(&c, &rigify(&c, &map, scheme), scheme % 2 == 1),
                ));
            }
            if families.contains('c') && scheme < 3 {
                variants.push((
                    format!("(c) depth sensor, scheme {scheme}"),
                    depth_sensor(&c, &map, scheme),
                ));
            }
            if families.contains('d') {
                // A convention's names on (a), (b) and (c) at once.
                let named = |k: C| convention_name(scheme, k);
                let mut nodes = renamed(&c, &map, &named, true);
                add_leaves(&mut nodes, rest_size(&c), &torso_of(&c, &map), scheme);
                add_extras(
                    &mut nodes,
                    &frame(&c, &map),
                    joint_of(&c, &map, C::Pelvis),
                    1,
                );
                let v = build(&c, &with_prefix(nodes, scheme), false);
                variants.push((
                    format!("(d) convention {scheme}"),
                    legs_rerested(&c, &map, &v, scheme % 3, &named),
                ));
            }
        }
        for (k, (what, v)) in variants.into_iter().enumerate() {
            let unit = units[(k + s) % 3];
            let v = reread(dir.path(), &format!("{name}-{k}"), &v, unit);
            let rest = (what.starts_with("(c)") || what.starts_with("(d)")).then_some(&plain_ref);
            out.push(judge(
                format!("{name} {what} (×{unit})"),
                &v,
                &plain,
                &character,
                rest,
            ));
        }
    }
    out
}

fn report(o: &[Outcome]) -> Vec<String> {
    let mut fails = Vec::new();
    for x in o {
        match &x.error {
            Some(e) => {
                eprintln!("{}: REFUSED {e}", x.what);
                fails.push(format!("{}: {e}", x.what));
            }
            None => {
                eprintln!(
                    "{}: positions {:.1e} H, retargeted {:.1e} H",
                    x.what, x.positions, x.retargeted
                );
                if !(x.positions <= 1e-6 && x.retargeted <= 1e-6) {
                    fails.push(format!(
                        "{}: positions {:.1e} H, retargeted {:.1e} H",
                        x.what, x.positions, x.retargeted
                    ));
                }
            }
        }
    }
    fails
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn generated_refused_families_map_like_the_plain_rig() {
    let Some(d) = common::data_dir() else { return };
    let o = outcomes(&d, "abcd");
    let fails = report(&o);
    eprintln!(
        "{} of {} variants map alike",
        o.len() - fails.len(),
        o.len()
    );
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// A rig carrying every name of a known convention whose named legs are
/// its arms (the leg names on the upper arm, forearm and hand, the arm
/// names on the thigh, shin and foot): the geometry cannot place the named
/// limbs, and the named legs hang from the chest beside the trunk, not
/// below it, so it is refused ("not a humanoid: the legs named … do not
/// point away from the spine"); it was mapped "from names (geometry
/// undecided)", the arms driving the character's legs.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_convention_whose_named_legs_point_the_wrong_way_is_refused() {
    let Some(d) = common::data_dir() else { return };
    let dir = tempfile::tempdir().unwrap();
    let mut fails = Vec::new();
    for (name, src) in sources(&d).into_iter().take(3) {
        let c = reread(dir.path(), &format!("{name}-plain"), &src, 1.0);
        let map = detect_clip(&c).unwrap().map;
        for conv in 0..4 {
            let swapped = |k: C| {
                let other = match k {
                    C::LShoulder => C::LHip,
                    C::LElbow => C::LKnee,
                    C::LWrist => C::LAnkle,
                    C::RShoulder => C::RHip,
                    C::RElbow => C::RKnee,
                    C::RWrist => C::RAnkle,
                    C::LHip => C::LShoulder,
                    C::LKnee => C::LElbow,
                    C::LAnkle => C::LWrist,
                    C::RHip => C::RShoulder,
                    C::RKnee => C::RElbow,
                    C::RAnkle => C::RWrist,
                    k => k,
                };
                convention_name(conv, other)
            };
            let v = build(
                &c,
                &with_prefix(renamed(&c, &map, &swapped, true), conv),
                false,
            );
            let v = reread(dir.path(), &format!("{name}-swapped-{conv}"), &v, 1.0);
            match detect_clip(&v) {
                Ok(det) => fails.push(format!(
                    "{name} convention {conv}: mapped as {} ({})",
                    det.map.convention, det.sides
                )),
                Err(e) => {
                    let e = e.to_string();
                    eprintln!("{name} convention {conv}: {e}");
                    if !e.contains("not a humanoid") || !e.contains("do not point away") {
                        fails.push(format!("{name} convention {conv}: {e}"));
                    }
                }
            }
        }
    }
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}

/// A depth-sensor skeleton file: Kinect names, the legs' rest bones
/// spread 50° or 60° out from the trunk's line, and only that rest pose
/// as its one frame (a skeleton definition, no motion to stand it up).
/// It maps every canonical joint the plain rig maps, to the joints with
/// those names, left on the left (the sides from the feet). The legs'
/// mean direction is what points away from the trunk: each leg's own
/// cosine (−0.64, −0.50) called it "a horizontal body". Built from the
/// sources whose rest skeleton stands.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_depth_sensor_skeleton_with_spread_legs_maps_from_its_rest_alone() {
    use surfmotion::mocap::PointConvention;
    use surfmotion::pose::retarget::{ClipNeutralSource, clip_poses};
    let Some(d) = common::data_dir() else { return };
    let dir = tempfile::tempdir().unwrap();
    let mut fails = Vec::new();
    let mut checked = 0;
    for (name, src) in sources(&d) {
        let c = reread(dir.path(), &format!("{name}-plain"), &src, 1.0);
        let map = detect_clip(&c).unwrap().map;
        if clip_poses(&c, &map).unwrap().reference.source != ClipNeutralSource::Rest {
            continue;
        }
        for deg in [50.0f64, 60.0] {
            let f = frame(&c, &map);
            let mut v = build(&c, &renamed(&c, &map, &kinect_name, true), false);
            for (k, sign) in [(C::LHip, 1.0), (C::RHip, -1.0)] {
                let here = v.joint(&kinect_name(k)).unwrap().idx();
                v = rerest(
                    &v,
                    here,
                    DQuat::from_axis_angle(f.fwd, sign * deg.to_radians()),
                );
            }
            let n = v.joint_count();
            let rest = Clip::new(
                v.joints().to_vec(),
                v.frame_time(),
                vec![DQuat::IDENTITY; n],
                v.joints().iter().map(|j| j.offset).collect(),
                v.units().clone(),
                v.up(),
                PointConvention::JointOrigins,
            )
            .unwrap();
            let what = format!("{name} legs spread {deg}°");
            let got = reread(dir.path(), &what, &rest, 1.0);
            checked += 1;
            let det = match detect_clip(&got) {
                Ok(det) => det,
                Err(e) => {
                    eprintln!("{what}: {e}");
                    fails.push(format!("{what}: {e}"));
                    continue;
                }
            };
            eprintln!("{what}: {} | {}", det.map.convention, det.sides);
            for k in Canonical::ALL {
                if map.joints.contains_key(&k) && det.map.joints.get(&k) != Some(&kinect_name(k)) {
                    fails.push(format!(
                        "{what}: {} = {:?}, not {}",
                        k.name(),
                        det.map.joints.get(&k),
                        kinect_name(k)
                    ));
                }
            }
        }
    }
    assert!(checked >= 4, "{checked}");
    assert!(fails.is_empty(), "{}", fails.join("\n"));
}
