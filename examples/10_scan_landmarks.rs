//! Evaluation of the automatic landmarks of static scans (issue 41):
//! each landmark against a hand-made landmark file, in % of the height,
//! and the time taken ([`surfmotion::tools::eval::landmarks`]).
//!
//! cargo run --release --example 10_scan_landmarks -- \
//!     ../shared/data/scans/smpl-template/human_man.obj tests/fixtures/smpl.landmarks.json
//! (`--group body` after the mesh for MakeHuman's base mesh; `MESH.pc2:0`
//! for frame 0 of a capture.)

use surfmotion::tools::eval::landmarks::evaluate_landmarks;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let (mesh, group, file) = match &a[..] {
        [m, f] => (m, None, f),
        [m, g, name, f] if g == "--group" => (m, Some(name.as_str()), f),
        _ => return Err("usage: 10_scan_landmarks MESH [--group NAME] LANDMARKS.json".into()),
    };
    print!("{}", evaluate_landmarks(mesh, group, file.as_ref())?);
    Ok(())
}
