//! The clips in mocap/ are what the project's own code generates.

use std::path::Path;
use surfmotion::rig::{LoadOptions, load_clip};
use surfmotion::synth::{Gait, gait_clip};

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
        assert_eq!(file.units.name, "m", "{}: {}", g.name(), file.units.reason);
        for f in 0..made.frame_count() {
            let (a, b) = (file.world_positions(f), made.world_positions(f));
            for (p, q) in a.iter().zip(&b) {
                assert!((*p - *q).length() < 1e-9, "{} frame {f}", g.name());
            }
        }
    }
}
