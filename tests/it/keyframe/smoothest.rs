//! The least mean smoothness of a path within 1 % of the targets
//! (`keyframe::smoothest`, Huang et al. 2015, Sec. 6.1's measure under the
//! issue's bands): Dinkelbach's method over the exact-length programme
//! against an exhaustive search on random graphs, its exact lower bound,
//! and `keyframe --grid --least-mean` on a small synthetic database.

use crate::common;

use std::collections::HashMap;
use surfmotion::graph::FlatFrame;
use surfmotion::keyframe::graph::KeyGraph;
use surfmotion::keyframe::options::SearchOptions;
use surfmotion::keyframe::segment::Target;
use surfmotion::keyframe::smoothest::{least_mean, lower_bound};

use common::keygraph::Lcg;

/// `seqs` sequences of 15-30 frames walking at different speeds, and
/// `jumps` random transitions priced 0.02-0.2 (a smoothness in metres).
fn random_graph(r: &mut Lcg, seqs: usize, jumps: usize) -> KeyGraph {
    let shape = common::keygraph::Shape {
        frames: (15, 16),
        cost: (0.02, 0.18),
        distinct: true,
    };
    common::keygraph::random_graph(r, seqs, jumps, &shape)
}

/// Every path of exactly `frames` frames (start counted) from `from` to
/// `to` with transitions at least `min_run` frames apart, as the distinct
/// `(distance, transitions)` with the least summed price of each: the
/// exhaustive programme (frame level; for one `(distance, k)` the least
/// sum gives the least mean, whatever follows).
fn all_paths(
    g: &KeyGraph,
    from: FlatFrame,
    to: FlatFrame,
    frames: usize,
    min_run: u32,
) -> Vec<(f64, usize, f64)> {
    type Row = Vec<(f64, usize, f64)>;
    let mut layer: HashMap<(FlatFrame, u32), Row> = HashMap::new();
    layer.insert((from, min_run), vec![(0.0, 0, 0.0)]);
    for _ in 1..frames {
        let mut next: HashMap<(FlatFrame, u32), Row> = HashMap::new();
        for (&(f, since), labels) in &layer {
            for e in g.successors(f) {
                if e.jump && since < min_run {
                    continue;
                }
                let s2 = if e.jump { 1 } else { (since + 1).min(min_run) };
                let row = next.entry((e.to, s2)).or_default();
                for &(d, k, s) in labels {
                    let j = usize::from(e.jump);
                    row.push((
                        d + g.step_of(e.to),
                        k + j,
                        s + if e.jump { e.cost } else { 0.0 },
                    ));
                }
            }
        }
        for row in next.values_mut() {
            row.sort_by(|a, b| {
                a.1.cmp(&b.1)
                    .then(a.0.total_cmp(&b.0))
                    .then(a.2.total_cmp(&b.2))
            });
            row.dedup_by(|a, b| a.1 == b.1 && (a.0 - b.0).abs() < 1e-12);
        }
        layer = next;
    }
    layer
        .into_iter()
        .filter(|((f, _), _)| *f == to)
        .flat_map(|(_, v)| v)
        .collect()
}

/// The mean price of the transitions along a frame path.
fn path_mean(g: &KeyGraph, path: &[FlatFrame]) -> Option<f64> {
    let s: Vec<f64> = path
        .windows(2)
        .filter_map(|w| g.edge(w[0], w[1]))
        .filter(|e| e.jump)
        .map(|e| e.cost)
        .collect();
    (!s.is_empty()).then(|| s.iter().sum::<f64>() / s.len() as f64)
}

/// On random graphs, against the exhaustive least mean `m*` over the
/// paths of exactly `N` frames within 1 % of the distance: the path
/// returned lands within 1 % and walks the graph, its mean (recomputed
/// from its frames) is never below `m*` and equals it in nearly every
/// case; the lower bound is never above `m*`; and a target some path
/// meets is met.
#[test]
fn least_mean_agrees_with_an_exhaustive_search_and_the_bound_holds() {
    let mut r = Lcg(71);
    let o = SearchOptions::default();
    let (mut compared, mut equal, mut found, mut bounded_above_min) = (0, 0, 0, 0);
    for case in 0..1500 {
        let g = random_graph(&mut r, 3, 14);
        let (a, b) = (
            FlatFrame::from_index(r.below(g.len())),
            FlatFrame::from_index(r.below(g.len())),
        );
        let Ok(p) = surfmotion::keyframe::Planner::new(g.clone(), &[a, b], 25.0, &o) else {
            continue;
        };
        let Some(c) = &p.chain else { continue };
        let frames = 25 + r.below(40);
        let all = all_paths(&g, a, b, frames, o.lattice.min_run);
        let with: Vec<&(f64, usize, f64)> = all.iter().filter(|x| x.1 > 0).collect();
        if with.len() < 2 {
            continue;
        }
        let (lo, hi) = with
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                (l.min(x.0), h.max(x.0))
            });
        let d = lo + (hi - lo) * r.next();
        if d < 0.05 {
            continue;
        }
        let exact = with
            .iter()
            .filter(|x| (x.0 - d).abs() < 0.01 * d)
            .map(|x| x.2 / x.1 as f64)
            .fold(f64::INFINITY, f64::min);
        let t = Target {
            distance: d,
            frames: frames as f64,
        };
        let got = least_mean(c, &t, 0.01, &o.lattice, 12).unwrap();
        let lb = lower_bound(c, &t, 0.01, o.lattice.max_frames, 1e-6).unwrap();
        if !exact.is_finite() {
            assert!(got.is_none(), "case {case}: a path where none lands");
            continue;
        }
        compared += 1;
        let lb = lb.unwrap_or_else(|| panic!("case {case}: no bound where m* = {exact}"));
        assert!(
            lb <= exact + 1e-9,
            "case {case}: bound {lb} above m* {exact}"
        );
        let least = c
            .arcs_by_index()
            .iter()
            .flatten()
            .filter(|a| a.jump)
            .map(|a| a.m.cost)
            .fold(f64::INFINITY, f64::min);
        bounded_above_min += usize::from(lb > least + 1e-6);
        let Some(s) = got else { continue };
        found += 1;
        let segs: Vec<_> = c
            .split(&s.found.arcs)
            .iter()
            .zip(&p.segments)
            .map(|(arcs, seg)| seg.decompose(arcs))
            .collect();
        let path = surfmotion::keyframe::join(&segs);
        assert_eq!((path[0], *path.last().unwrap()), (a, b), "case {case}");
        assert_eq!(path.len(), frames, "case {case}: {} frames", path.len());
        for w in path.windows(2) {
            assert!(
                g.edge(w[0], w[1]).is_some(),
                "case {case}: {w:?} is no edge"
            );
        }
        let dist: f64 = path[1..].iter().map(|&f| g.step_of(f)).sum();
        assert!((dist - d).abs() < 0.01 * d, "case {case}: {dist} for {d}");
        let mean = path_mean(&g, &path).expect("a transition");
        assert!(
            (mean - s.mean).abs() < 1e-9,
            "case {case}: {mean} vs {}",
            s.mean
        );
        assert!(mean >= exact - 1e-9, "case {case}: {mean} below m* {exact}");
        equal += usize::from(mean <= exact + 1e-9);
    }
    eprintln!(
        "compared {compared}, found {found}, equal {equal}, bound above the least price {bounded_above_min}"
    );
    assert!(compared >= 40, "only {compared} cases compared");
    assert!(found * 20 >= compared * 19, "found {found} of {compared}");
    assert!(
        equal * 10 >= found * 9,
        "the least mean in {equal} of {found}"
    );
    // The bound is informative (above the chain's least price) in some
    // cases.
    assert!(
        bounded_above_min * 4 >= compared,
        "{bounded_above_min} of {compared}"
    );
}

/// `keyframe --grid --least-mean` on the small synthetic database (CMU
/// walk 02_01 and run 02_03 on the samba character, 25 fps): every path
/// it reports lands within 1 % of both targets, its mean is never below
/// the exact lower bound, and on every target the default grid meets its
/// mean smoothness is not above the default path's. The grid reaches
/// 10 m and 8 s: on the clean synthetic database (issue 42) the default
/// paths of the former 7 m × 6 s grid met only 2 targets within 1 %.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn least_mean_grid_lands_within_1pct_and_is_no_worse_than_the_default_paths() {
    let Some(d) = common::data_dir() else { return };
    let db = common::walk_run_db(&d, "keyframe-smoothest-walk-run");
    let out = common::fixture_dir("keyframe-smoothest-out");
    let grid = |extra: &[&str], report: &std::path::Path| {
        let mut a: Vec<std::ffi::OsString> = vec![
            "keyframe".into(),
            "--db".into(),
            db.clone().into(),
            "--from".into(),
            "02_01:0".into(),
            "--to".into(),
            "02_03:30".into(),
            "--grid".into(),
            "--distances".into(),
            "1:10:1".into(),
            "--times".into(),
            "1:8:1".into(),
            "--report".into(),
            report.into(),
        ];
        a.extend(extra.iter().map(|s| s.into()));
        common::run_ok(std::process::Command::new(common::bin()).args(&a));
        let text = std::fs::read_to_string(report).unwrap();
        serde_json::from_str::<serde_json::Value>(&text).unwrap()
    };
    let lm = grid(&["--least-mean"], &out.join("least.json"));
    let def = grid(&[], &out.join("default.json"));
    let key = |q: &serde_json::Value| (q["distance"].to_string(), q["time"].to_string());
    let by: HashMap<_, _> = def["queries"]
        .as_array()
        .unwrap()
        .iter()
        .map(|q| (key(q), q.clone()))
        .collect();
    let (mut landed, mut compared) = (0, 0);
    for q in lm["queries"].as_array().unwrap() {
        let (dv, tv) = (q["distance"].as_f64().unwrap(), q["time"].as_f64().unwrap());
        if let Some(m) = q["least_mean"].as_f64() {
            landed += 1;
            let a = q["achieved"].as_array().unwrap();
            let (ad, at) = (a[0].as_f64().unwrap(), a[1].as_f64().unwrap());
            assert!((ad - dv).abs() < 0.01 * dv, "{dv} m: {ad}");
            assert!((at - tv).abs() < 0.01 * tv, "{tv} s: {at}");
            if let Some(lb) = q["lower_bound"].as_f64() {
                assert!(lb <= m + 1e-9, "{dv} m in {tv} s: bound {lb} above {m}");
            }
            assert!(q["transitions"].as_u64().unwrap() >= 1);
        }
        let dq = &by[&key(q)];
        if dq["within_1pct"].as_bool().unwrap()
            && let Some(ds) = dq["smoothness"].as_f64()
        {
            compared += 1;
            let m = q["least_mean_measured"]
                .as_f64()
                .unwrap_or_else(|| panic!("{dv} m in {tv} s: the default meets it, no least mean"));
            assert!(
                m <= ds + 1e-9,
                "{dv} m in {tv} s: {m} above the default's {ds}"
            );
        }
    }
    assert!(
        compared >= 3 && landed >= compared,
        "{landed} landed, {compared} compared"
    );
    assert_eq!(lm["kept"], lm["reachable"]);
}
