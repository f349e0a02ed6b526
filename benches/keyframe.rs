//! Key-frame search alone (Huang et al. 2015, Sec. 5.1): preparing the
//! walks and loops between two key-frames, and one query (a distance and
//! time target) with the exact-length search (the default) and with the
//! paper's walks and loops alone, on a generated frame graph shaped like a walk/run/walk
//! database at 25 fps (three cyclic sequences, 72/36/162 frames, loops
//! every gait cycle and transitions between them, 42 in all, as `db build`
//! finds on the synthetic database of the README). The figures in the
//! README come from `surfmotion keyframe --grid` on real databases.
//! `heading_*`: the same graph with a turn on every transition (±0.2-0.6
//! rad) and a heading target, which the walks' search puts into each
//! walk's repetition programme (the wrap of the facing error in the
//! dominance rule of the exact programme).
//! `bandai9_*`: a graph of the one-performer database's shape (9 clips of
//! 105 frames at the speeds of the Bandai walks, runs, dash and bow, 314
//! transitions at the spread of the graph's costs, 0.0007-0.008), one
//! query of
//! 40 m in 38 s (950 frames) by the exact-length search on one thread
//! without and with the cost pruning, and on two threads (layers of 4096
//! labels or more shared); `bandai9_layered_1thread` is the programme
//! without following one-arc nodes and without the dominance across
//! classes (the search before, for a before/after in one run);
//! `bandai9_fine_1thread` keeps all 32 bins in every cell (before the
//! coarse bins far from the goal, `LatticeOptions::coarse_bins`), and
//! `bandai9_pruned_1thread` is the default search.

use criterion::Criterion;
use std::hint::black_box;
use surfmotion::graph::FlatFrame;
use surfmotion::keyframe::graph::KeyGraph;
use surfmotion::keyframe::heading::HeadingTarget;
use surfmotion::keyframe::options::{Method, SearchOptions};
use surfmotion::keyframe::{Planner, Targets};

fn graph() -> KeyGraph {
    // (frames, metres per frame, gait period in frames)
    let seqs = [(72usize, 0.055, 27usize), (36, 0.13, 19), (162, 0.05, 28)];
    let mut centre = Vec::new();
    let mut sequence = Vec::new();
    let mut start = Vec::new();
    for (s, &(len, v, _)) in seqs.iter().enumerate() {
        start.push(centre.len());
        for f in 0..len {
            centre.push([v * f as f64, 0.03 * (f as f64 * 0.23).sin()]);
            sequence.push(s as u32);
        }
    }
    let n = centre.len();
    let mut succ: Vec<Vec<(FlatFrame, f64)>> = vec![Vec::new(); n];
    for f in 0..n - 1 {
        if sequence[f] == sequence[f + 1] {
            succ[f].push((FlatFrame::from_index(f + 1), 0.0));
        }
    }
    // Loops: every gait period, both ways.
    for (s, &(len, _, p)) in seqs.iter().enumerate() {
        let mut m = 5;
        while m + p + 2 < len {
            succ[start[s] + m + p].push((FlatFrame::from_index(start[s] + m + 1), 0.001));
            succ[start[s] + m].push((FlatFrame::from_index(start[s] + m + p + 1), 0.001));
            m += p / 2 + 3;
        }
    }
    // Between sequences.
    for (a, b, m, k) in [
        (0, 1, 30, 29),
        (0, 1, 58, 29),
        (1, 0, 29, 30),
        (1, 0, 29, 58),
        (0, 2, 53, 31),
        (2, 0, 31, 53),
        (1, 2, 29, 37),
        (2, 1, 37, 29),
        (1, 2, 30, 117),
        (2, 1, 117, 30),
    ] {
        succ[start[a] + m].push((FlatFrame::from_index(start[b] + k + 1), 0.004));
    }
    KeyGraph::new(&succ, centre, sequence)
}

/// The one-performer database's shape (module docs).
fn bandai9_graph() -> KeyGraph {
    let speeds = [0.05, 0.055, 0.04, 0.035, 0.045, 0.12, 0.13, 0.16, 0.002];
    let len = 105usize;
    let mut centre = Vec::new();
    let mut sequence = Vec::new();
    for (s, &v) in speeds.iter().enumerate() {
        for f in 0..len {
            centre.push([v * f as f64, 0.03 * (f as f64 * 0.25).sin()]);
            sequence.push(s as u32);
        }
    }
    let n = centre.len();
    let mut succ: Vec<Vec<(FlatFrame, f64)>> = vec![Vec::new(); n];
    for f in 0..n - 1 {
        if sequence[f] == sequence[f + 1] {
            succ[f].push((FlatFrame::from_index(f + 1), 0.0));
        }
    }
    let mut x = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut added = 0;
    while added < 314 {
        let (a, b) = ((next() * 9.0) as usize, (next() * 9.0) as usize);
        let m = a * len + 2 + (next() * (len - 4) as f64) as usize;
        let to = b * len + 2 + (next() * (len - 4) as f64) as usize;
        if to != m + 1 && !succ[m].iter().any(|e| e.0.index() == to) {
            succ[m].push((FlatFrame::from_index(to), 0.0007 + 0.0074 * next()));
            added += 1;
        }
    }
    KeyGraph::new(&succ, centre, sequence)
}

fn main() {
    let g = graph();
    let keys = [FlatFrame::new(0), FlatFrame::new(72 + 36 + 150)];
    let o = SearchOptions::default();
    let mut c = Criterion::default().configure_from_args();
    let mut grp = c.benchmark_group("keyframe/search");
    grp.sample_size(10);
    grp.bench_function("prepare", |b| {
        b.iter(|| Planner::new(black_box(g.clone()), &keys, 25.0, &o).unwrap())
    });
    let p = Planner::new(g.clone(), &keys, 25.0, &o).unwrap();
    let walks = SearchOptions {
        method: Method::Walks,
        ..Default::default()
    };
    for ((d, t), (name, o)) in [(10.0, 8.0), (20.0, 12.0), (3.0, 30.0)]
        .into_iter()
        .flat_map(|x| [(x, ("lattice", o)), (x, ("walks", walks))])
    {
        grp.bench_function(format!("{name}_{d}m_{t}s"), |b| {
            b.iter(|| {
                p.plan(
                    black_box(&Targets::Global {
                        distance: d,
                        time: t,
                    }),
                    &o,
                )
                .unwrap()
            })
        });
    }
    // One global target over a via key-frame: the exact-length search over
    // the chain of segments, and the walks' split.
    let via = [
        FlatFrame::new(0),
        FlatFrame::new(72 + 30),
        FlatFrame::new(72 + 36 + 150),
    ];
    let pv = Planner::new(g.clone(), &via, 25.0, &o).unwrap();
    // A grid of targets over the via (distances 4-16 m by 4 m × times
    // 2-10 s by 2 s, 20 queries per iteration, some too fast for the
    // graph), as `keyframe --grid` runs it: the extremes are kept across
    // the queries.
    grp.bench_function("via_grid_20_queries", |b| {
        b.iter(|| {
            for d in [4.0, 8.0, 12.0, 16.0] {
                for t in [2.0, 4.0, 6.0, 8.0, 10.0] {
                    black_box(
                        pv.plan(
                            &Targets::Global {
                                distance: d,
                                time: t,
                            },
                            &o,
                        )
                        .unwrap(),
                    );
                }
            }
        })
    });
    for (name, o) in [("lattice", o), ("walks", walks)] {
        grp.bench_function(format!("via_{name}_10m_8s"), |b| {
            b.iter(|| {
                pv.plan(
                    black_box(&Targets::Global {
                        distance: 10.0,
                        time: 8.0,
                    }),
                    &o,
                )
                .unwrap()
            })
        });
    }
    // A heading target on a graph whose transitions turn.
    let mut turning = g.clone();
    for (k, e) in turning.edges.iter_mut().filter(|e| e.jump).enumerate() {
        e.turn = [0.2, -0.4, 0.6, -0.3, 0.5][k % 5];
    }
    let ph = Planner::new(turning, &keys, 25.0, &o).unwrap();
    let heading = Some(HeadingTarget {
        degrees: 90.0,
        weight: 1.0 / 30.0,
        sectors: 8,
    });
    for (name, o) in [("lattice", o), ("walks", walks)] {
        let o = SearchOptions { heading, ..o };
        grp.bench_function(format!("heading_{name}_10m_8s"), |b| {
            b.iter(|| {
                ph.plan(
                    black_box(&Targets::Global {
                        distance: 10.0,
                        time: 8.0,
                    }),
                    &o,
                )
                .unwrap()
            })
        });
    }
    // The one-performer database's shape (module docs).
    let pb = Planner::new(
        bandai9_graph(),
        &[FlatFrame::new(0), FlatFrame::new(6 * 105 + 100)],
        25.0,
        &o,
    )
    .unwrap();
    let unpruned = SearchOptions {
        lattice: surfmotion::keyframe::options::LatticeOptions {
            prune: false,
            ..o.lattice
        },
        ..o
    };
    // The programme as it was before following one-arc nodes and the
    // dominance across classes (module docs of `keyframe::lattice`).
    let layered = SearchOptions {
        lattice: surfmotion::keyframe::options::LatticeOptions {
            follow: false,
            dominance: false,
            ..o.lattice
        },
        ..o
    };
    // Every cell keeps all its bins (module docs, "Coarse bins").
    let fine = SearchOptions {
        lattice: surfmotion::keyframe::options::LatticeOptions {
            coarse_from: f64::INFINITY,
            ..o.lattice
        },
        ..o
    };
    for (name, o, threads) in [
        ("layered_1thread", layered, 1),
        ("fine_1thread", fine, 1),
        ("unpruned_1thread", unpruned, 1),
        ("pruned_1thread", o, 1),
        (
            "pruned_2threads",
            SearchOptions {
                lattice: surfmotion::keyframe::options::LatticeOptions {
                    parallel_from: 4096,
                    ..o.lattice
                },
                ..o
            },
            2,
        ),
    ] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        grp.bench_function(format!("bandai9_{name}_40m_38s"), |b| {
            b.iter(|| {
                pool.install(|| {
                    pb.plan(
                        black_box(&Targets::Global {
                            distance: 40.0,
                            time: 38.0,
                        }),
                        &o,
                    )
                    .unwrap()
                })
            })
        });
    }
    // Session 13: a costly target of the paper's grid (18 m in 35 s) and
    // the heading query (10 m in 38 s facing +90°, transitions turning
    // ±0.2-0.6 rad) on the same graph, with the search of session 12
    // (`before`: no probe) and the default (the probe runs with a
    // heading target only, so the 18 m query is the same search twice).
    let before = surfmotion::keyframe::options::LatticeOptions {
        probe_bins: 0,
        ..o.lattice
    };
    let mut turning9 = bandai9_graph();
    for (k, e) in turning9.edges.iter_mut().filter(|e| e.jump).enumerate() {
        e.turn = [0.2, -0.4, 0.6, -0.3, 0.5][k % 5];
    }
    let ph9 = Planner::new(
        turning9,
        &[FlatFrame::new(0), FlatFrame::new(6 * 105 + 100)],
        25.0,
        &o,
    )
    .unwrap();
    for (name, lattice) in [("before", before), ("default", o.lattice)] {
        let plain = SearchOptions { lattice, ..o };
        grp.bench_function(format!("bandai9_{name}_18m_35s"), |b| {
            b.iter(|| {
                pb.plan(
                    black_box(&Targets::Global {
                        distance: 18.0,
                        time: 35.0,
                    }),
                    &plain,
                )
                .unwrap()
            })
        });
        let headed = SearchOptions {
            lattice,
            heading,
            ..o
        };
        grp.bench_function(format!("bandai9_heading_{name}_10m_38s"), |b| {
            b.iter(|| {
                ph9.plan(
                    black_box(&Targets::Global {
                        distance: 10.0,
                        time: 38.0,
                    }),
                    &headed,
                )
                .unwrap()
            })
        });
    }
    grp.finish();
}
