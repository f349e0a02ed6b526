//! Issue 43: the sparse similarity (candidate pairs from a nearest-neighbour
//! index, the full measure only there) against the dense matrix on a
//! synthetic database where both run.

use crate::common;

use std::path::{Path, PathBuf};
use surfmotion::db::build::Method;
use surfmotion::db::{BuildOptions, Manifest, Quiet, build};
use surfmotion::graph::compare::agreement;
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
/// sparse graph against the dense one; returns what it measured.
fn compare(db: &Path, tmp: &Path) -> String {
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
    // Issue 43 asks for 95 %; measured 90.5 % here (370 frames) and
    // 73.3 % at 3,234 frames (README): the target is not met yet. This
    // holds the line where it is; the costs of the transitions found are
    // the dense ones exactly.
    assert!(a.found() >= 0.85, "{line}");
    assert!(near.worst_cost <= 0.05, "{line}");
    line
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_sparse_graph_finds_the_dense_transitions() {
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let tmp = tempfile::tempdir().unwrap();
    eprintln!("{}", compare(&db, tmp.path()));
}

/// A measurement on a database named by `SURFMOTION_SCALE_DB` (e.g. one of
/// `scripts/scale-db.sh`'s): `SURFMOTION_SCALE_DB=DIR cargo test --release
/// --test it db::sparse::measure -- --ignored --nocapture`.
#[test]
#[ignore = "measurement: needs SURFMOTION_SCALE_DB (a database folder)"]
fn measure_the_sparse_graph_on_a_given_database() {
    let db = PathBuf::from(std::env::var("SURFMOTION_SCALE_DB").expect("SURFMOTION_SCALE_DB"));
    let tmp = tempfile::tempdir().unwrap();
    println!("{}: {}", db.display(), compare(&db, tmp.path()));
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
