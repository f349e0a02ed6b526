//! Parametric motion (Casas et al. 2013, Sec. 3) on a 9,971-vertex
//! character: the real samba mesh driven by the project's procedural walk,
//! run and circle walk (3 s each, skinning plus soft-tissue lag, as
//! `synth` makes them), in two spaces (walk-run by speed, walk-circle by
//! turn). Measures one hybrid-blended frame (Eq. 3) against one linear
//! blend, one transition decision (Eqs. 4-5), one controller frame and a
//! 60-second scripted session; prints the hybrid error and memory against
//! ε (Fig. 4) and the parameter errors across the valid ranges. Needs
//! ../shared/data (the samba mesh); skips without it.

#[path = "../tests/it/common/gaits.rs"]
mod gaits;

use criterion::Criterion;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use surfmotion::db::Manifest;
use surfmotion::embed::Embedding;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::jobs::SynthCharacter;
use surfmotion::mesh::blend::Blender;
use surfmotion::mesh::io::load_sequence;
use surfmotion::parametric::hybrid::{HybridBlend, HybridOptions};
use surfmotion::parametric::params::measure;
use surfmotion::parametric::script::{Request, play};
use surfmotion::parametric::transition::{TargetState, TransitionPlanner};
use surfmotion::parametric::{Control, Controller, Motion, MotionOptions};
use surfmotion::synth::Gait;

fn data() -> Option<PathBuf> {
    let p = std::env::var_os("SURFMOTION_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared/data"));
    p.join("4d/samba/samba.obj").is_file().then_some(p)
}

fn database(d: &Path, db: &Path) -> Manifest {
    let rest = load_sequence(
        &d.join("4d/samba/samba.obj").to_string_lossy(),
        &Default::default(),
    )
    .unwrap()
    .frame_mesh(0);
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json");
    let lm = Landmarks::load(&fixture, rest.vertex_count()).unwrap();
    let rig = Embedding::new(&rest, &lm, None).unwrap();
    let character = SynthCharacter {
        rest,
        rig,
        landmarks_json: std::fs::read(&fixture).unwrap(),
    };
    gaits::gaits_database(
        db,
        &character,
        &[Gait::Walk, Gait::Run, Gait::Turn],
        "samba_gaits",
        &[
            ("locomotion", &["walk", "run"], &["speed", "turn"]),
            ("turning", &["walk", "turn"], &["turn"]),
        ],
    )
}

fn main() {
    let Some(d) = data() else {
        eprintln!("SKIPPED: ../shared/data not found (set SURFMOTION_DATA)");
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("db");
    let manifest = database(&d, &dir);
    let t = std::time::Instant::now();
    let motion = Motion::build(&dir, &manifest, &MotionOptions::default()).unwrap();
    eprintln!("model built in {:.2} s", t.elapsed().as_secs_f64());
    let loco = motion.space_index("locomotion").unwrap();
    let turning = motion.space_index("turning").unwrap();
    let n = motion.topology.vertex_count();

    // Fig. 4: stored references and error against ε (walk-run space).
    let blender = Blender::new(&motion.topology).unwrap();
    let sp = &motion.spaces[loco];
    let originals: Vec<Vec<f32>> = sp.blend().blocks[..2].to_vec();
    for eps_mm in [20.0, 10.0, 5.0, 2.0, 1.0] {
        let t = std::time::Instant::now();
        let h = HybridBlend::build(
            originals.clone(),
            n,
            sp.grid(),
            &blender,
            &HybridOptions {
                epsilon: eps_mm * 1e-3,
                ..Default::default()
            },
        );
        eprintln!(
            "fig4: eps {eps_mm:>4} mm: {} intermediate references {:?}, max tested error {:.2} mm, {:.1} MB ({:.2} MB per reference), {:.1} s",
            h.intermediate_count(),
            h.pairs[0].weights,
            h.pairs[0].max_error * 1e3,
            h.correction_bytes() as f64 / 1e6,
            (sp.grid() * n * 12) as f64 / 1e6,
            t.elapsed().as_secs_f64()
        );
    }
    // Linear blending alone (no reference) against the true blend.
    let h0 = HybridBlend::build(
        originals,
        n,
        sp.grid(),
        &blender,
        &HybridOptions {
            epsilon: 1e9,
            ..Default::default()
        },
    );
    eprintln!(
        "fig4: linear only: max tested error {:.2} mm",
        h0.pairs[0].max_error * 1e3
    );

    // Parameters across the valid range: the map's round trip, and the
    // controller over four whole cycles.
    for (s, idx) in [(loco, 0usize), (turning, 1usize)] {
        let sp = &motion.spaces[s];
        let map = sp.axis().unwrap();
        let [lo, hi] = map.range;
        let mut worst_map: f64 = 0.0;
        let mut worst_play: f64 = 0.0;
        for i in 0..=20 {
            let p = lo + (hi - lo) * i as f64 / 20.0;
            let (u, _) = map.inverse(p);
            let back = measure(sp.steps(), u, motion.fps)[idx];
            let rel = |x: f64| {
                if idx == 0 {
                    (x - p).abs() / p * 100.0
                } else {
                    (x - p).abs()
                }
            };
            worst_map = worst_map.max(rel(back));
            let mut c = Controller::new(&motion, s);
            let ctl = if idx == 0 {
                Control {
                    speed: Some(p),
                    ..Default::default()
                }
            } else {
                Control {
                    turn: Some(p),
                    ..Default::default()
                }
            };
            c.control(&ctl);
            for _ in 0..60 {
                c.advance();
            }
            let (mut path, mut last, mut frames, mut wraps, mut prev) =
                (0.0, c.root(), 0, 0, c.phase());
            let h0 = c.heading();
            while wraps < 4 {
                c.advance();
                frames += 1;
                path += (c.root() - last).length();
                last = c.root();
                if c.phase() < prev {
                    wraps += 1;
                }
                prev = c.phase();
            }
            let secs = frames as f64 / motion.fps;
            let got = if idx == 0 {
                path / secs
            } else {
                (c.heading() - h0).to_degrees() / secs
            };
            worst_play = worst_play.max(rel(got));
        }
        eprintln!(
            "params: {} {} range [{lo:.3}, {hi:.3}]: fit {:?} (quadratic round trip {:.4}, table {:.4}); worst over 21 values: map {worst_map:.3}{u}, controller {worst_play:.3}{u}",
            sp.name(),
            map.parameter.name(),
            map.fit,
            map.error_quadratic,
            map.error_table,
            u = if idx == 0 { " %" } else { " deg/s" }
        );
    }

    let mut c = Criterion::default().configure_from_args().sample_size(30);
    let mut out = vec![[0.0; 3]; n];
    let sp = &motion.spaces[loco];
    c.bench_function(&format!("hybrid blend frame ({n} vertices)"), |b| {
        let mut ph = 0.0;
        b.iter(|| {
            ph = (ph + 0.7) % sp.grid() as f64;
            sp.blend().eval(black_box(0.37), ph, &mut out);
            black_box(&out);
        })
    });
    c.bench_function(&format!("linear blend frame ({n} vertices)"), |b| {
        let mut ph = 0.0;
        b.iter(|| {
            ph = (ph + 0.7) % sp.grid() as f64;
            sp.blend().eval_linear(black_box(0.37), ph, &mut out);
            black_box(&out);
        })
    });
    c.bench_function(&format!("controller frame ({n} vertices)"), |b| {
        let mut ctl = Controller::new(&motion, loco);
        ctl.control(&Control {
            speed: Some(2.0),
            turn: Some(20.0),
            ..Default::default()
        });
        b.iter(|| {
            black_box(ctl.advance());
        })
    });
    let opts = motion.options.transition;
    let table = motion.table(loco, turning);
    let mut planner = TransitionPlanner::with_capacity(opts.depth, 64);
    let src: Vec<usize> = (0..=opts.depth).map(|i| (i * 7 / 5) % sp.grid()).collect();
    c.bench_function("transition decision (trellis depth 30, Dijkstra)", |b| {
        b.iter(|| {
            black_box(planner.plan(
                table,
                black_box(&src),
                0.4,
                0.5,
                TargetState::AnyPhase,
                &[],
                motion.fps,
                &opts,
            ))
        })
    });
    let script = vec![
        Request {
            t: 0.0,
            space: Some("locomotion".into()),
            speed: Some(1.4),
            turn: None,
        },
        Request {
            t: 10.0,
            space: None,
            speed: Some(2.5),
            turn: Some(25.0),
        },
        Request {
            t: 20.0,
            space: Some("turning".into()),
            speed: None,
            turn: Some(30.0),
        },
        Request {
            t: 30.0,
            space: Some("locomotion".into()),
            speed: Some(1.8),
            turn: Some(-15.0),
        },
        Request {
            t: 45.0,
            space: None,
            speed: Some(2.8),
            turn: Some(0.0),
        },
    ];
    let mut group = c.benchmark_group("session");
    group.sample_size(10);
    group.bench_function(
        format!("60 s scripted session ({n} vertices, 1800 frames)"),
        |b| {
            b.iter(|| {
                let r = play(&motion, &script, Some(60.0), |f| {
                    black_box(f);
                    Ok::<(), std::convert::Infallible>(())
                });
                black_box(r.map(|r| r.frames))
            })
        },
    );
    group.finish();
    let Ok(r) = play(&motion, &script, Some(60.0), |f| {
        black_box(f);
        Ok::<(), std::convert::Infallible>(())
    });
    eprintln!(
        "session: {} frames in {:.3} s = {:.0}× real time; transitions: {}",
        r.frames,
        r.synthesis_seconds,
        r.realtime_factor,
        r.transitions
            .iter()
            .map(|t| format!(
                "{}→{} latency {:.2} s cost {:.3} decision {:.1} µs",
                t.from,
                t.to,
                t.latency,
                t.cost,
                t.decision_seconds * 1e6
            ))
            .collect::<Vec<_>>()
            .join("; ")
    );
    c.final_summary();
}
