//! Tutorial 1: read a mocap clip (BVH or AMC, any rig convention), convert
//! it to metres and Y-up, resample it to 30 fps and print the canonical
//! joints of its middle frame (units, up axis and rig convention are
//! detected; see `surfmotion inspect`).
//!
//! cargo run --release --example 01_mocap_positions -- ../shared/data/mocap/cmu-amc/02/02_01.amc

use surfmotion::rig::{Canonical, LoadOptions, detect_clip, load_clip};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("usage: CLIP.bvh|CLIP.amc")?;
    let mut clip = load_clip(path.as_ref(), &LoadOptions::default())?;
    clip.to_metres_y_up();
    let clip = clip.resampled(30.0);
    let poses = detect_clip(&clip)?.map.poses(&clip)?;
    for c in Canonical::ALL {
        println!("{:<11} {:.3}", c.name(), poses[poses.len() / 2][c.index()]);
    }
    Ok(())
}
