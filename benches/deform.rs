//! Deformation stage on real data (Huang et al. 2015, Sec. 5.2.3): the
//! samba capture as the database, the CMU 02_02 walk as the query. Every
//! retrieved frame of the walk (75) is deformed in turn, with the
//! turned-over-triangle repair and without it, against the floor: one
//! prefactored full-size 2-ring solve (`LᵀL`, 3 right-hand sides, one
//! thread). The default solves a level's regions and the repair's passes
//! over the triangles on the pool's threads (`DeformOptions::parallel_regions`,
//! session 28; `RAYON_NUM_THREADS` sets them); `part_sequential` solves
//! the regions one after another (the same frames bit for bit);
//! `part_in_pool` calls the default from a thread of rayon's pool (as
//! `retarget` deforms its frames, and the live session since session 46),
//! so its parallel steps are split inside the pool instead of each being
//! sent to it from outside.

mod common;

use criterion::Criterion;
use std::hint::black_box;
use surfmotion::db::Character;
use surfmotion::deform::unflip::RepairOptions;
use surfmotion::deform::{DeformMode, DeformOptions, Deformer, RepairTurns};
use surfmotion::drive::query::load_mocap;
use surfmotion::drive::{DriveOptions, synthesise};
use surfmotion::mesh::laplacian::uniform_region_rows;
use surfmotion::mesh::solver::FixedSolver;

fn main() {
    let Some(d) = common::data() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("samba");
    let m = surfmotion::db::Manifest {
        name: "samba".into(),
        topology: d.join("4d/samba/samba.obj"),
        fps: 30.0,
        units: "m".into(),
        up: "y".into(),
        human_sized: true,
        colors: None,
        sequences: vec![surfmotion::db::SequenceEntry {
            name: "dance".into(),
            path: d.join("4d/samba/samba.pc2"),
            fps: None,
        }],
        rig: surfmotion::db::RigSpec {
            landmarks: Some(common::samba_landmarks()),
            ..Default::default()
        },
        graph: Default::default(),
        deform: Default::default(),
        spaces: Vec::new(),
    };
    std::fs::create_dir_all(&db).unwrap();
    m.save(&db).unwrap();
    let ch = Character::load(&db, &surfmotion::db::Quiet).unwrap();
    let q = load_mocap(
        &d.join("mocap/cmu-amc/02/02_02.amc"),
        &Default::default(),
        30.0,
    )
    .unwrap();
    let none = DriveOptions {
        deform: DeformMode::None,
        ..Default::default()
    };
    let raw = synthesise(&ch, &q.poses, &q.reference, 30.0, &none).unwrap();
    let n = ch.n();
    let frames = raw.report.frames;
    let skeletons: Vec<_> = raw
        .positions
        .chunks(n)
        .map(|f| ch.rig().frame_joints(f))
        .collect();

    let mut c = Criterion::default().configure_from_args();
    let mut g = c.benchmark_group("deform/samba_10k");
    g.sample_size(10);
    let no_repair = DeformOptions {
        repair: RepairOptions {
            rounds: 0,
            ..Default::default()
        },
        ..Default::default()
    };
    // The default up to session 26 (the seam read off the last region
    // solved, the repair against the skin's turns only) and the default's
    // seams with that repair: the surface repair's cost is the difference
    // (issue 42).
    let old = DeformOptions {
        parent_seams: false,
        repair_turns: RepairTurns::Skin,
        ..Default::default()
    };
    let skin_repair = DeformOptions {
        repair_turns: RepairTurns::Skin,
        ..Default::default()
    };
    let sequential = DeformOptions {
        parallel_regions: false,
        ..Default::default()
    };
    for (name, opts) in [
        ("part_75_frames", DeformOptions::default()),
        ("part_sequential_75_frames", sequential),
        ("part_no_repair_75_frames", no_repair),
        ("part_old_default_75_frames", old),
        ("part_skin_repair_75_frames", skin_repair),
    ] {
        let def = Deformer::new(&ch, DeformMode::Part, &opts).unwrap();
        let mut ws = def.workspace();
        let mut out = vec![[0.0; 3]; n];
        g.bench_function(name, |b| {
            b.iter(|| {
                for ((src, sk), q) in raw.positions.chunks(n).zip(&skeletons).zip(&raw.query) {
                    def.deform(&ch, black_box(src), sk, q, &mut out, &mut ws);
                }
            })
        });
        if name == "part_75_frames" {
            g.bench_function("part_in_pool_75_frames", |b| {
                b.iter(|| {
                    rayon::scope(|_| {
                        for ((src, sk), q) in
                            raw.positions.chunks(n).zip(&skeletons).zip(&raw.query)
                        {
                            def.deform(&ch, black_box(src), sk, q, &mut out, &mut ws);
                        }
                    })
                })
            });
        }
    }
    // The floor: the whole body's 2-ring system, prefactored, one solve.
    let all: Vec<u32> = (0..n as u32).collect();
    let lap = uniform_region_rows(ch.topology().triangles(), &all, n);
    let mut trip = Vec::new();
    for r in &lap {
        for &(a, wa) in r {
            for &(b, wb) in r {
                trip.push((a, b, wa * wb));
            }
        }
    }
    for i in 0..n as u32 {
        trip.push((i, i, 1e-3));
    }
    let solver = FixedSolver::definite(n, trip).unwrap();
    let mut sws = solver.workspace(3);
    let rhs = raw.positions[..n].to_vec();
    let mut x = vec![[0.0; 3]; n];
    g.bench_function("solve_2ring", |b| {
        b.iter(|| solver.solve::<3>(black_box(&rhs), &[], &mut x, &mut sws))
    });
    g.finish();
    c.final_summary();
    let med = |b: &str| common::median_ns("deform/samba_10k", b);
    if let Some(s) = med("solve_2ring") {
        for (name, what) in [
            ("part_75_frames", "part"),
            (
                "part_in_pool_75_frames",
                "part, called on a thread of the pool",
            ),
            ("part_sequential_75_frames", "regions one after another"),
            ("part_no_repair_75_frames", "without the repair"),
            ("part_old_default_75_frames", "the default up to session 26"),
            ("part_skin_repair_75_frames", "the skin's repair only"),
        ] {
            if let Some(p) = med(name) {
                let p = p / frames as f64;
                println!(
                    "per frame, {what}: {:.2} ms ({:.2}x the 2-ring solve)",
                    p / 1e6,
                    p / s
                );
            }
        }
        println!("solve {:.2} ms", s / 1e6);
    }
}
