//! The travel scaled by the stride and the torso levelled on the
//! shoulders' line (issue 44, `TravelScale::Stride`, `Level::Shoulders`):
//! CMU 02_01, 02_02 and 02_03 as the native AMC and as the CC-rig BVH
//! conversion (`two_files::CC_PAIRS`, 02_03's pair also mirrored and its
//! BVH turned and rescaled) and CMU 01_01 as the AMC and the cgspeed BVH,
//! retargeted onto one character with each line and placement, the two
//! results compared as `pose::anchor` does. Printed per pair: what the
//! placement reads (each result's travel over its clip's, the pelvises'
//! and the bodies' offsets along the walk) and how far the character's
//! feet slide while the clip's are planted.

use crate::common;

use super::anchor::{Apart, apart};
use super::level::levelled;
use super::level_variants::{mirrored_back, walk_variants};
use super::two_files::{CC_PAIRS, poses_at_30, two_files, varied};
use glam::{DQuat, DVec3};
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::{
    Anchor, ClipPoses, Footfalls, Level, Placement, TravelScale, leg_length,
};
use surfmotion::rig::Canonical;

use Canonical as C;

/// The lines measured.
pub(super) const LINES: [(&str, Level); 3] = [
    ("chest", Level::Chest),
    ("midpoints", Level::Midpoints),
    ("shoulders", Level::Shoulders),
];

/// The placements measured: the kernel's first; the last two with the
/// feet on the clip's footfalls.
pub(super) fn placements() -> [(&'static str, Placement); 6] {
    let p = |anchor, scale| Placement {
        anchor,
        scale,
        ..Placement::default()
    };
    let feet = |scale| Placement {
        anchor: Anchor::Root,
        scale,
        footfalls: Footfalls::Targets,
    };
    [
        ("root,legs", Placement::default()),
        ("root,stance", p(Anchor::Root, TravelScale::Stance)),
        ("root,stride", p(Anchor::Root, TravelScale::Stride)),
        ("joints,stride", p(Anchor::Joints, TravelScale::Stride)),
        ("root,legs,feet", feet(TravelScale::Legs)),
        ("root,stance,feet", feet(TravelScale::Stance)),
    ]
}

fn flat(v: DVec3) -> DVec3 {
    DVec3::new(v.x, 0.0, v.z)
}

/// The result's travel (its pelvis's horizontal path) over the clip's
/// root's.
pub(super) fn travel_ratio(result: &[Pose], clip: &[Pose]) -> f64 {
    let path = |p: &[Pose]| {
        p.windows(2)
            .map(|w| flat(w[1][C::Pelvis.index()] - w[0][C::Pelvis.index()]).length())
            .sum::<f64>()
    };
    path(result) / path(clip)
}

/// The character's feet's horizontal motion (metres per frame, mean over
/// the foot joints of both feet) in the frames where the clip's same foot
/// joint moves less than 1 % of its leg from the frame before.
pub(super) fn slide(result: &[Pose], clip: &[Pose]) -> f64 {
    let leg = leg_length(&clip[clip.len() / 2]);
    let (mut sum, mut n) = (0.0, 0usize);
    for i in 1..result.len().min(clip.len()) {
        for c in [C::LAnkle, C::LToe, C::RAnkle, C::RToe] {
            let j = c.index();
            if flat(clip[i][j] - clip[i - 1][j]).length() < 0.01 * leg {
                sum += flat(result[i][j] - result[i - 1][j]).length();
                n += 1;
            }
        }
    }
    sum / n.max(1) as f64
}

/// Mean signed offsets (fractions of `h`) of `b` against `a` along `a`'s
/// walk (forward from its hips and shoulders): the pelvises', the joints'
/// means', and the vertical of the joints' means.
fn offsets(a: &[Pose], b: &[Pose], h: f64) -> (f64, f64, f64) {
    let n = a.len().min(b.len());
    let (mut pelvis, mut body, mut up) = (0.0, 0.0, 0.0);
    for (pa, pb) in a[..n].iter().zip(&b[..n]) {
        let v = (pa[C::LHip.index()] - pa[C::RHip.index()])
            + (pa[C::LShoulder.index()] - pa[C::RShoulder.index()]);
        let fwd = flat(v).normalize().cross(DVec3::Y);
        let mean = |p: &Pose| p.iter().copied().sum::<DVec3>() / Canonical::COUNT as f64;
        pelvis += (pb[C::Pelvis.index()] - pa[C::Pelvis.index()]).dot(fwd);
        body += (mean(pb) - mean(pa)).dot(fwd);
        up += mean(pb).y - mean(pa).y;
    }
    let k = n as f64 * h;
    (pelvis / k, body / k, up / k)
}

/// One pair's two results with one line and placement.
#[derive(Debug, Clone, Copy)]
struct Row {
    apart: Apart,
    /// Along the first result's walk, the second's pelvis and the mean
    /// of its joints ahead (fractions of the height).
    pelvis_ahead: f64,
    body_ahead: f64,
    /// Each result's feet's slide (metres per frame).
    slides: (f64, f64),
}

/// One pair with every line and placement: the rows (pair, line,
/// placement, row) and, printed, what each placement reads.
fn measure(
    name: &str,
    (character, h): (&Pose, f64),
    (ca, cb, back): (&ClipPoses, &ClipPoses, DQuat),
) -> Vec<(String, &'static str, &'static str, Row)> {
    let mut rows = Vec::new();
    for (ln, l) in LINES {
        for (pn, pl) in placements() {
            let ra = levelled(character, ca, pl, l, DQuat::IDENTITY);
            let rb = levelled(character, cb, pl, l, back);
            let g = apart(&ra, &rb, h);
            let (dp, db, du) = offsets(&ra, &rb, h);
            let (ta, tb) = (travel_ratio(&ra, &ca.poses), travel_ratio(&rb, &cb.poses));
            let (sa, sb) = (slide(&ra, &ca.poses), slide(&rb, &cb.poses));
            eprintln!(
                "{name} {ln} {pn}: mean {:.2} p95 {:.2} the pelvises {:.2} best translation {:.2} \
                 (% of the height); travel over the clip's {ta:.4} / {tb:.4} (their ratio \
                 {:.4}); along the walk the pelvis {:+.2}, the body {:+.2}, up {:+.2} %; feet \
                 slide {:.3} / {:.3} cm/frame",
                100.0 * g.mean,
                100.0 * g.p95,
                100.0 * g.pelvis,
                100.0 * g.any,
                tb * path_of(&cb.poses) / (ta * path_of(&ca.poses)),
                100.0 * dp,
                100.0 * db,
                100.0 * du,
                100.0 * sa,
                100.0 * sb
            );
            let row = Row {
                apart: g,
                pelvis_ahead: dp,
                body_ahead: db,
                slides: (sa, sb),
            };
            rows.push((name.to_string(), ln, pn, row));
        }
    }
    rows
}

/// The clip's root's horizontal path.
pub(super) fn path_of(p: &[Pose]) -> f64 {
    p.windows(2)
        .map(|w| flat(w[1][C::Pelvis.index()] - w[0][C::Pelvis.index()]).length())
        .sum()
}

/// The three CC pairs (and 02_03's variants) and 01_01 with every line
/// and placement.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_two_files_placed_by_the_stride_and_levelled_on_the_shoulders() {
    let Some(d) = common::data_dir() else { return };
    let m = d.join("mocap");
    let (character, h) = common::walk_character();
    let mut rows = Vec::new();
    for (a, b, variant) in CC_PAIRS {
        let f = two_files(&m, a, b);
        let (ca, cb, back) = varied(poses_at_30(&f.al), poses_at_30(&f.bl), variant);
        let name = format!("{a} vs {b} {variant}");
        rows.extend(measure(&name, (&character, h), (&ca, &cb, back)));
    }
    let f = two_files(&m, "cmu-amc/01/01_01.amc", "cmu-bvh/01_01.bvh");
    let (ca, cb) = (poses_at_30(&f.al), poses_at_30(&f.bl));
    let name = "01_01 AMC vs cgspeed BVH";
    rows.extend(measure(name, (&character, h), (&ca, &cb, DQuat::IDENTITY)));
    let of = |end: &str, ln: &str, pn: &str| {
        rows.iter()
            .find(|r| r.0.ends_with(end) && r.1 == ln && r.2 == pn)
            .map(|r| r.3)
            .unwrap()
    };
    // Why the placed pairs move apart as the posture comes closer
    // (measured, session 37): with the kernel's placement the BVH's
    // result trails the AMC's along the walk (its pelvis 1.38-1.92 % of
    // the height behind: the conversion's legs are 1.164 times the
    // AMC's and it travels 1.146 times as far, so its strides on the
    // character are 1.3-3.0 % shorter), whichever the line; the pelvis →
    // chest line leans the BVH's body ahead of its pelvis and hides
    // 1.1-1.4 of it, the midpoints line 0.2-0.4. The standing hip
    // height's scale puts the pelvises together along the walk (within
    // 0.05 %) and slides both results' feet more.
    for pair in ["002_01.bvh ", "002_02.bvh ", "002_03.bvh "] {
        let (c, mid) = (
            of(pair, "chest", "root,legs"),
            of(pair, "midpoints", "root,legs"),
        );
        for r in [c, mid] {
            assert!(r.pelvis_ahead < -0.01, "{pair}: {r:?}");
        }
        let hidden = |r: Row| r.body_ahead - r.pelvis_ahead;
        assert!(hidden(c) > hidden(mid) + 0.005, "{pair}: {c:?} {mid:?}");
        let st = of(pair, "midpoints", "root,stance");
        assert!(st.pelvis_ahead.abs() < 0.002, "{pair}: {st:?}");
        assert!(
            st.slides.0 > mid.slides.0 && st.slides.1 > mid.slides.1,
            "{pair}: {st:?}"
        );
    }
    // 01_01 (one skeleton, the thorax's length dropped): the kernel's
    // line gives the AMC's result, the shoulders' line a quarter of the
    // midpoints line's gap (0.19 against 0.79 %, measured).
    let (c, mid, sh) = (
        of("cgspeed BVH", "chest", "root,legs"),
        of("cgspeed BVH", "midpoints", "root,legs"),
        of("cgspeed BVH", "shoulders", "root,legs"),
    );
    assert!(c.apart.mean < 1e-3, "{c:?}");
    assert!(sh.apart.mean < 0.5 * mid.apart.mean, "{sh:?} {mid:?}");
    // 02_03's variants: the plain pair's figures (`pose::two_files`'
    // bounds: mirrored 1e-3 of the height, turned and rescaled 1e-4).
    for (ln, _) in LINES {
        for (pn, _) in placements() {
            let plain = of("002_03.bvh ", ln, pn).apart;
            for (v, tol) in [("mirrored", 1e-3), ("turned", 1e-4)] {
                let g = of(v, ln, pn).apart;
                for (x, y) in [(g.mean, plain.mean), (g.p95, plain.p95)] {
                    assert!((x - y).abs() < tol, "{ln} {pn} {v}: {x} against {y}");
                }
            }
        }
    }
}

/// A generated walk along a circle and its variants (root moved inside
/// the body, mirrored, turned 30° and rescaled to centimetres), levelled
/// on the shoulders' line and placed with each placement, compared with
/// the plain clip's result (no data needed).
#[test]
fn variants_of_one_motion_placed_by_the_stride() {
    let (character, h) = common::walk_character();
    let walk = surfmotion::synth::gait_clip(surfmotion::synth::Gait::Turn, 4.0, 30.0);
    let map = surfmotion::rig::detect_clip(&walk).unwrap().map;
    let plain = surfmotion::pose::retarget::clip_poses(&walk, &map).unwrap();
    let variants = walk_variants(&plain);
    let flip = mirrored_back(&character);
    let l = Level::Shoulders;
    for (pn, pl) in placements() {
        let base = levelled(&character, &plain, pl, l, DQuat::IDENTITY);
        eprintln!(
            "generated turn, shoulders {pn}: travel over the clip's {:.4}, feet slide {:.3} \
             cm/frame",
            travel_ratio(&base, &plain.poses),
            100.0 * slide(&base, &plain.poses)
        );
        for (name, cp, back) in &variants {
            let mut r = levelled(&character, cp, pl, l, *back);
            if *name == "mirrored" {
                r = r.into_iter().map(&flip).collect();
            }
            let g = apart(&base, &r, h);
            eprintln!(
                "generated turn, {name}, shoulders {pn}: mean {:.3} p95 {:.3} the pelvises \
                 {:.3} best translation {:.3} (% of the height)",
                100.0 * g.mean,
                100.0 * g.p95,
                100.0 * g.pelvis,
                100.0 * g.any
            );
            if !name.starts_with("root moved") {
                // The kernel has no side, heading or unit of its own.
                assert!(g.mean < 1e-3, "{name}, {pn}: {g:?}");
            } else {
                // The shoulders' line does not read the root: no posture.
                assert!(g.any < 1e-4, "{name}, {pn}: {g:?}");
            }
        }
    }
}
