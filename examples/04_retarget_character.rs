//! Tutorial 4: drive a 4D character database from a mocap clip (Huang et
//! al. 2015): the Surface Motion Graph is built (or read from the cache),
//! the clip's skeleton is matched through it, and the retrieved surfaces
//! are blended and deformed to follow the clip.
//!
//! cargo run --release --example 04_retarget_character -- DB_DIR CLIP OUT.glb
//! (a database: tutorial 2, `surfmotion synth ...` or `surfmotion db init ...`)

use surfmotion::db::Quiet;
use surfmotion::jobs::RetargetJob;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let [db, clip, out] = &a[..] else {
        return Err("usage: 04_retarget_character DB_DIR CLIP OUT.glb".into());
    };
    let job = RetargetJob::load(db.as_ref(), Default::default(), &Quiet)?;
    let run = job.run(clip.as_ref())?;
    let e = run.velocity_error(&job.character).mean_cm;
    println!("joint-velocity error {e:.2} cm/frame");
    job.write(run.output.positions, out.as_ref())?;
    Ok(())
}
