//! The whole body's gap between two files of one performance, decomposed
//! by source (issue 44: CMU 02_03 as the native AMC and as the CC-rig BVH
//! conversion "within 1 % of the height"; docs/mocap.md, "One performance
//! in two files").
//!
//! Per pair (aligned in time by `two_files::aligned`, both read at 30 fps
//! as `retarget` reads them), every canonical joint is built on one
//! character (`common::walk_character`, its bone lengths) from each file's
//! own bone directions, parent to child from the pelvis, no kernel
//! involved. Levels, each the mean over frames and the 19 joints of the
//! distance between the two files' skeletons, over the height:
//! - `read`: the world directions as the files give them, the BVH's turned
//!   by the one yaw that fits the AMC's best: any retarget that copies
//!   every bone's direction shows this about the pelvis;
//! - `calibrated`: each file's directions in its own body heading frame,
//!   each bone's mean offset between the files removed (a constant
//!   per-bone correction: what a rest pose, a reference or the rigs'
//!   joint placement can account for); what remains changes frame by
//!   frame: the two files carry different motion there;
//! - each with the pelvises together (`rel`) and with the best translation
//!   of each frame (`any`: the geometric median of the 19 joints' offsets,
//!   the least any rule placing the pelvis can reach).
//!
//! Against them the kernel's results (`retarget`), the same measures:
//! `abs` (as placed), `any` (each frame's best translation: the posture
//! alone). So the kernel's `abs` splits into the pelvis's placement (`abs
//! − any`), the kernel's posture beyond the files' directions (`any −
//! read any`), the rigs' constant offsets (`read any − calibrated any`)
//! and the motion that differs frame by frame (`calibrated any`).
//! Timing and sampling: the same `read` level from the files as loaded
//! (not aligned: the conversion starts 1/120 s later) and at the files'
//! own rates (every BVH frame against its AMC frame, 60 pairs a second).
//! The levelling: the BVH's skeletons turned about the pelvis by the AMC
//! clip's ground tilt (`ground_tilt`, which the kernel levels by).

use crate::common;

use super::two_files::{CC_PAIRS, TwoFiles, best_yaw, poses_at_30, two_files, varied};
use glam::{DQuat, DVec3};
use surfmotion::mocap::Clip;
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::{ClipPoses, choose_reference, ground_tilt, retarget};
use surfmotion::rig::{Canonical, detect_clip};

use Canonical as C;

/// Every canonical bone (parent, child), parents first.
fn bones() -> Vec<(C, C)> {
    Canonical::ALL
        .iter()
        .filter_map(|&c| c.parent().map(|p| (p, c)))
        .collect()
}

/// The pair of joints each of `bones()` takes its direction from in both
/// files: the bone itself, or where it has no length in some frame of
/// either file (CMU 01_01's cgspeed BVH puts the neck's base on the
/// chest) its parent's start to its end.
fn effective_bones(pa: &[Pose], pb: &[Pose]) -> Vec<(C, C)> {
    bones()
        .into_iter()
        .map(|(a, b)| {
            let short = pa
                .iter()
                .chain(pb)
                .any(|p| p[a.index()].distance(p[b.index()]) < 1e-4);
            match (short, a.parent()) {
                (true, Some(g)) => (g, b),
                _ => (a, b),
            }
        })
        .collect()
}

/// The body's heading frame of `p` (left, up, forward from the hips' and
/// shoulders' lines) as a rotation taking body axes to world.
fn heading(p: &Pose) -> DQuat {
    let l = (p[C::LHip.index()] - p[C::RHip.index()])
        + (p[C::LShoulder.index()] - p[C::RShoulder.index()]);
    let left = DVec3::new(l.x, 0.0, l.z).normalize_or_zero();
    let fwd = left.cross(DVec3::Y);
    DQuat::from_mat3(&glam::DMat3::from_cols(left, DVec3::Y, fwd))
}

/// Unit direction of bone (a, b) in `p`.
fn dir(p: &Pose, a: C, b: C) -> DVec3 {
    (p[b.index()] - p[a.index()]).normalize_or_zero()
}

/// A skeleton on `character`'s bone lengths from the directions `d[i]` of
/// `bones()[i]`, its pelvis at the origin.
fn built(character: &Pose, d: &[DVec3]) -> Pose {
    let mut out = [DVec3::ZERO; Canonical::COUNT];
    for (i, &(a, b)) in bones().iter().enumerate() {
        let len = character[a.index()].distance(character[b.index()]);
        out[b.index()] = out[a.index()] + len * d[i];
    }
    out
}

/// The point `t` minimising Σ |d_j − t| (Weiszfeld's iteration).
pub(super) fn geometric_median(d: &[DVec3]) -> DVec3 {
    let mut t = d.iter().copied().sum::<DVec3>() / d.len() as f64;
    for _ in 0..1000 {
        let (mut num, mut den) = (DVec3::ZERO, 0.0);
        for &x in d {
            let w = 1.0 / x.distance(t).max(1e-12);
            num += w * x;
            den += w;
        }
        let next = num / den;
        if next.distance(t) < 1e-12 {
            return next;
        }
        t = next;
    }
    t
}

/// Per frame: the offsets of the 19 joints (a − b) with the pelvises
/// together (`rel`), as placed (`abs`) and after the frame's best
/// translation (`any`). Returned: mean over frames and joints of each,
/// over `h`, and per joint the `any` mean (over `h`).
struct Gap {
    abs: f64,
    rel: f64,
    any: f64,
    per_joint: [f64; Canonical::COUNT],
}

fn gap(a: &[Pose], b: &[Pose], h: f64) -> Gap {
    let n = a.len().min(b.len());
    let p = C::Pelvis.index();
    let (mut abs, mut rel, mut any) = (0.0, 0.0, 0.0);
    let mut per_joint = [0.0; Canonical::COUNT];
    for f in 0..n {
        let d: Vec<DVec3> = (0..Canonical::COUNT).map(|j| a[f][j] - b[f][j]).collect();
        let t = geometric_median(&d);
        for (j, &x) in d.iter().enumerate() {
            abs += x.length();
            rel += (x - d[p]).length();
            any += (x - t).length();
            per_joint[j] += (x - t).length() / (n as f64 * h);
        }
    }
    let k = (n * Canonical::COUNT) as f64 * h;
    Gap {
        abs: abs / k,
        rel: rel / k,
        any: any / k,
        per_joint,
    }
}

/// The `read` level: each file's world directions on the character, the
/// second turned by the one yaw (a 0.05° scan over ±40°) that fits the first best.
/// Also returned: that yaw (degrees).
fn read_level(character: &Pose, pa: &[Pose], pb: &[Pose], h: f64) -> (Gap, f64) {
    let n = pa.len().min(pb.len());
    let bs = effective_bones(&pa[..n], &pb[..n]);
    let yaw = best_yaw(&pa[..n], &pb[..n], &bs, 800);
    let q = DQuat::from_rotation_y(yaw.to_radians());
    let sa: Vec<Pose> = (0..n)
        .map(|f| {
            let d: Vec<DVec3> = bs.iter().map(|&(x, y)| dir(&pa[f], x, y)).collect();
            built(character, &d)
        })
        .collect();
    let sb: Vec<Pose> = (0..n)
        .map(|f| {
            let d: Vec<DVec3> = bs.iter().map(|&(x, y)| q * dir(&pb[f], x, y)).collect();
            built(character, &d)
        })
        .collect();
    (gap(&sa, &sb, h), yaw)
}

/// The `calibrated` level: each file's directions in its own heading
/// frame, the second's bones each turned by the arc between the two
/// files' mean directions. Also returned: per bone, the mean angle left
/// between the two files' directions (degrees), and the two skeletons
/// (for the per-group shares).
struct Calibrated {
    gap: Gap,
    bone_deg: Vec<f64>,
    a: Vec<Vec<DVec3>>,
    b: Vec<Vec<DVec3>>,
}

fn calibrated_level(character: &Pose, pa: &[Pose], pb: &[Pose], h: f64) -> Calibrated {
    let n = pa.len().min(pb.len());
    let bs = effective_bones(&pa[..n], &pb[..n]);
    let local = |p: &Pose, x: C, y: C| heading(p).inverse() * dir(p, x, y);
    let la: Vec<Vec<DVec3>> = (0..n)
        .map(|f| bs.iter().map(|&(x, y)| local(&pa[f], x, y)).collect())
        .collect();
    let mut lb: Vec<Vec<DVec3>> = (0..n)
        .map(|f| bs.iter().map(|&(x, y)| local(&pb[f], x, y)).collect())
        .collect();
    for i in 0..bs.len() {
        let (mut ma, mut mb) = (DVec3::ZERO, DVec3::ZERO);
        for f in 0..n {
            ma += la[f][i];
            mb += lb[f][i];
        }
        let arc = DQuat::from_rotation_arc(mb.normalize(), ma.normalize());
        for row in lb.iter_mut() {
            row[i] = arc * row[i];
        }
    }
    let bone_deg = (0..bs.len())
        .map(|i| {
            (0..n)
                .map(|f| la[f][i].angle_between(lb[f][i]).to_degrees())
                .sum::<f64>()
                / n as f64
        })
        .collect();
    let sa: Vec<Pose> = la.iter().map(|d| built(character, d)).collect();
    let sb: Vec<Pose> = lb.iter().map(|d| built(character, d)).collect();
    Calibrated {
        gap: gap(&sa, &sb, h),
        bone_deg,
        a: la,
        b: lb,
    }
}

/// The kernel's results of `cp` on `character`.
fn results(character: &Pose, cp: &ClipPoses) -> Vec<Pose> {
    retarget(character, &cp.reference, &cp.poses)
        .into_iter()
        .map(|(p, _)| p)
        .collect()
}

/// `cp` measured from its most neutral frame (its rest not offered).
fn frame_referenced(mut cp: ClipPoses) -> ClipPoses {
    let rotations = cp.reference.rotations.clone();
    cp.reference = choose_reference(None, &cp.poses).unwrap();
    cp.reference.rotations = rotations;
    cp
}

/// What one pair's decomposition measured (fractions of the height).
struct Row {
    name: String,
    read: Gap,
    yaw: f64,
    cal: Calibrated,
    kernel: Gap,
    kernel_frames: Gap,
    /// The kernel's pelvises apart (mean, of the height).
    kernel_pelvis: f64,
    /// The calibrated skeletons (the data's floor of the posture), each
    /// turned by the AMC's heading and put on its own kernel result's
    /// pelvis: what this kernel's placement allows.
    cal_placed: Gap,
    unaligned_read: Gap,
    native_read: Gap,
    levelled_read: Gap,
    shares: Vec<(&'static str, f64)>,
}

const GROUPS: [(&str, &[C]); 3] = [
    (
        "trunk",
        &[
            C::Spine,
            C::Chest,
            C::Neck,
            C::Head,
            C::LShoulder,
            C::RShoulder,
            C::LHip,
            C::RHip,
        ],
    ),
    (
        "legs",
        &[C::LKnee, C::LAnkle, C::LToe, C::RKnee, C::RAnkle, C::RToe],
    ),
    ("arms", &[C::LElbow, C::LWrist, C::RElbow, C::RWrist]),
];

/// One pair's decomposition: `raw` the two clips as loaded, `al` aligned
/// in time, `ca`/`cb` the aligned clips' poses at 30 fps (a variant's),
/// `back` what turns the second's kernel result back.
fn decompose(
    name: &str,
    (character, h): (&Pose, f64),
    raw: (&Clip, &Clip),
    al: (&Clip, &Clip),
    ca: &ClipPoses,
    cb: &ClipPoses,
    back: DQuat,
) -> Row {
    let n = ca.poses.len().min(cb.poses.len());
    let (pa, pb) = (&ca.poses[..n], &cb.poses[..n]);
    let (read, yaw) = read_level(character, pa, pb, h);
    let cal = calibrated_level(character, pa, pb, h);
    // A turned clip's result turned back about the character's root (the
    // kernel keeps the clip's heading of travel).
    let c0 = character[C::Pelvis.index()] * DVec3::new(1.0, 0.0, 1.0);
    let un = |r: Vec<Pose>| -> Vec<Pose> {
        r.into_iter()
            .map(|x| x.map(|v| c0 + back * (v - c0)))
            .collect()
    };
    let (ka, kb) = (results(character, ca), un(results(character, cb)));
    let kernel = gap(&ka, &kb, h);
    let p = C::Pelvis.index();
    let kn = ka.len().min(kb.len());
    let kernel_pelvis = (0..kn).map(|f| ka[f][p].distance(kb[f][p])).sum::<f64>() / (kn as f64 * h);
    let placed = |dirs: &[Vec<DVec3>], k: &[Pose]| -> Vec<Pose> {
        (0..kn.min(n))
            .map(|f| {
                let q = heading(&pa[f]);
                built(character, &dirs[f]).map(|v| k[f][p] + q * v)
            })
            .collect()
    };
    let cal_placed = gap(&placed(&cal.a, &ka), &placed(&cal.b, &kb), h);
    let kernel_frames = gap(
        &results(character, &frame_referenced(ca.clone())),
        &un(results(character, &frame_referenced(cb.clone()))),
        h,
    );
    // Timing: as loaded, each from its first frame, both at 30 fps.
    let at30 = |c: &Clip| {
        let c = c.try_resampled(30.0).unwrap();
        let map = detect_clip(&c).unwrap().map;
        map.poses(&c).unwrap()
    };
    let (ua, ub) = (at30(raw.0), at30(raw.1));
    let (unaligned_read, _) = read_level(character, &ua, &ub, h);
    // Sampling: every BVH frame against its AMC frame at the files' rates.
    let native = |c: &Clip| detect_clip(c).unwrap().map.poses(c).unwrap();
    let (na, nb) = (native(al.0), native(al.1));
    let step = (al.0.fps() / al.1.fps()).round().max(1.0) as usize;
    let m = nb.len().min(na.len() / step);
    let na2: Vec<Pose> = (0..m).map(|k| na[k * step]).collect();
    let (native_read, _) = read_level(character, &na2, &nb[..m], h);
    // Levelling: each file's poses turned about each pelvis by its own
    // ground tilt, as the kernel levels a clip (the AMC's floor slopes,
    // the conversion's does not).
    let level = |poses: &[Pose]| -> Vec<Pose> {
        let tilt = ground_tilt(poses);
        poses
            .iter()
            .map(|x| {
                let o = x[p];
                x.map(|v| o + tilt * (v - o))
            })
            .collect()
    };
    let (levelled_read, _) = read_level(character, &level(pa), &level(pb), h);
    // Shares of the frame-by-frame part: the BVH's calibrated directions
    // of one group replaced by the AMC's (a group is the bones ending at
    // its joints), the drop of the calibrated `any`.
    let bs = bones();
    let sa: Vec<Pose> = cal.a.iter().map(|d| built(character, d)).collect();
    let shares = GROUPS
        .iter()
        .map(|&(g, joints)| {
            let sb: Vec<Pose> = (0..n)
                .map(|f| {
                    let d: Vec<DVec3> = bs
                        .iter()
                        .enumerate()
                        .map(|(i, &(_, y))| match joints.contains(&y) {
                            true => cal.a[f][i],
                            false => cal.b[f][i],
                        })
                        .collect();
                    built(character, &d)
                })
                .collect();
            (g, cal.gap.any - gap(&sa, &sb, h).any)
        })
        .collect();
    Row {
        name: name.to_string(),
        read,
        yaw,
        cal,
        kernel,
        kernel_frames,
        kernel_pelvis,
        cal_placed,
        unaligned_read,
        native_read,
        levelled_read,
        shares,
    }
}

fn print(r: &Row) {
    let pc = |x: f64| format!("{:.2}", 100.0 * x);
    let j = |g: &Gap, c: C| pc(g.per_joint[c.index()]);
    eprintln!(
        "{}: kernel abs {} (any {}, rel {}, the pelvises {}; both from a frame: abs {}, any {}; \
         the data's posture on the kernel's pelvises: abs {}) | \
         files' directions read: rel {} any {} (yaw {:+.2}°; unaligned any {}, \
         native rate any {}, each levelled by its ground any {}) | calibrated: rel {} any {} \
         | split of the kernel's abs: pelvis placement {}, kernel posture {}, \
         rigs' constant offsets {}, frame-by-frame motion {}",
        r.name,
        pc(r.kernel.abs),
        pc(r.kernel.any),
        pc(r.kernel.rel),
        pc(r.kernel_pelvis),
        pc(r.kernel_frames.abs),
        pc(r.kernel_frames.any),
        pc(r.cal_placed.abs),
        pc(r.read.rel),
        pc(r.read.any),
        r.yaw,
        pc(r.unaligned_read.any),
        pc(r.native_read.any),
        pc(r.levelled_read.any),
        pc(r.cal.gap.rel),
        pc(r.cal.gap.any),
        pc(r.kernel.abs - r.kernel.any),
        pc(r.kernel.any - r.read.any),
        pc(r.read.any - r.cal.gap.any),
        pc(r.cal.gap.any),
    );
    let names: Vec<String> = bones()
        .iter()
        .zip(&r.cal.bone_deg)
        .map(|((_, b), d)| format!("{b:?} {d:.1}"))
        .collect();
    eprintln!(
        "{}: calibrated, per joint (any, %): head {} wrists {}/{} ankles {}/{} toes {}/{}; \
         kernel: head {} ankles {}/{} toes {}/{}; shares of the calibrated any: {:?}; \
         bones apart frame by frame (mean °, by child): {}",
        r.name,
        j(&r.cal.gap, C::Head),
        j(&r.cal.gap, C::LWrist),
        j(&r.cal.gap, C::RWrist),
        j(&r.cal.gap, C::LAnkle),
        j(&r.cal.gap, C::RAnkle),
        j(&r.cal.gap, C::LToe),
        j(&r.cal.gap, C::RToe),
        j(&r.kernel, C::Head),
        j(&r.kernel, C::LAnkle),
        j(&r.kernel, C::RAnkle),
        j(&r.kernel, C::LToe),
        j(&r.kernel, C::RToe),
        r.shares
            .iter()
            .map(|(g, s)| format!("{g} {:.2}", 100.0 * s))
            .collect::<Vec<_>>(),
        names.join(", "),
    );
}

/// Issue 44's 02_03 pair (and 02_01, 02_02; 01_01's AMC against the
/// cgspeed BVH of the same skeleton as the control; 02_03 mirrored and
/// turned + rescaled as variants), decomposed as the module says.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_two_files_gap_decomposed_by_source() {
    let Some(d) = common::data_dir() else { return };
    let m = d.join("mocap");
    let (character, h) = common::walk_character();
    let mut rows = Vec::new();
    let control = ("cmu-amc/01/01_01.amc", "cmu-bvh/01_01.bvh", "");
    for (a, b, variant) in std::iter::once(control).chain(CC_PAIRS) {
        let TwoFiles { amc, bvh, al, bl } = two_files(&m, a, b);
        // "turned": the BVH turned 30° about the vertical and scaled by 1.37.
        let (ca, cb, back) = varied(poses_at_30(&al), poses_at_30(&bl), variant);
        let name = format!(
            "{a} vs {b}{}",
            if variant.is_empty() {
                String::new()
            } else {
                format!(" ({variant})")
            }
        );
        let row = decompose(
            &name,
            (&character, h),
            (&amc, &bvh),
            (&al, &bl),
            &ca,
            &cb,
            back,
        );
        print(&row);
        rows.push((a, variant, row));
    }
    for (a, variant, r) in &rows {
        // The best translation never does worse than the pelvises together.
        for g in [&r.read, &r.cal.gap, &r.kernel] {
            assert!(g.any <= g.rel + 1e-6 && g.any <= g.abs + 1e-6, "{}", r.name);
        }
        if a.contains("01_01") {
            // One capture in one skeleton: the kernel retargets both alike.
            // The cgspeed BVH's clavicles and neck base sit elsewhere on
            // the chest (3° and 1° off); an offset fixed in the chest's
            // frame turns against the heading frame the calibration works
            // in, so 0.29 % is left (measured): the calibrated level is an
            // upper bound of the motion that differs.
            assert!(r.kernel.abs < 1e-3, "{}: {}", r.name, r.kernel.abs);
            assert!(r.cal.gap.any < 0.004, "{}: {}", r.name, r.cal.gap.any);
            assert!(r.cal.gap.any < 0.25 * r.read.any, "{}", r.name);
            continue;
        }
        // The decomposition as measured (session 34): the motion the two
        // files differ by frame by frame is under the 1 % of the
        // height; the rigs' constant offsets are most of the files' raw
        // gap; the kernel's posture is well above the data's floor, and
        // levelling each clip by its own ground and the conversion's
        // 1/120 s offset each widen the raw gap.
        assert!(r.cal.gap.any < 0.01, "{}: {}", r.name, r.cal.gap.any);
        assert!(r.cal.gap.any < 0.25 * r.read.any, "{}", r.name);
        assert!(r.kernel.any > r.cal.gap.any + 0.003, "{}", r.name);
        assert!(r.levelled_read.any > r.read.any, "{}", r.name);
        assert!(r.unaligned_read.any > r.read.any, "{}", r.name);
        assert!((r.native_read.any - r.read.any).abs() < 5e-4, "{}", r.name);
        // With this kernel's placement, even the data's posture stays
        // above 1 %: the pelvises' gap is what stands between.
        assert!(r.cal_placed.abs > 0.01, "{}: {}", r.name, r.cal_placed.abs);
        assert!(r.kernel_pelvis > 0.01, "{}: {}", r.name, r.kernel_pelvis);
        // The variants of 02_03 decompose as the plain pair: the files'
        // levels within 1e-4 of the height, the kernel's within 1e-3
        // (`pose::two_files`' bounds).
        if !variant.is_empty() {
            let plain = &rows.iter().find(|x| x.0 == *a && x.1.is_empty()).unwrap().2;
            for (x, y, tol) in [
                (r.read.any, plain.read.any, 1e-4),
                (r.cal.gap.any, plain.cal.gap.any, 1e-4),
                (r.kernel.abs, plain.kernel.abs, 1e-3),
                (r.kernel.any, plain.kernel.any, 1e-3),
            ] {
                assert!((x - y).abs() < tol, "{}: {x} against {y}", r.name);
            }
        }
    }
}
