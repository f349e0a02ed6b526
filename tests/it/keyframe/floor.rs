//! The smoothness floor (`keyframe::floor`, Huang et al. 2015, Sec. 6.1) on
//! a small synthetic database (CMU walk 02_01 and run 02_03 on the samba
//! character, 25 fps).

use crate::common;

use surfmotion::keyframe::floor::{FloorOptions, path_floor, transition_floor};
use surfmotion::keyframe::smoothness::{FrameSet, Surface, profile, transition_smoothness};

fn walk_run_db(d: &std::path::Path) -> std::path::PathBuf {
    common::walk_run_db(d, "keyframe-floor-walk-run")
}

/// The frame-pair distance of the floor is the measure's (stride 1) and a
/// lower bound of it with a stride; the floor's best window measures what
/// `transition_smoothness` measures for it and is no worse than any
/// transition of the graph whose window it covers; a path between two
/// key-frames of different sequences cannot be smoother on average than
/// the floor, and the graph's transitions give a path floor no lower than
/// every frame pair's.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn floor_is_the_measure_minimised_over_every_frame_pair_and_bounds_the_graph() {
    let Some(d) = common::data_dir() else { return };
    let ch = surfmotion::db::Character::load(&walk_run_db(&d), &surfmotion::db::Quiet).unwrap();
    let frames = FrameSet::new(&ch);
    assert_eq!(frames.len(), ch.frame_count());
    let surface = Surface::new(ch.topology().triangles(), ch.n());
    let g = ch.graph();
    let f = surfmotion::graph::FlatFrame::new;
    for (a, b) in [(f(3), f(40)), (f(10), f(90)), (f(50), f(100))] {
        let exact = frames.distance(a, b, 1);
        let p = profile(&ch, &surface, a, b.next(), 0, false);
        let want = p[0].unwrap().0;
        assert!((exact - want).abs() < 1e-9, "{a}, {b}: {exact} vs {want}");
        assert!(frames.distance(a, b, 16) <= exact + 1e-12);
        assert!(exact > 0.0);
    }
    assert_eq!(frames.distance(f(7), f(7), 1), 0.0);
    let opts = FloorOptions::of_graph(g.options());
    let t = transition_floor(&ch, &frames, &opts);
    let best = t.best.clone().expect("a window fits");
    assert!((opts.min_window..=opts.max_window).contains(&best.window));
    let seq = |name: &str| g.sequences().iter().position(|s| s.name == name).unwrap();
    let (a, b) = (
        g.flat_id(seq(&best.from), best.m),
        g.flat_id(seq(&best.to), best.n),
    );
    let s = transition_smoothness(&ch, a, b.next(), best.window);
    assert!((s - best.smoothness).abs() < 1e-9, "{best:?} measures {s}");
    let mut covered = 0;
    for tr in g.transitions() {
        let (li, lj) = (g.sequences()[tr.from].len, g.sequences()[tr.to].len);
        let fits = tr.m.min(tr.n) >= tr.window
            && tr.m + tr.window < li
            && tr.n + tr.window < lj
            && (opts.min_window..=opts.max_window).contains(&tr.window);
        if !fits {
            continue;
        }
        let (x, y) = (g.flat_id(tr.from, tr.m), g.flat_id(tr.to, tr.n));
        let s = transition_smoothness(&ch, x, y.next(), tr.window);
        assert!(best.smoothness <= s + 1e-9, "{tr:?}: {s} < floor {best:?}");
        covered += 1;
    }
    assert!(covered > 0);
    assert_eq!(t.pairs.len(), 3);
    // Walk 02_01:0 to run 02_03:30: at least one transition.
    let (from, to) = (g.flat_id(0, 0), g.flat_id(1, 30));
    let priced = surfmotion::keyframe::KeyframeOptions {
        transition_cost: surfmotion::keyframe::TransitionCost::Smoothness,
        ..Default::default()
    };
    let graph = surfmotion::keyframe::key_graph(&ch, &priced);
    let all = surfmotion::keyframe::graph::KeyGraph::of_character_with(&ch, Some(&t.bounds));
    let pg = path_floor(&graph, from, to, 20);
    let pa = path_floor(&all, from, to, 20);
    assert!(!pg.direct && !pa.direct);
    let (kg, vg) = pg.best.expect("the graph joins walk and run");
    let (_, va) = pa.best.expect("so does every frame pair");
    assert!(va <= vg + 1e-9 && va >= 0.0, "{va} > {vg}");
    assert!((1..=20).contains(&kg));
}
