//! Geometry kernels on real meshes: samba (9,971 vertices), armadillo
//! (14,587), and the armadillo subdivided once (~58K) and twice (~233K).
//! Per size: factorisation, the bare prefactored 3-column solve (the floor),
//! Poisson reconstruction, one non-linear blend of two pre-decomposed frames,
//! and the per-input-frame polar decomposition. After the runs, per-frame
//! figures are printed as ratios to the solve at the same size.

mod common;

use criterion::{BenchmarkId, Criterion};
use glam::{DMat3, DQuat, DVec3};
use std::hint::black_box;
use surfmotion::mesh::Mesh;
use surfmotion::mesh::blend::Blender;
use surfmotion::mesh::frames::RestFrames;
use surfmotion::mesh::io::{LoadOptions, load_sequence, obj::read_obj};
use surfmotion::mesh::poisson::Poisson;
use surfmotion::mesh::subdivide::midpoint;

use common::{data, median_ns};

/// A smooth non-rigid pose change: a twist about +Y growing with height and a bend.
fn twist(m: &Mesh) -> Vec<[f64; 3]> {
    let b = m.bounds();
    let h = (b.max[1] - b.min[1]).max(1e-9);
    m.positions()
        .iter()
        .map(|p| {
            let t = (p[1] - b.min[1]) / h;
            let q = DQuat::from_rotation_y(1.2 * t) * DQuat::from_rotation_z(0.3 * t * t);
            (q * DVec3::from_array(*p)).to_array()
        })
        .collect()
}

struct Case {
    name: String,
    mesh: Mesh,
    other: Vec<[f64; 3]>,
}

fn cases(d: &std::path::Path) -> Vec<Case> {
    let samba = load_sequence(
        d.join("4d/samba/samba.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    let arm = read_obj(&d.join("scans/armadillo/armadillo.obj")).unwrap();
    let arm1 = midpoint(&arm);
    let arm2 = midpoint(&arm1);
    let mut v = vec![Case {
        name: "samba_10k".into(),
        other: samba.frame(60).to_vec(),
        mesh: samba.frame_mesh(0),
    }];
    for (n, m) in [
        ("armadillo_15k", arm),
        ("armadillo_58k", arm1),
        ("armadillo_233k", arm2),
    ] {
        v.push(Case {
            name: n.into(),
            other: twist(&m),
            mesh: m,
        });
    }
    v
}

fn bench(c: &mut Criterion, cases: &[Case]) {
    for case in cases {
        let mut g = c.benchmark_group(format!("kernels/{}", case.name));
        let big = case.mesh.vertex_count() > 100_000;
        g.sample_size(if big { 10 } else { 20 });
        let m = &case.mesh;
        g.bench_function("factor", |b| b.iter(|| Poisson::new(black_box(m)).unwrap()));
        let poisson = Poisson::new(m).unwrap();
        let mut pw = poisson.workspace();
        let grads =
            RestFrames::new(m.positions(), m.triangles()).gradients(&case.other, m.triangles());
        let mut x = vec![[0.0; 3]; m.vertex_count()];
        poisson.assemble(&grads, &mut pw);
        g.bench_function("solve", |b| b.iter(|| poisson.solve(&mut pw, &mut x)));
        g.bench_function("reconstruct", |b| {
            b.iter(|| poisson.reconstruct(black_box(&grads), &mut pw, &mut x))
        });
        let blender = Blender::new(m).unwrap();
        let mut bw = blender.workspace();
        let ga = blender.decompose(m.positions(), &mut bw);
        let gb = blender.decompose(&case.other, &mut bw);
        let mut out = vec![[0.0; 3]; m.vertex_count()];
        g.bench_function("blend", |b| {
            b.iter(|| blender.blend(&ga, &gb, black_box(0.4), &mut out, &mut bw))
        });
        let mut gd = ga.clone();
        g.bench_function("decompose", |b| {
            b.iter(|| blender.decompose_into(black_box(&case.other), &mut bw, &mut gd))
        });
        g.bench_with_input(BenchmarkId::new("polar", "x1000"), &grads, |b, gr| {
            b.iter(|| {
                let mut s = DMat3::ZERO;
                for t in gr.iter().take(1000) {
                    s += surfmotion::mesh::frames::polar(*t).1;
                }
                s
            })
        });
        g.finish();
    }
}

fn main() {
    let Some(d) = data() else {
        eprintln!("benchmark skipped: no ../shared/data");
        return;
    };
    let cases = cases(&d);
    let mut c = Criterion::default().configure_from_args();
    bench(&mut c, &cases);
    c.final_summary();
    println!("\nper-frame cost as a ratio to the prefactored 3-column solve at the same size:");
    println!(
        "{:<16} {:>9} {:>10} {:>10} {:>12} {:>8} {:>10}",
        "mesh", "vertices", "factor ms", "solve ms", "reconstruct", "blend", "decompose"
    );
    for case in &cases {
        let g = format!("kernels/{}", case.name);
        let (Some(f), Some(s), Some(r), Some(b), Some(dc)) = (
            median_ns(&g, "factor"),
            median_ns(&g, "solve"),
            median_ns(&g, "reconstruct"),
            median_ns(&g, "blend"),
            median_ns(&g, "decompose"),
        ) else {
            continue;
        };
        println!(
            "{:<16} {:>9} {:>10.1} {:>10.3} {:>11.2}x {:>7.2}x {:>9.2}x",
            case.name,
            case.mesh.vertex_count(),
            f / 1e6,
            s / 1e6,
            r / s,
            b / s,
            dc / s
        );
    }
}
