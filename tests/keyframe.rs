//! Key-frame animation (Huang et al. 2015, Sec. 5.1): the search on
//! synthetic frame graphs (walks, loops, repetitions against brute force
//! and Dijkstra) and the `keyframe` command on a small synthetic database.

mod common;

use std::collections::BinaryHeap;
use std::process::Command;
use surfmotion::keyframe::graph::KeyGraph;
use surfmotion::keyframe::repeats::{Measure, Problem, brute_force, solve_exact, solve_ilp};
use surfmotion::keyframe::search::{SearchOptions, Target};
use surfmotion::keyframe::{Planner, Targets};

/// A small deterministic generator (no dependency).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn below(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
}

fn random_problem(r: &mut Lcg, loops: &mut Vec<Measure>) -> (Measure, f64, f64) {
    loops.clear();
    for _ in 0..1 + r.below(3) {
        loops.push(Measure {
            cost: 0.05 * r.next(),
            distance: 0.2 + 1.5 * r.next(),
            frames: 3 + r.below(12) as u32,
        });
    }
    let walk = Measure {
        cost: 0.1 * r.next(),
        distance: 2.0 * r.next(),
        frames: 1 + r.below(20) as u32,
    };
    (walk, 3.0 * r.next(), 40.0 * r.next())
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
        };
        // No count past the frames at which the time error alone exceeds the
        // cost of n = 0 can be optimal: brute force up to there.
        let c0 = p.cost(&vec![0; loops.len()]);
        let frames = t - walk.frames as f64 + (c0 - walk.cost) / p.w_time;
        let limit = (frames.max(0.0) / 3.0).ceil() as u32;
        let b = brute_force(&p, limit);
        let e = solve_exact(&p, f64::INFINITY, 1_000_000).unwrap();
        let i = solve_ilp(&p).unwrap();
        assert!(
            (e.cost - b.cost).abs() < 1e-9,
            "case {case}: exact {e:?} brute {b:?}"
        );
        assert!(
            (i.cost - b.cost).abs() < 1e-6,
            "case {case}: ilp {i:?} brute {b:?}"
        );
        assert!((p.cost(&e.n) - e.cost).abs() < 1e-9);
    }
}
