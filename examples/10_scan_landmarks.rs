//! Evaluation of the automatic landmarks of static scans (issue 41):
//! each landmark against a hand-made landmark file, in % of the height,
//! and the time taken.
//!
//! cargo run --release --example 10_scan_landmarks -- \
//!     ../shared/data/scans/smpl-template/human_man.obj tests/fixtures/smpl.landmarks.json
//! (`--group body` after the mesh for MakeHuman's base mesh; `MESH.pc2:0`
//! for frame 0 of a capture.)

use std::time::Instant;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::embed::scan_landmarks::{ScanOptions, estimate, find};
use surfmotion::mesh::io::load_sequence;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let (mesh_spec, group, fixture) = match &a[..] {
        [m, f] => (m, None, f),
        [m, g, name, f] if g == "--group" => (m, Some(name.clone()), f),
        _ => return Err("usage: 10_scan_landmarks MESH [--group NAME] LANDMARKS.json".into()),
    };
    let seq = load_sequence(mesh_spec, &Default::default())?;
    let mut mesh = seq.frame_mesh(0);
    if let Some(g) = group {
        let mut m = seq.mesh().select_groups(&[g]).ok_or("no such group")?;
        m.set_positions(mesh.positions())?;
        mesh = m;
    }
    let t = Instant::now();
    let found = find(mesh.positions(), mesh.triangles(), &ScanOptions::default());
    let secs = t.elapsed().as_secs_f64();
    let auto = match found {
        Ok(f) => f,
        Err(e) => {
            println!("{e}");
            match estimate(mesh.positions(), mesh.triangles())?.0 {
                Some(f) => f,
                None => return Ok(()),
            }
        }
    };
    let lm = Landmarks::load(fixture.as_ref(), mesh.vertex_count())?;
    let p = mesh.positions();
    println!(
        "{} ({} vertices): {:.3} s, confidence {:.2}, height {:.4}, symmetry {:.2}%, up {:?}, facing {:?}, {} extremities",
        mesh_spec,
        mesh.vertex_count(),
        secs,
        auto.confidence,
        auto.height,
        auto.symmetry_percent,
        auto.up.map(|x| (x * 100.0).round() / 100.0),
        auto.facing.map(|x| (x * 100.0).round() / 100.0),
        auto.extremities.len()
    );
    let (mut sum, mut n) = (0.0, 0);
    for &l in lm.marks.keys() {
        let Some(m) = auto.marks.get(l.name()) else {
            continue;
        };
        let Some(q) = lm.point(l, p) else { continue };
        let d: f64 = (0..3)
            .map(|i| (q[i] - m.point[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        let pct = 100.0 * d / auto.height;
        sum += pct;
        n += 1;
        println!(
            "  {:10} {:5.2}%  conf {:.2}  auto [{:.3}, {:.3}, {:.3}]  file [{:.3}, {:.3}, {:.3}]  {}",
            l.name(),
            pct,
            m.confidence,
            m.point[0],
            m.point[1],
            m.point[2],
            q[0],
            q[1],
            q[2],
            m.how
        );
    }
    println!(
        "  mean {:.2}% of the height over {n} landmarks",
        sum / n.max(1) as f64
    );
    for d in &auto.doubts {
        println!("  doubt: {d}");
    }
    Ok(())
}
