//! The line the reference's torso is stood upright on (issue 44,
//! `pose::retarget::Level`): CMU 02_01, 02_02 and 02_03 as the native AMC
//! and as the CC-rig BVH conversion (`two_files::CC_PAIRS`, with 02_03's
//! pair mirrored and its BVH turned and rescaled), retargeted onto one
//! character with each levelling line and two placements (the kernel's,
//! the body's), the two results compared as `pose::anchor` does; and, per
//! aligned frame, how far apart the two files hold each line (the data's
//! share). The generated variants are `pose::level_variants`.

use crate::common;

use super::anchor::{Apart, apart};
use super::two_files::{CC_PAIRS, poses_at_30, two_files, varied};
use glam::{DQuat, DVec3};
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::{
    Anchor, ClipPoses, LEVEL_ENV, Level, PLACEMENT_ENV, Placement, Toes, TravelScale, retarget,
    retarget_levelled,
};
use surfmotion::rig::Canonical;

use Canonical as C;

pub(super) const LEVELS: [(&str, Level); 4] = [
    ("chest", Level::Chest),
    ("midpoints", Level::Midpoints),
    ("trunk", Level::Trunk),
    ("shoulders", Level::Shoulders),
];

/// The kernel's placement and the body's (the joints' mean, the travel by
/// the standing hip height).
pub(super) fn placements() -> [(&'static str, Placement); 2] {
    let body = Placement {
        anchor: Anchor::Joints,
        scale: TravelScale::Stance,
        ..Placement::default()
    };
    [("root,legs", Placement::default()), ("joints,stance", body)]
}

/// The result's joint positions of `cp` on `character`, turned by `back`
/// about the character's rest anchor of `pl` (seen from above).
pub(super) fn levelled(
    character: &Pose,
    cp: &ClipPoses,
    pl: Placement,
    l: Level,
    back: DQuat,
) -> Vec<Pose> {
    let c0 = match pl.anchor {
        Anchor::Root => character[C::Pelvis.index()],
        Anchor::Hips => 0.5 * (character[C::LHip.index()] + character[C::RHip.index()]),
        Anchor::Joints => character.iter().copied().sum::<DVec3>() / Canonical::COUNT as f64,
    } * DVec3::new(1.0, 0.0, 1.0);
    let (r, p) = (&cp.reference, &cp.poses);
    retarget_levelled(character, character, r, p, Toes::Rigid, pl, l)
        .into_iter()
        .map(|(x, _)| x.map(|v| c0 + back * (v - c0)))
        .collect()
}

/// The trunk's lines measured per frame (the kernel's and the options'
/// first): from the mean of the first joints to the mean of the second
/// (`Trunk` approximated by its lower three points → its upper three).
const LINES: [(&str, &[C], &[C]); 10] = [
    ("pelvis → chest (chest)", &[C::Pelvis], &[C::Chest]),
    (
        "hips → shoulders (midpoints)",
        &[C::LHip, C::RHip],
        &[C::LShoulder, C::RShoulder],
    ),
    (
        "pelvis, hips, spine → chest, neck, shoulders (trunk)",
        &[C::Pelvis, C::Spine],
        &[C::Chest, C::Neck],
    ),
    ("pelvis → neck", &[C::Pelvis], &[C::Neck]),
    ("hips → neck", &[C::LHip, C::RHip], &[C::Neck]),
    ("hips → chest", &[C::LHip, C::RHip], &[C::Chest]),
    ("spine → neck", &[C::Spine], &[C::Neck]),
    ("spine → chest", &[C::Spine], &[C::Chest]),
    (
        "pelvis → shoulders",
        &[C::Pelvis],
        &[C::LShoulder, C::RShoulder],
    ),
    ("chest → neck", &[C::Chest], &[C::Neck]),
];

/// The line of `p` from the mean of `lo` to the mean of `hi` (for the
/// trunk's, each side also takes its pair's midpoint: the hips' below,
/// the shoulders' above).
fn line(p: &Pose, name: &str, lo: &[C], hi: &[C]) -> DVec3 {
    let mean = |cs: &[C], extra: &[C]| {
        let mut v: Vec<DVec3> = cs.iter().map(|c| p[c.index()]).collect();
        if !extra.is_empty() {
            v.push(extra.iter().map(|c| p[c.index()]).sum::<DVec3>() / extra.len() as f64);
        }
        v.iter().copied().sum::<DVec3>() / v.len() as f64
    };
    let trunk = name.ends_with("(trunk)");
    let (a, b) = if trunk {
        (
            mean(lo, &[C::LHip, C::RHip]),
            mean(hi, &[C::LShoulder, C::RShoulder]),
        )
    } else {
        (mean(lo, &[]), mean(hi, &[]))
    };
    (b - a).normalize()
}

/// Per aligned frame, the two files' line (of [`LINES`]) apart: mean
/// signed degrees about the AMC's left-right axis and about its forward
/// axis, and the mean angle.
fn lines_apart(a: &[Pose], b: &[Pose], (name, lo, hi): (&str, &[C], &[C])) -> (f64, f64, f64) {
    let n = a.len().min(b.len());
    let (mut pitch, mut roll, mut all) = (0.0, 0.0, 0.0);
    for (pa, pb) in a[..n].iter().zip(&b[..n]) {
        let v = (pa[C::LHip.index()] - pa[C::RHip.index()])
            + (pa[C::LShoulder.index()] - pa[C::RShoulder.index()]);
        let left = DVec3::new(v.x, 0.0, v.z).normalize();
        let fwd = left.cross(DVec3::Y);
        let (la, lb) = (line(pa, name, lo, hi), line(pb, name, lo, hi));
        let axis = la.cross(lb);
        pitch += axis.dot(left).asin().to_degrees();
        roll += axis.dot(fwd).asin().to_degrees();
        all += la.angle_between(lb).to_degrees();
    }
    let k = n as f64;
    (pitch / k, roll / k, all / k)
}

/// The mean distance per joint between two results (% of `h`).
fn per_joint(a: &[Pose], b: &[Pose], h: f64) -> String {
    let n = a.len().min(b.len());
    let cols: Vec<String> = Canonical::ALL
        .iter()
        .map(|c| {
            let j = c.index();
            let d: f64 = (0..n).map(|f| a[f][j].distance(b[f][j])).sum::<f64>();
            format!("{c:?} {:.2}", 100.0 * d / n as f64 / h)
        })
        .collect();
    cols.join(", ")
}

/// 02_01, 02_02, 02_03 (and 02_03's variants) with every levelling line
/// and both placements.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_two_files_levelled_on_each_line() {
    let Some(d) = common::data_dir() else { return };
    let m = d.join("mocap");
    let (character, h) = common::walk_character();
    let env_free =
        std::env::var_os(LEVEL_ENV).is_none() && std::env::var_os(PLACEMENT_ENV).is_none();
    let mut rows: Vec<(String, &str, &str, Apart)> = Vec::new();
    // Per plain pair, the pelvis → chest and the midpoints lines apart
    // per frame (mean degrees).
    let mut line_gaps: Vec<(f64, f64)> = Vec::new();
    for (a, b, variant) in CC_PAIRS {
        let f = two_files(&m, a, b);
        let (ca, cb, back) = varied(poses_at_30(&f.al), poses_at_30(&f.bl), variant);
        let name = format!("{a} vs {b} {variant}");
        if variant.is_empty() {
            let all_of = |i: usize| lines_apart(&ca.poses, &cb.poses, LINES[i]).2;
            line_gaps.push((all_of(0), all_of(1)));
            for l in LINES {
                let (p, r, all) = lines_apart(&ca.poses, &cb.poses, l);
                eprintln!(
                    "{name}: the line {} apart per frame {all:.2}° (about left-right {p:+.2}°, \
                     about forward {r:+.2}°)",
                    l.0
                );
            }
        }
        for (pn, pl) in placements() {
            for (ln, l) in LEVELS {
                let ra = levelled(&character, &ca, pl, l, DQuat::IDENTITY);
                let rb = levelled(&character, &cb, pl, l, back);
                if env_free && l == Level::Chest && pl == Placement::default() {
                    let main: Vec<Pose> = retarget(&character, &ca.reference, &ca.poses)
                        .into_iter()
                        .map(|x| x.0)
                        .collect();
                    assert_eq!(main, ra, "{name}: the default line is the kernel's");
                }
                let g = apart(&ra, &rb, h);
                eprintln!(
                    "{name} {pn} {ln}: mean {:.2} p95 {:.2} the pelvises {:.2} best translation \
                     {:.2} (% of the height)",
                    100.0 * g.mean,
                    100.0 * g.p95,
                    100.0 * g.pelvis,
                    100.0 * g.any
                );
                if variant.is_empty() && pn == "root,legs" {
                    eprintln!("{name} {ln} per joint: {}", per_joint(&ra, &rb, h));
                }
                rows.push((name.clone(), pn, ln, g));
            }
        }
    }
    // CMU 01_01 as the AMC and as the cgspeed BVH (one skeleton; the
    // conversion drops the thorax's length, so its neck and shoulders
    // hang lower on the same rotations): the kernel's line gives the
    // same result, the midpoints line does not (0.79 % apart, measured).
    let f = two_files(&m, "cmu-amc/01/01_01.amc", "cmu-bvh/01_01.bvh");
    let (ca, cb) = (poses_at_30(&f.al), poses_at_30(&f.bl));
    for (ln, l) in LEVELS {
        let pl = Placement::default();
        let ra = levelled(&character, &ca, pl, l, DQuat::IDENTITY);
        let rb = levelled(&character, &cb, pl, l, DQuat::IDENTITY);
        let g = apart(&ra, &rb, h);
        eprintln!(
            "01_01 AMC vs cgspeed BVH, root,legs {ln}: mean {:.2} p95 {:.2} best translation \
             {:.2} (% of the height)",
            100.0 * g.mean,
            100.0 * g.p95,
            100.0 * g.any
        );
        if l == Level::Chest {
            assert!(g.mean < 1e-3, "{ln}: {g:?}");
        } else if l == Level::Midpoints {
            assert!(g.mean > 3e-3, "{ln}: {g:?}");
        }
    }
    let of = |end: &str, pn: &str, ln: &str| {
        rows.iter()
            .find(|r| r.0.ends_with(end) && r.1 == pn && r.2 == ln)
            .map(|r| r.3)
            .unwrap()
    };
    // As measured (session 36): the midpoints line is placed alike by the
    // two rigs better than the pelvis → chest line and takes the posture
    // (each frame's best translation) closer on 02_01 and 02_02 (0.74 →
    // 0.65, 0.86 → 0.72; 02_03 0.96 → 1.00), but with the kernel's
    // placement the results as placed move apart on every pair; the
    // trunk's line leaves more posture than the kernel's everywhere.
    for (pair, (d_chest, d_mid)) in ["002_01.bvh ", "002_02.bvh ", "002_03.bvh "]
        .iter()
        .zip(&line_gaps)
    {
        assert!(d_mid < d_chest, "{pair}: {d_mid} against {d_chest}");
        let (c, m, t) = (
            of(pair, "root,legs", "chest"),
            of(pair, "root,legs", "midpoints"),
            of(pair, "root,legs", "trunk"),
        );
        assert!(
            m.mean > c.mean && t.any > c.any,
            "{pair}: {c:?} {m:?} {t:?}"
        );
        if !pair.starts_with("002_03") {
            assert!(m.any < c.any - 0.0005, "{pair}: {c:?} {m:?}");
        }
    }
    for (pn, _) in placements() {
        for (ln, _) in LEVELS {
            let plain = of("002_03.bvh ", pn, ln);
            // Mirrored: within 0.1 % of the height; turned and rescaled:
            // within 1e-4 (`pose::two_files`' bounds).
            for (v, tol) in [("mirrored", 1e-3), ("turned", 1e-4)] {
                let g = of(v, pn, ln);
                for (x, y) in [(g.mean, plain.mean), (g.p95, plain.p95)] {
                    assert!((x - y).abs() < tol, "{pn} {ln} {v}: {x} against {y}");
                }
            }
        }
    }
}
