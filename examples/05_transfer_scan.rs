//! Tutorial 5: animate a static scan from mocap clips (Confluent Motion,
//! de Aguiar et al. 2007): landmarks → rig and markers → factor once →
//! any number of clips, each a GLB.
//!
//! cargo run --release --example 05_transfer_scan -- \
//!     ../shared/data/scans/armadillo/armadillo.obj tests/fixtures/armadillo.landmarks.json \
//!     ../shared/data/mocap/cmu-amc/02/02_01.amc armadillo_walk.glb

use surfmotion::embed::landmarks::Landmarks;
use surfmotion::jobs::ScanTransferJob;
use surfmotion::mesh::io::load_sequence;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let [scan, landmarks, clip, out] = &a[..] else {
        return Err("usage: 05_transfer_scan SCAN LANDMARKS CLIP OUT.glb".into());
    };
    let mesh = load_sequence(scan, &Default::default())?.frame_mesh(0);
    let lm = Landmarks::load(landmarks.as_ref(), mesh.vertex_count())?;
    let job = ScanTransferJob::prepare(&mesh, &lm, scan, Default::default())?;
    let run = job.run(clip.as_ref())?;
    job.write(run.positions, out.as_ref())?;
    Ok(())
}
