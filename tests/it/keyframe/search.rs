//! Key-frame animation (Huang et al. 2015, Sec. 5.1): the search on
//! synthetic frame graphs (walks, loops, repetitions against brute force
//! and Dijkstra) and the `keyframe` command on a small synthetic database.

use crate::common;

use std::collections::BinaryHeap;
use std::process::Command;
use surfmotion::graph::FlatFrame;
use surfmotion::keyframe::graph::KeyGraph;
use surfmotion::keyframe::options::SearchOptions;
use surfmotion::keyframe::repeats::{Problem, Tally, brute_force, solve_exact, solve_ilp};
use surfmotion::keyframe::{Planner, Targets};

use common::keygraph::Lcg;

/// The frame at position `i` of the graph.
fn ff(i: usize) -> FlatFrame {
    FlatFrame::from_index(i)
}

fn random_problem(r: &mut Lcg, loops: &mut Vec<Tally>) -> (Tally, f64, f64) {
    loops.clear();
    for _ in 0..1 + r.below(3) {
        loops.push(Tally {
            cost: 0.05 * r.next(),
            distance: 0.2 + 1.5 * r.next(),
            frames: 3 + r.below(12) as u32,
        });
    }
    let walk = Tally {
        cost: 0.1 * r.next(),
        distance: 2.0 * r.next(),
        frames: 1 + r.below(20) as u32,
    };
    (walk, 3.0 * r.next(), 40.0 * r.next())
}

/// The exact programme and the ILP find the brute-force optimum of `p`
/// (case `case`, time target `t` frames); returns the brute-force optimum.
/// No count past the frames at which the time error alone exceeds the
/// cost of n = 0 can be optimal: brute force goes up to there.
fn assert_solvers_agree(
    p: &Problem,
    t: f64,
    case: usize,
) -> surfmotion::keyframe::repeats::Repeats {
    let c0 = p.cost(&vec![0; p.loops.len()]);
    let frames = t - p.walk.frames as f64 + (c0 - p.walk.cost) / p.w_time;
    let limit = (frames.max(0.0) / 3.0).ceil() as u32;
    let b = brute_force(p, limit);
    let e = solve_exact(p, f64::INFINITY, 1_000_000).unwrap();
    let i = solve_ilp(p).unwrap();
    assert!(
        (e.cost - b.cost).abs() < 1e-9,
        "case {case}: exact {e:?} brute {b:?}"
    );
    assert!(
        (i.cost - b.cost).abs() < 1e-6,
        "case {case}: ilp {i:?} brute {b:?}"
    );
    assert!((p.cost(&e.n) - e.cost).abs() < 1e-9);
    b
}

#[test]
fn ilp_exact_and_brute_force_agree_on_random_repetition_problems() {
    let mut r = Lcg(7);
    let mut loops = Vec::new();
    for case in 0..200 {
        let (walk, d, t) = random_problem(&mut r, &mut loops);
        let p = Problem {
            walk,
            loops: &loops,
            distance: d,
            frames: t,
            w_dist: 1.0 / 0.3,
            w_time: 0.1,
            heading: None,
            max_loop_frames: None,
        };
        assert_solvers_agree(&p, t, case);
    }
}

/// The repetition counts are chosen with the heading term (the final
/// facing is the walk's turn plus `Σ θ_i n_i`, its error wrapped): the
/// ILP (the wrap integer as one more sign-split term) and the exact
/// programme (turn in the dominance rule) find the brute-force optimum of
/// the whole cost. Scoring Eq. 7's own counts with the heading afterwards
/// (the search before) misses it in many cases, which the test also
/// checks so that it can tell the two apart.
#[test]
fn heading_is_optimised_jointly_with_the_repetition_counts() {
    use surfmotion::keyframe::repeats::Turns;
    let mut r = Lcg(19);
    let mut loops = Vec::new();
    let (mut cases, mut worse_after) = (0, 0);
    for case in 0..200 {
        let (walk, d, t) = random_problem(&mut r, &mut loops);
        let turns: Vec<f64> = loops.iter().map(|_| 2.0 * r.next() - 1.0).collect();
        let heading = Turns {
            offset: std::f64::consts::PI * (2.0 * r.next() - 1.0),
            loops: &turns,
            // 1/30 per degree, per radian.
            weight: 180.0 / (30.0 * std::f64::consts::PI),
        };
        let p = Problem {
            walk,
            loops: &loops,
            distance: d,
            frames: t,
            w_dist: 1.0 / 0.3,
            w_time: 0.1,
            heading: Some(heading),
            max_loop_frames: None,
        };
        let b = assert_solvers_agree(&p, t, case);
        let i = solve_ilp(&p).unwrap();
        assert!((p.cost(&i.n) - i.cost).abs() < 1e-9);
        // Eq. 7's counts, scored with the heading afterwards.
        let plain = Problem {
            heading: None,
            max_loop_frames: None,
            ..p.clone()
        };
        let eq7 = solve_exact(&plain, f64::INFINITY, 1_000_000).unwrap();
        assert!(p.cost(&eq7.n) >= b.cost - 1e-9, "case {case}");
        worse_after += usize::from(p.cost(&eq7.n) > b.cost + 1e-6);
        cases += 1;
    }
    assert!(
        worse_after * 5 >= cases,
        "the heading changed the counts in only {worse_after} of {cases} cases"
    );
}

/// A random frame graph: `seqs` sequences of 20-40 frames walking at
/// different speeds (with a lateral sway), and random transitions.
fn random_graph(r: &mut Lcg, seqs: usize, jumps: usize) -> KeyGraph {
    random_graph_costing(r, seqs, jumps, 0.001, 0.01)
}

/// `random_graph` with each transition costing `least + span · u`,
/// `u` uniform in [0, 1).
fn random_graph_costing(r: &mut Lcg, seqs: usize, jumps: usize, least: f64, span: f64) -> KeyGraph {
    let shape = common::keygraph::Shape {
        frames: (20, 21),
        cost: (least, span),
        distinct: false,
    };
    common::keygraph::random_graph(r, seqs, jumps, &shape)
}

/// Dijkstra on the frame graph with the zero-target cost of a step:
/// transition cost + w_dist · step + w_time · 1 frame.
fn dijkstra(g: &KeyGraph, from: FlatFrame, to: FlatFrame, wd: f64, wt: f64) -> Option<f64> {
    #[derive(PartialEq)]
    struct Item(f64, FlatFrame);
    impl Eq for Item {}
    impl PartialOrd for Item {
        fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
            Some(self.cmp(o))
        }
    }
    impl Ord for Item {
        fn cmp(&self, o: &Self) -> std::cmp::Ordering {
            o.0.total_cmp(&self.0)
        }
    }
    let mut d = vec![f64::INFINITY; g.len()];
    d[from.index()] = wt; // the start frame counts (Eq. 12)
    let mut h = BinaryHeap::new();
    h.push(Item(wt, from));
    while let Some(Item(c, u)) = h.pop() {
        if c > d[u.index()] {
            continue;
        }
        for e in g.successors(u) {
            let nc = c + e.cost + wd * g.step_of(e.to) + wt;
            if nc < d[e.to.index()] {
                d[e.to.index()] = nc;
                h.push(Item(nc, e.to));
            }
        }
    }
    d[to.index()].is_finite().then_some(d[to.index()])
}

fn exact() -> SearchOptions {
    SearchOptions {
        gap: 0.0,
        ..Default::default()
    }
}

#[test]
fn zero_targets_give_the_dijkstra_shortest_path() {
    let mut r = Lcg(11);
    let mut compared = 0;
    for case in 0..400 {
        let g = random_graph(&mut r, 3, 16);
        let from = ff(r.below(g.len()));
        let to = ff(r.below(g.len()));
        let o = exact();
        let w = o.weights;
        let want = dijkstra(&g, from, to, w.distance, w.time);
        let planner = Planner::new(g.clone(), &[from, to], 25.0, &o);
        match (want, planner) {
            (None, Err(_)) => {}
            (Some(want), Ok(p)) => {
                let plan = p
                    .plan(
                        &Targets::Global {
                            distance: 0.0,
                            time: 0.0,
                        },
                        &o,
                    )
                    .unwrap();
                assert!(
                    (plan.cost.total - want).abs() < 1e-9,
                    "case {case}: search {} dijkstra {want} ({from} -> {to}, {:?}, path {:?})",
                    plan.cost.total,
                    plan.stats,
                    plan.path
                );
                assert!(plan.segments[0].loops.is_empty());
                compared += 1;
            }
            (w, p) => panic!("case {case}: dijkstra {w:?}, search {:?}", p.err()),
        }
    }
    assert!(compared > 10, "only {compared} connected cases");
}

#[test]
fn paths_start_and_end_at_the_key_frames_pass_every_via_and_follow_edges() {
    let mut r = Lcg(5);
    let mut checked = 0;
    for case in 0..40 {
        let g = random_graph(&mut r, 3, 14);
        let keys: Vec<FlatFrame> = (0..3).map(|_| ff(r.below(g.len()))).collect();
        let o = SearchOptions::default();
        let Ok(p) = Planner::new(g.clone(), &keys, 25.0, &o) else {
            continue;
        };
        for targets in [
            Targets::Global {
                distance: 3.0,
                time: 4.0,
            },
            Targets::PerSegment(vec![(1.0, 1.5), (2.0, 2.5)]),
        ] {
            let plan = p.plan(&targets, &o).unwrap();
            let path = &plan.path;
            assert_eq!(path[0], keys[0], "case {case}");
            assert_eq!(*path.last().unwrap(), keys[2], "case {case}");
            assert_eq!(plan.segments.len(), 2);
            assert_eq!(plan.segments[0].to, keys[1]);
            assert_eq!(*plan.segments[0].path.last().unwrap(), keys[1]);
            assert_eq!(plan.segments[1].path[0], keys[1]);
            assert_walks_the_graph(&g, &plan, case);
            checked += 1;
        }
    }
    assert!(checked > 10, "only {checked} connected cases");
}

/// Every step of the plan's path is an arc of `g`, and the plan's
/// measures (frames, distance, cost) are the path's.
fn assert_walks_the_graph(g: &KeyGraph, plan: &surfmotion::keyframe::Plan, case: usize) {
    let (mut cost, mut dist) = (0.0, 0.0);
    for w in plan.path.windows(2) {
        let e = g.edge(w[0], w[1]);
        assert!(e.is_some(), "case {case}: {} -> {} is no edge", w[0], w[1]);
        cost += e.unwrap().cost;
        dist += g.step_of(w[1]);
    }
    assert_eq!(plan.measure.frames as usize, plan.path.len(), "case {case}");
    assert!((plan.measure.distance - dist).abs() < 1e-9, "case {case}");
    assert!((plan.measure.cost - cost).abs() < 1e-9, "case {case}");
}

#[test]
fn loops_are_repeated_to_meet_a_reachable_target() {
    // One sequence walking 0.05 m per frame with a loop 30 -> 11 (20 frames,
    // 1 m): 0 -> 39 plus k loops makes 1.95 + k m in 40 + 20k frames.
    let g = common::line_key_graph(40, 0.05, &[(30, 11, 0.002)]);
    let o = exact();
    let p = Planner::new(g, &[ff(0), ff(39)], 20.0, &o).unwrap();
    let plan = p
        .plan(
            &Targets::Global {
                distance: 6.95,
                time: 140.0 / 20.0,
            },
            &o,
        )
        .unwrap();
    assert_eq!(plan.segments[0].loops.len(), 1);
    assert_eq!(plan.segments[0].loops[0].repeats, 5);
    assert_eq!(plan.measure.frames, 140);
    assert!((plan.measure.distance - 6.95).abs() < 1e-9);
}

fn run(args: &[&std::ffi::OsStr]) -> std::process::Output {
    Command::new(common::bin()).args(args).output().unwrap()
}

/// `keyframe --db DB --from 02_01:0 --to 02_03:30` and `rest`.
fn walk_to_run(db: &std::path::Path, rest: &[&std::ffi::OsStr]) -> std::process::Output {
    let mut a: Vec<&std::ffi::OsStr> = vec![
        "keyframe".as_ref(),
        "--db".as_ref(),
        db.as_os_str(),
        "--from".as_ref(),
        "02_01:0".as_ref(),
        "--to".as_ref(),
        "02_03:30".as_ref(),
    ];
    a.extend_from_slice(rest);
    run(&a)
}

/// The `keyframe` command on a small synthetic database (CMU walk 02_01 and
/// run 02_03, 25 fps): the written sequence travels the distance and lasts
/// the time the report gives; bad input is a one-line error with exit 1.
/// The small synthetic database (CMU walk 02_01 and run 02_03 on the
/// samba character, 25 fps), built once for the tests that need it.
fn walk_run_db(d: &std::path::Path) -> &'static std::path::Path {
    static DB: std::sync::OnceLock<std::path::PathBuf> = std::sync::OnceLock::new();
    DB.get_or_init(|| common::walk_run_db(d, "keyframe-walk-run"))
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn cli_output_travels_what_the_report_says_and_refuses_bad_input() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let db = walk_run_db(&d);
    let out = tmp.path().join("kf.pc2");
    let report = tmp.path().join("kf.json");
    let o = walk_to_run(
        db,
        &[
            "--distance".as_ref(),
            "6".as_ref(),
            "--time".as_ref(),
            "4".as_ref(),
            "-o".as_ref(),
            out.as_os_str(),
            "--report".as_ref(),
            report.as_os_str(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let seq =
        surfmotion::mesh::io::load_sequence(out.to_str().unwrap(), &Default::default()).unwrap();
    let n = seq.mesh().vertex_count();
    let travelled = surfmotion::keyframe::graph::travelled(seq.all_positions(), n);
    let fps = r["fps"].as_f64().unwrap();
    let dist = r["distance"].as_f64().unwrap();
    let time = r["time"].as_f64().unwrap();
    assert_eq!(seq.frame_count(), r["frames"].as_u64().unwrap() as usize);
    assert!((seq.frame_count() as f64 / fps - time).abs() < 1e-9);
    // The search's CPU time beside its wall time (Linux: the thread's
    // run time; one thread, so never more than the wall time).
    let (wall, cpu) = (
        r["search_seconds"].as_f64().unwrap(),
        &r["search_cpu_seconds"],
    );
    if cfg!(target_os = "linux") {
        let cpu = cpu.as_f64().unwrap();
        assert!(
            cpu >= 0.0 && cpu <= wall + 1e-3,
            "cpu {cpu} s, wall {wall} s"
        );
    }
    // f32 positions in the file: agreement to 0.1 mm over the path.
    assert!(
        (travelled - dist).abs() < 1e-4,
        "file {travelled} m, report {dist} m"
    );
    assert!(
        r["distance_error"].as_f64().unwrap().abs() < 0.06,
        "{}",
        r["distance_error"]
    );
    assert!(
        r["time_error"].as_f64().unwrap().abs() < 0.04 + 1e-9,
        "{}",
        r["time_error"]
    );
    let segs = r["segments"].as_array().unwrap();
    assert_eq!(segs[0]["from"], "02_01:0");
    assert_eq!(segs[0]["to"], "02_03:30");
    assert!(r["cost"]["total"].as_f64().unwrap() >= r["cost"]["transition"].as_f64().unwrap());
    // A target the graph cannot reach (100 m in 1 s) gives the best
    // compromise, flagged as such.
    let far = tmp.path().join("far.pc2");
    let o = walk_to_run(
        db,
        &[
            "--distance".as_ref(),
            "100".as_ref(),
            "--time".as_ref(),
            "1".as_ref(),
            "-o".as_ref(),
            far.as_os_str(),
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(text.contains("not met within 1 %"), "{text}");
    // A small grid with its heat-map: one cell per target, each with the
    // achieved figures the JSON report gives.
    let svg = tmp.path().join("grid.svg");
    let png = tmp.path().join("grid.png");
    let grid_report = tmp.path().join("grid.json");
    for plot in [&svg, &png] {
        let o = walk_to_run(
            db,
            &[
                "--grid".as_ref(),
                "--distances".as_ref(),
                "4,6,8".as_ref(),
                "--times".as_ref(),
                "3,4".as_ref(),
                "--plot".as_ref(),
                plot.as_os_str(),
                "--report".as_ref(),
                grid_report.as_os_str(),
            ],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let g: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&grid_report).unwrap()).unwrap();
    let queries = g["queries"].as_array().unwrap();
    assert_eq!(queries.len(), 6);
    // Every query's CPU time beside its wall time, and their spread (the
    // wall-time keys kept).
    for key in ["query_ms_mean", "query_ms_std", "query_ms_max"] {
        assert!(g[key].as_f64().is_some(), "{key}");
    }
    if cfg!(target_os = "linux") {
        for q in queries {
            let (wall, cpu) = (
                q["seconds"].as_f64().unwrap(),
                q["cpu_seconds"].as_f64().unwrap(),
            );
            assert!(
                cpu >= 0.0 && cpu <= wall + 1e-3,
                "cpu {cpu} s, wall {wall} s"
            );
        }
        let (mean, max) = (
            g["query_cpu_ms_mean"].as_f64().unwrap(),
            g["query_cpu_ms_max"].as_f64().unwrap(),
        );
        assert!(mean <= max && max <= g["query_ms_max"].as_f64().unwrap() + 1.0);
    }
    // Smoothness split by transition kind: the key-frames lie in two
    // sequences, so every path crosses at least once; the taken
    // transitions add up to the queries', and the graph's split to its
    // whole.
    let (mut total, mut across) = (0, 0);
    for q in queries {
        let (n, a) = (
            q["transitions"].as_u64().unwrap(),
            q["across"].as_u64().unwrap(),
        );
        assert!(a >= 1 && a <= n, "{q}");
        total += n;
        across += a;
    }
    let count = |k: &str| g[k]["count"].as_u64().unwrap();
    assert_eq!(count("taken_across"), across);
    assert_eq!(count("taken_within") + across, total);
    assert_eq!(
        count("graph_smoothness_within") + count("graph_smoothness_across"),
        count("graph_smoothness")
    );
    assert!(count("graph_smoothness_within") > 0 && count("graph_smoothness_across") > 0);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert_eq!(text.matches("<title>").count(), 6, "{text}");
    let q = &queries[0];
    let want = format!(
        "{} m in {} s: {:.3} m",
        q["distance"].as_f64().unwrap(),
        q["time"].as_f64().unwrap(),
        q["achieved_distance"].as_f64().unwrap()
    );
    assert!(text.contains(&want), "{want} not in the SVG");
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    // 2 time columns × 3 distance rows of 8 pixels (IHDR width, height).
    assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 16);
    assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 24);
    // Bad input: one line on stderr, exit 1.
    let x = tmp.path().join("x.pc2");
    let bad_with = |args: &[&str], env: &[(&str, &str)], want: &[&str]| {
        let mut a: Vec<&std::ffi::OsStr> =
            vec!["keyframe".as_ref(), "--db".as_ref(), db.as_os_str()];
        a.extend(args.iter().map(|s| std::ffi::OsStr::new(*s)));
        a.extend(["-o".as_ref(), x.as_os_str()]);
        common::run_cli(&a, None, env).assert_bad_input(&format!("{args:?}"), want);
        assert!(!x.exists(), "{args:?}: nothing written");
    };
    let bad = |args: &[&str], want: &str| bad_with(args, &[], &[want]);
    bad(
        &[
            "--from",
            "nope:0",
            "--to",
            "02_03:30",
            "--distance",
            "1",
            "--time",
            "1",
        ],
        "no sequence 'nope'",
    );
    bad(
        &[
            "--from",
            "02_01:9999",
            "--to",
            "02_03:30",
            "--distance",
            "1",
            "--time",
            "1",
        ],
        "frames (0 to",
    );
    // Frame 0 of a sequence is entered by no transition (they land on n+1).
    bad(
        &[
            "--from",
            "02_03:5",
            "--to",
            "02_01:0",
            "--distance",
            "1",
            "--time",
            "1",
        ],
        "no path from key-frame 02_03:5 to 02_01:0",
    );
    bad(
        &[
            "--from",
            "02_01:0",
            "--to",
            "02_03:30",
            "--distance",
            "-1",
            "--time",
            "1",
        ],
        "distance -1",
    );
    bad(
        &[
            "--from",
            "02_01:0",
            "--to",
            "02_03:30",
            "--distance",
            "1",
            "--time",
            "NaN",
        ],
        "time NaN",
    );
    // A heading that is no number made every cost NaN, with exit 0; it is
    // now a usage error (clap's: the reason, then a pointer to --help).
    let to_run = ["--from", "02_01:0", "--to", "02_03:30"];
    bad_with(
        &[
            &to_run[..],
            &["--distance", "1", "--time", "1", "--heading", "nan"],
        ]
        .concat(),
        &[],
        &["--heading", "expected a finite number"],
    );
    // A far-out-of-range target gives a long compromise path; one longer
    // than the memory budget is refused before any mesh is built (it ran
    // for minutes and gigabytes, unchecked) when the output holds every
    // frame (a GLB); a point cache streams it (s15).
    let glb = tmp.path().join("x.glb");
    let mut a: Vec<&std::ffi::OsStr> = vec!["keyframe".as_ref(), "--db".as_ref(), db.as_os_str()];
    a.extend(
        [&to_run[..], &["--distance", "1000", "--time", "4", "-o"]]
            .concat()
            .iter()
            .map(|s| std::ffi::OsStr::new(*s)),
    );
    a.push(glb.as_os_str());
    common::run_cli(&a, None, &[("SURFMOTION_MEMORY_LIMIT", "8MB")])
        .assert_bad_input("a long path to a GLB", &["a GLB of", "would need"]);
    assert!(!glb.exists());
}

/// The largest distance between output frame `out` and database frame
/// `db` moved by the floor motion (rotation about the vertical, then a
/// floor translation) that best maps it there, and that rotation (radians,
/// `x + iz` sense: the opposite of `rotate_yaw`'s).
fn placed_residual(out: &[[f64; 3]], db: &[[f64; 3]]) -> (f64, f64) {
    let centre = |p: &[[f64; 3]]| {
        let n = p.len() as f64;
        let s = p.iter().fold([0.0; 2], |s, q| [s[0] + q[0], s[1] + q[2]]);
        [s[0] / n, s[1] / n]
    };
    let (co, cd) = (centre(out), centre(db));
    // b ≈ w a for a, b as x + iz about their centres: w = Σ b conj(a).
    let (mut re, mut im) = (0.0, 0.0);
    for (o, a) in out.iter().zip(db) {
        let (ax, az, bx, bz) = (a[0] - cd[0], a[2] - cd[1], o[0] - co[0], o[2] - co[1]);
        re += bx * ax + bz * az;
        im += bz * ax - bx * az;
    }
    let th = im.atan2(re);
    let (c, s) = (th.cos(), th.sin());
    let worst = out.iter().zip(db).fold(0.0f64, |m, (o, a)| {
        let (ax, az) = (a[0] - cd[0], a[2] - cd[1]);
        let (x, z) = (c * ax - s * az + co[0], s * ax + c * az + co[1]);
        m.max(((o[0] - x).powi(2) + (o[1] - a[1]).powi(2) + (o[2] - z).powi(2)).sqrt())
    });
    (worst, th)
}

/// `keyframe` with one and with two `--via` key-frames (the second with a
/// heading target), blended and with `--no-blend`: the written file lasts
/// the time and travels the distance the report gives, in total and per
/// segment (between the output frames of consecutive key-frames); the
/// output frame at every key-frame position is that key-frame's database
/// frame, placed (moved rigidly on the floor), so the output passes every
/// via in order. A blended output is checked at the key-frames outside
/// every transition's blend window (inside one the frame is a blend); the
/// unblended output at all of them, and its final rotation is the report's
/// final heading.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn cli_output_with_vias_passes_every_key_frame_in_the_written_file() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let db = walk_run_db(&d);
    let ch = surfmotion::db::Character::load(db, &surfmotion::db::Quiet).unwrap();
    let queries: [(&[&str], &str, &str, Option<&str>); 2] = [
        (&["02_03:20"], "6", "4", None),
        (&["02_03:20", "02_01:40"], "10", "7", Some("45")),
    ];
    let mut free_vias = 0;
    for (qi, (vias, dist, time, heading)) in queries.iter().enumerate() {
        for blend in [true, false] {
            let name = format!("q{qi}{}", if blend { "" } else { "n" });
            let out = tmp.path().join(format!("{name}.pc2"));
            let report = tmp.path().join(format!("{name}.json"));
            let mut a: Vec<std::ffi::OsString> = Vec::new();
            for v in vias.iter() {
                a.extend(["--via".into(), v.into()]);
            }
            a.extend(["--distance".into(), dist.into()]);
            a.extend(["--time".into(), time.into()]);
            if let Some(h) = heading {
                a.extend(["--heading".into(), h.into()]);
            }
            if !blend {
                a.push("--no-blend".into());
            }
            a.extend(["-o".into(), out.clone().into_os_string()]);
            a.extend(["--report".into(), report.clone().into_os_string()]);
            let a: Vec<&std::ffi::OsStr> = a.iter().map(|x| x.as_os_str()).collect();
            let o = walk_to_run(db, &a);
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            let r: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
            let seq =
                surfmotion::mesh::io::load_sequence(out.to_str().unwrap(), &Default::default())
                    .unwrap();
            let n = seq.mesh().vertex_count();
            let pos = seq.all_positions();
            let fps = r["fps"].as_f64().unwrap();
            assert_eq!(seq.frame_count(), r["frames"].as_u64().unwrap() as usize);
            assert!((seq.frame_count() as f64 / fps - r["time"].as_f64().unwrap()).abs() < 1e-9);
            let travelled = surfmotion::keyframe::graph::travelled(pos, n);
            let want = r["distance"].as_f64().unwrap();
            assert!(
                (travelled - want).abs() < 1e-4,
                "{name}: file {travelled} m, report {want} m"
            );
            // The key-frames in order and their output frames: the first
            // segment counts its start frame, later ones share it.
            let keys: Vec<&str> = r["keys"]
                .as_array()
                .unwrap()
                .iter()
                .map(|k| k.as_str().unwrap())
                .collect();
            let want_keys: Vec<&str> = std::iter::once("02_01:0")
                .chain(vias.iter().copied())
                .chain(std::iter::once("02_03:30"))
                .collect();
            assert_eq!(keys, want_keys, "{name}");
            let segs = r["segments"].as_array().unwrap();
            assert_eq!(segs.len(), keys.len() - 1, "{name}");
            let windows: Vec<(usize, usize)> = r["transitions"]
                .as_array()
                .unwrap()
                .iter()
                .map(|t| {
                    let (k, l) = (t["at"].as_u64().unwrap(), t["window"].as_u64().unwrap());
                    (k.saturating_sub(l) as usize, (k + l) as usize)
                })
                .collect();
            let in_window = |p: usize| windows.iter().any(|&(lo, hi)| lo <= p && p < hi);
            // Each segment travels its reported distance in the file. A
            // blended transition eases the floor speed over its window,
            // keeping the window's path length: a key-frame inside a
            // window moves distance between its two segments, so those
            // are checked together.
            let mut at = vec![0usize];
            let (mut first, mut want) = (0usize, 0.0);
            for (i, s) in segs.iter().enumerate() {
                assert_eq!(s["from"], keys[i], "{name}");
                assert_eq!(s["to"], keys[i + 1], "{name}");
                let frames = (s["time"].as_f64().unwrap() * fps).round() as usize;
                at.push(at[i] + frames - usize::from(i == 0));
                want += s["distance"].as_f64().unwrap();
                if blend && i + 1 < segs.len() && in_window(at[i + 1]) {
                    continue;
                }
                let span = &pos[at[first] * n..(at[i + 1] + 1) * n];
                let got = surfmotion::keyframe::graph::travelled(span, n);
                assert!(
                    (got - want).abs() < 1e-4,
                    "{name} segments {first}..={i}: file {got} m, report {want} m"
                );
                (first, want) = (i + 1, 0.0);
            }
            assert_eq!(*at.last().unwrap() + 1, seq.frame_count(), "{name}");
            let mut turns = Vec::new();
            for (i, (&k, &p)) in keys.iter().zip(&at).enumerate() {
                let blended = in_window(p);
                if blend && blended {
                    continue;
                }
                let id = surfmotion::keyframe::parse_key(&ch, k).unwrap();
                let (res, th) = placed_residual(&pos[p * n..(p + 1) * n], ch.frame(id));
                assert!(
                    res < 1e-4,
                    "{name}: output frame {p} is not key-frame {k} placed ({res} m off)"
                );
                turns.push(th);
                if blend && i > 0 && i + 1 < keys.len() {
                    free_vias += 1;
                }
            }
            if !blend {
                assert_eq!(turns.len(), keys.len(), "{name}");
                let fitted = -(turns[turns.len() - 1] - turns[0]).to_degrees();
                let report = r["final_heading_deg"].as_f64().unwrap();
                assert!(
                    wrap_deg(fitted - report).abs() < 0.01,
                    "{name}: the file turns {fitted}°, the report {report}°"
                );
            }
            if let Some(h) = heading {
                let h: f64 = h.parse().unwrap();
                assert_eq!(r["heading_target_deg"].as_f64(), Some(h));
                let facing = r["final_facing_deg"].as_f64().unwrap();
                let err = r["heading_error_deg"].as_f64().unwrap();
                assert!((wrap_deg(facing - h) - err).abs() < 1e-9, "{name}");
                // The default weight, 1/30 per degree.
                let term = r["cost"]["heading"].as_f64().unwrap();
                assert!(
                    (term - err.abs() / 30.0).abs() < 1e-9,
                    "{name}: {term}, {err}°"
                );
            }
        }
    }
    // A via outside every blend window was checked in a blended output.
    assert!(
        free_vias >= 1,
        "{free_vias} vias checked in the blended outputs"
    );
}

/// Every distinct (distance, cheapest transition cost) of the paths of
/// exactly `frames` frames (start counted) from `from` to `to` whose
/// transitions are at least `min_run` frames apart: the exhaustive
/// programme the lattice search bins (frame level, no pruning).
fn all_exact_length(
    g: &KeyGraph,
    from: FlatFrame,
    to: FlatFrame,
    frames: usize,
    min_run: u32,
) -> Vec<(f64, f64)> {
    use std::collections::HashMap;
    // (frame, frames since the last transition, capped) -> labels.
    let mut layer: HashMap<(FlatFrame, u32), Vec<(f64, f64)>> = HashMap::new();
    layer.insert((from, min_run), vec![(0.0, 0.0)]);
    for _ in 1..frames {
        let mut next: HashMap<(FlatFrame, u32), Vec<(f64, f64)>> = HashMap::new();
        for (&(f, since), labels) in &layer {
            for e in g.successors(f) {
                if e.jump && since < min_run {
                    continue;
                }
                let s2 = if e.jump { 1 } else { (since + 1).min(min_run) };
                let row = next.entry((e.to, s2)).or_default();
                for &(d, c) in labels {
                    row.push((d + g.step_of(e.to), c + e.cost));
                }
            }
        }
        for row in next.values_mut() {
            row.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
            row.dedup_by(|a, b| (a.0 - b.0).abs() < 1e-9);
        }
        layer = next;
    }
    let mut out: Vec<(f64, f64)> = layer
        .into_iter()
        .filter(|((f, _), _)| *f == to)
        .flat_map(|(_, v)| v)
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    out.dedup_by(|a, b| (a.0 - b.0).abs() < 1e-9);
    out
}

#[test]
fn exact_length_search_matches_an_exhaustive_search_on_random_graphs() {
    // Targets drawn between the least and the most distance of the paths
    // of exactly N frames: the lattice search must land within 1 % at N
    // frames whenever some path does, and never report a cost below the
    // exhaustive optimum.
    let mut r = Lcg(23);
    let (mut compared, mut within) = (0, 0);
    let o = SearchOptions::default();
    let w = o.weights;
    for case in 0..400 {
        let g = random_graph(&mut r, 3, 16);
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        let Ok(p) = Planner::new(g.clone(), &[a, b], 25.0, &o) else {
            continue;
        };
        let frames = 30 + r.below(50);
        let all = all_exact_length(&g, a, b, frames, o.lattice.min_run);
        if all.len() < 2 {
            continue;
        }
        let lo = all.first().unwrap().0;
        let hi = all.last().unwrap().0;
        let d = lo + (hi - lo) * r.next();
        if d < 0.05 {
            continue;
        }
        let best = all
            .iter()
            .map(|&(x, c)| c + w.distance * (x - d).abs())
            .fold(f64::INFINITY, f64::min);
        let lands = all.iter().any(|&(x, _)| (x - d).abs() <= 0.01 * d);
        let plan = p
            .plan(
                &Targets::Global {
                    distance: d,
                    time: frames as f64 / 25.0,
                },
                &o,
            )
            .unwrap();
        assert_eq!(
            plan.stats.exact_length, 1,
            "case {case}: lattice found nothing"
        );
        assert!(
            plan.cost.total >= best - 1e-9 || plan.measure.frames as usize != frames,
            "case {case}: cost {} below the exhaustive optimum {best}",
            plan.cost.total
        );
        if lands {
            compared += 1;
            let ok = plan.measure.frames as usize == frames
                && (plan.measure.distance - d).abs() <= 0.01 * d;
            within += usize::from(ok);
            assert!(
                plan.cost.total <= best + 0.05,
                "case {case}: cost {} vs exhaustive {best}",
                plan.cost.total
            );
        }
    }
    assert!(compared >= 20, "only {compared} cases compared");
    assert_eq!(within, compared, "{within} of {compared} landed within 1 %");
}

/// Key-frames given as skeleton poses resolve to the nearest database
/// frame by `c_skel` (Eq. 28): a pose written from a database frame
/// resolves to that frame at distance 0, a frame of the clip the database
/// was made from to that frame; unreadable poses are one-line errors with
/// exit 1.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn pose_key_frames_resolve_to_the_nearest_database_frame_and_bad_poses_exit_1() {
    let Some(d) = common::data_dir() else { return };
    let db = walk_run_db(&d);
    let tmp = tempfile::tempdir().unwrap();
    let ch = surfmotion::db::Character::load(db, &surfmotion::db::Quiet).unwrap();
    let id = surfmotion::keyframe::parse_key(&ch, "02_03:30").unwrap();
    let pose: Vec<[f64; 3]> = ch.pose(id).iter().map(|p| p.to_array()).collect();
    let pose_file = tmp.path().join("pose.json");
    std::fs::write(&pose_file, serde_json::to_string(&pose).unwrap()).unwrap();
    let r = surfmotion::keyframe::pose::nearest_frame(&ch, "pose", ch.pose(id));
    assert_eq!((r.id, r.frame.as_str()), (id, "02_03:30"));
    assert!(r.distance < 1e-9, "{}", r.distance);
    let report = tmp.path().join("kf.json");
    let out = tmp.path().join("kf.pc2");
    let clip = d.join("mocap/cmu-amc/02/02_01.amc");
    let from = format!("{}:10", clip.display());
    let o = run(&[
        "keyframe".as_ref(),
        "--db".as_ref(),
        db.as_os_str(),
        "--from".as_ref(),
        from.as_ref(),
        "--to".as_ref(),
        pose_file.as_os_str(),
        "--distance".as_ref(),
        "6".as_ref(),
        "--time".as_ref(),
        "4".as_ref(),
        "--no-blend".as_ref(),
        "-o".as_ref(),
        out.as_os_str(),
        "--report".as_ref(),
        report.as_os_str(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("nearest database frame 02_03:30 (skeleton distance 0.000 m"),
        "{text}"
    );
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    assert_eq!(r["keys"][1], "02_03:30");
    assert_eq!(r["poses"][1]["frame"], "02_03:30");
    // Frame 10 of the clip the database's 02_01 was made from.
    assert_eq!(r["keys"][0], "02_01:10", "{}", r["poses"][0]);
    let bad_json = tmp.path().join("bad.json");
    std::fs::write(&bad_json, "[[0, 1, 2]]").unwrap();
    let missing = format!("{}:3", tmp.path().join("none.bvh").display());
    let past = format!("{}:100000", clip.display());
    for (key, want) in [
        (bad_json.to_str().unwrap(), "1 joints, expected 19"),
        (missing.as_str(), "none.bvh"),
        (past.as_str(), "frames at 25 fps"),
    ] {
        let o = walk_to_run(
            db,
            &[
                "--via".as_ref(),
                key.as_ref(),
                "--distance".as_ref(),
                "6".as_ref(),
                "--time".as_ref(),
                "4".as_ref(),
                "-o".as_ref(),
                out.as_os_str(),
            ],
        );
        assert_eq!(o.status.code(), Some(1), "{key}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(e.trim().lines().count(), 1, "{key}: {e}");
        assert!(e.contains(want), "{key}: {e}");
    }
}

/// `random_graph` with a random turn (±1 rad) on every transition.
fn turning_graph(r: &mut Lcg) -> KeyGraph {
    let mut g = random_graph(r, 3, 16);
    for e in g.edges.iter_mut().filter(|e| e.jump) {
        e.turn = 2.0 * r.next() - 1.0;
    }
    g
}

fn wrap_deg(x: f64) -> f64 {
    (x + 180.0).rem_euclid(360.0) - 180.0
}

/// The walks search (exact, no gap) through `keys` on `g` for `t`: the
/// plain plan, the plan with a heading target 60° past the plain plan's
/// facing (weight 1/30 per degree), and that target in degrees; `None`
/// when there is no plain plan.
fn walks_plain_and_turned_60(
    g: &KeyGraph,
    keys: &[FlatFrame],
    t: &Targets,
) -> Option<(surfmotion::keyframe::Plan, surfmotion::keyframe::Plan, f64)> {
    use surfmotion::keyframe::heading::HeadingTarget;
    use surfmotion::keyframe::options::Method;
    let o = SearchOptions {
        method: Method::Walks,
        gap: 0.0,
        ..Default::default()
    };
    let p = Planner::new(g.clone(), keys, 25.0, &o).ok()?;
    let plain = p.plan(t, &o).ok()?;
    let want = wrap_deg(plain.facing_deg + 60.0);
    let h = SearchOptions {
        heading: Some(HeadingTarget {
            degrees: want,
            weight: 1.0 / 30.0,
            sectors: 8,
        }),
        ..o
    };
    let turned = p.plan(t, &h).unwrap();
    Some((plain, turned, want))
}

/// A heading target (`--heading`) turns the final facing towards it: the
/// reported facing is the sum of the path's transition turns, and asking
/// for 60° more than the plain result's facing brings the error well
/// under 60° in most cases.
#[test]
fn heading_target_turns_the_final_facing() {
    use surfmotion::keyframe::heading::HeadingTarget;
    let mut r = Lcg(31);
    let (mut cases, mut closer, mut sum) = (0, 0, 0.0);
    for _ in 0..300 {
        let g = turning_graph(&mut r);
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        let o = SearchOptions::default();
        let Ok(p) = Planner::new(g.clone(), &[a, b], 25.0, &o) else {
            continue;
        };
        let t = Targets::Global {
            distance: 1.0 + 2.0 * r.next(),
            time: 2.0 + 2.0 * r.next(),
        };
        let Ok(plain) = p.plan(&t, &o) else { continue };
        if plain.stats.exact_length == 0 {
            continue;
        }
        let turns: f64 = plain
            .path
            .windows(2)
            .map(|w| g.edge(w[0], w[1]).unwrap().turn)
            .sum();
        assert!((wrap_deg(turns.to_degrees()) - plain.facing_deg).abs() < 1e-6);
        let want = wrap_deg(plain.facing_deg + 60.0);
        let h = SearchOptions {
            heading: Some(HeadingTarget {
                degrees: want,
                weight: 1.0 / 30.0,
                sectors: 8,
            }),
            ..o
        };
        let turned = p.plan(&t, &h).unwrap();
        let err = wrap_deg(turned.facing_deg - want).abs();
        assert!(
            (turned.cost.heading - err / 30.0).abs() < 1e-9,
            "{} vs {err}",
            turned.cost.heading
        );
        cases += 1;
        closer += usize::from(err < 30.0);
        sum += err;
    }
    // Without the heading term every error would be 60°.
    let mean = sum / cases.max(1) as f64;
    assert!(cases >= 50, "{cases} cases");
    assert!(
        mean < 45.0 && 4 * closer >= cases,
        "mean error {mean:.1}°, {closer} of {cases} within 30° of the heading target"
    );
}

/// Every distinct (distance, cheapest cost) of the paths of exactly
/// `frames` frames through `keys` in order (each via key-frame passed, the
/// path may pass it again), transitions `min_run` apart: exhaustive.
fn all_exact_length_via(
    g: &KeyGraph,
    keys: &[FlatFrame],
    frames: usize,
    min_run: u32,
) -> Vec<(f64, f64)> {
    use std::collections::HashMap;
    let last = keys.len() - 2; // stage of the last segment
    let mut layer: HashMap<(FlatFrame, u32, usize), Vec<(f64, f64)>> = HashMap::new();
    layer.insert((keys[0], min_run, 0), vec![(0.0, 0.0)]);
    for _ in 1..frames {
        let mut next: HashMap<(FlatFrame, u32, usize), Vec<(f64, f64)>> = HashMap::new();
        for (&(f, since, stage), labels) in &layer {
            for e in g.successors(f) {
                if e.jump && since < min_run {
                    continue;
                }
                let s2 = if e.jump { 1 } else { (since + 1).min(min_run) };
                let mut stages = vec![stage];
                let mut st = stage;
                while st < last && e.to == keys[st + 1] {
                    st += 1;
                    stages.push(st);
                }
                for st in stages {
                    let row = next.entry((e.to, s2, st)).or_default();
                    for &(d, c) in labels {
                        row.push((d + g.step_of(e.to), c + e.cost));
                    }
                }
            }
        }
        for row in next.values_mut() {
            row.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
            row.dedup_by(|a, b| (a.0 - b.0).abs() < 1e-9);
        }
        layer = next;
    }
    let end = *keys.last().unwrap();
    let mut out: Vec<(f64, f64)> = layer
        .into_iter()
        .filter(|((f, _, st), _)| *f == end && *st == last)
        .flat_map(|(_, v)| v)
        .collect();
    out.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    out.dedup_by(|a, b| (a.0 - b.0).abs() < 1e-9);
    out
}

/// One global target over key-frames with a via is split over the
/// segments by the exact-length search on their chain: it lands within
/// 1 % at the target's frame count whenever some path through the
/// key-frames does (the exhaustive programme), and no cost is below the
/// exhaustive optimum. The walks' split (`--search walks`) lands in fewer.
#[test]
fn one_global_target_over_via_keyframes_is_split_by_the_exact_length_search() {
    let mut r = Lcg(41);
    let (mut compared, mut within, mut walks_within) = (0, 0, 0);
    let o = SearchOptions::default();
    let walks = SearchOptions {
        method: surfmotion::keyframe::options::Method::Walks,
        ..o
    };
    let w = o.weights;
    for case in 0..900 {
        let g = random_graph(&mut r, 3, 16);
        let keys: Vec<FlatFrame> = (0..3).map(|_| ff(r.below(g.len()))).collect();
        if keys[0] == keys[1] || keys[1] == keys[2] {
            continue;
        }
        let Ok(p) = Planner::new(g.clone(), &keys, 25.0, &o) else {
            continue;
        };
        let frames = 40 + r.below(40);
        let all = all_exact_length_via(&g, &keys, frames, o.lattice.min_run);
        if all.len() < 2 {
            continue;
        }
        // A distance some path makes, so that the target is reachable.
        let d = all[r.below(all.len())].0;
        if d < 0.05 {
            continue;
        }
        let best = all
            .iter()
            .map(|&(x, c)| c + w.distance * (x - d).abs())
            .fold(f64::INFINITY, f64::min);
        let t = Targets::Global {
            distance: d,
            time: frames as f64 / 25.0,
        };
        let plan = p.plan(&t, &o).unwrap();
        let lands = |pl: &surfmotion::keyframe::Plan| {
            pl.measure.frames as usize == frames && (pl.measure.distance - d).abs() < 0.01 * d
        };
        assert!(
            plan.cost.total >= best - 1e-9 || plan.measure.frames as usize != frames,
            "case {case}: cost {} below the exhaustive optimum {best}",
            plan.cost.total
        );
        // The path passes the via key-frame and ends at the last.
        assert!(plan.path.contains(&keys[1]) && *plan.path.last().unwrap() == keys[2]);
        compared += 1;
        within += usize::from(lands(&plan));
        walks_within += usize::from(lands(&p.plan(&t, &walks).unwrap()));
    }
    assert!(compared >= 30, "only {compared} cases compared");
    assert_eq!(within, compared, "{within} of {compared} landed within 1 %");
    assert!(
        walks_within < compared,
        "the walks' split landed in all {compared}: the test shows nothing"
    );
}

/// The reachability oracle of the grid agrees with the exhaustive
/// programme: a target is reachable (some path of exactly N frames lands
/// strictly within 1 %) exactly when the oracle finds a witness, and "out
/// of range" is never said of a reachable target.
#[test]
fn reachability_oracle_agrees_with_an_exhaustive_search() {
    use surfmotion::keyframe::lattice::{Chain, Reachability, oracle};
    use surfmotion::keyframe::segment::Target;
    let mut r = Lcg(53);
    let o = SearchOptions::default();
    let (mut yes, mut no) = (0, 0);
    for case in 0..700 {
        let g = random_graph(&mut r, 3, 16);
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        let Ok(p) = Planner::new(g.clone(), &[a, b], 25.0, &o) else {
            continue;
        };
        let frames = 30 + r.below(40);
        let all = all_exact_length(&g, a, b, frames, o.lattice.min_run);
        if all.is_empty() {
            continue;
        }
        let (lo, hi) = (all[0].0, all.last().unwrap().0);
        let d = (lo - 0.1 + (hi - lo + 0.2) * r.next()).max(0.05);
        let truth = all.iter().any(|&(x, _)| (x - d).abs() < 0.01 * d);
        let c = Chain::of(&p.segments).unwrap();
        let t = Target {
            distance: d,
            frames: frames as f64,
        };
        let said = oracle(&c, &t, 0.01, 256, o.lattice.min_run).unwrap();
        assert_eq!(
            said == Reachability::Reachable,
            truth,
            "case {case}: oracle {said:?}, exhaustive {truth} ({d} m in {frames} frames)"
        );
        if truth {
            yes += 1;
        } else {
            no += 1;
        }
    }
    assert!(yes >= 20 && no >= 20, "{yes} reachable, {no} not");
}

/// With Eq. 7's time weight made small, the plain optimum trades a time
/// error for a cheaper path; the search (`--within 1`, the default) still
/// returns a path within 1 % of both targets whenever one exists, and
/// without it (`--within 0`) it often does not.
#[test]
fn the_search_meets_both_targets_within_1pct_when_some_path_does() {
    let mut r = Lcg(61);
    let base = SearchOptions {
        weights: surfmotion::keyframe::options::Weights {
            distance: 1.0 / 0.3,
            time: 0.001,
        },
        ..Default::default()
    };
    let plain = SearchOptions {
        lattice: surfmotion::keyframe::options::LatticeOptions {
            within: 0.0,
            ..base.lattice
        },
        ..base
    };
    let (mut cases, mut met, mut plain_met) = (0, 0, 0);
    for _ in 0..300 {
        let g = random_graph(&mut r, 3, 16);
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        let Ok(p) = Planner::new(g.clone(), &[a, b], 25.0, &base) else {
            continue;
        };
        let frames = 30 + r.below(40);
        let all = all_exact_length(&g, a, b, frames, base.lattice.min_run);
        if all.is_empty() {
            continue;
        }
        let d = all[r.below(all.len())].0;
        if d < 0.05 {
            continue;
        }
        let t = Targets::Global {
            distance: d,
            time: frames as f64 / 25.0,
        };
        let ok = |pl: &surfmotion::keyframe::Plan| {
            pl.measure.frames as usize == frames && (pl.measure.distance - d).abs() < 0.01 * d
        };
        cases += 1;
        met += usize::from(ok(&p.plan(&t, &base).unwrap()));
        plain_met += usize::from(ok(&p.plan(&t, &plain).unwrap()));
    }
    assert!(cases >= 50, "{cases} cases");
    assert_eq!(met, cases, "{met} of {cases} within 1 %");
    assert!(
        plain_met < cases,
        "Eq. 7 alone met all {cases}: the test shows nothing"
    );
}

/// Every simple path of frames from `from` to `to` (depth-first).
fn simple_paths(g: &KeyGraph, from: FlatFrame, to: FlatFrame) -> Vec<Vec<FlatFrame>> {
    fn go(
        g: &KeyGraph,
        to: FlatFrame,
        path: &mut Vec<FlatFrame>,
        on: &mut [bool],
        out: &mut Vec<Vec<FlatFrame>>,
    ) {
        let u = *path.last().unwrap();
        if u == to {
            out.push(path.clone());
            return;
        }
        for e in g.successors(u) {
            if !on[e.to.index()] {
                on[e.to.index()] = true;
                path.push(e.to);
                go(g, to, path, on, out);
                path.pop();
                on[e.to.index()] = false;
            }
        }
    }
    let mut on = vec![false; g.len()];
    on[from.index()] = true;
    let mut out = Vec::new();
    go(g, to, &mut vec![from], &mut on, &mut out);
    out
}

/// Every simple cycle of frames, as frame lists (each from its least
/// frame, once).
fn simple_cycles(g: &KeyGraph) -> Vec<Vec<FlatFrame>> {
    fn go(
        g: &KeyGraph,
        v: FlatFrame,
        path: &mut Vec<FlatFrame>,
        on: &mut [bool],
        out: &mut Vec<Vec<FlatFrame>>,
    ) {
        let u = *path.last().unwrap();
        for e in g.successors(u) {
            if e.to == v {
                out.push(path.clone());
            } else if e.to > v && !on[e.to.index()] {
                on[e.to.index()] = true;
                path.push(e.to);
                go(g, v, path, on, out);
                path.pop();
                on[e.to.index()] = false;
            }
        }
    }
    let mut out = Vec::new();
    let mut on = vec![false; g.len()];
    for v in FlatFrame::all(g.len()) {
        on[v.index()] = true;
        go(g, v, &mut vec![v], &mut on, &mut out);
        on[v.index()] = false;
    }
    out
}

/// The measure of the steps of a closed (`closed`) or open frame list.
fn frames_measure(g: &KeyGraph, frames: &[FlatFrame], closed: bool) -> Tally {
    let mut m = Tally {
        frames: if closed { 0 } else { 1 },
        ..Default::default()
    };
    let mut steps: Vec<(FlatFrame, FlatFrame)> = frames.windows(2).map(|w| (w[0], w[1])).collect();
    if closed {
        steps.push((*frames.last().unwrap(), frames[0]));
    }
    for (a, b) in steps {
        let e = g.edge(a, b).unwrap();
        m.cost += e.cost;
        m.distance += g.step_of(b);
        m.frames += 1;
    }
    m
}

/// The least Eq. 16 (with the problem's heading term) over every `n`
/// whose loop frames stay within `budget`, and that `n` (exhaustive,
/// depth-first).
fn brute_counts(p: &Problem, budget: f64) -> (f64, Vec<u32>) {
    fn go(p: &Problem, i: usize, n: &mut Vec<u32>, left: f64, best: &mut (f64, Vec<u32>)) {
        if i == p.loops.len() {
            let c = p.cost(n);
            if c < best.0 {
                *best = (c, n.clone());
            }
            return;
        }
        let mut k = 0;
        loop {
            n[i] = k;
            go(p, i + 1, n, left - f64::from(k * p.loops[i].frames), best);
            k += 1;
            if f64::from(k * p.loops[i].frames) > left {
                break;
            }
        }
        n[i] = 0;
    }
    let mut best = (f64::INFINITY, Vec::new());
    go(
        p,
        0,
        &mut vec![0; p.loops.len()],
        budget.max(0.0),
        &mut best,
    );
    best
}

/// The paper's search (walks plus repeated loops, `--search walks`) with
/// its ILP repetition solver (Eqs. 23-25) finds the optimum of Eq. 13 that
/// an exhaustive search finds on small random graphs: every simple frame
/// path between the key-frames, every simple cycle sharing a frame with
/// it, every repetition count up to where the time error alone exceeds
/// the cost of none. The exact programme agrees too.
#[test]
fn walks_search_with_the_ilp_matches_brute_force_on_small_random_graphs() {
    use surfmotion::keyframe::options::{Method, Solver};
    let mut r = Lcg(53);
    let mut compared = 0;
    for case in 0..300 {
        let g = random_graph(&mut r, 2, 5);
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        if a == b {
            continue;
        }
        let (d, t) = (0.3 + 2.5 * r.next(), 0.4 + 1.6 * r.next());
        let target = Targets::Global {
            distance: d,
            time: t,
        };
        let ilp = SearchOptions {
            method: Method::Walks,
            solver: Solver::Ilp,
            gap: 0.0,
            ..Default::default()
        };
        let Ok(p) = Planner::new(g.clone(), &[a, b], 25.0, &ilp) else {
            continue;
        };
        let plan = p.plan(&target, &ilp).unwrap();
        if !plan.stats.bounds_hit.is_empty() {
            continue;
        }
        let w = ilp.weights;
        let cycles: Vec<(Vec<FlatFrame>, Tally)> = simple_cycles(&g)
            .into_iter()
            .map(|c| {
                let m = frames_measure(&g, &c, true);
                (c, m)
            })
            .collect();
        let mut best = f64::INFINITY;
        let paths = simple_paths(&g, a, b);
        assert!(!paths.is_empty(), "case {case}");
        for path in &paths {
            let walk = frames_measure(&g, path, false);
            let loops: Vec<Tally> = cycles
                .iter()
                .filter(|(c, _)| c.iter().any(|f| path.contains(f)))
                .map(|x| x.1)
                .collect();
            let pr = Problem {
                walk,
                loops: &loops,
                distance: d,
                frames: t * 25.0,
                w_dist: w.distance,
                w_time: w.time,
                heading: None,
                max_loop_frames: None,
            };
            let c0 = pr.cost(&vec![0; loops.len()]);
            let budget = pr.frames - walk.frames as f64 + (c0 - walk.cost) / w.time;
            best = best.min(brute_counts(&pr, budget).0);
        }
        assert!(
            (plan.cost.total - best).abs() < 1e-6,
            "case {case}: ilp {} brute force {best} ({a} -> {b}, {d} m, {t} s)",
            plan.cost.total
        );
        let exact = SearchOptions {
            solver: Solver::Exact,
            ..ilp
        };
        let e = p.plan(&target, &exact).unwrap();
        assert!((e.cost.total - best).abs() < 1e-6, "case {case}: exact");
        compared += 1;
    }
    assert!(compared >= 30, "only {compared} cases");
}

/// The turn of the steps of a closed (`closed`) or open frame list
/// (radians, the sum of its edges' turns).
fn frames_turn(g: &KeyGraph, frames: &[FlatFrame], closed: bool) -> f64 {
    let mut steps: Vec<(FlatFrame, FlatFrame)> = frames.windows(2).map(|w| (w[0], w[1])).collect();
    if closed {
        steps.push((*frames.last().unwrap(), frames[0]));
    }
    steps.iter().map(|&(a, b)| g.edge(a, b).unwrap().turn).sum()
}

/// With a heading target, the walks' search (exact programme and ILP)
/// finds the optimum of Eq. 13 plus the heading term that an exhaustive
/// search finds on small random graphs with turning transitions: every
/// simple path, every simple cycle sharing a frame with it, every count,
/// the path's turn the walk's plus each loop's times its count. Before,
/// the counts were Eq. 7's and the heading only chose between walks: the
/// test checks that this gives a higher cost in some cases.
#[test]
fn walks_search_with_a_heading_target_matches_brute_force_on_small_random_graphs() {
    use surfmotion::keyframe::heading::HeadingTarget;
    use surfmotion::keyframe::options::{Method, Solver};
    use surfmotion::keyframe::repeats::Turns;
    let mut r = Lcg(59);
    let (mut compared, mut worse_after) = (0, 0);
    for case in 0..200 {
        let mut g = random_graph(&mut r, 2, 5);
        for e in g.edges.iter_mut().filter(|e| e.jump) {
            e.turn = 4.0 * r.next() - 2.0;
        }
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        if a == b {
            continue;
        }
        let (d, t) = (0.3 + 2.5 * r.next(), 0.4 + 1.6 * r.next());
        let deg = 360.0 * r.next() - 180.0;
        let target = Targets::Global {
            distance: d,
            time: t,
        };
        let per_degree = 1.0 / 30.0;
        let ilp = SearchOptions {
            method: Method::Walks,
            solver: Solver::Ilp,
            gap: 0.0,
            heading: Some(HeadingTarget {
                degrees: deg,
                weight: per_degree,
                sectors: 8,
            }),
            ..Default::default()
        };
        let Ok(p) = Planner::new(g.clone(), &[a, b], 25.0, &ilp) else {
            continue;
        };
        let plan = p.plan(&target, &ilp).unwrap();
        if !plan.stats.bounds_hit.is_empty() {
            continue;
        }
        let w = ilp.weights;
        let cycles: Vec<(Vec<FlatFrame>, Tally, f64)> = simple_cycles(&g)
            .into_iter()
            .map(|c| {
                let m = frames_measure(&g, &c, true);
                let turn = frames_turn(&g, &c, true);
                (c, m, turn)
            })
            .collect();
        let (mut best, mut after) = (f64::INFINITY, f64::INFINITY);
        let paths = simple_paths(&g, a, b);
        assert!(!paths.is_empty(), "case {case}");
        for path in &paths {
            let walk = frames_measure(&g, path, false);
            let near: Vec<&(Vec<FlatFrame>, Tally, f64)> = cycles
                .iter()
                .filter(|(c, _, _)| c.iter().any(|f| path.contains(f)))
                .collect();
            let loops: Vec<Tally> = near.iter().map(|x| x.1).collect();
            let turns: Vec<f64> = near.iter().map(|x| x.2).collect();
            let pr = Problem {
                walk,
                loops: &loops,
                distance: d,
                frames: t * 25.0,
                w_dist: w.distance,
                w_time: w.time,
                heading: Some(Turns {
                    offset: frames_turn(&g, path, false) - deg.to_radians(),
                    loops: &turns,
                    weight: per_degree.to_degrees(),
                }),
                max_loop_frames: None,
            };
            let c0 = pr.cost(&vec![0; loops.len()]);
            let budget = pr.frames - walk.frames as f64 + (c0 - walk.cost) / w.time;
            best = best.min(brute_counts(&pr, budget).0);
            // Eq. 7's own counts, the heading added afterwards.
            let plain = Problem {
                heading: None,
                max_loop_frames: None,
                ..pr.clone()
            };
            let c0 = plain.cost(&vec![0; loops.len()]);
            let budget = pr.frames - walk.frames as f64 + (c0 - walk.cost) / w.time;
            after = after.min(pr.cost(&brute_counts(&plain, budget).1));
        }
        assert!(
            (plan.cost.total - best).abs() < 1e-6,
            "case {case}: ilp {} brute force {best} ({a} -> {b}, {d} m, {t} s, {deg}°)",
            plan.cost.total
        );
        let exact = SearchOptions {
            solver: Solver::Exact,
            ..ilp
        };
        let e = p.plan(&target, &exact).unwrap();
        assert!(
            (e.cost.total - best).abs() < 1e-6,
            "case {case}: exact {} brute force {best}",
            e.cost.total
        );
        assert!(after >= best - 1e-9, "case {case}");
        worse_after += usize::from(after > best + 1e-6);
        compared += 1;
    }
    assert!(compared >= 30, "only {compared} cases");
    assert!(
        worse_after >= 3,
        "the joint optimum beat Eq. 7's counts in only {worse_after} of {compared} cases"
    );
}

/// Key-frames with two vias: the path starts and ends at the key-frames,
/// passes both vias in order (each segment ends at its key-frame), every
/// step is an edge of the graph and the measures are the path's, with the
/// exact-length search and with the walks (each way of building a
/// segment's path).
#[test]
fn paths_pass_two_vias_in_order_with_either_search() {
    use surfmotion::keyframe::options::Method;
    let mut r = Lcg(61);
    let mut checked = [0usize; 2];
    for case in 0..60 {
        let g = random_graph(&mut r, 3, 18);
        let keys: Vec<FlatFrame> = (0..4).map(|_| ff(r.below(g.len()))).collect();
        let o = SearchOptions::default();
        let Ok(p) = Planner::new(g.clone(), &keys, 25.0, &o) else {
            continue;
        };
        for (mi, method) in [Method::Lattice, Method::Walks].into_iter().enumerate() {
            let o = SearchOptions { method, ..o };
            for targets in [
                Targets::Global {
                    distance: 4.0,
                    time: 5.0,
                },
                Targets::PerSegment(vec![(1.0, 1.5), (2.0, 2.5), (1.5, 2.0)]),
            ] {
                let Ok(plan) = p.plan(&targets, &o) else {
                    continue;
                };
                assert_eq!(plan.path[0], keys[0], "case {case}");
                assert_eq!(*plan.path.last().unwrap(), keys[3], "case {case}");
                assert_eq!(plan.segments.len(), 3);
                for (i, s) in plan.segments.iter().enumerate() {
                    assert_eq!((s.from, s.to), (keys[i], keys[i + 1]), "case {case}");
                    assert_eq!(s.path[0], keys[i], "case {case}");
                    assert_eq!(*s.path.last().unwrap(), keys[i + 1], "case {case}");
                    // The walk with its loops is the segment's path.
                    let loop_frames: usize = s
                        .loops
                        .iter()
                        .map(|l| l.frames.len() * l.repeats as usize)
                        .sum();
                    assert_eq!(s.walk.len() + loop_frames, s.path.len(), "case {case}");
                }
                assert_walks_the_graph(&g, &plan, case);
                checked[mi] += 1;
            }
        }
    }
    assert!(checked[0] > 10 && checked[1] > 10, "{checked:?} cases");
}

/// The heading term (`--heading`) counts in the walks-and-loops search
/// too (the fallback of the exact-length search): with the heading
/// target 60° off the plain result's facing, the path found costs no more
/// under Eq. 7 plus the heading term than the plain one (whose facing
/// misses by 60°), and the facing error drops on average. Before, the
/// walks ignored the target and every error stayed 60°.
#[test]
fn heading_target_counts_in_the_walks_search() {
    let mut r = Lcg(67);
    let (mut cases, mut sum) = (0, 0.0);
    for case in 0..200 {
        let g = turning_graph(&mut r);
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        let t = Targets::Global {
            distance: 1.0 + 2.0 * r.next(),
            time: 2.0 + 2.0 * r.next(),
        };
        let Some((plain, turned, want)) = walks_plain_and_turned_60(&g, &[a, b], &t) else {
            continue;
        };
        assert_eq!(turned.stats.exact_length, 0, "case {case}");
        let err = wrap_deg(turned.facing_deg - want).abs();
        assert!(
            (turned.cost.heading - err / 30.0).abs() < 1e-9,
            "case {case}"
        );
        let plain_total = plain.cost.total + 60.0 / 30.0;
        assert!(
            turned.cost.total <= plain_total + 1e-9,
            "case {case}: {} > {plain_total}",
            turned.cost.total
        );
        cases += 1;
        sum += err;
    }
    let mean = sum / cases.max(1) as f64;
    assert!(cases >= 50, "{cases} cases");
    assert!(
        mean < 50.0,
        "mean facing error {mean:.1}° over {cases} cases"
    );
}

/// The walks' split over several segments with a heading target: the
/// same rule, the turn summed over the segments.
#[test]
fn heading_target_counts_in_the_walks_split_over_vias() {
    let mut r = Lcg(71);
    let (mut cases, mut lower) = (0, 0);
    for case in 0..150 {
        let g = turning_graph(&mut r);
        let keys: Vec<FlatFrame> = (0..3).map(|_| ff(r.below(g.len()))).collect();
        let t = Targets::Global {
            distance: 2.0 + 2.0 * r.next(),
            time: 3.0 + 2.0 * r.next(),
        };
        let Some((plain, turned, _)) = walks_plain_and_turned_60(&g, &keys, &t) else {
            continue;
        };
        let plain_total = plain.cost.total + 60.0 / 30.0;
        assert!(
            turned.cost.total <= plain_total + 1e-9,
            "case {case}: {} > {plain_total}",
            turned.cost.total
        );
        cases += 1;
        lower += usize::from(turned.cost.total < plain_total - 1e-9);
    }
    assert!(cases >= 30, "{cases} cases");
    assert!(lower * 5 >= cases, "{lower} of {cases} improved");
}

/// The relaxation of a union of loop sets merged from each set's hull is
/// the relaxation of all the loops (the walks' split relies on it).
#[test]
fn merged_cones_equal_the_cone_of_all_loops() {
    use surfmotion::keyframe::repeats::{cone, cone_gap, merge_cones};
    let mut r = Lcg(73);
    let mut buf = Vec::new();
    for case in 0..300 {
        let sets: Vec<Vec<Tally>> = (0..1 + r.below(3))
            .map(|_| {
                let mut v = Vec::new();
                random_problem(&mut r, &mut v);
                v
            })
            .collect();
        let all: Vec<Tally> = sets.iter().flatten().copied().collect();
        let cones: Vec<_> = sets.iter().map(|s| cone(s).unwrap()).collect();
        let merged = merge_cones(cones.iter(), &mut buf).unwrap();
        let direct = cone(&all).unwrap();
        assert_eq!(merged, direct, "case {case}");
        let (qd, qt) = (3.0 * r.next() - 0.5, 60.0 * r.next() - 5.0);
        assert_eq!(
            cone_gap(qd, qt, Some(&merged), 3.0, 0.1),
            cone_gap(qd, qt, Some(&direct), 3.0, 0.1)
        );
    }
}

/// The exact-length extremes a chain keeps across queries are the table
/// computed afresh, however far earlier queries grew it.
#[test]
fn extremes_kept_across_queries_equal_a_fresh_table() {
    use surfmotion::keyframe::lattice::chain_extremes;
    let mut r = Lcg(79);
    let mut checked = 0;
    for _ in 0..400 {
        let g = random_graph(&mut r, 3, 16);
        let keys: Vec<FlatFrame> = (0..3).map(|_| ff(r.below(g.len()))).collect();
        let o = SearchOptions::default();
        let Ok(p) = Planner::new(g, &keys, 25.0, &o) else {
            continue;
        };
        let Some(c) = &p.chain else { continue };
        for m in [30usize, 10, 70, 200, 150] {
            let kept = c.extremes(m).unwrap();
            let fresh = chain_extremes(c, m).unwrap();
            assert!(kept.frames() >= m);
            for u in 0..c.node_count() as u32 {
                for k in 0..=m {
                    let (a, b) = kept.at(u, k);
                    let (x, y) = fresh.at(u, k);
                    assert!(a == x && b == y, "node {u}, {k} frames");
                }
            }
        }
        checked += 1;
        if checked == 20 {
            break;
        }
    }
    assert!(checked == 20, "{checked}");
}

/// The smoothness measure on a real database (Sec. 6.1): a jump from a
/// frame to its own successor pairs every frame with itself, so it is 0
/// (guards the pairing `M_i(m+k)` with `M_j(n+k)`, `n = entered − 1`, and
/// the alignment); the surface distance never exceeds the vertex-set one;
/// and the transitions re-chosen by measured distortion carry exactly the
/// smoothness the reports measure for them, with windows in range.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn smoothness_is_zero_on_identical_overlaps_and_measured_transitions_report_their_cost() {
    use surfmotion::keyframe::select::{SelectOptions, measured};
    use surfmotion::keyframe::smoothness::{transition_smoothness, transition_smoothness_both};
    let Some(d) = common::data_dir() else { return };
    let ch = surfmotion::db::Character::load(walk_run_db(&d), &surfmotion::db::Quiet).unwrap();
    let f = surfmotion::keyframe::parse_key(&ch, "02_01:40").unwrap();
    assert_eq!(transition_smoothness(&ch, f, f.next(), 4), 0.0);
    for t in ch.graph().transitions().iter().take(2) {
        let a = ch.graph().flat_id(t.from, t.m);
        let b = ch.graph().flat_id(t.to, t.n).next();
        let s = transition_smoothness_both(&ch, a, b, t.window);
        assert!(s.surface > 0.0 && s.surface <= s.vertex + 1e-12, "{s:?}");
    }
    // The grid's cache of frame pairs (measured once, prefilled in
    // parallel) gives the direct measure, at the graph's window and at
    // the shorter windows the timeline gives close transitions.
    let mut cache = surfmotion::keyframe::smoothness::Measurer::new(&ch);
    let jumps = surfmotion::keyframe::grid::graph_jumps(
        &ch,
        &surfmotion::keyframe::graph::KeyGraph::of_character(&ch),
    );
    cache.prefill(&ch, &jumps[..3.min(jumps.len())]);
    let filled = cache.len();
    assert!(filled > 0);
    for &(a, b, l) in jumps.iter().take(3) {
        for w in [l, l.saturating_sub(2).max(1)] {
            assert_eq!(
                cache.transition(&ch, a, b, w),
                transition_smoothness_both(&ch, a, b, w),
                "{a} -> {b}, window {w}"
            );
        }
    }
    assert_eq!(cache.len(), filled, "shorter windows reuse the pairs");
    // Fewer candidates and shorter windows than the defaults: the same
    // code, in a few seconds.
    let opts = SelectOptions {
        candidates: 6,
        stride: 16,
        max_window: 6,
    };
    let chosen = measured(&ch, &opts);
    assert!(!chosen.is_empty());
    let lo = ch.graph().options().min_window;
    for c in &chosen {
        assert!((lo..=opts.max_window).contains(&c.window), "{c:?}");
        let (sa, _) = ch.graph().frame_of(c.from);
        let (sb, _) = ch.graph().frame_of(c.to.prev().unwrap());
        assert!(
            ch.graph()
                .edges()
                .iter()
                .any(|e| e.from == sa && e.to == sb)
        );
        let s = transition_smoothness(&ch, c.from, c.to, c.window);
        assert!((s - c.smoothness).abs() < 1e-12, "{c:?} measures {s}");
    }
}

/// A target far out of reach (1000 m in 3 s) gets Eq. 7's best compromise
/// within the horizon (`options::Horizon`: here max(2 × 75, 75 + 250) = 325
/// frames), flagged by its error, from either search: before the horizon
/// the exact-length search returned a path of thousands of frames (Eq. 7
/// trades 0.1 per frame of time error for up to 0.3 per frame of distance
/// gained) and the walks' search ran for minutes on the README's
/// database. The compromise travels no farther than the most any path
/// within the horizon can, and `Planner::reach_of` says the distance is
/// out of reach.
#[test]
fn a_far_target_gets_the_best_compromise_within_the_horizon() {
    use surfmotion::keyframe::options::Method;
    let mut r = Lcg(29);
    let mut checked = 0;
    for case in 0..40 {
        let g = random_graph(&mut r, 3, 16);
        let from = ff(r.below(g.len()));
        let to = ff(r.below(g.len()));
        let Ok(p) = Planner::new(g, &[from, to], 25.0, &SearchOptions::default()) else {
            continue;
        };
        let (distance, time) = (1000.0, 3.0);
        let o = SearchOptions::default();
        let horizon = o.horizon.frames(time * 25.0);
        assert_eq!(horizon, 325.0);
        let Some(reach) = p.reach_of(distance, time, &o) else {
            continue;
        };
        assert!(reach.min_time.is_none(), "case {case}: {reach:?}");
        let most = reach.max_in_horizon.expect("a path within the horizon");
        assert!(most < 0.99 * distance);
        for method in [Method::Lattice, Method::Walks] {
            let o = SearchOptions { method, ..o };
            let plan = p
                .plan(&Targets::Global { distance, time }, &o)
                .unwrap_or_else(|e| panic!("case {case} {method:?}: {e}"));
            let frames = plan.path.len() as f64;
            assert!(
                frames <= horizon,
                "case {case} {method:?}: {frames} frames past the horizon {horizon}"
            );
            assert!(plan.measure.distance <= most + 1e-9);
            // Flagged: the distance misses by far more than 1 %.
            assert!((plan.measure.distance - distance).abs() > 0.01 * distance);
        }
        checked += 1;
    }
    assert!(checked >= 10, "only {checked} connected cases");
}

/// As `random_graph`, with transitions dear enough (0.05-0.5) for the
/// cost pruning of the exact-length search to bite.
fn random_dear_graph(r: &mut Lcg, seqs: usize, jumps: usize) -> KeyGraph {
    random_graph_costing(r, seqs, jumps, 0.05, 0.45)
}

/// The cost pruning of the exact-length search (a frame count or a label
/// whose least cost to the goal reaches the best total so far is not
/// searched further) returns what the unpruned search returns, on random
/// graphs with dear transitions; the programme under a cap just above its
/// own result's cost returns that result, the least cost to the goal
/// bounds it, and a cap just below it changes the outcome in some cases
/// (the pruning does cut labels here, so the comparison is not vacuous).
#[test]
fn cost_pruning_keeps_the_unpruned_result_on_random_graphs() {
    use surfmotion::keyframe::lattice::{solve_capped, solve_exact_length};
    use surfmotion::keyframe::options::LatticeOptions;
    let mut r = Lcg(97);
    let o = SearchOptions::default();
    let off = SearchOptions {
        lattice: LatticeOptions {
            prune: false,
            ..o.lattice
        },
        ..o
    };
    let (mut compared, mut found, mut bit) = (0, 0, 0);
    for case in 0..300 {
        let g = random_dear_graph(&mut r, 3, 16);
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        let Ok(p) = Planner::new(g.clone(), &[a, b], 25.0, &o) else {
            continue;
        };
        for _ in 0..4 {
            let t = Targets::Global {
                distance: 0.2 + 3.0 * r.next(),
                time: 0.6 + 2.4 * r.next(),
            };
            match (p.plan(&t, &o), p.plan(&t, &off)) {
                (Ok(x), Ok(y)) => {
                    assert_eq!(x.path, y.path, "case {case} {t:?}");
                    assert_eq!(x.measure, y.measure, "case {case} {t:?}");
                    assert_eq!(x.cost, y.cost, "case {case} {t:?}");
                    found += usize::from(x.stats.exact_length > 0);
                }
                (Err(x), Err(y)) => assert_eq!(x, y, "case {case}"),
                (x, y) => panic!("case {case} {t:?}: {x:?} against {y:?}"),
            }
            compared += 1;
        }
        let Some(c) = &p.chain else { continue };
        let frames = 30 + r.below(50);
        let ext = c.extremes(frames).unwrap();
        let (lo, hi) = ext.at(c.start_node(), frames);
        if !lo.is_finite() {
            continue;
        }
        let d = lo + (hi - lo) * r.next();
        let (tol, wd, lat) = (0.02 * d + 0.01, 1.0 / 0.3, o.lattice);
        let Some((f, _)) = solve_exact_length(c, &ext, frames, d, tol, wd, None, &lat) else {
            continue;
        };
        let cost = f.measure.cost;
        assert!(ext.least_cost(c.start_node(), frames) <= cost + 1e-12);
        let same = solve_capped(c, &ext, frames, d, tol, wd, None, &lat, cost + 1e-9);
        assert_eq!(same.map(|x| x.0), Some(f.clone()), "case {case}");
        let below = solve_capped(c, &ext, frames, d, tol, wd, None, &lat, cost - 1e-6);
        bit += usize::from(below.is_none_or(|x| x.0 != f));
    }
    eprintln!("{compared} searches compared ({found} by the programme), pruning bit {bit} times");
    assert!(compared >= 400 && found >= 100, "{compared} / {found}");
    assert!(bit >= 20, "a cap below the optimum changed {bit} results");
}

/// The probe (a programme with fewer bins whose path caps the full one,
/// `LatticeOptions::probe_bins`, with a heading target): on random graphs
/// whose transitions turn (dear transitions, so that the caps bite, and
/// the cheap ones of `random_graph`) every query's Eq. 7 total is at most
/// the search's without the probe, a query that search meets within 1 %
/// is met, and where the paths differ the probe's is cheaper (the full
/// programme's result is kept whenever it is not dearer). Without a
/// heading target the probe does not run: the same paths. (A probe that
/// made a path dearer or lost a met target fails it.)
#[test]
fn the_probe_gives_no_dearer_path_than_the_search_without_it() {
    use surfmotion::keyframe::heading::HeadingTarget;
    use surfmotion::keyframe::options::LatticeOptions;
    let mut r = Lcg(131);
    let heading = Some(HeadingTarget {
        degrees: 90.0,
        weight: 1.0 / 30.0,
        sectors: 8,
    });
    let o = SearchOptions {
        heading,
        ..Default::default()
    };
    assert!(o.lattice.probe_bins > 0);
    let off = SearchOptions {
        lattice: LatticeOptions {
            probe_bins: 0,
            ..o.lattice
        },
        ..o
    };
    let plain = |s: &SearchOptions| SearchOptions {
        heading: None,
        ..*s
    };
    let (mut compared, mut same, mut cheaper) = (0, 0, 0);
    let meets = |p: &surfmotion::keyframe::Plan, d: f64, t: f64| {
        (p.measure.distance - d).abs() < 0.01 * d
            && (f64::from(p.measure.frames) / 25.0 - t).abs() < 0.01 * t
    };
    for case in 0..300 {
        let mut g = if case % 2 == 0 {
            random_dear_graph(&mut r, 3, 16)
        } else {
            random_graph(&mut r, 3, 16)
        };
        for (k, e) in g.edges.iter_mut().filter(|e| e.jump).enumerate() {
            e.turn = [0.2, -0.4, 0.6, -0.3, 0.5][(k + case) % 5];
        }
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        let Ok(p) = Planner::new(g.clone(), &[a, b], 25.0, &o) else {
            continue;
        };
        for _ in 0..4 {
            let (d, time) = (0.2 + 3.0 * r.next(), 0.6 + 2.4 * r.next());
            let t = Targets::Global { distance: d, time };
            match (p.plan(&t, &o), p.plan(&t, &off)) {
                (Ok(x), Ok(y)) => {
                    assert!(
                        x.cost.total <= y.cost.total + 1e-9,
                        "case {case} {t:?}: {} against {}",
                        x.cost.total,
                        y.cost.total
                    );
                    if meets(&y, d, time) {
                        assert!(meets(&x, d, time), "case {case} {t:?}: met no longer");
                    }
                    if x.path == y.path {
                        same += 1;
                    } else {
                        assert!(x.cost.total < y.cost.total + 1e-12, "case {case}");
                        cheaper += 1;
                    }
                }
                (Err(x), Err(y)) => assert_eq!(x, y, "case {case}"),
                (x, y) => panic!("case {case} {t:?}: {x:?} against {y:?}"),
            }
            if let (Ok(x), Ok(y)) = (p.plan(&t, &plain(&o)), p.plan(&t, &plain(&off))) {
                assert_eq!(x.path, y.path, "case {case} {t:?}: without a heading");
            }
            compared += 1;
        }
    }
    eprintln!("{compared} searches compared: {same} the same path, {cheaper} cheaper");
    // On these graphs the probe has not changed a path (692 of 692 equal
    // when written); on bandai9's heading query it found a cheaper one
    // (README, session 13).
    assert!(compared >= 400, "{compared} / {cheaper}");
}

/// The exact-length programme shares its larger layers among the threads
/// of the rayon pool and appends their outputs in node order: the same
/// path, measure and cost on 1, 2 and 3 threads (every layer shared here).
#[test]
fn exact_length_search_gives_the_same_path_on_any_number_of_threads() {
    let mut r = Lcg(101);
    let o = SearchOptions {
        lattice: surfmotion::keyframe::options::LatticeOptions {
            parallel_from: 1,
            ..Default::default()
        },
        ..Default::default()
    };
    let pools: Vec<rayon::ThreadPool> = [1, 2, 3]
        .into_iter()
        .map(|n| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .unwrap()
        })
        .collect();
    let mut found = 0;
    for case in 0..120 {
        let g = random_dear_graph(&mut r, 4, 30);
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        let Ok(p) = Planner::new(g.clone(), &[a, b], 25.0, &o) else {
            continue;
        };
        let t = Targets::Global {
            distance: 0.5 + 4.0 * r.next(),
            time: 1.0 + 4.0 * r.next(),
        };
        let runs: Vec<_> = pools
            .iter()
            .map(|pool| pool.install(|| p.plan(&t, &o)))
            .collect();
        for x in &runs[1..] {
            match (&runs[0], x) {
                (Ok(a), Ok(b)) => {
                    assert_eq!(a.path, b.path, "case {case}");
                    assert_eq!(a.measure, b.measure, "case {case}");
                    assert_eq!(a.cost, b.cost, "case {case}");
                }
                (Err(a), Err(b)) => assert_eq!(a, b, "case {case}"),
                (a, b) => panic!("case {case}: {a:?} against {b:?}"),
            }
        }
        found += usize::from(runs[0].as_ref().is_ok_and(|x| x.stats.exact_length > 0));
    }
    assert!(found >= 30, "only {found} paths by the exact-length search");
}

/// The exact-length programme follows a label through the nodes that
/// leave it one arc only (the frames after a transition, before another
/// may be taken, and transition heads that start no transition) instead
/// of binning it at each, and drops a label that a label of a higher
/// class (more frames since its last transition) in the same bin
/// dominates: no path is lost. On random graphs with fine bins (so that
/// binning hardly merges), both that programme and the layer-by-layer
/// one with every class apart land within the tolerance exactly when
/// some path of that length does, at the exhaustive optimum of
/// transition cost + `w_dist |D − d|` up to the bins' resolution, never
/// below it.
#[test]
fn following_one_arc_nodes_loses_no_path_against_an_exhaustive_search() {
    use surfmotion::keyframe::lattice::solve_exact_length;
    use surfmotion::keyframe::options::LatticeOptions;
    let mut r = Lcg(131);
    let (mut compared, mut landed, mut same) = (0, 0, 0);
    for case in 0..300 {
        let jumps = 6 + r.below(20);
        let g = random_graph(&mut r, 3, jumps);
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        let o = SearchOptions::default();
        let Ok(p) = Planner::new(g.clone(), &[a, b], 25.0, &o) else {
            continue;
        };
        let Some(c) = &p.chain else { continue };
        let frames = 20 + r.below(40);
        let all = all_exact_length(&g, a, b, frames, o.lattice.min_run);
        if all.len() < 2 {
            continue;
        }
        let (lo, hi) = (all[0].0, all[all.len() - 1].0);
        let d = lo + (hi - lo) * r.next();
        if d < 0.05 {
            continue;
        }
        let (tol, wd) = (0.02 * d + 0.01, 1.0 / 0.3);
        let best = all
            .iter()
            .filter(|&&(x, _)| (x - d).abs() <= tol)
            .map(|&(x, c)| c + wd * (x - d).abs())
            .fold(f64::INFINITY, f64::min);
        let ext = c.extremes(frames).unwrap();
        let mut got = Vec::new();
        for follow in [true, false] {
            let lat = LatticeOptions {
                bins: 4096,
                follow,
                dominance: follow,
                ..o.lattice
            };
            // The start frame counts: `frames − 1` arc frames.
            let f = solve_exact_length(c, &ext, frames - 1, d, tol, wd, None, &lat);
            assert_eq!(
                f.is_some(),
                best.is_finite(),
                "case {case} follow {follow}: found {f:?}, exhaustive best {best}"
            );
            if let Some((f, sc)) = f {
                assert!(
                    sc >= best - 1e-9,
                    "case {case} follow {follow}: {sc} < {best}"
                );
                assert!(
                    sc <= best + 0.01,
                    "case {case} follow {follow}: {sc} vs {best}"
                );
                assert_eq!(f.measure.frames as usize, frames - 1, "case {case}");
                got.push(sc);
            }
        }
        compared += 1;
        if let [x, y] = got[..] {
            landed += 1;
            same += usize::from((x - y).abs() < 1e-9);
        }
    }
    eprintln!("{compared} compared, {landed} landed, {same} at the same cost either way");
    assert!(compared >= 20 && landed >= 10, "{compared} / {landed}");
}

/// The reach line of a missed target never contradicts itself: it said
/// "5.000 m needs more than 14.0 s; at most 41.491 m within the horizon"
/// on the demo database (a distance no path length's range holds, though
/// longer paths travel farther). "More than the horizon" is said only of
/// a distance beyond the most any path within it travels.
#[test]
fn a_missed_targets_reach_line_does_not_contradict_itself() {
    let d = common::fixture_dir("keyframe-reach-words");
    common::run_ok(
        std::process::Command::new(common::bin())
            .arg("demo")
            .arg("-o")
            .arg(&d),
    );
    let db = d.join("database");
    let mut lines = 0;
    for distance in ["2", "5", "9", "12", "1000"] {
        let o = common::run_ok(
            std::process::Command::new(common::bin())
                .args(["keyframe", "--db"])
                .arg(&db)
                .args(["--from", "walk:0", "--to", "run:50", "--time", "4"])
                .args(["--distance", distance, "-o"])
                .arg(d.join("kf.pc2")),
        );
        let out = String::from_utf8_lossy(&o.stdout).to_string();
        let Some(line) = out.lines().find(|l| l.starts_with("reach:")) else {
            continue;
        };
        lines += 1;
        let most: f64 = line
            .rsplit("at most ")
            .next()
            .and_then(|s| s.split(' ').next())
            .and_then(|s| s.parse().ok())
            .unwrap_or_else(|| panic!("no 'at most' in {line:?}"));
        let target: f64 = distance.parse().unwrap();
        if line.contains("needs more than") {
            assert!(most < target, "{distance} m: {line}");
        } else if most >= target {
            assert!(
                line.contains("needs at least") || line.contains("none within"),
                "{distance} m: {line}"
            );
        }
    }
    assert!(
        lines >= 3,
        "only {lines} targets missed: the check saw too little"
    );
}

/// The coarse bins far from the goal (`LatticeOptions::coarse_bins`,
/// module docs of `keyframe::lattice`, "Coarse bins") against the fine
/// search (every cell keeps all its bins) on random graphs and long paths
/// (windows many times the final one): every target the fine search
/// meets within 1 % (distance and time) the coarse one meets too, and its
/// Eq. 7 total is within 0.05 of the fine one's (the bound the README
/// claims for the fine search against an exhaustive one).
#[test]
fn coarse_bins_far_from_the_goal_meet_what_the_fine_search_meets() {
    use surfmotion::keyframe::options::LatticeOptions;
    let mut r = Lcg(131);
    let coarse = SearchOptions::default();
    assert!(
        coarse.lattice.coarse_bins < coarse.lattice.bins && coarse.lattice.coarse_from.is_finite()
    );
    let fine = SearchOptions {
        lattice: LatticeOptions {
            coarse_from: f64::INFINITY,
            ..coarse.lattice
        },
        ..coarse
    };
    let (mut met, mut differ, mut worst) = (0, 0, 0.0f64);
    for _ in 0..160 {
        let g = random_graph(&mut r, 3, 24);
        let (a, b) = (ff(r.below(g.len())), ff(r.below(g.len())));
        let Ok(p) = Planner::new(g.clone(), &[a, b], 25.0, &coarse) else {
            continue;
        };
        let frames = 80 + r.below(160);
        // Speeds the graph's sequences make (0.01-0.09 m a frame).
        let d = frames as f64 * (0.012 + 0.07 * r.next());
        let t = frames as f64 / 25.0;
        let target = Targets::Global {
            distance: d,
            time: t,
        };
        let within = |pl: &surfmotion::keyframe::Plan| {
            (pl.measure.distance - d).abs() < 0.01 * d
                && (pl.measure.frames as f64 / 25.0 - t).abs() < 0.01 * t
        };
        let f = p.plan(&target, &fine).unwrap();
        let c = p.plan(&target, &coarse).unwrap();
        if f.path != c.path {
            differ += 1;
        }
        if within(&f) {
            met += 1;
            assert!(
                within(&c),
                "{d} m in {t} s: fine {:?}, coarse {:?}",
                f.measure,
                c.measure
            );
            worst = worst.max(c.cost.total - f.cost.total);
        }
    }
    eprintln!(
        "{met} met by the fine search; {differ} paths differ; coarse total at most {worst:.4} above"
    );
    assert!(met >= 30, "{met} targets met");
    assert!(
        differ >= 1,
        "no path differs: the coarse bins were not exercised"
    );
    assert!(
        worst <= 0.05,
        "coarse Eq. 7 total {worst} above the fine one"
    );
}

/// A time target longer than the longest path the exact-length search
/// considers (`LatticeOptions::max_frames`) is reported as a bound hit:
/// `--time 3600` at 25 fps (90,000 frames against 20,000) returned an
/// 800 s path and said nothing (attack run, s14). Here the cap is 100
/// frames and the target 8 s (200 frames at 25 fps); a target under the
/// cap hits no such bound.
#[test]
fn a_time_target_past_the_search_cap_is_reported_as_a_bound_hit() {
    use surfmotion::keyframe::options::LatticeOptions;
    let mut r = Lcg(41);
    let mut checked = 0;
    for _ in 0..20 {
        let g = random_graph(&mut r, 3, 16);
        let from = ff(r.below(g.len()));
        let to = ff(r.below(g.len()));
        let Ok(p) = Planner::new(g, &[from, to], 25.0, &SearchOptions::default()) else {
            continue;
        };
        let o = SearchOptions {
            lattice: LatticeOptions {
                max_frames: 100,
                ..SearchOptions::default().lattice
            },
            ..SearchOptions::default()
        };
        let capped = |time: f64| {
            p.plan(
                &Targets::Global {
                    distance: 2.0,
                    time,
                },
                &o,
            )
            .map(|plan| {
                plan.stats
                    .bounds_hit
                    .iter()
                    .any(|b| b.contains("longest path the exact-length search considers"))
            })
            .ok()
        };
        let (Some(long), Some(short)) = (capped(8.0), capped(2.0)) else {
            continue;
        };
        assert!(long, "an 8 s target past a 100-frame cap hit no bound");
        assert!(!short, "a 2 s target under the cap reported the cap");
        checked += 1;
    }
    assert!(checked >= 5, "only {checked} connected cases");
}

/// Issue 39.11, a false "no path": on a four-clip synthetic database (CMU
/// 02_01, 02_03, Bandai walk and walk-left, 30 fps) `--from 02_01:0 --to
/// 02_03:20 --distance 20 --time 10.5` exited 1 with "no sequence of
/// transitions joins them" while 10 s and 11 s were answered: the
/// exact-length search found nothing near its aim in the eight frame
/// counts it tried, and the walks' search, whose enumeration stopped
/// before reaching the goal (0 walks), had nothing to fall back on.
/// Whenever a path joins the key-frames, every target gets one (the best
/// compromise), with either search, even with the walk enumeration
/// bounded to (almost) nothing as it was on that graph.
#[test]
fn joined_key_frames_never_give_a_false_no_path() {
    use surfmotion::keyframe::options::{Limits, Method};
    let mut r = Lcg(3911);
    let bounded = Limits {
        expansions: 1,
        cycles: 8,
        ..Default::default()
    };
    let mut cases = 0;
    for case in 0..60 {
        let (seqs, jumps) = (3 + r.below(3), 10 + r.below(30));
        let g = random_graph(&mut r, seqs, jumps);
        let keys: Vec<FlatFrame> = (0..2 + r.below(2)).map(|_| ff(r.below(g.len()))).collect();
        for limits in [Limits::default(), bounded] {
            let base = SearchOptions {
                limits,
                ..Default::default()
            };
            let Ok(p) = Planner::new(g.clone(), &keys, 25.0, &base) else {
                continue;
            };
            for _ in 0..6 {
                let distance = 0.05 + 8.0 * r.next();
                let time = 0.1 + 12.0 * r.next();
                for method in [Method::Lattice, Method::Walks] {
                    let o = SearchOptions { method, ..base };
                    let t = Targets::Global { distance, time };
                    let plan = p.plan(&t, &o).unwrap_or_else(|e| {
                        panic!("case {case} {keys:?} {method:?} {distance} m {time} s: {e}")
                    });
                    assert_walks_the_graph(&g, &plan, case);
                    cases += 1;
                }
            }
        }
    }
    assert!(cases >= 200, "{cases} cases");
}

/// Issue 46.12: `--times '0:3600:0.036'` was refused as "100001 values,
/// at most 100001" (the check divided without the rounding slack of the
/// values it makes). A range is refused only above its cap, with the
/// count it would make.
#[test]
fn a_range_of_100001_values_is_not_refused_as_more_than_100001() {
    use surfmotion::keyframe::grid::{MAX_RANGE_VALUES, parse_range};
    for s in ["0:3600:0.036", "0:100000:1", "0:1:0.00001"] {
        let v = parse_range(s).unwrap_or_else(|e| panic!("{s}: {e}"));
        assert_eq!(v.len(), MAX_RANGE_VALUES, "{s}");
    }
    for (s, n) in [
        ("0:3600:0.0359", "100279 values"),
        ("0:100001:1", "100002 values"),
    ] {
        let e = parse_range(s).unwrap_err();
        assert!(e.contains(n) && e.contains("at most 100001"), "{s}: {e}");
    }
}
