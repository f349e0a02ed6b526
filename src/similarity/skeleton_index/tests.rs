use super::*;
use crate::synth::{Gait, gait_clip};
use glam::{DQuat, DVec3};

/// A seeded xorshift in [0, 1).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
    fn sym(&mut self, r: f64) -> f64 {
        (2.0 * self.next() - 1.0) * r
    }
}

fn gait_poses(g: Gait, seconds: f64) -> Vec<Pose> {
    let clip = gait_clip(g, seconds, 30.0);
    (0..clip.frame_count())
        .map(|f| {
            let w = clip.world_positions(f);
            std::array::from_fn(|j| w[j])
        })
        .collect()
}

/// A varied skeleton set: three gaits as made, mirrored, turned and moved
/// on the floor, rescaled, jittered, with duplicated frames (exact ties).
fn varied_set(rng: &mut Rng) -> Vec<Pose> {
    let mut out = Vec::new();
    for g in Gait::ALL {
        let base = gait_poses(g, 2.0);
        let turn = DQuat::from_rotation_y(rng.sym(3.0));
        let shift = DVec3::new(rng.sym(5.0), 0.0, rng.sym(5.0));
        let scale = 0.8 + 0.4 * rng.next();
        for p in &base {
            out.push(*p);
            out.push(p.map(|v| DVec3::new(-v.x, v.y, v.z)));
            out.push(p.map(|v| turn * v + shift));
            out.push(p.map(|v| v * scale));
            let mut jit = *p;
            for v in &mut jit {
                *v += DVec3::new(rng.sym(0.03), rng.sym(0.03), rng.sym(0.03));
            }
            out.push(jit);
        }
    }
    let dups: Vec<Pose> = out.iter().step_by(7).copied().collect();
    out.extend(dups);
    out
}

fn jittered(p: &Pose, rng: &mut Rng, r: f64) -> Pose {
    let turn = DQuat::from_rotation_y(rng.sym(3.1));
    let shift = DVec3::new(rng.sym(3.0), rng.sym(0.05), rng.sym(3.0));
    p.map(|v| turn * (v + DVec3::new(rng.sym(r), rng.sym(r), rng.sym(r))) + shift)
}

#[test]
fn the_lower_bound_is_never_above_the_distance() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let set = varied_set(&mut rng);
    for _ in 0..20_000 {
        let a = set[(rng.next() * set.len() as f64) as usize];
        let b = if rng.next() < 0.5 {
            jittered(
                &set[(rng.next() * set.len() as f64) as usize],
                &mut rng,
                0.1,
            )
        } else {
            // Unstructured joints: any point cloud, tilted too.
            std::array::from_fn(|_| DVec3::new(rng.sym(1.0), rng.sym(2.0), rng.sym(1.0)))
        };
        let (d, lb) = (
            skeleton_distance(&a, &b),
            lower_bound(&features(&a), &features(&b)),
        );
        assert!(lb <= d * (1.0 + 1e-12) + 1e-12, "LB {lb} > c_skel {d}");
        // The bound is symmetric; the distance nearly so.
        assert_eq!(lb, lower_bound(&features(&b), &features(&a)));
    }
}

#[test]
fn the_index_finds_what_the_scan_finds() {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let set = varied_set(&mut rng);
    let index = PoseIndex::new(&set);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let mut scratch = Search::default();
    let mut queries = 0;
    for k in [1, 2, 8, 128, set.len() - 1, set.len(), set.len() + 5] {
        for i in 0..40 {
            let q = match i % 4 {
                // A database frame itself: ties with its duplicates.
                0 => set[(rng.next() * set.len() as f64) as usize],
                1 => jittered(
                    &set[(rng.next() * set.len() as f64) as usize],
                    &mut rng,
                    0.02,
                ),
                2 => jittered(
                    &set[(rng.next() * set.len() as f64) as usize],
                    &mut rng,
                    0.3,
                ),
                _ => std::array::from_fn(|_| DVec3::new(rng.sym(1.0), rng.sym(2.0), rng.sym(1.0))),
            };
            nearest_scan(&set, &q, k, &mut a);
            index.nearest(&set, &q, k, &mut scratch, &mut b);
            assert_eq!(a.len(), k.min(set.len()));
            assert_eq!(a, b, "k {k} query {i}");
            queries += 1;
        }
    }
    // The index computes fewer distances than a scan would.
    assert!(scratch.evaluated < (queries * set.len()) as u64);
}

#[test]
fn exact_ties_are_ordered_by_frame_id() {
    let p = gait_poses(Gait::Walk, 0.5);
    // The same pose four times and once turned and moved (c_skel 0 up to
    // rounding): the k smallest by (cost, id) whatever the ties.
    let q = p[3];
    let moved = q.map(|v| DQuat::from_rotation_y(1.0) * v + DVec3::new(2.0, 0.0, 1.0));
    let set: Vec<Pose> = vec![p[0], q, p[5], q, moved, q, p[9], q];
    let index = PoseIndex::new(&set);
    let (mut a, mut b, mut s) = (Vec::new(), Vec::new(), Search::default());
    for k in 1..=set.len() {
        nearest_scan(&set, &q, k, &mut a);
        index.nearest(&set, &q, k, &mut s, &mut b);
        assert_eq!(a, b, "k {k}");
    }
    nearest_scan(&set, &q, 2, &mut a);
    assert_eq!(a, vec![(0.0, 1), (0.0, 3)]);
}

#[test]
fn one_frame_none_and_non_finite_frames() {
    let p = gait_poses(Gait::Run, 0.5);
    let (mut a, mut b, mut s) = (Vec::new(), Vec::new(), Search::default());
    let one = vec![p[2]];
    let index = PoseIndex::new(&one);
    index.nearest(&one, &p[4], 5, &mut s, &mut b);
    nearest_scan(&one, &p[4], 5, &mut a);
    assert_eq!((a.len(), &a), (1, &b));
    let none: Vec<Pose> = Vec::new();
    PoseIndex::new(&none).nearest(&none, &p[4], 5, &mut s, &mut b);
    assert!(b.is_empty());
    // A frame with a NaN joint is outside the tree but still ranked.
    let mut bad = p.clone();
    bad[3][5].x = f64::NAN;
    let index = PoseIndex::new(&bad);
    for k in [1, 3, bad.len()] {
        nearest_scan(&bad, &p[7], k, &mut a);
        index.nearest(&bad, &p[7], k, &mut s, &mut b);
        assert_eq!(format!("{a:?}"), format!("{b:?}"), "k {k}");
    }
    // A NaN query falls back to the scan.
    let mut q = p[7];
    q[0].y = f64::NAN;
    nearest_scan(&bad, &q, 4, &mut a);
    index.nearest(&bad, &q, 4, &mut s, &mut b);
    assert_eq!(format!("{a:?}"), format!("{b:?}"));
}
