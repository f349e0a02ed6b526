//! Property tests for the geometry kernels on random meshes (subdivided
//! icosahedra with random vertex jitter) and random rigid motions.

use glam::{DQuat, DVec3};
use proptest::prelude::*;
use surfmotion::mesh::Mesh;
use surfmotion::mesh::blend::Blender;
use surfmotion::mesh::laplacian::{cotan_triplets, to_rows};
use surfmotion::mesh::subdivide::{icosahedron, midpoint};

/// A xorshift stream of numbers in [-0.5, 0.5).
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s % 10_000) as f64 / 10_000.0 - 0.5
    }
}

fn jittered(seed: u64, amount: f64) -> Mesh {
    let m = midpoint(&icosahedron());
    let mut rnd = uniform(seed);
    let p: Vec<[f64; 3]> = m
        .positions()
        .iter()
        .map(|q| q.map(|v| v * (1.0 + amount * rnd())))
        .collect();
    m.with_positions(&p).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]

    /// L·1 = 0, L symmetric, and −L positive semi-definite along random vectors.
    #[test]
    fn laplacian_invariants(seed in any::<u64>(), amount in 0.0f64..0.6, x in proptest::collection::vec(-1.0f64..1.0, 42)) {
        let m = jittered(seed, amount);
        let rows = to_rows(m.vertex_count(), cotan_triplets(&m));
        let mut quad = 0.0;
        for (i, r) in rows.iter().enumerate() {
            let s: f64 = r.iter().map(|e| e.1).sum();
            prop_assert!(s.abs() < 1e-9);
            for &(j, v) in r {
                let back = rows[j as usize].iter().find(|e| e.0 as usize == i).unwrap().1;
                prop_assert!((back - v).abs() < 1e-12);
                quad -= x[i] * v * x[j as usize];
            }
        }
        prop_assert!(quad >= -1e-9, "xᵀ(−L)x = {quad}");
    }

    /// Blending a mesh with a rigidly moved copy gives the partially moved mesh.
    #[test]
    fn blend_of_rigid_motion_is_rigid(seed in any::<u64>(), ax in -1.0f64..1.0, ay in 0.1f64..1.0, angle in 0.0f64..3.0, alpha in 0.0f64..1.0) {
        let m = jittered(seed, 0.3);
        let axis = DVec3::new(ax, ay, 0.3).normalize();
        let rot = DQuat::from_axis_angle(axis, angle);
        let shift = DVec3::new(0.5, -1.0, 2.0);
        let moved: Vec<[f64; 3]> = m.positions().iter().map(|p| (rot * DVec3::from_array(*p) + shift).to_array()).collect();
        let b = Blender::new(&m).unwrap();
        let mut ws = b.workspace();
        let (g1, g2) = (b.decompose(m.positions(), &mut ws), b.decompose(&moved, &mut ws));
        let mut out = vec![[0.0; 3]; m.vertex_count()];
        b.blend(&g1, &g2, alpha, &mut out, &mut ws);
        let c1 = g1.centroid;
        let c = c1 * (1.0 - alpha) + g2.centroid * alpha;
        let ra = DQuat::from_axis_angle(axis, angle * alpha);
        for (o, p) in out.iter().zip(m.positions()) {
            let want = ra * (DVec3::from_array(*p) - c1) + c;
            prop_assert!((DVec3::from_array(*o) - want).length() < 1e-7);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, .. ProptestConfig::default() })]

    /// Untangling never turns more triangles over than it was given, and
    /// the count it returns is the true count (regression: a move that
    /// fixed two triangles of a fan and turned a third over used to go
    /// uncounted, so the repair reported none left while one was).
    #[test]
    fn untangling_is_monotone_and_counts_truly(seed in 1u64..u64::MAX, amount in 0.05f64..1.0, share in 0.05f64..0.5) {
        use surfmotion::deform::unflip::{Adjacency, turned_over};
        use surfmotion::deform::untangle::{references, untangle};
        let m = midpoint(&midpoint(&icosahedron()));
        let (src, tris) = (m.positions().to_vec(), m.triangles());
        let turn = vec![DQuat::IDENTITY; src.len()];
        let adj = Adjacency::new(src.len(), tris);
        let (mut normals, mut areas) = (vec![DVec3::ZERO; tris.len()], vec![0.0; tris.len()]);
        references(tris, &src, &turn, &mut normals, &mut areas);
        // Shove a random share of the vertices.
        let mut rnd = uniform(seed);
        let mut out = src.clone();
        for p in out.iter_mut() {
            if rnd() + 0.5 < share {
                *p = [p[0] + amount * rnd(), p[1] + amount * rnd(), p[2] + amount * rnd()];
            }
        }
        let bad = turned_over(tris, &src, &out, &turn);
        let given = bad.len();
        let left = untangle(tris, &adj, &normals, &areas, &mut out, bad, &Default::default());
        let recount = turned_over(tris, &src, &out, &turn);
        prop_assert_eq!(&left, &recount);
        prop_assert!(recount.len() <= given, "{} -> {}", given, recount.len());
        prop_assert!(out.iter().flatten().all(|x| x.is_finite()));
    }
}

/// A standing character's canonical joints (metres, Y up, facing +Z).
fn rest_skeleton() -> surfmotion::pose::Pose {
    [
        [0.0, 1.0, 0.0],
        [0.0, 1.15, 0.0],
        [0.0, 1.35, 0.0],
        [0.0, 1.5, 0.0],
        [0.0, 1.65, 0.02],
        [0.18, 1.45, 0.0],
        [0.45, 1.45, 0.0],
        [0.7, 1.45, 0.0],
        [-0.18, 1.45, 0.0],
        [-0.45, 1.45, 0.0],
        [-0.7, 1.45, 0.0],
        [0.1, 0.95, 0.0],
        [0.1, 0.52, 0.01],
        [0.1, 0.08, 0.0],
        [0.1, 0.0, 0.15],
        [-0.1, 0.95, 0.0],
        [-0.1, 0.52, 0.01],
        [-0.1, 0.08, 0.0],
        [-0.1, 0.0, 0.15],
    ]
    .map(DVec3::from_array)
}

/// The rest skeleton with every bone turned by a random rotation about its
/// parent joint (the spine and the two hips by one: the pelvis is rigid),
/// moved.
fn random_pose(rnd: &mut impl FnMut() -> f64, spread: f64) -> surfmotion::pose::Pose {
    use surfmotion::rig::Canonical;
    let rest = rest_skeleton();
    let rot = |rnd: &mut dyn FnMut() -> f64| {
        let axis = DVec3::new(rnd(), rnd(), rnd()).normalize_or(DVec3::Y);
        DQuat::from_axis_angle(axis, spread * rnd())
    };
    let hips = rot(rnd);
    let mut p = rest;
    p[0] = rest[0] + DVec3::new(rnd(), rnd(), rnd());
    for c in Canonical::ALL.iter().skip(1) {
        let par = c.parent().unwrap().index();
        let q = match c {
            Canonical::Spine | Canonical::LHip | Canonical::RHip => hips,
            _ => rot(rnd),
        };
        p[c.index()] = p[par] + q * (rest[c.index()] - rest[par]);
    }
    p
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, .. ProptestConfig::default() })]

    /// A pose of the skeleton itself is fitted back exactly; joints moved by
    /// noise give a pose with the skeleton's bone lengths that is no further
    /// from them than the pose they were made from.
    #[test]
    fn the_rigid_fit_returns_a_posed_skeleton_and_beats_the_true_pose(seed in 1u64..u64::MAX, spread in 0.0f64..3.0, noise in 0.0f64..0.05) {
        use surfmotion::embed::rigid::{FitOptions, RigidSkeleton};
        use surfmotion::pose::measure::bone_lengths;
        let mut rnd = uniform(seed);
        let rest = rest_skeleton();
        let sk = RigidSkeleton::calibrate(&rest, &[rest]);
        let truth = random_pose(&mut rnd, spread);
        let fit = sk.fit(&truth, &FitOptions::default());
        prop_assert!(fit.max < 1e-7, "exact pose: off by {}", fit.max);
        let measured = truth.map(|p| p + noise * DVec3::new(rnd(), rnd(), rnd()));
        let fit = sk.fit(&measured, &FitOptions::default());
        let (want, got) = (bone_lengths(&rest), bone_lengths(&fit.pose));
        for b in 1..want.len() {
            prop_assert!((got[b] - want[b]).abs() < 1e-9, "bone {b}: {} vs {}", got[b], want[b]);
        }
        let e = |p: &surfmotion::pose::Pose| -> f64 {
            p.iter().zip(&measured).map(|(a, b)| a.distance_squared(*b)).sum()
        };
        prop_assert!(e(&fit.pose) <= e(&truth) + 1e-12, "fit {} > truth {}", e(&fit.pose), e(&truth));
    }
}

/// Non-finite measured joints (a NaN in a cache) neither panic nor hang the
/// fit; a skeleton calibrated from no frames keeps its rest lengths.
#[test]
fn the_rigid_fit_survives_non_finite_joints() {
    use surfmotion::embed::rigid::{FitOptions, RigidSkeleton};
    let rest = rest_skeleton();
    let sk = RigidSkeleton::calibrate(&rest, &[]);
    assert_eq!(
        sk.lengths(),
        surfmotion::pose::measure::bone_lengths(&rest),
        "no frames: rest lengths"
    );
    for bad in [f64::NAN, f64::INFINITY] {
        let mut m = rest;
        m[3].x = bad;
        let f = sk.fit(&m, &FitOptions::default());
        assert!(f.iterations <= FitOptions::default().max_iterations);
        let mut all = [DVec3::splat(bad); 19];
        all[0] = DVec3::ZERO;
        let f = sk.fit(&all, &FitOptions::default());
        assert!(f.pose[0].is_finite() || !f.rms.is_finite());
    }
}
