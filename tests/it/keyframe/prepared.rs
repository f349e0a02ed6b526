//! Key-frame synthesis on the character's prepared blender (issue 40):
//! one preparation (`keyframe::prepare`, a `drive::Prepared`) serves every
//! query of a job, bit for bit the one-off `keyframe::synthesise`, and a
//! preparation of another character is refused with a typed error.

use crate::common;
use surfmotion::db::{Character, Quiet};
use surfmotion::keyframe::{
    KeyframeError, KeyframeOptions, Targets, parse_key, plan_path, prepare, synthesise,
};

const FPS: f64 = 30.0;

#[test]
fn one_preparation_serves_every_query_and_another_characters_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    common::procedural_walk_run_database(&a, "a", 0.035, FPS);
    common::procedural_walk_run_database(&b, "b", 0.05, FPS);
    let ca = Character::load(&a, &Quiet).unwrap();
    let cb = Character::load(&b, &Quiet).unwrap();
    assert_ne!(ca.n(), cb.n(), "two characters of different vertex counts");
    let opts = KeyframeOptions::default();
    let keys = [
        parse_key(&ca, "walk:0").unwrap(),
        parse_key(&ca, "run:20").unwrap(),
    ];
    let prepared = prepare(&ca).unwrap();
    for (distance, time) in [(3.0, 2.5), (5.0, 4.0)] {
        let targets = Targets::Global { distance, time };
        let held = synthesise(&ca, &keys, &targets, &opts).unwrap();
        let planned = plan_path(&ca, &keys, &targets, &opts, &mut |_| {}).unwrap();
        let mut positions: Vec<[f64; 3]> = Vec::new();
        let s = planned
            .synthesise_into::<_, KeyframeError>(&ca, &prepared, &targets, &opts, &mut positions)
            .unwrap();
        assert_eq!(s.plan.path, held.plan.path, "{distance} m in {time} s");
        assert!(!positions.is_empty());
        assert!(
            positions == held.positions,
            "{distance} m in {time} s: frames differ from the one-off synthesis"
        );
    }
    let other = prepare(&cb).unwrap();
    let targets = Targets::Global {
        distance: 3.0,
        time: 2.5,
    };
    let planned = plan_path(&ca, &keys, &targets, &opts, &mut |_| {}).unwrap();
    let mut positions: Vec<[f64; 3]> = Vec::new();
    let r =
        planned.synthesise_into::<_, KeyframeError>(&ca, &other, &targets, &opts, &mut positions);
    match r {
        Err(KeyframeError::Unprepared(m)) => assert!(m.contains("vertices"), "{m}"),
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a preparation of another character was accepted"),
    }
    assert!(positions.is_empty(), "no frame made with the wrong blender");
}
