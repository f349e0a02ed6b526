//! Tutorial 2: animate a static scan from a mocap clip (Confluent Motion):
//! landmarks → rig and markers → factor once → every frame → a GLB.
//!
//! cargo run --release --example 02_transfer_scan -- \
//!     ../shared/data/scans/armadillo/armadillo.obj tests/fixtures/armadillo.landmarks.json \
//!     ../shared/data/mocap/cmu-amc/02/02_01.amc armadillo_walk.glb

use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::{load_sequence, save_sequence};
use surfmotion::retarget::query::load_mocap;
use surfmotion::rig::embed::landmarks::Landmarks;
use surfmotion::transfer::{Job, MarkerOptions, MarkerSpec, Source, prepare, transfer};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let [scan, landmarks, clip, out] = a.as_slice() else {
        eprintln!("usage: 02_transfer_scan SCAN.obj LANDMARKS.json CLIP OUT.glb");
        return Ok(());
    };
    let mesh = load_sequence(scan, &Default::default())?.frame_mesh(0);
    let lm = Landmarks::load(landmarks.as_ref(), mesh.vertex_count())?;
    // Repair, embed the rig, place ~180 markers in rings along the bones.
    let prepared = prepare(&mesh, MarkerSpec::Landmarks(&lm, MarkerOptions::default()))?;
    let clip = load_mocap(clip.as_ref(), &Default::default(), 30.0)?;
    // Factor the harmonic and Poisson systems once; marker motion per frame.
    let mut job = Job::new(&prepared, Source::Mocap(&clip.poses, &clip.reference))?;
    let (positions, stats) = transfer(
        &job.confluent,
        &mut job.motion,
        &Default::default(),
        &|_| {},
    );
    println!(
        "{} frames, {} markers, {:.2} ms per frame",
        stats.frames,
        stats.markers,
        1e3 * stats.solve_seconds / stats.frames.max(1) as f64
    );
    let seq = MeshSequence::new(prepared.mesh.clone(), positions, Some(30.0))?;
    save_sequence(&seq, out.as_ref(), Some(30.0))?;
    Ok(())
}
