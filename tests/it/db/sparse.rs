//! Issue 43: the sparse similarity (candidate pairs from a nearest-neighbour
//! index, the full measure only there) against the dense matrix on a
//! synthetic database where both run.

use crate::common;

// The first version of the shape descriptor's binning, the oracle of the
// bit-identity tests (outside the library since session 28).
use super::histogram_reference as reference;

use std::path::{Path, PathBuf};
use surfmotion::db::build::Method;
use surfmotion::db::{BuildOptions, Manifest, Quiet, build};
use surfmotion::graph::compare::agreement;
use surfmotion::similarity::PairDistance;
use surfmotion::similarity::Similarity;

/// A manifest in `to` naming the database `from`'s files (absolute paths),
/// so that each method's cache goes to a folder of its own.
fn manifest_copy(from: &Path, to: &Path) -> PathBuf {
    let mut m = Manifest::load(from).unwrap();
    m.topology = Manifest::resolve(from, &m.topology);
    for s in &mut m.sequences {
        s.path = Manifest::resolve(from, &s.path);
    }
    for p in [&mut m.rig.landmarks, &mut m.rig.parts]
        .into_iter()
        .flatten()
    {
        *p = Manifest::resolve(from, p);
    }
    std::fs::create_dir_all(to).unwrap();
    m.save(to).unwrap();
    to.to_path_buf()
}

/// Builds `db` by both methods (in copies under `tmp`) and checks the
/// sparse graph against the dense one; returns what it measured. `strict`:
/// the 95 % and a sparse transition in every ordered sequence pair
/// that has a dense one; else the line held since session 20 (85 %).
fn compare(db: &Path, tmp: &Path, strict: bool) -> String {
    let dense_dir = manifest_copy(db, &tmp.join("dense"));
    let sparse_dir = manifest_copy(db, &tmp.join("sparse"));
    let opts = |m| BuildOptions {
        method: Some(m),
        ..Default::default()
    };
    let (dm, dg, dr) = build(&dense_dir, &opts(Method::Dense), &Quiet).unwrap();
    let (sm, sg, sr) = build(&sparse_dir, &opts(Method::Sparse), &Quiet).unwrap();
    assert_eq!((dr.method, sr.method), ("dense", "sparse"));
    let (Similarity::Dense(dense), Similarity::Sparse(sparse)) = (&dm, &sm) else {
        panic!("the methods asked for")
    };
    let n = dense.len();
    assert_eq!(sparse.len(), n);
    // Every stored value is the dense matrix's, both ways.
    for a in 0..n {
        for (b, v) in sparse.row(a) {
            assert_eq!(v, dense.get(a, b as usize), "({a}, {b})");
        }
    }
    assert!(
        sr.stored_pairs < dr.stored_pairs,
        "{} of {}",
        sr.stored_pairs,
        dr.stored_pairs
    );
    let a = agreement(&dg, &sg, 0, 0.05);
    let near = agreement(&dg, &sg, 2, 0.05);
    let line = format!(
        "{n} frames: sparse stores {} of {} pairs ({:.1} %); dense {} transitions, sparse {}; found at the same frames with cost within 5 %: {} ({:.1} %); within 2 frames: {} ({:.1} %), worst cost difference {:.2} %; build {:.1} s dense, {:.1} s sparse",
        sr.stored_pairs,
        dr.stored_pairs,
        100.0 * sr.stored_pairs as f64 / dr.stored_pairs as f64,
        a.reference,
        a.compared,
        a.near_and_cost,
        100.0 * a.found(),
        near.near_and_cost,
        100.0 * near.found(),
        100.0 * near.worst_cost,
        dr.describe_seconds + dr.pairs_seconds + dr.graph_seconds,
        sr.describe_seconds + sr.pairs_seconds + sr.graph_seconds,
    );
    // Issue 43 asks for 95 % with costs within 5 %; the costs of the
    // transitions found are the dense ones exactly.
    assert!(a.found() >= if strict { 0.95 } else { 0.85 }, "{line}");
    assert!(near.worst_cost <= 0.05, "{line}");
    if !strict {
        return line;
    }
    // Every ordered sequence pair with a dense transition has a sparse one
    // (the graph keeps the best transitions of every sequence pair, also
    // of dissimilar motions: the per-pair candidates' purpose).
    for t in dg.transitions() {
        assert!(
            sg.transitions()
                .iter()
                .any(|u| (u.from, u.to) == (t.from, t.to)),
            "no sparse transition {} -> {}: {line}",
            dg.sequences()[t.from].name,
            dg.sequences()[t.to].name
        );
    }
    line
}

/// A variant of the database `from` in `to`: its sequences cut in two
/// (the first 45 % and the rest), the second pieces turned 90° about the
/// vertical, the first sequence also mirrored (x → −x: a motion whose
/// frames are nobody's nearest, the shape measure being invariant to turns
/// only), all in reverse order. Same topology and rig.
fn variant_db(from: &Path, to: &Path) -> PathBuf {
    use surfmotion::mesh::io::pc2::{read_pc2, write_pc2};
    let mut m = Manifest::load(from).unwrap();
    assert_eq!(
        m.up.to_ascii_lowercase(),
        "y",
        "the synthetic database is Y-up"
    );
    std::fs::create_dir_all(to).unwrap();
    let mut pieces: Vec<(String, usize, Vec<[f64; 3]>)> = Vec::new();
    for (k, s) in m.sequences.iter().enumerate() {
        let pc = read_pc2(&Manifest::resolve(from, &s.path)).unwrap();
        let v = pc.points;
        let frames = pc.positions.len() / v;
        let cut = frames * 45 / 100;
        let turned: Vec<[f64; 3]> = pc.positions[cut * v..]
            .iter()
            .map(|p| [p[2], p[1], -p[0]])
            .collect();
        pieces.push((
            format!("{}_head", s.name),
            v,
            pc.positions[..cut * v].to_vec(),
        ));
        pieces.push((format!("{}_tail_turned", s.name), v, turned));
        if k == 0 {
            let mirrored = pc.positions.iter().map(|p| [-p[0], p[1], p[2]]).collect();
            pieces.push((format!("{}_mirrored", s.name), v, mirrored));
        }
    }
    pieces.reverse();
    let template = m.sequences[0].clone();
    m.sequences = pieces
        .into_iter()
        .map(|(name, v, pos)| {
            let path = to.join(format!("{name}.pc2"));
            write_pc2(v, &pos, &path).unwrap();
            surfmotion::db::SequenceEntry {
                name,
                path,
                ..template.clone()
            }
        })
        .collect();
    m.topology = Manifest::resolve(from, &m.topology);
    for p in [&mut m.rig.landmarks, &mut m.rig.parts]
        .into_iter()
        .flatten()
    {
        *p = Manifest::resolve(from, p);
    }
    m.save(to).unwrap();
    to.to_path_buf()
}

/// Issue 43 on generated variants: cut, turned, mirrored and re-ordered
/// sequences (7 of them, among them pairs of dissimilar motions) — the
/// sparse graph finds ≥ 95 % of the dense transitions with their costs,
/// and a transition in every ordered sequence pair that has one.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_sparse_graph_finds_the_dense_transitions_of_a_variant_database() {
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let tmp = tempfile::tempdir().unwrap();
    let variant = variant_db(&db, &tmp.path().join("variant"));
    eprintln!("{}", compare(&variant, tmp.path(), true));
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_sparse_graph_finds_the_dense_transitions() {
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let tmp = tempfile::tempdir().unwrap();
    eprintln!("{}", compare(&db, tmp.path(), false));
}

/// A measurement on a database named by `SURFMOTION_SCALE_DB` (e.g. one of
/// `scripts/scale-db.sh`'s): `SURFMOTION_SCALE_DB=DIR cargo test --release
/// --test it db::sparse::measure -- --ignored --nocapture`.
#[test]
#[ignore = "measurement: needs SURFMOTION_SCALE_DB (a database folder)"]
fn measure_the_sparse_graph_on_a_given_database() {
    let db = PathBuf::from(std::env::var("SURFMOTION_SCALE_DB").expect("SURFMOTION_SCALE_DB"));
    let tmp = tempfile::tempdir().unwrap();
    println!("{}: {}", db.display(), compare(&db, tmp.path(), true));
}

/// Issue 43: `inspect` judges a sparse database's graph cache by the key
/// `db build` gave it (the sparse similarity's), and its sparse similarity
/// file as a cache file of its own; a dense database's as before. Before,
/// a sparse database's current graph read "stale" and its sparse file "not
/// a file db build writes".
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn inspect_judges_a_sparse_graph_by_its_own_key() {
    use surfmotion::tools::inspect::{InspectOptions, Report, inspect};
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let tmp = tempfile::tempdir().unwrap();
    let states = |dir: &Path| -> Vec<(String, bool, String)> {
        let Report::Database(r) = inspect(dir, &InspectOptions::default()).unwrap() else {
            panic!("not read as a database")
        };
        r.cache
            .into_iter()
            .map(|e| (e.what, e.up_to_date, e.state))
            .collect()
    };
    let find = |v: &[(String, bool, String)], what: &str| {
        v.iter()
            .find(|e| e.0 == what)
            .cloned()
            .unwrap_or_else(|| panic!("no {what} in {v:?}"))
    };
    for method in [Method::Sparse, Method::Dense] {
        let dir = manifest_copy(&db, &tmp.path().join(format!("{method:?}")));
        let opts = BuildOptions {
            method: Some(method),
            ..Default::default()
        };
        build(&dir, &opts, &Quiet).unwrap();
        let v = states(&dir);
        let graph = find(&v, "graph (shape)");
        assert!(graph.1, "{method:?}: {graph:?}");
        let similarity = match method {
            Method::Sparse => "sparse similarity (shape)",
            Method::Dense => "similarity matrix (shape)",
        };
        assert!(find(&v, similarity).1, "{method:?}: {v:?}");
        // Another key in the graph file: stale, whichever the method.
        let gpath = surfmotion::db::build::graph_path(&dir, surfmotion::similarity::Measure::Shape);
        let text = std::fs::read_to_string(&gpath).unwrap();
        let (head, rest) = text.split_once(',').unwrap();
        assert!(head.starts_with("{\"key\":"), "{head}");
        std::fs::write(&gpath, format!("{{\"key\":1,{rest}")).unwrap();
        let graph = find(&states(&dir), "graph (shape)");
        assert!(
            !graph.1 && graph.2.starts_with("stale"),
            "{method:?}: {graph:?}"
        );
    }
    // The sparse file cut: damaged, not up to date.
    let dir = tmp.path().join("Sparse");
    let spath = surfmotion::db::build::sparse_path(&dir, surfmotion::similarity::Measure::Shape);
    let bytes = std::fs::read(&spath).unwrap();
    std::fs::write(&spath, &bytes[..bytes.len() - 5]).unwrap();
    let s = find(&states(&dir), "sparse similarity (shape)");
    assert!(!s.1 && s.2.starts_with("damaged"), "{s:?}");
}

/// The full measure read from a dense build's matrix (the same values a
/// sparse build computes: `compare` checks it value by value), the cheap
/// descriptors from the shape set; or, without a matrix, the cheap
/// distance for both (pairs are counted, transitions mean nothing).
struct Looked<'a> {
    shape: &'a surfmotion::similarity::ShapeSet,
    dense: Option<&'a surfmotion::similarity::SimilarityMatrix>,
}

impl surfmotion::similarity::PairDistance for Looked<'_> {
    fn frames(&self) -> usize {
        self.shape.frames()
    }
    fn distance(&self, a: usize, b: usize) -> f64 {
        match self.dense {
            Some(m) => m.get(a, b) as f64,
            None => 0.0,
        }
    }
}

impl surfmotion::similarity::sparse::Features for Looked<'_> {
    fn feature_len(&self) -> usize {
        self.shape.feature_len()
    }
    fn feature(&self, a: usize, out: &mut [f32]) {
        self.shape.feature(a, out)
    }
}

/// Option sets from `SURFMOTION_SPARSE_OPTIONS`: `neighbours,per_pair,
/// spread,per_sequence[,rerank[,stride]]` or `name=value,...` (the
/// default's fields overridden, [`SparseOptions::with_overrides`]),
/// separated by `;` (default: the current default; `rerank` and `stride`
/// when left out: the default's).
fn option_sets(
    base: surfmotion::similarity::SparseOptions,
) -> Vec<surfmotion::similarity::SparseOptions> {
    let Ok(text) = std::env::var("SURFMOTION_SPARSE_OPTIONS") else {
        return vec![base];
    };
    text.split(';')
        .filter(|s| !s.trim().is_empty())
        .map(|s| {
            if s.contains('=') {
                return base.with_overrides(s).expect(s);
            }
            let v: Vec<usize> = s.split(',').map(|x| x.trim().parse().expect(s)).collect();
            surfmotion::similarity::SparseOptions {
                neighbours: v[0],
                per_pair: v[1],
                spread: v[2],
                per_sequence: v[3],
                rerank: v.get(4).copied().unwrap_or(base.rerank),
                stride: v.get(5).copied().unwrap_or(base.stride),
                ..base
            }
        })
        .collect()
}

/// Issue 43, the choice of the sparse options: describes the database
/// named by `SURFMOTION_SCALE_DB` once, then runs `sparse_pairs` and the
/// graph for each option set of `SURFMOTION_SPARSE_OPTIONS`, the full
/// measure read from the database's dense cache (`db build --similarity
/// dense` first; its `graph-shape.json` is the reference) or, without one,
/// pairs counted only. `SURFMOTION_SCALE_DB=DIR SURFMOTION_SPARSE_OPTIONS=
/// '24,8,5,0;12,8,5,0' cargo test --release --test it
/// db::sparse::options -- --ignored --nocapture`.
#[test]
#[ignore = "measurement: needs SURFMOTION_SCALE_DB (a database folder)"]
fn options_measured_against_the_dense_cache() {
    use surfmotion::db::build::{
        describe_shape, graph_path, read_graph_cache, similarity_key, similarity_path,
        sparse_options,
    };
    use surfmotion::graph::SurfaceMotionGraph;
    use surfmotion::similarity::{Measure, sparse::sparse_pairs};
    let db = PathBuf::from(std::env::var("SURFMOTION_SCALE_DB").expect("SURFMOTION_SCALE_DB"));
    let m = Manifest::load(&db).unwrap();
    let key = similarity_key(&db, &m, Measure::Shape).unwrap();
    let dense =
        surfmotion::db::cache::read_matrix(&similarity_path(&db, Measure::Shape), key).unwrap();
    let reference = dense
        .as_ref()
        .and_then(|_| read_graph_cache(&graph_path(&db, Measure::Shape)).ok())
        .map(|(_, g)| g);
    let t = std::time::Instant::now();
    let (shape, spans) = describe_shape(&db, &m, &Quiet).unwrap();
    let n = shape.frames();
    println!(
        "{}: {n} frames, {} sequences, described in {:.1} s; dense cache: {}",
        db.display(),
        spans.len(),
        t.elapsed().as_secs_f64(),
        dense.is_some()
    );
    let set = Looked {
        shape: &shape,
        dense: dense.as_ref(),
    };
    let topts = m.graph.transition_options();
    for o in option_sets(sparse_options(&m)) {
        let (sim, stats) = sparse_pairs(&set, spans.clone(), &o, &|_: u64| {});
        let mut line = format!(
            "neighbours {} per_pair {} spread {} per_sequence {} pool {} cover {} rerank {} stride {}: candidates {} (nearest {}, per sequence {}, per pair {}), pairs {} (alone: nearest {}, per sequence {}, per pair {}) (+ {} re-ranking), ({:.1} % of {}), index {:.1} s (scan {:.1} s), CPU index {:.1} s, scan {:.1} s, pairs {:.1} s",
            o.neighbours,
            o.per_pair,
            o.spread,
            o.per_sequence,
            o.pool,
            o.cover,
            o.rerank,
            o.stride,
            stats.candidates,
            stats.near_candidates,
            stats.sequence_candidates,
            stats.pair_candidates,
            stats.pairs,
            stats.pairs_by_source[0],
            stats.pairs_by_source[1],
            stats.pairs_by_source[2],
            stats.rerank_pairs,
            100.0 * stats.pairs as f64 / (n as f64 * (n as f64 + 1.0) / 2.0),
            n * (n + 1) / 2,
            stats.index_seconds,
            stats.scan_seconds,
            stats.cpu_seconds[0],
            stats.cpu_seconds[1],
            stats.cpu_seconds[2]
        );
        if let Some(reference) = &reference {
            let g =
                SurfaceMotionGraph::build(&sim, Measure::Shape, &topts, &m.graph.edits()).unwrap();
            let a = agreement(reference, &g, 0, 0.05);
            line += &format!(
                "; transitions {} (dense {}), found {} ({:.1} %), worst cost {:.2} %",
                a.compared,
                a.reference,
                a.near_and_cost,
                100.0 * a.found(),
                100.0 * a.worst_cost
            );
            println!("{line}");
            if std::env::var_os("SURFMOTION_SPARSE_MISSES").is_some() {
                let cheap = cheap_centres(&shape, &spans, &o, &topts);
                for l in misses(
                    &transitions_of(reference),
                    &transitions_of(&g),
                    &sim,
                    &cheap,
                ) {
                    println!("  {l}");
                }
                for l in pool_ranks(reference, &g, &shape, &spans, &o) {
                    println!("  {l}");
                }
            }
            continue;
        }
        println!("{line}");
    }
}

/// Issue 43, session 29: for each dense transition the sparse graph
/// misses, where its frames stand in the pool (the nearest frames overall
/// by the cheap descriptor, as `candidates` ranks them): the rank of the
/// target frame among the source frame's nearest, and the reverse; the
/// rank of the first frame of the target sequence there; how many of the
/// pool's per-sequence candidates link the sequence pair (either way);
/// then per sequence pair the count of those links.
fn pool_ranks(
    dense: &surfmotion::graph::SurfaceMotionGraph,
    sparse: &surfmotion::graph::SurfaceMotionGraph,
    shape: &surfmotion::similarity::ShapeSet,
    spans: &[surfmotion::similarity::Span],
    o: &surfmotion::similarity::SparseOptions,
) -> Vec<String> {
    use surfmotion::similarity::candidates::{CandidateOptions, index_candidates};
    use surfmotion::similarity::sparse::project;
    let (f, dims) = project(shape, o.dims);
    let n = f.len() / dims;
    let seq = |x: usize| spans.iter().position(|s| x < s.start + s.len).unwrap();
    let copts = CandidateOptions {
        neighbours: 0,
        stride: o.stride,
        per_sequence: o.per_sequence,
        pool: o.pool.max(64),
        cover: 0,
        min_gap: o.min_gap,
        reach: 0,
    };
    let pooled = index_candidates(&f, dims, spans, &copts).per_sequence;
    let mut links = std::collections::BTreeMap::new();
    for &(a, b) in &pooled {
        let (i, j) = (seq(a), seq(b as usize));
        *links.entry((i.min(j), i.max(j))).or_insert(0usize) += 1;
    }
    // Every frame ranked from `a` (nearer first, ties by frame), as the
    // index keeps them: not `a`, not its own sequence within `min_gap`.
    let ranked = |a: usize| -> Vec<usize> {
        let d2 = |b: usize| -> f32 {
            (0..dims)
                .map(|k| (f[a * dims + k] - f[b * dims + k]).powi(2))
                .sum()
        };
        let mut all: Vec<(f32, usize)> = (0..n)
            .filter(|&b| b != a && (seq(b) != seq(a) || b.abs_diff(a) >= o.min_gap.max(1)))
            .map(|b| (d2(b), b))
            .collect();
        all.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        all.into_iter().map(|x| x.1).collect()
    };
    let mut out = Vec::new();
    for t in dense.transitions() {
        let found = sparse.transitions().iter().any(|u| {
            (u.from, u.to, u.m, u.n) == (t.from, t.to, t.m, t.n)
                && (u.cost - t.cost).abs() <= 0.05 * t.cost.abs().max(1e-12)
        });
        if found {
            continue;
        }
        let (ga, gb) = (spans[t.from].start + t.m, spans[t.to].start + t.n);
        let (ra, rb) = (ranked(ga), ranked(gb));
        let rank = |r: &[usize], x: usize| r.iter().position(|&y| y == x).map_or(0, |p| p + 1);
        let first =
            |r: &[usize], s: usize| r.iter().position(|&y| seq(y) == s).map_or(0, |p| p + 1);
        let key = (t.from.min(t.to), t.from.max(t.to));
        out.push(format!(
            "pool miss {} -> {} ({}, {}): rank of target from source {}, of source from target {}; first frame of the target sequence at {}, of the source sequence at {}; pool links of the pair {}",
            spans[t.from].name,
            spans[t.to].name,
            t.m,
            t.n,
            rank(&ra, gb),
            rank(&rb, ga),
            first(&ra, t.to),
            first(&rb, t.from),
            links.get(&key).copied().unwrap_or(0)
        ));
    }
    let s = spans.len();
    let unlinked: Vec<String> = (0..s)
        .flat_map(|i| (i..s).map(move |j| (i, j)))
        .filter(|k| !links.contains_key(k))
        .map(|(i, j)| format!("{}-{}", spans[i].name, spans[j].name))
        .collect();
    let mut counts: Vec<usize> = links.values().copied().collect();
    counts.sort_unstable();
    out.push(format!(
        "pool {}: {} of {} sequence pairs linked; links per linked pair min {:?} median {:?}; unlinked: {}",
        copts.pool,
        links.len(),
        s * (s + 1) / 2,
        counts.first(),
        counts.get(counts.len() / 2),
        unlinked.join(" ")
    ));
    out
}

/// A graph's transitions (one place that reads them).
fn transitions_of(
    g: &surfmotion::graph::SurfaceMotionGraph,
) -> Vec<surfmotion::similarity::transitions::Transition> {
    g.transitions().to_vec()
}

/// The centres of each unordered sequence pair's best cheap transitions
/// (as many as the re-ranking examines, at least 8): what the per-pair
/// scan looks at, global frames, the first in the earlier sequence.
fn cheap_centres(
    shape: &surfmotion::similarity::ShapeSet,
    spans: &[surfmotion::similarity::Span],
    o: &surfmotion::similarity::SparseOptions,
    t: &surfmotion::similarity::transitions::TransitionOptions,
) -> Vec<(usize, u32)> {
    use surfmotion::similarity::{pair_scan, sparse::project};
    let (features, dims) = project(shape, o.dims);
    let opts = surfmotion::similarity::transitions::TransitionOptions {
        top_n: o.rerank.max(o.per_pair).max(8),
        max_window: o.band.saturating_sub(1).max(t.min_window),
        ..*t
    };
    pair_scan::best_per_pair(&features, dims, spans, &opts)
}

/// The dense transitions the sparse graph misses (not at the same frames
/// with cost within 5 %), one line each: sequences, frames, cost, rank in
/// its sequence pair, whether the centre pair is stored, the nearest
/// examined cheap centre of the same sequence pair (frames along the
/// diagonal, diagonals off) and the nearest sparse transition of the same
/// ordered pair (|Δm| + |Δn|, cost relative); then a summary.
fn misses(
    dense: &[surfmotion::similarity::transitions::Transition],
    sparse: &[surfmotion::similarity::transitions::Transition],
    sim: &surfmotion::similarity::SparseSimilarity,
    cheap: &[(usize, u32)],
) -> Vec<String> {
    let spans = &sim.spans;
    let seq = |f: usize| spans.iter().position(|s| f < s.start + s.len).unwrap();
    let mut out = Vec::new();
    let (mut far, mut stored) = (Vec::new(), 0);
    for t in dense {
        let same =
            |u: &&surfmotion::similarity::transitions::Transition| (u.from, u.to) == (t.from, t.to);
        let hit = sparse.iter().filter(same).any(|u| {
            (u.m, u.n) == (t.m, t.n) && (u.cost - t.cost).abs() <= 0.05 * t.cost.abs().max(1e-12)
        });
        if hit {
            continue;
        }
        let rank = 1 + dense
            .iter()
            .filter(same)
            .filter(|u| u.cost < t.cost)
            .count();
        let (ga, gb) = (spans[t.from].start + t.m, spans[t.to].start + t.n);
        let (x, y) = (ga.min(gb), ga.max(gb));
        stored += usize::from(sim.stored(ga, gb).is_some());
        let near_cheap = cheap
            .iter()
            .filter(|&&(a, b)| seq(a) == seq(x) && seq(b as usize) == seq(y))
            .map(|&(a, b)| {
                let along = a as i64 - x as i64;
                let off = (b as i64 - a as i64) - (y as i64 - x as i64);
                (along.abs() + off.abs(), along, off)
            })
            .min();
        let near_sparse = sparse
            .iter()
            .filter(same)
            .map(|u| (u.m.abs_diff(t.m) + u.n.abs_diff(t.n), u.cost / t.cost - 1.0))
            .min_by(|p, q| p.0.cmp(&q.0));
        if let Some(c) = near_cheap {
            far.push(c.0);
        }
        out.push(format!(
            "miss {} -> {} ({}, {}) L {} cost {:.5} rank {rank}; centre stored {}; nearest cheap centre {:?}; nearest sparse transition {:?}",
            spans[t.from].name,
            spans[t.to].name,
            t.m,
            t.n,
            t.window,
            t.cost,
            sim.stored(ga, gb).is_some(),
            near_cheap.map(|c| (c.1, c.2)),
            near_sparse.map(|(d, r)| format!("{d} frames, {:+.1} %", 100.0 * r)),
        ));
    }
    far.sort_unstable();
    let q = |p: usize| far.get(far.len().saturating_sub(1) * p / 100).copied();
    out.push(format!(
        "{} misses, centre stored in {stored}; |along| + |off| to the nearest cheap centre: 10th {:?}, 50th {:?}, 90th {:?}",
        out.len(),
        q(10),
        q(50),
        q(90)
    ));
    out
}

/// The descriptor and norms of `points` by the current binning and by the
/// first version, as bits.
fn both_binnings(
    points: &[(glam::DVec3, f64)],
    grid: &surfmotion::similarity::histogram::ShapeGrid,
) -> [(Vec<u32>, Vec<u64>); 2] {
    use surfmotion::similarity::histogram::{DESCRIPTOR_LEN, PHI_SUB, describe_weighted};
    let bits = |out: &[f32], norms: &[f64; PHI_SUB]| {
        (
            out.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            norms.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
        )
    };
    let (mut out, mut norms) = (vec![f32::NAN; DESCRIPTOR_LEN], [f64::NAN; PHI_SUB]);
    describe_weighted(points, grid, &mut Vec::new(), &mut out, &mut norms);
    let new = bits(&out, &norms);
    let (mut out, mut norms) = (vec![f32::NAN; DESCRIPTOR_LEN], [f64::NAN; PHI_SUB]);
    reference::describe_weighted(points, grid, &mut Vec::new(), &mut out, &mut norms);
    [new, bits(&out, &norms)]
}

/// Issue 43, session 27 (a unit test of `similarity::histogram` until
/// session 28, when the first version left the library): the cheaper
/// binning (φ once per voxel column, φ-major fine bins, the re-binning over
/// all rings at once) gives the first version's descriptors bit for bit —
/// so no cached similarity or graph changes — on voxels of a posed capsule
/// (one side pushed out) turned (also by a fraction of a fine bin),
/// mirrored, rescaled, moved and in reversed order, and on surface samples
/// (the colour measure's, not in columns).
#[test]
fn cheaper_binning_equals_the_first_version_bit_for_bit() {
    use glam::{DQuat, DVec3};
    use surfmotion::similarity::colour::surface_samples;
    use surfmotion::similarity::histogram::ShapeGrid;
    use surfmotion::similarity::voxel::{VoxelScratch, occupancy};
    let m = surfmotion::synth::shapes::capsule_mesh(0.15, 0.8, 32, 8);
    let posed = |turn: f64, bend: f64| -> Vec<DVec3> {
        m.positions()
            .iter()
            .map(|p| {
                let mut v = DVec3::from_array(*p);
                if v.x > 0.05 {
                    v.x += bend * (v.y + 0.6);
                }
                DQuat::from_rotation_y(turn) * v + DVec3::new(0.3, 0.0, -0.2)
            })
            .collect()
    };
    let grid = ShapeGrid {
        voxel: 0.02,
        r_max: 0.8,
    };
    let mut sc = VoxelScratch::default();
    let variants: [&dyn Fn(DVec3) -> DVec3; 5] = [
        &|v| v,
        &|v| DQuat::from_rotation_y(0.0123) * v,
        &|v| DVec3::new(-v.x, v.y, v.z),
        &|v| v * 1.37 + DVec3::new(-2.1, 0.4, 7.3),
        &|v| DQuat::from_rotation_x(0.4) * v * 0.61,
    ];
    let mut checked = 0;
    for (k, f) in variants.iter().enumerate() {
        for bend in [0.0, 0.3] {
            let pts: Vec<DVec3> = posed(0.7 * k as f64, bend).into_iter().map(f).collect();
            let mut voxels = Vec::new();
            occupancy(&pts, m.triangles(), grid.voxel, &mut sc, |p, w| {
                voxels.push((p, w))
            });
            assert!(voxels.len() > 1000);
            let [new, old] = both_binnings(&voxels, &grid);
            assert!(new == old, "variant {k}, bend {bend}: voxels differ");
            voxels.reverse();
            let [new, old] = both_binnings(&voxels, &grid);
            assert!(
                new == old,
                "variant {k}, bend {bend}: reversed voxels differ"
            );
            let mut samples = Vec::new();
            surface_samples(&pts, m.triangles(), &mut samples);
            let [new, old] = both_binnings(&samples, &grid);
            assert!(
                new == old,
                "variant {k}, bend {bend}: surface samples differ"
            );
            checked += 3;
        }
    }
    assert_eq!(checked, 30);
}

/// The frames (every `step`th) of the real 4D capture `name`, with its
/// triangles, and variants of each: as captured, mirrored (x → −x), turned
/// 0.3 rad about the vertical and moved, rescaled by 1/100.
fn capture_variants(
    d: &Path,
    name: &str,
    step: usize,
) -> (Vec<[u32; 3]>, Vec<glam::DVec3>, Vec<Vec<glam::DVec3>>) {
    use glam::{DQuat, DVec3};
    use surfmotion::mesh::io::{LoadOptions, load_sequence};
    let path = d.join(format!("4d/{name}/{name}.pc2"));
    let seq = load_sequence(path.to_str().unwrap(), &LoadOptions::default()).unwrap();
    let tris = seq.mesh().triangles().to_vec();
    let pts =
        |i: usize| -> Vec<DVec3> { seq.frame(i).iter().map(|p| DVec3::from_array(*p)).collect() };
    let turn = DQuat::from_rotation_y(0.3);
    let variants: [&dyn Fn(DVec3) -> DVec3; 4] = [
        &|v| v,
        &|v| DVec3::new(-v.x, v.y, v.z),
        &|v| turn * v + DVec3::new(0.37, 0.0, -1.9),
        &|v| v * 0.01,
    ];
    let frames = (0..seq.frame_count())
        .step_by(step)
        .flat_map(|i| {
            variants
                .iter()
                .map(move |f| pts(i).into_iter().map(f).collect())
        })
        .collect();
    (tris, pts(0), frames)
}

/// Issue 43, session 27: the shape descriptor's cheaper binning (φ once
/// per voxel column, φ-major fine bins, the coarse re-binning over all
/// rings at once) equals the first version's bit for bit — every value and
/// norm — on frames of both real 4D captures and their mirrored, turned,
/// moved and rescaled variants; so no cached similarity or graph changes
/// and the cache keys stay. (Mirrored frames are binned with the grid of
/// the unmirrored rest frame: any grid must give equal bits.)
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_cheaper_descriptors_equal_the_first_versions_on_real_frames() {
    use surfmotion::similarity::ShapeSet;
    use surfmotion::similarity::histogram::{DESCRIPTOR_LEN, PHI_SUB, ShapeScratch, describe};
    let Some(d) = common::data_dir() else { return };
    let mut checked = 0;
    for (name, step) in [("samba", 7), ("crane", 9)] {
        let (tris, rest, frames) = capture_variants(&d, name, step);
        let grid = ShapeSet::grid_for(&rest, &tris);
        let (mut scratch, mut vs) = (ShapeScratch::default(), Default::default());
        for (k, f) in frames.iter().enumerate() {
            let mut new = (vec![f32::NAN; DESCRIPTOR_LEN], [f64::NAN; PHI_SUB]);
            let mut old = new.clone();
            let nv = describe(f, &tris, &grid, &mut scratch, &mut new.0, &mut new.1);
            let ov = reference::describe(f, &tris, &grid, &mut vs, &mut old.0, &mut old.1);
            assert!(
                nv > 1000.0 && nv.to_bits() == ov.to_bits(),
                "{name} {k}: {nv} voxels, {ov}"
            );
            let differ = new
                .0
                .iter()
                .zip(&old.0)
                .filter(|(a, b)| a.to_bits() != b.to_bits());
            assert_eq!(
                differ.count(),
                0,
                "{name} frame variant {k}: descriptor values differ"
            );
            let norms = new
                .1
                .iter()
                .zip(&old.1)
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(
                norms,
                "{name} frame variant {k}: norms {:?} vs {:?}",
                new.1, old.1
            );
            checked += 1;
        }
    }
    eprintln!("{checked} descriptors equal bit for bit");
    assert!(checked > 100, "{checked}");
}

/// The per-frame CPU of the shape descriptor, the current binning against
/// the first version (one thread, `CLOCK_THREAD_CPUTIME_ID`), on the samba
/// capture's frames and their variants: `cargo test --release --test it
/// db::sparse::descriptor_cost -- --ignored --nocapture` (ignored: a
/// measurement, it asserts nothing; it needs the shared data).
#[test]
#[ignore = "measurement: prints the descriptor's CPU per frame; needs ../shared/data"]
fn descriptor_cost_per_frame() {
    use surfmotion::similarity::ShapeSet;
    use surfmotion::similarity::histogram::{DESCRIPTOR_LEN, PHI_SUB, ShapeScratch, describe};
    let d = common::data_path();
    let (tris, rest, frames) = capture_variants(&d, "samba", 1);
    let grid = ShapeSet::grid_for(&rest, &tris);
    let cpu = || {
        let mut t = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: a valid clock id and a valid out-pointer.
        unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
        t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64
    };
    let (mut out, mut norms) = (vec![0.0; DESCRIPTOR_LEN], [0.0; PHI_SUB]);
    let (mut scratch, mut vs) = (ShapeScratch::default(), Default::default());
    for round in 0..3 {
        let t0 = cpu();
        for f in &frames {
            describe(f, &tris, &grid, &mut scratch, &mut out, &mut norms);
        }
        let t1 = cpu();
        for f in &frames {
            reference::describe(f, &tris, &grid, &mut vs, &mut out, &mut norms);
        }
        let t2 = cpu();
        let n = frames.len() as f64;
        println!(
            "round {round}: {} frames: current {:.3} ms/frame, first version {:.3} ms/frame ({:.2}x)",
            frames.len(),
            1e3 * (t1 - t0) / n,
            1e3 * (t2 - t1) / n,
            (t2 - t1) / (t1 - t0)
        );
    }
}

/// Generated frames for the reach test: seven coordinates, the cheap
/// descriptor the first six, the full measure all seven (so at least the
/// cheap distance, and not ranked as it is).
struct Motions(Vec<[f32; 7]>);

impl surfmotion::similarity::PairDistance for Motions {
    fn frames(&self) -> usize {
        self.0.len()
    }
    fn distance(&self, a: usize, b: usize) -> f64 {
        let (p, q) = (&self.0[a], &self.0[b]);
        p.iter()
            .zip(q)
            .map(|(x, y)| ((x - y) as f64).powi(2))
            .sum::<f64>()
            .sqrt()
    }
}

impl surfmotion::similarity::sparse::Features for Motions {
    fn feature_len(&self) -> usize {
        6
    }
    fn feature(&self, a: usize, out: &mut [f32]) {
        out.copy_from_slice(&self.0[a][..6]);
    }
}

/// `sequences` generated motions (and their spans): groups of four
/// re-timed, noisy copies of a loop around a group centre (a motion and its
/// speed variants, as `scripts/scale-db.sh` makes them), lengths 50-97
/// frames; the last sequence far from every other (nobody's nearest, as a
/// mirrored piece is).
fn generated_motions(sequences: usize) -> (Motions, Vec<surfmotion::similarity::Span>) {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    };
    let (mut frames, mut spans) = (Vec::new(), Vec::new());
    for s in 0..sequences {
        let group = s / 4;
        let len = 50 + (s * 29) % 48;
        let speed = 0.8 + 0.1 * (s % 4) as f32;
        let centre = [
            (group % 3) as f32 * 3.0,
            (group / 3 % 3) as f32 * 3.0,
            (group / 9) as f32 * 3.0,
        ];
        let far = if s + 1 == sequences { 40.0 } else { 0.0 };
        let start = frames.len();
        for t in 0..len {
            let a = t as f32 * speed * std::f32::consts::TAU / 40.0 + group as f32;
            frames.push([
                centre[0] + a.cos() + 0.05 * rnd() + far,
                centre[1] + a.sin() + 0.05 * rnd(),
                centre[2] + 0.3 * (2.0 * a).sin() + 0.05 * rnd(),
                0.2 * (3.0 * a).cos(),
                0.1 * rnd(),
                0.1 * rnd(),
                0.2 * (5.0 * a + s as f32).sin(),
            ]);
        }
        spans.push(surfmotion::similarity::Span {
            name: format!("s{s}"),
            start,
            len,
        });
    }
    (Motions(frames), spans)
}

/// Issue 43, session 33 (`SparseOptions::reach`): each sequence takes the
/// per-pair scan and the cover rule's trees only with the `reach`
/// sequences it is most linked to. On generated motions (groups of speed
/// variants, one far motion) of 12, 24 and 48 sequences: at most
/// `sequences · (reach + 1)` sequence pairs are scanned (all of them
/// without a reach), every sequence reaches at least `reach` others (also
/// the far one), the per-pair and per-sequence candidates stay within
/// their bounds, which grow with the sequences, not their square; every
/// reached pair's stored pairs, values and transitions are those of the
/// build without a reach, exactly; the far motion keeps transitions both
/// ways; and a reach of at least the other sequences changes nothing.
#[test]
fn a_reach_bounds_the_sequence_pairs_and_keeps_the_reached_ones_exact() {
    use surfmotion::graph::{GraphEdits, SurfaceMotionGraph, TransitionOptions};
    use surfmotion::similarity::Measure;
    use surfmotion::similarity::candidates::{CandidateOptions, index_candidates};
    use surfmotion::similarity::sparse::{SparseOptions, project, sparse_pairs};
    let reach = 4;
    for sequences in [12usize, 24, 48] {
        let (set, spans) = generated_motions(sequences);
        let n = spans.iter().map(|s| s.len).sum::<usize>();
        let base = SparseOptions {
            neighbours: 8,
            dims: 6,
            rerank: 16,
            pool: 32,
            ..SparseOptions::default()
        };
        let with = SparseOptions { reach, ..base };
        let (all, all_stats) = sparse_pairs(&set, spans.clone(), &base, &|_: u64| {});
        let (sim, stats) = sparse_pairs(&set, spans.clone(), &with, &|_: u64| {});
        let s = sequences as u64;
        let what = format!("{sequences} sequences: {stats:?} / {all_stats:?}");
        assert_eq!(all_stats.sequence_pairs, s * (s + 1) / 2, "{what}");
        assert!(stats.sequence_pairs <= s * (reach as u64 + 1), "{what}");
        assert!(stats.pairs < all_stats.pairs, "{what}");
        // The candidates that are per sequence pair: within their bounds.
        assert!(
            stats.pair_candidates <= stats.sequence_pairs * 3 * with.per_pair as u64,
            "{what}"
        );
        // The reached pairs, from the index as the build takes them.
        let (f, dims) = project(&set, with.dims);
        let copts = CandidateOptions {
            reach,
            ..with.candidates()
        };
        let found = index_candidates(&f, dims, &spans, &copts);
        let reached = found.reached.clone().expect("a reach below the sequences");
        let at = |i: usize, j: usize| reached[i * sequences + j];
        let mut scanned = 0;
        for i in 0..sequences {
            let others = (0..sequences).filter(|&j| j != i && at(i, j)).count();
            assert!(at(i, i) && others >= reach, "{what}: s{i} reaches {others}");
            for j in 0..sequences {
                assert_eq!(at(i, j), at(j, i), "{what}: ({i}, {j})");
                scanned += usize::from(j >= i && at(i, j));
            }
        }
        assert_eq!(scanned as u64, stats.sequence_pairs, "{what}");
        // The trees' candidates only for reached pairs: at most the pool's
        // (`per_sequence` in each sequence among `pool`) plus every
        // `stride`-th frame's `per_sequence` in each reached sequence.
        let asking = |len: usize| len.div_ceil(with.stride) as u64;
        let trees: u64 = (0..sequences)
            .flat_map(|i| (0..sequences).map(move |j| (i, j)))
            .filter(|&(i, j)| at(i, j))
            .map(|(i, _)| asking(spans[i].len) * with.per_sequence as u64)
            .sum();
        let pooled = n.div_ceil(with.stride) as u64 * with.pool as u64;
        assert!(stats.sequence_candidates <= pooled + trees, "{what}");
        // Every reached pair: the same stored pairs, values and transitions.
        let topts = TransitionOptions::default();
        let edits = GraphEdits::default();
        let g_all = SurfaceMotionGraph::build(&all, Measure::Shape, &topts, &edits).unwrap();
        let g = SurfaceMotionGraph::build(&sim, Measure::Shape, &topts, &edits).unwrap();
        let mut kept = 0;
        for i in 0..sequences {
            for j in 0..sequences {
                if !at(i, j) {
                    continue;
                }
                let (b, b_all) = (sim.block(i, j), all.block(i, j));
                assert_eq!(b, b_all, "{what}: block ({i}, {j})");
                for &(r, c) in &b {
                    let (x, y) = (spans[i].start + r, spans[j].start + c);
                    assert_eq!(sim.get(x, y).to_bits(), all.get(x, y).to_bits());
                }
                let t = transitions_between(&g, i, j);
                assert_eq!(
                    t,
                    transitions_between(&g_all, i, j),
                    "{what}: transitions ({i}, {j})"
                );
                kept += t.len();
            }
        }
        assert!(kept > 0 && kept <= g.transitions().len(), "{what}");
        // The far motion keeps transitions to and from the others.
        let far = sequences - 1;
        let out = g.transitions().iter().any(|t| t.from == far && t.to != far);
        let into = g.transitions().iter().any(|t| t.to == far && t.from != far);
        assert!(out && into, "{what}: s{far} out {out}, in {into}");
        // A reach of every other sequence: nothing changes.
        let every = SparseOptions {
            reach: sequences - 1,
            ..base
        };
        let (same, _) = sparse_pairs(&set, spans.clone(), &every, &|_: u64| {});
        assert_eq!(same, all, "{what}");
        eprintln!(
            "{sequences} sequences, {n} frames: sequence pairs scanned {} of {}, pairs compared {} of {}, transitions {} of {}",
            stats.sequence_pairs,
            all_stats.sequence_pairs,
            stats.pairs,
            all_stats.pairs,
            g.transitions().len(),
            g_all.transitions().len()
        );
    }
}

/// Issue 43, session 34 (`SparseOptions::far`): the sequence pairs a reach
/// does not scan get their best transitions from the far search (their
/// whole cheap block, its best cheap transitions descended to the full
/// measure's minima). On generated motions (groups of speed variants, one
/// far motion; 16, 32 and 48 sequences, reach 2 and 4): the graph of the
/// bounded build holds the dense graph's best transition (same frames,
/// window and cost) of at least 90 % of the far pairs, both ways, and
/// misses fewer of them and finds more of the dense transitions than
/// without the far search (`far` 0), which misses at least twice as many.
/// The far search scans each far pair once and keeps at most `far`
/// centres of each. Measured (session 34): at 16 sequences, reach 2, the
/// best of 95 of 100 far pairs kept (82.1 % of the dense transitions).
#[test]
fn the_far_search_keeps_every_sequence_pairs_best_transition() {
    use surfmotion::graph::{GraphEdits, SurfaceMotionGraph, TransitionOptions};
    use surfmotion::similarity::matrix::{SimilarityMatrix, all_pairs};
    use surfmotion::similarity::sparse::{SparseOptions, sparse_pairs};
    use surfmotion::similarity::{Measure, candidates};
    let topts = TransitionOptions::default();
    let edits = GraphEdits::default();
    for (sequences, reach) in [(16usize, 2usize), (32, 4), (48, 2)] {
        let (set, spans) = generated_motions(sequences);
        let dense = SimilarityMatrix::new(spans.clone(), all_pairs(&set, &|_| {})).unwrap();
        let g_dense = SurfaceMotionGraph::build(&dense, Measure::Shape, &topts, &edits).unwrap();
        let base = SparseOptions {
            neighbours: 8,
            dims: 6,
            rerank: 16,
            pool: 32,
            reach,
            ..SparseOptions::default()
        };
        let mut seen = Vec::new();
        for far in [base.far, 0] {
            let opts = SparseOptions { far, ..base };
            let (sim, stats) = sparse_pairs(&set, spans.clone(), &opts, &|_: u64| {});
            let g = SurfaceMotionGraph::build(&sim, Measure::Shape, &topts, &edits).unwrap();
            let what = format!("{sequences} sequences, reach {reach}, far {far}: {stats:?}");
            // The far pairs: those not reached, from the index as the
            // build takes them.
            let (f, dims) = surfmotion::similarity::sparse::project(&set, opts.dims);
            let copts = candidates::CandidateOptions {
                reach,
                ..opts.candidates()
            };
            let reached = candidates::index_candidates(&f, dims, &spans, &copts)
                .reached
                .expect("a reach below the sequences");
            let far_pairs: Vec<(usize, usize)> = (0..sequences)
                .flat_map(|i| (i + 1..sequences).map(move |j| (i, j)))
                .filter(|&(i, j)| !reached[i * sequences + j])
                .collect();
            assert!(far_pairs.len() > sequences, "{what}");
            if far > 0 {
                assert_eq!(stats.far_sequence_pairs, far_pairs.len() as u64, "{what}");
                assert!(
                    stats.far_candidates <= (far * far_pairs.len()) as u64,
                    "{what}"
                );
            } else {
                assert_eq!(stats.far_sequence_pairs, 0, "{what}");
            }
            let mut missed = Vec::new();
            for &(i, j) in &far_pairs {
                for (x, y) in [(i, j), (j, i)] {
                    let d = transitions_between(&g_dense, x, y);
                    if let Some(best) = d.first()
                        && !transitions_between(&g, x, y).contains(best)
                    {
                        missed.push((x, y, *best));
                    }
                }
            }
            let found = g_dense
                .transitions()
                .iter()
                .filter(|t| {
                    transitions_between(&g, t.from, t.to).contains(&(
                        t.m,
                        t.n,
                        t.window,
                        t.cost.to_bits(),
                    ))
                })
                .count();
            let share = found as f64 / g_dense.transitions().len() as f64;
            eprintln!(
                "{sequences} sequences, reach {reach}, far {far}: far pairs {}, their best missed {}, dense transitions found {found} of {} ({:.1} %), pairs compared {}",
                far_pairs.len(),
                missed.len(),
                g_dense.transitions().len(),
                100.0 * share,
                stats.pairs
            );
            if far > 0 {
                assert!(
                    missed.len() * 10 <= 2 * far_pairs.len(),
                    "{what}: missed {missed:?}"
                );
            }
            seen.push((missed.len(), share));
        }
        let ((with, share_with), (without, share_without)) = (seen[0], seen[1]);
        assert!(
            with * 2 <= without && share_with > share_without,
            "{sequences} sequences: far pairs' best missed {with} with the far search, {without} without; dense found {share_with} / {share_without}"
        );
    }
}

/// The transitions of `g` from sequence `i` to `j`: frames, window and the
/// cost's bits.
fn transitions_between(
    g: &surfmotion::graph::SurfaceMotionGraph,
    i: usize,
    j: usize,
) -> Vec<(usize, usize, usize, u64)> {
    g.transitions()
        .iter()
        .filter(|t| (t.from, t.to) == (i, j))
        .map(|t| (t.m, t.n, t.window, t.cost.to_bits()))
        .collect()
}

/// `set`'s motions with their sequences in reverse order and every value
/// scaled by `scale` (a re-ordered, rescaled variant: the same motions, so
/// the same transitions up to the sequences' numbering).
fn reordered(
    set: &Motions,
    spans: &[surfmotion::similarity::Span],
    scale: f32,
) -> (Motions, Vec<surfmotion::similarity::Span>) {
    let (mut frames, mut out) = (Vec::new(), Vec::new());
    for s in spans.iter().rev() {
        let start = frames.len();
        frames.extend(
            set.0[s.start..s.start + s.len]
                .iter()
                .map(|p| p.map(|x| x * scale)),
        );
        out.push(surfmotion::similarity::Span { start, ..s.clone() });
    }
    (Motions(frames), out)
}

/// The transitions of `g` that are not the dense method's candidates: not
/// a local minimum of the dense matrix (a smaller 8-neighbour), or whose
/// window cost (Eq. 3 per blended frame) on the dense matrix differs from
/// the graph's by more than 1e-6 relative or is beaten by another window.
fn not_dense_candidates(
    dense: &surfmotion::similarity::SimilarityMatrix,
    g: &surfmotion::graph::SurfaceMotionGraph,
    topts: &surfmotion::graph::TransitionOptions,
) -> usize {
    let spans = &dense.spans;
    let bad = |t: &surfmotion::similarity::transitions::Transition| {
        let (si, sj) = (&spans[t.from], &spans[t.to]);
        let c = |r: i64, s: i64| dense.get(si.start + r as usize, sj.start + s as usize) as f64;
        let (m, n) = (t.m as i64, t.n as i64);
        let smaller = (-1..=1i64)
            .flat_map(|x| (-1..=1i64).map(move |y| (x, y)))
            .any(|(x, y)| {
                let (r, s) = (m + x, n + y);
                r >= 0 && s >= 0 && r < si.len as i64 && s < sj.len as i64 && c(r, s) < c(m, n)
            });
        let cost = |l: i64| {
            let mut d = 0.0;
            for k in -l..=l {
                let alpha = (k + l) as f64 / (2 * l) as f64;
                d += alpha.min(1.0 - alpha) * c(m + k, n + k);
            }
            d / (2 * l + 1) as f64
        };
        let fit = (m.min(n))
            .min(si.len as i64 - 1 - m)
            .min(sj.len as i64 - 1 - n)
            .min(topts.max_window as i64);
        let own = cost(t.window as i64);
        let beaten = (topts.min_window as i64..=fit).any(|l| cost(l) < own * (1.0 - 1e-6));
        smaller || beaten || (own - t.cost).abs() > 1e-6 * t.cost.abs().max(1e-12)
    };
    g.transitions().iter().filter(|t| bad(t)).count()
}

/// Issue 43 where the dense method runs, on generated motions (groups of
/// four re-timed copies of a loop — the slanted valleys of speed variants
/// — and one far motion), 24 and 32 sequences, as made and re-ordered and
/// rescaled ×1.37: the default options (session 39: the closure, `rerank`
/// 256) against session 38's (no closure, `rerank` 128). Measured
/// (session 39), 24 / 32 sequences as made: dense transitions found 1,906
/// → 1,908 of 2,074 (91.9 → 92.0 %) and 3,356 → 3,360 of 3,624 (92.6 →
/// 92.7 %); graph transitions that are not the dense method's candidates
/// 198 → 192 and 304 → 296 (the closure's third round still finds some to
/// settle on these noisy motions). Under the 95 % here: the misses
/// are valleys never evaluated. Asserted: no fewer found and no more
/// non-candidates than session 38's options, the recall held at 90 %, the
/// variant within 1 %.
#[test]
fn the_default_sparse_build_keeps_the_dense_candidates() {
    use surfmotion::graph::{GraphEdits, SurfaceMotionGraph, TransitionOptions};
    use surfmotion::similarity::Measure;
    use surfmotion::similarity::matrix::{SimilarityMatrix, all_pairs};
    use surfmotion::similarity::sparse::{SparseOptions, sparse_pairs};
    let topts = TransitionOptions::default();
    let edits = GraphEdits::default();
    let now = SparseOptions {
        dims: 6,
        ..SparseOptions::default()
    };
    let before = SparseOptions {
        closure: 0,
        rerank: 128,
        ..now
    };
    for sequences in [24usize, 32] {
        let (made, spans) = generated_motions(sequences);
        let mut found = Vec::new();
        for (name, (set, spans)) in [
            ("as made", (Motions(made.0.clone()), spans.clone())),
            ("re-ordered, ×1.37", reordered(&made, &spans, 1.37)),
        ] {
            let dense = SimilarityMatrix::new(spans.clone(), all_pairs(&set, &|_| {})).unwrap();
            let g_dense =
                SurfaceMotionGraph::build(&dense, Measure::Shape, &topts, &edits).unwrap();
            let n = set.0.len() as u64;
            let mut row = Vec::new();
            for (which, opts) in [("session 38", before), ("default", now)] {
                let (sim, stats) = sparse_pairs(&set, spans.clone(), &opts, &|_: u64| {});
                let g = SurfaceMotionGraph::build(&sim, Measure::Shape, &topts, &edits).unwrap();
                let a = agreement(&g_dense, &g, 0, 0.05);
                let odd = not_dense_candidates(&dense, &g, &topts);
                eprintln!(
                    "{sequences} sequences {name}, {which}: dense {} transitions, sparse {}, found {} ({:.1} %), not dense candidates {odd}; pairs compared {} of {}; closure {:?}",
                    a.reference,
                    a.compared,
                    a.near_and_cost,
                    100.0 * a.found(),
                    stats.pairs,
                    n * (n - 1) / 2,
                    stats.closure
                );
                assert!(a.reference > 8 * sequences, "{name}: {a:?}");
                assert!(stats.pairs < n * (n - 1) / 2, "{name}: {stats:?}");
                row.push((a, odd));
            }
            let ((old, odd_old), (new, odd_new)) = (row[0], row[1]);
            let what = format!("{sequences} sequences {name}: {old:?} -> {new:?}");
            assert!(new.near_and_cost >= old.near_and_cost, "{what}");
            assert!(new.found() >= 0.9, "{what}");
            assert!(odd_new <= odd_old, "{what}: {odd_old} -> {odd_new}");
            found.push(new.found());
        }
        assert!(
            (found[0] - found[1]).abs() <= 0.01,
            "{sequences} sequences: the variant {found:?}"
        );
    }
}
