//! The clips in mocap/ are what the project's own code generates.

use crate::common;

use std::path::Path;
use surfmotion::rig::{LoadOptions, load_clip};
use surfmotion::synth::{Gait, gait_clip};
use surfmotion::tools::eval::{FootOptions, clip_sliding};

#[test]
fn committed_clips_match_the_generator() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("mocap");
    for g in Gait::ALL {
        let file = load_clip(
            &dir.join(format!("{}.bvh", g.name())),
            &LoadOptions::default(),
        )
        .unwrap();
        let made = gait_clip(g, 4.0, 30.0);
        assert_eq!(file.frame_count(), made.frame_count(), "{}", g.name());
        assert!((file.fps() - 30.0).abs() < 1e-9);
        assert_eq!(
            file.units().name,
            "m",
            "{}: {}",
            g.name(),
            file.units().reason
        );
        for f in 0..made.frame_count() {
            let (a, b) = (file.world_positions(f), made.world_positions(f));
            for (p, q) in a.iter().zip(&b) {
                assert!((*p - *q).length() < 1e-9, "{} frame {f}", g.name());
            }
        }
    }
}

/// Issue 39.3: the procedural walk, run and turn skated (the foot slid
/// forward on the floor ~10 cm/frame while the knee lifted it at the wrong
/// phase). Every gait's toes and ankles hold still while on the floor.
#[test]
fn procedural_gaits_do_not_skate() {
    let opts = FootOptions::default();
    for g in Gait::ALL {
        let clip = gait_clip(g, 4.0, 30.0);
        let s = clip_sliding(&clip, &opts).unwrap();
        eprintln!("{}: {s:?}", g.name());
        assert!(s.contact_frames > 60, "{}: {s:?}", g.name());
        assert!(
            s.p95_cm_per_frame <= 1.0,
            "{}: feet slide {:.2} cm/frame (p95) on the floor",
            g.name(),
            s.p95_cm_per_frame
        );
    }
}

/// A clip whose feet glide along the floor (the old procedural walk's
/// fault, made on purpose: the whole body carried forward in a held
/// stance) is flagged at any speed.
#[test]
fn a_skating_clip_is_flagged() {
    let opts = FootOptions::default();
    let walk = gait_clip(Gait::Walk, 2.0, 30.0);
    let skate = glide(&walk, 0.02);
    let s = clip_sliding(&skate, &opts).unwrap();
    assert!(
        (s.median_cm_per_frame - 2.0).abs() < 0.1,
        "a foot carried 2 cm/frame reads {s:?}"
    );
    let fast = clip_sliding(&glide(&walk, 0.10), &opts).unwrap();
    assert!(
        (fast.median_cm_per_frame - 10.0).abs() < 0.5,
        "a foot carried 10 cm/frame reads {fast:?}"
    );
}

/// `clip`'s first frame held, its root carried `step` metres along +Z a frame.
fn glide(clip: &surfmotion::mocap::Clip, step: f64) -> surfmotion::mocap::Clip {
    let n = clip.joints().len();
    let mut c = clip.clone().into_parts();
    for f in 0..clip.frame_count() {
        for j in 0..n {
            c.rotations[f * n + j] = clip.rotations()[j];
            c.translations[f * n + j] = clip.translations()[j];
        }
        c.translations[f * n].z += step * f as f64;
    }
    surfmotion::mocap::Clip::from_parts(c).unwrap()
}

/// Real walks and a jog (CMU 02_01, 02_02, 02_03, Bandai walks) read low on the same
/// measure, so the procedural bound is what captured feet do.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn captured_walks_do_not_skate() {
    let Some(d) = common::data_dir() else {
        return;
    };
    let m = d.join("mocap");
    let opts = FootOptions::default();
    for f in [
        "cmu-amc/02/02_01.amc",
        "cmu-amc/02/02_02.amc",
        "cmu-amc/02/02_03.amc",
        "bandai-namco/dataset-1_walk_normal_001.bvh",
        "bandai-namco/dataset-2_walk_normal_001.bvh",
        "bandai-namco/dataset-1_walk_tired_001.bvh",
    ] {
        let clip = load_clip(&m.join(f), &LoadOptions::default()).unwrap();
        let s = clip_sliding(&clip, &opts).unwrap();
        eprintln!("{f}: {s:?}");
        assert!(s.contact_frames > 0, "{f}");
        assert!(s.median_cm_per_frame <= 1.0, "{f}: {s:?}");
    }
}
