//! Tutorial 3: build a database's Surface Motion Graph (all-frames
//! similarity and transitions, cached in DIR/cache) and export the
//! skeleton of every frame (JSON and BVH in DIR/skeletons).
//!
//! cargo run --release --example 03_build_database -- synth_db

use surfmotion::db::Quiet;
use surfmotion::jobs::{build_database, export_skeletons};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args().nth(1).ok_or("usage: DB_DIR")?;
    let (_, r) = build_database(dir.as_ref(), &Default::default(), &Quiet)?;
    println!("{} frames, {} transitions", r.frames, r.transitions);
    let sk = export_skeletons(dir.as_ref(), &Default::default())?;
    println!("skeletons in {}", sk.output.display());
    Ok(())
}
