//! The gaits database shared by tests/parametric.rs, tests/web.rs and
//! benches/parametric.rs (which includes this file by path): the project's
//! procedural clips (Gait: walk, run, circle walk; 3 s at 30 fps) on a
//! character, written as `synth` writes a database, with parametric spaces
//! (Casas et al. 2013, Sec. 3) added to its manifest.
#![allow(dead_code)]

use std::path::Path;
use surfmotion::db::{Manifest, SpaceEntry};
use surfmotion::jobs::{SynthCharacter, SynthClip, SynthOptions, write_synthetic_database};
use surfmotion::synth::{Gait, gait_clip};

/// A parametric space: name, sequences (gait names) and parameters.
pub type Space<'a> = (&'a str, &'a [&'a str], &'a [&'a str]);

/// Writes the database of `character` performing `gaits` into `db`
/// (replacing one there), named `name`, with `spaces`; returns its manifest.
pub fn gaits_database(
    db: &Path,
    character: &SynthCharacter,
    gaits: &[Gait],
    name: &str,
    spaces: &[Space],
) -> Manifest {
    std::fs::create_dir_all(db).unwrap();
    let timed: Vec<(Gait, f64)> = gaits.iter().map(|&g| (g, 3.0)).collect();
    write_gaits(db, character, &timed, name, 30.0);
    let mut m = Manifest::load(db).unwrap();
    m.spaces = spaces
        .iter()
        .map(|(name, seqs, params)| SpaceEntry {
            name: name.to_string(),
            sequences: seqs.iter().map(|s| s.to_string()).collect(),
            parameters: params.iter().map(|s| s.to_string()).collect(),
            epsilon_mm: None,
        })
        .collect();
    m.save(db).unwrap();
    m
}

/// Writes the database of `character` performing each `(gait, seconds)`
/// at `fps` into `db` as `synth` writes one (replacing one there; no truth
/// skeletons, no plausibility), named `name`.
pub fn write_gaits(
    db: &Path,
    character: &SynthCharacter,
    gaits: &[(Gait, f64)],
    name: &str,
    fps: f64,
) {
    let clips: Vec<SynthClip> = gaits
        .iter()
        .map(|&(g, seconds)| SynthClip::from_clip(g.name(), &gait_clip(g, seconds, fps)).unwrap())
        .collect();
    let opts = SynthOptions {
        fps,
        name: Some(name.into()),
        truth: false,
        plausibility: false,
        force: true,
        ..Default::default()
    };
    write_synthetic_database(db, character, &clips, &opts, &mut |_, _| {}).unwrap();
}
