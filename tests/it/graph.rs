//! Surface Motion Graph on real 4D data: similarity, transitions, cache.

use crate::common;

use glam::{DQuat, DVec3};
use std::path::Path;
use surfmotion::db::{BuildOptions, Manifest, Quiet, SequenceEntry, build};
use surfmotion::graph::{GraphParts, SurfaceMotionGraph, TransitionOptions};
use surfmotion::mesh::io::pc2::{read_pc2, write_pc2};
use surfmotion::similarity::{Measure, PairDistance, ShapeSet, SimilarityMatrix, Span, VertexSet};

/// A database in a temporary folder with the given sequences of samba
/// frames (`name`, first frame, end frame), written as PC2 caches.
fn samba_db(d: &Path, tmp: &Path, seqs: &[(&str, usize, usize)]) -> Manifest {
    let topo = d.join("4d/samba/samba.obj");
    let all = read_pc2(&d.join("4d/samba/samba.pc2")).unwrap();
    let n = 9971;
    assert_eq!(all.points, n);
    let mut sequences = Vec::new();
    for (name, a, b) in seqs {
        let p = tmp.join(format!("{name}.pc2"));
        write_pc2(n, &all.positions[a * n..b * n], &p).unwrap();
        sequences.push(SequenceEntry {
            name: name.to_string(),
            path: p.file_name().unwrap().into(),
            fps: None,
        });
    }
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json");
    let m = Manifest {
        name: "samba".into(),
        topology: topo,
        fps: 30.0,
        units: "m".into(),
        up: "y".into(),
        human_sized: true,
        colors: None,
        sequences,
        rig: surfmotion::db::RigSpec {
            landmarks: Some(fixture),
            ..Default::default()
        },
        graph: Default::default(),
        deform: Default::default(),
        spaces: Vec::new(),
    };
    m.save(tmp).unwrap();
    m
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn samba_matrix_is_symmetric_zero_on_the_diagonal_and_has_loops() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    samba_db(&d, tmp.path(), &[("dance", 0, 175)]);
    for measure in [Measure::Shape, Measure::Vertex, Measure::Skeleton] {
        let opts = BuildOptions {
            measure: Some(measure),
            force: false,
            ..Default::default()
        };
        let (m, g, r) = build(tmp.path(), &opts, &Quiet).unwrap();
        assert_eq!(m.len(), 175);
        assert!(!r.similarity_cached && !r.graph_cached);
        let mut off = Vec::new();
        for a in 0..175 {
            assert!(
                m.get(a, a).abs() < 1e-5,
                "{measure:?} self {a}: {}",
                m.get(a, a)
            );
            for b in 0..175 {
                assert_eq!(m.get(a, b), m.get(b, a));
                assert!(m.get(a, b).is_finite() && m.get(a, b) >= 0.0);
                if a != b {
                    off.push(m.get(a, b));
                }
            }
        }
        // Neighbouring frames are more alike than frames far apart.
        let near: f32 = (0..174).map(|a| m.get(a, a + 1)).sum::<f32>() / 174.0;
        let mean = off.iter().sum::<f32>() / off.len() as f32;
        assert!(
            near < 0.3 * mean,
            "{measure:?}: neighbours {near}, mean {mean}"
        );
        // Loops within the dance, in both directions, well off the diagonal.
        assert!(g.transitions().len() >= 2, "{measure:?}");
        for t in g.transitions() {
            assert_eq!((t.from, t.to), (0, 0));
            assert!(t.m.abs_diff(t.n) >= 10);
            assert!(t.m >= t.window && t.m + t.window < 175);
            assert!(g.transitions().iter().any(|u| u.m == t.n && u.n == t.m));
            // A transition is far cheaper than a typical frame pair.
            assert!(
                (t.cost as f32) < 0.25 * mean,
                "{measure:?} {t:?} mean {mean}"
            );
        }
        let loops: Vec<String> = g
            .transitions()
            .iter()
            .map(|t| format!("{}->{} L={} cost {:.4}", t.m, t.n, t.window, t.cost))
            .collect();
        eprintln!("samba {measure:?} loops: {}", loops.join(", "));
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn shape_distance_ignores_rotation_about_the_vertical() {
    let Some(d) = common::data_dir() else { return };
    let all = read_pc2(&d.join("4d/samba/samba.pc2")).unwrap();
    let topo = surfmotion::mesh::io::obj::read_obj(&d.join("4d/samba/samba.obj")).unwrap();
    let n = topo.vertex_count();
    let frame = |k: usize| all.positions[k * n..(k + 1) * n].to_vec();
    let turn = |f: &[[f64; 3]], a: f64| -> Vec<[f64; 3]> {
        let q = DQuat::from_rotation_y(a);
        f.iter()
            .map(|p| (q * DVec3::from_array(*p) + DVec3::new(0.4, 0.0, -1.3)).to_array())
            .collect()
    };
    let rest: Vec<DVec3> = topo
        .positions()
        .iter()
        .map(|p| DVec3::from_array(*p))
        .collect();
    let mut shape = ShapeSet::new(ShapeSet::grid_for(&rest, topo.triangles()));
    let mut vertex = VertexSet::new(n, Default::default());
    let f0 = frame(0);
    // Frame 0, frame 0 turned by angles off the search grid, frame 60.
    let seqs = [f0.clone(), turn(&f0, 0.61), turn(&f0, 2.9), frame(60)];
    for s in &seqs {
        shape.push_sequence(s, n, topo.triangles(), false);
        vertex.push_sequence(s, false);
    }
    for set in [&shape as &dyn PairDistance, &vertex] {
        let other = set.distance(0, 3);
        assert!(other > 0.0);
        for k in [1, 2] {
            let d = set.distance(0, k);
            // Half a 1.8° step and the voxel grid leave a small residue.
            assert!(
                d < 0.1 * other,
                "turned {k}: {d} vs a different pose {other}"
            );
        }
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn two_clips_sharing_a_segment_get_a_transition_inside_it() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    // "first" is frames 0..110 of the dance, "second" frames 70..175: they
    // share frames 70..110 (first's 70..110 = second's 0..40).
    samba_db(&d, tmp.path(), &[("first", 0, 110), ("second", 70, 175)]);
    let (_, g, _) = build(tmp.path(), &BuildOptions::default(), &Quiet).unwrap();
    let across: Vec<_> = g
        .transitions()
        .iter()
        .filter(|t| t.from == 0 && t.to == 1)
        .collect();
    assert!(!across.is_empty() && across.len() <= 4);
    let best = across[0];
    assert_eq!(best.m, best.n + 70, "{best:?}");
    assert!((70..110).contains(&best.m), "{best:?}");
    assert!(
        best.m - best.window >= 69 && best.m + best.window <= 110,
        "{best:?}"
    );
    assert!(best.cost < 1e-6, "{best:?}");
    // And back: second -> first at the same frames.
    assert!(
        g.transitions()
            .iter()
            .any(|t| t.from == 1 && t.to == 0 && t.n == t.m + 70 && t.cost < 1e-6)
    );
    // The frame graph lets a path jump across at the transition.
    let adj = g.adjacency();
    let from = g.flat_id(0, best.m);
    assert!(
        adj.successors(from)
            .any(|(t, _)| t == g.flat_id(1, best.n + 1))
    );
}

/// The two forms of a database frame (issue 40: `FlatFrame` and
/// `FrameId`, one direction per name) on real data, with the sequences cut
/// unevenly and listed in two orders: `flat_id` numbers the frames of the
/// sequences in graph order without gaps, `frame_at` / `frame_of` give every
/// one back, `checked_flat_id` refuses a frame or sequence past the end, and
/// the adjacency holds exactly the natural steps and the transitions that
/// land inside their target, each between the flat ids of its frames.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn flat_ids_and_frame_ids_go_both_ways_in_any_sequence_order() {
    use surfmotion::graph::{FlatFrame, FrameId};
    let Some(d) = common::data_dir() else { return };
    let cuts = [("a", 0, 37), ("b", 37, 98), ("c", 98, 175)];
    let mut reversed = cuts;
    reversed.reverse();
    let mut named: Vec<Vec<(String, usize, FlatFrame)>> = Vec::new();
    for order in [cuts, reversed] {
        let tmp = tempfile::tempdir().unwrap();
        samba_db(&d, tmp.path(), &order);
        let (_, g, _) = build(tmp.path(), &BuildOptions::default(), &Quiet).unwrap();
        assert_eq!(g.frame_count(), 175);
        let mut next = 0u32;
        let mut all = Vec::new();
        for (s, q) in g.sequences().iter().enumerate() {
            for t in 0..q.len {
                let f = g.flat_id(s, t);
                assert_eq!(f, FlatFrame::new(next), "{}:{t}", q.name);
                next += 1;
                let id = FrameId {
                    seq: s as u32,
                    frame: t as u32,
                };
                assert_eq!(g.frame_at(f), id);
                assert_eq!(g.frame_of(f), (s, t));
                assert_eq!(g.checked_flat_id(id), Some(f));
                all.push((q.name.clone(), t, f));
            }
            let past = FrameId {
                seq: s as u32,
                frame: q.len as u32,
            };
            assert_eq!(g.checked_flat_id(past), None, "{}", q.name);
        }
        let beyond = FrameId {
            seq: g.sequences().len() as u32,
            frame: 0,
        };
        assert_eq!(g.checked_flat_id(beyond), None);
        // The adjacency: natural steps inside each sequence and the
        // transitions landing inside their target, nothing else.
        let adj = g.adjacency();
        let mut want: Vec<(FlatFrame, FlatFrame)> = Vec::new();
        for (s, q) in g.sequences().iter().enumerate() {
            want.extend((1..q.len).map(|t| (g.flat_id(s, t - 1), g.flat_id(s, t))));
        }
        for t in g.transitions() {
            if t.n + 1 < g.sequences()[t.to].len {
                let to = g.flat_id(t.to, t.n).next();
                assert_eq!(g.frame_of(to), (t.to, t.n + 1));
                want.push((g.flat_id(t.from, t.m), to));
            }
        }
        let mut have: Vec<(FlatFrame, FlatFrame)> = FlatFrame::all(g.frame_count())
            .flat_map(|f| adj.successors(f).map(move |(t, _)| (f, t)))
            .collect();
        want.sort();
        have.sort();
        assert_eq!(have, want);
        // The JSON of the adjacency is that of the bare numbers.
        let numbers: Vec<u32> = adj.targets.iter().map(|f| f.get()).collect();
        assert_eq!(
            serde_json::to_string(&adj.targets).unwrap(),
            serde_json::to_string(&numbers).unwrap()
        );
        all.sort_by(|x, y| (&x.0, x.1).cmp(&(&y.0, y.1)));
        named.push(all);
    }
    // The same captured frame has another flat id in the other order, and
    // each order names every frame once.
    let (first, second) = (&named[0], &named[1]);
    assert_eq!(first.len(), second.len());
    let moved = first
        .iter()
        .zip(second)
        .inspect(|(x, y)| assert_eq!((&x.0, x.1), (&y.0, y.1)))
        .filter(|(x, y)| x.2 != y.2)
        .count();
    // a (37 frames) then b (61) then c (77), and c, b, a: no frame keeps
    // its flat id (b starts at 37, then at 77).
    assert_eq!(moved, 175);
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_second_build_uses_the_cache_until_an_input_changes() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let mut m = samba_db(&d, tmp.path(), &[("a", 0, 60), ("b", 60, 120)]);
    let opts = BuildOptions::default();
    let (m1, g1, r1) = build(tmp.path(), &opts, &Quiet).unwrap();
    assert!(!r1.similarity_cached && r1.pairs > 0);
    let (m2, g2, r2) = build(tmp.path(), &opts, &Quiet).unwrap();
    assert!(r2.similarity_cached && r2.graph_cached && r2.pairs == 0);
    assert_eq!(m1.spans(), m2.spans());
    assert!(m1 == m2, "matrix differs after the cache");
    assert!(g1 == g2, "graph differs after the cache:\n{g1:?}\n{g2:?}");
    // A graph edit rebuilds the graph only.
    m.graph.forbid = vec!["a -> b".into()];
    m.save(tmp.path()).unwrap();
    let (_, g3, r3) = build(tmp.path(), &opts, &Quiet).unwrap();
    assert!(r3.similarity_cached && !r3.graph_cached);
    assert!(!g3.transitions().iter().any(|t| t.from == 0 && t.to == 1));
    assert!(g2.transitions().iter().any(|t| t.from == 0 && t.to == 1));
    // New frame data invalidates the matrix.
    let all = read_pc2(&tmp.path().join("b.pc2")).unwrap();
    write_pc2(
        all.points,
        &all.positions[..30 * all.points],
        &tmp.path().join("b.pc2"),
    )
    .unwrap();
    let (m4, _, r4) = build(tmp.path(), &opts, &Quiet).unwrap();
    assert!(!r4.similarity_cached);
    assert_eq!(m4.len(), 90);
    // A bad edit is reported with the manifest's name for it.
    m.graph.forbid = vec!["a -> nobody".into()];
    m.save(tmp.path()).unwrap();
    let e = build(tmp.path(), &opts, &Quiet).unwrap_err().to_string();
    assert!(e.contains("nobody") && e.contains("character.toml"), "{e}");
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn cli_builds_caches_and_exports_the_graph() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    samba_db(&d, tmp.path(), &[("dance", 0, 175)]);
    let run = |args: &[&str]| {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_surfmotion"))
            .args(args)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    let dir = tmp.path().to_str().unwrap();
    let first: serde_json::Value =
        serde_json::from_str(&run(&["db", "build", dir, "--json"])).unwrap();
    assert_eq!(first["similarity_cached"], false);
    assert_eq!(first["frames"], 175);
    let second = run(&["db", "build", dir]);
    assert!(second.contains("similarity: cached"), "{second}");
    assert!(second.contains("dance:"), "lists transitions: {second}");
    let dot = run(&["graph", dir, "--dot"]);
    assert!(
        dot.starts_with("digraph") && dot.contains("s0 -> s0"),
        "{dot}"
    );
    let json: serde_json::Value = serde_json::from_str(&run(&["graph", dir, "--json"])).unwrap();
    let n = json["graph"]["transitions"].as_array().unwrap().len();
    assert!(n >= 2);
    assert_eq!(json["adjacency"]["offsets"].as_array().unwrap().len(), 176);
    let png = tmp.path().join("m.png");
    run(&[
        "graph",
        dir,
        "--matrix",
        png.to_str().unwrap(),
        "--size",
        "350",
    ]);
    let img = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()))
        .read_info()
        .unwrap();
    assert_eq!((img.info().width, img.info().height), (350, 350));
    // Another measure is cached beside the first.
    run(&["db", "build", dir, "--measure", "vertex"]);
    assert!(tmp.path().join("cache/similarity-vertex.bin").exists());
    assert!(tmp.path().join("cache/similarity-shape.bin").exists());
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn colour_measure_on_a_coloured_samba() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let mut m = samba_db(&d, tmp.path(), &[("dance", 0, 175)]);
    // Colour the dancer: a red top, a blue skirt, skin below the knees,
    // shaded by the side she faces (so turning shows in colour).
    let topo = surfmotion::mesh::io::obj::read_obj(&d.join("4d/samba/samba.obj")).unwrap();
    let colours: Vec<[f64; 3]> = topo
        .positions()
        .iter()
        .map(|p| {
            let side = 0.5 + 0.5 * ((p[2] + 0.05) * 8.0).tanh();
            if p[1] > 1.05 {
                [0.9, 0.15 + 0.3 * side, 0.1]
            } else if p[1] > 0.45 {
                [0.1, 0.2 * side, 0.85]
            } else {
                [0.85, 0.65, 0.5]
            }
        })
        .collect();
    let coloured = topo.clone().with_colors(colours).unwrap();
    let cpath = tmp.path().join("colours.obj");
    surfmotion::mesh::io::save_sequence(
        &surfmotion::mesh::MeshSequence::single(coloured),
        &cpath,
        None,
    )
    .unwrap();
    m.colors = Some("colours.obj".into());
    m.save(tmp.path()).unwrap();
    // With colours the default measure is the 6D one.
    let (mat, g, r) = build(tmp.path(), &BuildOptions::default(), &Quiet).unwrap();
    assert_eq!(r.measure, Measure::Colour);
    let mut off = 0.0;
    for a in 0..175 {
        assert!(mat.get(a, a).abs() < 1e-6, "self {a}: {}", mat.get(a, a));
        for b in 0..175 {
            assert_eq!(mat.get(a, b), mat.get(b, a));
            off += mat.get(a, b) as f64;
        }
    }
    let mean = off / (175.0 * 174.0);
    let near: f64 = (0..174).map(|a| mat.get(a, a + 1) as f64).sum::<f64>() / 174.0;
    assert!(near < 0.5 * mean, "neighbours {near}, mean {mean}");
    assert!(!g.transitions().is_empty());
    // Turning a frame about the vertical keeps it near itself.
    let all = read_pc2(&d.join("4d/samba/samba.pc2")).unwrap();
    let n = topo.vertex_count();
    let f0 = all.positions[..n].to_vec();
    let q = DQuat::from_rotation_y(1.3);
    let turned: Vec<[f64; 3]> = f0
        .iter()
        .map(|p| (q * DVec3::from_array(*p)).to_array())
        .collect();
    let rest: Vec<DVec3> = topo
        .positions()
        .iter()
        .map(|p| DVec3::from_array(*p))
        .collect();
    let col = surfmotion::mesh::io::load_sequence(cpath.to_str().unwrap(), &Default::default())
        .unwrap()
        .mesh()
        .colors()
        .unwrap()
        .to_vec();
    let mut set =
        surfmotion::similarity::ColourSet::new(ShapeSet::grid_for(&rest, topo.triangles()), col);
    set.push_sequence(&f0, n, topo.triangles(), false);
    set.push_sequence(&turned, n, topo.triangles(), false);
    set.push_sequence(&all.positions[60 * n..61 * n], n, topo.triangles(), false);
    let (same, other) = (set.distance(0, 1), set.distance(0, 2));
    assert!(same < 0.2 * other, "turned {same}, other pose {other}");
}

/// A similarity matrix of periodic motions: sequence `s` plays a cycle at
/// `rates[s]` cycles per frame from phase `offsets[s]`; two frames differ by
/// how far apart their phases are, so every pair of sequences has minima.
fn periodic_matrix(rates: &[f64], offsets: &[f64], frames: usize) -> SimilarityMatrix {
    let spans: Vec<Span> = (0..rates.len())
        .map(|s| Span {
            name: format!("cycle{s}"),
            start: s * frames,
            len: frames,
        })
        .collect();
    let phase = |a: usize| (offsets[a / frames] + rates[a / frames] * (a % frames) as f64).fract();
    let n = rates.len() * frames;
    let data = (0..n * n)
        .map(|k| {
            let d = (phase(k / n) - phase(k % n)).abs();
            (std::f64::consts::PI * d).sin().abs() as f32
        })
        .collect();
    SimilarityMatrix::new(spans, data).unwrap()
}

/// An edit of a graph's parts that makes them disagree.
type PartsEdit = Box<dyn Fn(&mut GraphParts)>;

/// Issue 40: a Surface Motion Graph is made only by `build` or from parts
/// that agree (`SurfaceMotionGraph::new`, which the cache reader uses too):
/// every graph round-trips through its parts and through JSON unchanged, in
/// either order of its sequences; each kind of disagreement is refused,
/// naming what disagrees, directly and through the cache's JSON.
#[test]
fn a_graph_is_made_only_from_parts_that_agree() {
    let rates = [0.031, 0.047, 0.038];
    for offsets in [[0.0, 0.3, 0.6], [0.6, 0.3, 0.0]] {
        let m = periodic_matrix(&rates, &offsets, 90);
        let g = SurfaceMotionGraph::build(
            &m,
            Measure::Shape,
            &TransitionOptions::default(),
            &Default::default(),
        )
        .unwrap();
        assert!(g.edges().len() >= 3 && g.transitions().len() >= 3, "{g:?}");
        assert_eq!(SurfaceMotionGraph::new(g.clone().into_parts()).unwrap(), g);
        let json = serde_json::to_string(&g).unwrap();
        assert_eq!(
            serde_json::from_str::<SurfaceMotionGraph>(&json).unwrap(),
            g
        );
        let e0 = &g.edges()[0];
        let other = g
            .edges()
            .iter()
            .position(|e| (e.from, e.to) != (e0.from, e0.to));
        let other = other.unwrap();
        let cases: Vec<(&str, PartsEdit)> = vec![
            (
                "starts at flat frame",
                Box::new(|p| p.sequences[1].start += 1),
            ),
            ("joins sequences", Box::new(|p| p.transitions[0].to = 3)),
            ("past the end", Box::new(|p| p.transitions[0].m = 90)),
            (
                "has cost NaN",
                Box::new(|p| p.transitions[0].cost = f64::NAN),
            ),
            ("half-window", Box::new(|p| p.transitions[0].window = 91)),
            ("that do not exist", Box::new(|p| p.edges[0].to = 5)),
            (
                "not one of its own",
                Box::new(move |p| {
                    let t = p.edges[other].transitions[0];
                    p.edges[0].transitions.push(t)
                }),
            ),
            (
                "twice",
                Box::new(|p| {
                    let t = p.edges[0].transitions[0];
                    p.edges[0].transitions.push(t)
                }),
            ),
            (
                "repeats the sequence pair",
                Box::new(|p| {
                    let e = p.edges[0].clone();
                    p.edges.push(e)
                }),
            ),
            ("cheapest", Box::new(|p| p.edges[0].cost += 0.5)),
            (
                "is on no edge",
                Box::new(|p| {
                    let e = &mut p.edges[0];
                    if e.transitions.len() == 1 {
                        p.edges.remove(0);
                    } else {
                        let cheapest = e.transitions[0];
                        e.transitions.retain(|&k| k != cheapest);
                        p.transitions[cheapest].cost = e.cost;
                    }
                }),
            ),
        ];
        for (what, edit) in &cases {
            let mut parts = g.clone().into_parts();
            edit(&mut parts);
            let err = SurfaceMotionGraph::new(parts.clone()).unwrap_err();
            assert!(err.contains(what), "{what}: {err}");
            if parts.transitions.iter().all(|t| t.cost.is_finite()) {
                // Through the cache's JSON (no NaN in JSON).
                let mut v = serde_json::to_value(&g).unwrap();
                v["sequences"] = serde_json::to_value(&parts.sequences).unwrap();
                v["transitions"] = serde_json::to_value(&parts.transitions).unwrap();
                v["edges"] = serde_json::to_value(&parts.edges).unwrap();
                let err = serde_json::from_value::<SurfaceMotionGraph>(v).unwrap_err();
                assert!(err.to_string().contains(what), "{what}: {err}");
            }
        }
    }
}
