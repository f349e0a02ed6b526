//! Tutorial 1: read a mocap clip (BVH or AMC, any rig convention), convert
//! it to metres and Y-up, resample it to 30 fps and print the canonical
//! joints of one frame.
//!
//! cargo run --release --example 01_mocap_positions -- ../shared/data/mocap/cmu-amc/02/02_01.amc

use surfmotion::retarget::query::load_mocap;
use surfmotion::rig::Canonical;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let Some(path) = std::env::args().nth(1) else {
        eprintln!("usage: 01_mocap_positions CLIP.bvh|CLIP.amc");
        return Ok(());
    };
    // Units, up axis and rig convention are detected; see `surfmotion inspect`.
    let clip = load_mocap(path.as_ref(), &Default::default(), 30.0)?;
    println!(
        "{path}: {} frames at {} fps (from {} fps), {} rig",
        clip.poses.len(),
        clip.fps,
        clip.source_fps,
        clip.convention
    );
    if let Some(pose) = clip.poses.get(clip.poses.len() / 2) {
        for c in Canonical::ALL {
            let p = pose[c.index()];
            println!("{:<11} {:>7.3} {:>7.3} {:>7.3}", c.name(), p.x, p.y, p.z);
        }
    }
    Ok(())
}
