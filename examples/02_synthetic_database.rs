//! Tutorial 2: a synthetic 4D database, no files needed: the procedural
//! humanoid, its rig embedded from its landmarks, walking and running
//! (skinning plus soft-tissue lag), written as a new database folder.
//!
//! cargo run --release --example 02_synthetic_database -- synth_db

use surfmotion::jobs::{SynthCharacter, SynthClip, SynthOptions, write_synthetic_database};
use surfmotion::synth::{Gait, gait_clip};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).unwrap_or_else(|| "synth_db".into());
    let walk = SynthClip::from_clip("walk", &gait_clip(Gait::Walk, 4.0, 30.0))?;
    let run = SynthClip::from_clip("run", &gait_clip(Gait::Run, 3.0, 30.0))?;
    let opts = SynthOptions::default(); // an existing database in `out` is refused
    let ch = SynthCharacter::humanoid()?;
    let r = write_synthetic_database(out.as_ref(), &ch, &[walk, run], &opts, &mut |_, _| {})?;
    println!("{out}: {} frames", r.frames);
    Ok(())
}
