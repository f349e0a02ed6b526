//! CMU 05_06 as re-saved by a third-party writer (`cmu-bvh-altered`, its
//! End Sites zero, its offsets another subject's): the retarget of its
//! frame 38 (30 fps; file frame 152 at 120 fps) is head-down, a
//! cartwheel-like pose, and this checks that it is the capture's motion,
//! not a misreading of the file (issue 44, session 23).
//!
//! What was measured (2026-11-30, session 23): the file's channels are
//! `Zrotation Yrotation Xrotation` on every joint. Read as declared, the
//! right ankle stays on the floor (0.06-0.09 m) through file frames 96-240
//! while the hands come down to 0.10 and 0.31 m, the head to 0.63 m and
//! the left foot up to 1.82 m (frame 168): a standing foot and two hands
//! on the floor, the other leg over the body. Read in any of the five
//! other rotation orders, the standing ankle rises 0.3-1.9 m off the
//! floor in the same frames (an independent Python FK of the file; the
//! reader agrees with it at frame 152 to 1e-15 m, and with bvhio at the
//! frames of `mocap::reference`). The positions move smoothly (no Euler
//! wrap). The original CMU 05_06 is not in `../shared/data`; CMU lists
//! subject 5's dances with a "cartwheel-like start". So: a real motion.
//! The live page's drawn skeleton standing upright while the mesh is
//! head-down is the page showing the newest incoming frame beside an
//! older mesh (issue 45's lag and skipped frames), not this reader.

use crate::common;

use surfmotion::rig::load_clip;

/// Per file frame in `frames`, (right ankle height, head height, lowest
/// hand height, highest foot height), metres above the clip's lowest
/// ankle over those frames.
fn heights(path: &std::path::Path, frames: std::ops::Range<usize>) -> Vec<[f64; 4]> {
    // As the verbs read it (units and up axis judged from the body).
    let mut clip = load_clip(path, &Default::default()).unwrap();
    clip.to_metres_y_up();
    let names = clip.point_names();
    let at = |n: &str| names.iter().position(|x| x == n).unwrap();
    let (ra, la, hd) = (at("RightFoot"), at("LeftFoot"), at("Head"));
    let (lh, rh) = (at("LeftHand"), at("RightHand"));
    let rows: Vec<[f64; 4]> = frames
        .map(|f| {
            let p = clip.points_at(f);
            [p[ra].y, p[hd].y, p[lh].y.min(p[rh].y), p[la].y.max(p[ra].y)]
        })
        .collect();
    let floor = rows.iter().map(|r| r[0]).fold(f64::INFINITY, f64::min);
    rows.into_iter().map(|r| r.map(|y| y - floor)).collect()
}

/// Whether the rows show a body standing on its right foot with its head
/// down, its hands near the floor and a foot over it: the standing ankle
/// within 5 cm of its lowest, the head below 0.7 m, the lowest hand
/// within 0.35 m of the floor and a foot above 1.5 m, somewhere.
fn standing_cartwheel(rows: &[[f64; 4]]) -> (bool, f64) {
    let rise = rows.iter().map(|r| r[0]).fold(0.0, f64::max);
    let head_down = rows.iter().any(|r| r[1] < 0.7 && r[2] < 0.35 && r[3] > 1.5);
    (rise < 0.05 && head_down, rise)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_altered_05_06_cartwheel_is_the_capture_not_a_misreading() {
    let Some(d) = common::data_dir() else { return };
    let src = d.join("mocap/cmu-bvh-altered/05_06.bvh");
    let span = 96..240;
    let as_read = heights(&src, span.clone());
    let (ok, rise) = standing_cartwheel(&as_read);
    assert!(
        ok,
        "05_06 as read: the standing ankle rises {rise:.3} m, or no head-down frame"
    );
    let dir = common::fixture_dir("cartwheel");
    // The same rotations written with every joint's channels in X Y Z
    // order: the reader follows the declared order, so the same heights.
    let xyz = dir.join("05_06_xyz.bvh");
    common::bvh::in_xyz_order(&src, &xyz);
    assert!(
        std::fs::read_to_string(&xyz)
            .unwrap()
            .contains("Xrotation Yrotation Zrotation")
    );
    let rewritten = heights(&xyz, span.clone());
    for (f, (a, b)) in as_read.iter().zip(&rewritten).enumerate() {
        for k in 0..4 {
            assert!(
                (a[k] - b[k]).abs() < 1e-6,
                "frame {}: {a:?} vs {b:?}",
                span.start + f
            );
        }
    }
    // A misreading: the rotation channels relabelled X Y Z, their values
    // left in the file's Z Y X order. The standing foot leaves the floor,
    // so the check above would catch a reader that misorders them.
    let text = std::fs::read_to_string(&src).unwrap();
    let (head, motion) = text.split_at(text.find("MOTION").unwrap());
    let misread = dir.join("05_06_misread.bvh");
    std::fs::write(
        &misread,
        head.replace(
            "Zrotation Yrotation Xrotation",
            "Xrotation Yrotation Zrotation",
        ) + motion,
    )
    .unwrap();
    let (ok, rise) = standing_cartwheel(&heights(&misread, span));
    assert!(
        !ok && rise > 0.2,
        "misread: standing ankle rises {rise:.3} m"
    );
}
