//! Vertices in no triangle (issue 41: a capture cut by a script keeps
//! them; an exporter leaves a point): samba with three stray points put
//! into its numbering — first, in the middle and last — each 2 cm off a
//! body vertex and moving with it in every captured frame. `db init` →
//! `db build` → `retarget` (CMU 02_02) runs; the output keeps every vertex
//! in the input's numbering; each stray point stays at its captured
//! distance from the body; and the rest of the surface is the clean
//! capture's result.

use super::partial::{init_build_retarget, landmarks_json};
use crate::common;
use std::path::{Path, PathBuf};
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::mesh::io::{LoadOptions, load_sequence, pc2::read_pc2};
use surfmotion::mesh::{Mesh, MeshSequence};

const FRAMES: usize = 40;

/// A stray point: its index in the result, the body vertex (input index)
/// it moves with, and its offset from that vertex.
type Stray = (usize, u32, [f64; 3]);

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

/// `seq`'s first frames with a stray point inserted before each of
/// `at` (indices of the result), each `offset` from body vertex `near`
/// (an input index) in every frame. Returns the mesh, the frames, and
/// each input vertex's new index.
fn with_strays(seq: &MeshSequence, strays: &[Stray]) -> (Mesh, Vec<[f64; 3]>, Vec<u32>) {
    let n = seq.mesh().vertex_count();
    let total = n + strays.len();
    // Slot of each result index: Some(input vertex) or a stray.
    let mut slots: Vec<Option<u32>> = Vec::with_capacity(total);
    let mut next = 0u32;
    for i in 0..total {
        if strays.iter().any(|s| s.0 == i) {
            slots.push(None);
        } else {
            slots.push(Some(next));
            next += 1;
        }
    }
    let mut index = vec![0u32; n];
    for (i, s) in slots.iter().enumerate() {
        if let Some(v) = s {
            index[*v as usize] = i as u32;
        }
    }
    let frame = |f: &[[f64; 3]]| -> Vec<[f64; 3]> {
        let mut k = 0;
        slots
            .iter()
            .map(|s| match s {
                Some(v) => f[*v as usize],
                None => {
                    let (_, near, o) = strays[k];
                    k += 1;
                    let p = f[near as usize];
                    [p[0] + o[0], p[1] + o[1], p[2] + o[2]]
                }
            })
            .collect()
    };
    let tris = seq
        .mesh()
        .triangles()
        .iter()
        .map(|t| t.map(|v| index[v as usize]))
        .collect();
    let mesh = Mesh::new(frame(seq.frame(0)), tris).unwrap();
    let mut all = Vec::new();
    for f in 0..FRAMES {
        all.extend(frame(seq.frame(f)));
    }
    (mesh, all, index)
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn stray_vertices_are_carried_through_retargeting_and_change_nothing_else() {
    let Some(d) = common::data_dir() else { return };
    let t = tempfile::tempdir().unwrap();
    let seq = load_sequence(
        d.join("4d/samba/samba.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    let n = seq.mesh().vertex_count();
    let lm = Landmarks::load(&fixture("samba.landmarks.json"), n).unwrap();
    // Inside the head 2 cm below its top, 2 cm off a middle vertex, 2 cm
    // off the lowest (within the body's bounds, as a cut's leftovers are).
    let p0 = seq.frame(0);
    let by = |key: &dyn Fn(&[f64; 3]) -> f64| {
        (0..n as u32)
            .max_by(|&a, &b| key(&p0[a as usize]).total_cmp(&key(&p0[b as usize])))
            .unwrap()
    };
    let (top, low) = (by(&|p| p[1]), by(&|p| -p[1]));
    // Spread through the numbering (first, middle, last), and appended
    // after the body's vertices (its numbering unchanged).
    let spread = [
        (0, top, [0.0, -0.02, 0.0]),
        (n / 2, n as u32 / 2, [0.02, 0.0, 0.0]),
        (n + 2, low, [0.0, 0.0, 0.02]),
    ];
    let tail = spread.map(|(_, near, o)| (0, near, o));
    let tail = [
        (n, tail[0].1, tail[0].2),
        (n + 1, tail[1].1, tail[1].2),
        (n + 2, tail[2].1, tail[2].2),
    ];
    let clean: Vec<u32> = (0..n as u32).collect();
    let mut out = Vec::new();
    let variants: [(&str, &[Stray]); 3] = [("clean", &[]), ("tail", &tail), ("spread", &spread)];
    for (name, strays) in variants {
        let (m, f, ix) = match strays.is_empty() {
            true => (
                seq.frame_mesh(0),
                seq.all_positions()[..FRAMES * n].to_vec(),
                clean.clone(),
            ),
            false => with_strays(&seq, strays),
        };
        let lmf = t.path().join(format!("{name}.landmarks.json"));
        std::fs::write(&lmf, landmarks_json(&lm, &ix, &[], &[])).unwrap();
        let run = init_build_retarget(&d, t.path(), name, &m, &f, Some(&lmf));
        if !strays.is_empty() {
            let first = strays[0].0;
            let said =
                format!("3 vertices of the topology are in no triangle (first: vertex {first})");
            assert!(run.init.contains(&said), "{}", run.init);
        }
        let pc = read_pc2(&t.path().join(format!("{name}.out.pc2"))).unwrap();
        out.push((pc.points, pc.positions, ix, strays));
    }
    let (nc, clean_out) = (out[0].0, &out[0].1);
    assert_eq!(nc, n);
    let frames = clean_out.len() / n;
    for (ns, pos, index, strays) in &out[1..] {
        assert_eq!(*ns, n + 3);
        assert_eq!(pos.len() / (n + 3), frames);
        // Every body vertex where the clean capture's result put it; with
        // the body's numbering unchanged, to rounding in all but a few frames (the fold repair of a frame can
        // take another turn on a last-bit difference: 3.5 mm at one vertex
        // of one frame of 75 when this was written).
        let (mut worst, mut moved) = (0.0f64, 0);
        for f in 0..frames {
            let mut here = 0.0f64;
            for v in 0..n {
                let a = clean_out[f * n + v];
                let b = pos[f * (n + 3) + index[v] as usize];
                here = here.max(dist(a, b));
            }
            worst = worst.max(here);
            moved += usize::from(here > 1e-4);
        }
        let at: Vec<usize> = strays.iter().map(|s| s.0).collect();
        eprintln!(
            "strays at {at:?}: body vertices differ by up to {worst:.3e} m; {moved} of {frames} frames by more than 0.1 mm"
        );
        // Renumbered (the spread points shift the body's ids), the LBS
        // constraints sampled by id differ: within millimetres.
        let renumbered = index.iter().enumerate().any(|(v, &i)| i as usize != v);
        assert!(
            worst < 0.01 && (renumbered || moved * 20 <= frames),
            "{at:?}: {worst} m, {moved} frames"
        );
        // Each stray point at its captured distance from the body vertex
        // nearest it (its carrier) in every frame (the skinning turns the
        // offset, it does not stretch it), finite.
        for (s, &(at, near, o)) in strays.iter().enumerate() {
            let q = seq.frame(0)[near as usize];
            let here = [q[0] + o[0], q[1] + o[1], q[2] + o[2]];
            let (carrier, r0) = (0..n)
                .map(|v| (v, dist(seq.frame(0)[v], here)))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap();
            let carrier = index[carrier] as usize;
            for f in 0..frames {
                let p = pos[f * (n + 3) + at];
                let r = dist(p, pos[f * (n + 3) + carrier]);
                assert!(
                    p.iter().all(|x| x.is_finite()) && (r - r0).abs() < 0.002 + 0.1 * r0,
                    "stray {s} frame {f}: {r} m from vertex {carrier} ({r0} m captured)"
                );
            }
        }
    }
}
