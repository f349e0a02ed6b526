//! The rest frame rule by pose `PoseRule::Held` (issue 41, an option of
//! `db init`: `SURFMOTION_AUTORIG=rest=held`): the pose the capture holds
//! longest, of its more standing half. Session 26's rule
//! (`PoseRule::Standing`, the most standing) chose a step of crane's walk
//! (frame 86, a knee bent); this one must choose each capture's still
//! start, whatever the order of the frames.

use crate::common;

use surfmotion::embed::rest::{PoseRule, RestOptions, choose_rest_frame};

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_held_pose_is_the_still_start_in_any_order() {
    let Some(d) = common::data_dir() else { return };
    let held = RestOptions {
        pose_rule: PoseRule::Held,
        ..RestOptions::automatic()
    };
    // Each capture's still start (looked at: samba's arms hanging, crane's
    // A-pose), as frames of the capture.
    for (name, still) in [("samba", 0..12), ("crane", 0..14)] {
        let c = super::auto::capture(&d, name);
        let n = c.frames.len();
        let reversed: Vec<usize> = (0..n).rev().collect();
        let from_middle: Vec<usize> = (0..n).map(|k| (k + n / 2) % n).collect();
        for order in [(0..n).collect::<Vec<_>>(), reversed, from_middle] {
            let mut all: Vec<&[[f64; 3]]> = vec![c.frames[order[0]].as_slice()];
            all.extend(order.iter().map(|&k| c.frames[k].as_slice()));
            let topo = c.mesh.with_positions(all[0]).unwrap();
            let choice = choose_rest_frame(&topo, &all, &held).unwrap();
            let frame = order[choice.frame.saturating_sub(1)];
            assert!(
                still.contains(&frame),
                "{name}, frames from {}: rest frame {frame} (of the capture), not of its still start {still:?}: {}",
                order[0],
                choice.why
            );
        }
    }
}
