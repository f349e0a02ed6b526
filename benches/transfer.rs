//! Confluent Motion per frame (de Aguiar et al. 2007) on samba (9,971
//! vertices, its own capture as the template), the armadillo (14,587, a CMU
//! walk) and the armadillo subdivided twice (~233K, the same walk). Per
//! size: setup (rig, markers, both factorisations), one transferred frame,
//! and the two prefactored solves a frame contains (4-column harmonic,
//! 3-column Poisson). The ratio frame / (both solves) is printed at the end.

mod common;

use criterion::Criterion;
use std::hint::black_box;
use std::path::PathBuf;
use surfmotion::drive::query::load_mocap;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::mesh::Mesh;
use surfmotion::mesh::harmonic::Harmonic;
use surfmotion::mesh::io::obj::read_obj;
use surfmotion::mesh::poisson::Poisson;
use surfmotion::mesh::subdivide::midpoint;
use surfmotion::transfer::confluent::orient_frames;
use surfmotion::transfer::markers::generate;
use surfmotion::transfer::{Driving, Job, MarkerOptions, MarkerSpec, SignMode, prepare};

use common::{data, median_ns, samba, samba_landmarks};

struct Case {
    name: &'static str,
    mesh: Mesh,
    landmarks: PathBuf,
    mocap: Option<PathBuf>,
}

fn fixture(n: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(n)
}

fn bench(c: &mut Criterion, d: &std::path::Path, cases: &[Case]) {
    let seq = samba(d);
    for case in cases {
        let mut g = c.benchmark_group(format!("transfer/{}", case.name));
        let big = case.mesh.vertex_count() > 100_000;
        g.sample_size(if big { 10 } else { 20 });
        let m = &case.mesh;
        let lm = Landmarks::load(&case.landmarks, m.vertex_count()).unwrap();
        let opts = MarkerOptions::default();
        let prepared = prepare(m, MarkerSpec::Landmarks(&lm, opts)).unwrap();
        let rig = prepared.rig.as_ref().unwrap();
        let tmarkers = generate(&seq.frame_mesh(0), rig, &opts);
        let clip = case
            .mocap
            .as_ref()
            .map(|p| load_mocap(p, &Default::default(), 30.0).unwrap());
        let source = || match &clip {
            Some(c) => Driving::Mocap(&c.poses, &c.reference),
            None => Driving::Template {
                frames: &seq,
                markers: &tmarkers,
                reference: 0,
                align: glam::DQuat::IDENTITY,
            },
        };
        g.bench_function("setup", |b| {
            b.iter(|| {
                let p = prepare(black_box(m), MarkerSpec::Landmarks(&lm, opts)).unwrap();
                Job::new(&p, source()).unwrap().confluent.marker_count()
            })
        });
        let mut job = Job::new(&prepared, source()).unwrap();
        let k = job.motion.markers;
        orient_frames(&mut job.motion.rotations, k, SignMode::Consistent);
        let f = job.motion.frames() / 2;
        let (rot, tg) = job.motion.frame(f);
        let mut ws = job.confluent.workspace();
        let mut out = vec![[0.0; 3]; prepared.mesh.vertex_count()];
        g.bench_function("frame", |b| {
            b.iter(|| job.confluent.frame(black_box(rot), tg, &mut ws, &mut out))
        });
        // The floor: the same two prefactored solves on their own.
        let mut boundary = Vec::new();
        let mut seen = vec![false; prepared.mesh.vertex_count()];
        for mk in prepared
            .markers
            .iter()
            .filter(|x| job.used.contains(&x.name))
        {
            for v in prepared.mesh.triangles()[mk.triangle as usize] {
                if !seen[v as usize] {
                    seen[v as usize] = true;
                    boundary.push(v);
                }
            }
        }
        let h = Harmonic::new(&prepared.mesh, &boundary).unwrap();
        let mut hw = h.workspace::<4>();
        let values = vec![[0.5; 4]; boundary.len()];
        let mut field = vec![[0.0; 4]; prepared.mesh.vertex_count()];
        g.bench_function("harmonic_solve", |b| {
            b.iter(|| h.solve(black_box(&values), &mut field, &mut hw))
        });
        let p = Poisson::new(&prepared.mesh).unwrap();
        let mut pw = p.workspace();
        pw.b.iter_mut().for_each(|r| *r = [1.0, 0.0, 0.0]);
        g.bench_function("poisson_solve", |b| b.iter(|| p.solve(&mut pw, &mut out)));
        g.finish();
    }
}

fn main() {
    let Some(d) = data() else { return };
    let arm = read_obj(&d.join("scans/armadillo/armadillo.obj")).unwrap();
    let walk = d.join("mocap/cmu-amc/02/02_01.amc");
    let cases = vec![
        Case {
            name: "samba_10k",
            mesh: samba(&d).frame_mesh(0),
            landmarks: samba_landmarks(),
            mocap: None,
        },
        Case {
            name: "armadillo_233k",
            mesh: midpoint(&midpoint(&arm)),
            landmarks: fixture("armadillo.landmarks.json"),
            mocap: Some(walk.clone()),
        },
        Case {
            name: "armadillo_15k",
            mesh: arm,
            landmarks: fixture("armadillo.landmarks.json"),
            mocap: Some(walk),
        },
    ];
    let mut c = Criterion::default().configure_from_args();
    bench(&mut c, &d, &cases);
    c.final_summary();
    println!(
        "\nper-frame transfer against its two prefactored solves (harmonic 4 columns + Poisson 3):"
    );
    println!(
        "{:<16} {:>9} {:>9} {:>10} {:>10} {:>10} {:>8} {:>9}",
        "mesh", "vertices", "setup s", "frame ms", "harm. ms", "poiss. ms", "ratio", "frames/s"
    );
    for case in &cases {
        let g = format!("transfer/{}", case.name);
        let (Some(s), Some(f), Some(h), Some(p)) = (
            median_ns(&g, "setup"),
            median_ns(&g, "frame"),
            median_ns(&g, "harmonic_solve"),
            median_ns(&g, "poisson_solve"),
        ) else {
            continue;
        };
        println!(
            "{:<16} {:>9} {:>9.2} {:>10.2} {:>10.2} {:>10.2} {:>7.2}x {:>9.0}",
            case.name,
            case.mesh.vertex_count(),
            s / 1e9,
            f / 1e6,
            h / 1e6,
            p / 1e6,
            f / (h + p),
            1e9 / f
        );
    }
}
