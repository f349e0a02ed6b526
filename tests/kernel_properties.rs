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
