//! Tutorial 3: drive a 4D character database from a mocap clip (Huang et
//! al. 2015): the Surface Motion Graph is built (or read from the cache),
//! the clip's skeleton is matched through it, and the retrieved surfaces
//! are blended and deformed to follow the clip.
//!
//! cargo run --release --example 03_retarget_character -- DB_DIR CLIP OUT.glb
//! (a database: `surfmotion synth ...` or `surfmotion db init ...`)

use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::save_sequence;
use surfmotion::retarget::character::Character;
use surfmotion::retarget::query::load_mocap;
use surfmotion::retarget::{RetargetOptions, synthesise};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let [db, clip, out] = a.as_slice() else {
        eprintln!("usage: 03_retarget_character DB_DIR CLIP OUT.glb");
        return Ok(());
    };
    let ch = Character::load(db.as_ref(), &surfmotion::db::Quiet)?;
    let fps = ch.manifest.fps;
    let clip = load_mocap(clip.as_ref(), &Default::default(), fps)?;
    let r = synthesise(
        &ch,
        &clip.poses,
        &clip.reference,
        fps,
        &RetargetOptions::default(),
    )?;
    println!(
        "{} frames, {} transitions",
        r.report.frames,
        r.report.jumps.iter().filter(|j| j.transition).count()
    );
    let seq = MeshSequence::new(ch.topology_metres(), r.positions, Some(fps))?;
    save_sequence(&seq, out.as_ref(), Some(fps))?;
    Ok(())
}
