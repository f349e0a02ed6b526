//! Fuzz target: a `play` control script must never panic; every value it
//! accepts is finite and within the script's bounds.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::Path;
use surfmotion::parametric::Parameter;
use surfmotion::parametric::script::{MAX_SECONDS, MAX_SPEED, MAX_TURN, parse_script_for};

fuzz_target!(|data: &[u8]| {
    let t = String::from_utf8_lossy(data);
    let spaces: [(&str, &[Parameter]); 2] = [
        ("locomotion", &[Parameter::Speed, Parameter::Turn]),
        ("turning", &[Parameter::Turn]),
    ];
    if let Ok(script) = parse_script_for(&t, Path::new("s.json"), &spaces) {
        for r in &script {
            assert!((0.0..=MAX_SECONDS).contains(&r.t));
            assert!(r.speed.is_none_or(|v| v.abs() <= MAX_SPEED));
            assert!(r.turn.is_none_or(|v| v.abs() <= MAX_TURN));
        }
    }
});
