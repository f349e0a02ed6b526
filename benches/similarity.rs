//! Similarity stage on real data (samba, 175 frames, 10K vertices): the
//! per-frame descriptors (and the first version's, which they equal bit for
//! bit: the ratio is the binning's saving), the per-pair distances of each measure, the whole
//! 175 × 175 shape matrix, and the transition search over it. Whole-database
//! figures (1,000 frames) come from `surfmotion db build --json`, which
//! reports descriptor and all-pairs times.

mod common;
/// The first version's binning (outside the library: the tests' oracle).
#[path = "../tests/it/db/histogram_reference.rs"]
mod histogram_reference;

use criterion::measurement::WallTime;
use criterion::{BenchmarkGroup, Criterion};
use glam::DVec3;
use std::hint::black_box;
use surfmotion::embed::Embedding;
use surfmotion::embed::frames::{SkeletonKind, poses};
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::graph::transitions::{TransitionOptions, find};
use surfmotion::similarity::histogram::{DESCRIPTOR_LEN, PHI_SUB, ShapeGrid, describe};
use surfmotion::similarity::{
    PairDistance, ShapeSet, SimilarityMatrix, SkeletonSet, Span, VertexSet, all_pairs,
};

fn main() {
    let Some(d) = common::data() else { return };
    let seq = common::samba(&d);
    let rest = seq.frame_mesh(0);
    let n = rest.vertex_count();
    let frames = seq.frame_count();
    let pts: Vec<DVec3> = seq
        .frame(40)
        .iter()
        .map(|p| DVec3::from_array(*p))
        .collect();
    let rest_pts: Vec<DVec3> = rest
        .positions()
        .iter()
        .map(|p| DVec3::from_array(*p))
        .collect();
    let grid = ShapeSet::grid_for(&rest_pts, rest.triangles());
    let mut shape = ShapeSet::new(grid);
    shape.push_sequence(seq.all_positions(), n, rest.triangles(), false);
    let mut vertex = VertexSet::new(n, Default::default());
    vertex.push_sequence(seq.all_positions(), false);
    let fixture = common::samba_landmarks();
    let lm = Landmarks::load(&fixture, n).unwrap();
    let rig = Embedding::new(&rest, &lm, None).unwrap();
    let skel = SkeletonSet {
        poses: poses(&rig, seq.all_positions(), n, SkeletonKind::Regressor),
    };

    let mut c = Criterion::default().configure_from_args();
    let mut g = c.benchmark_group("similarity/samba");
    let tris = rest.triangles();
    bench_describe(&mut g, "shape_describe_frame", &pts, tris, &grid, describe);
    // The first version's binning, which `describe` equals bit for bit
    // (issue 43, session 27): the ratio of the two is the saving.
    let first = histogram_reference::describe;
    bench_describe(
        &mut g,
        "shape_describe_frame_first_version",
        &pts,
        tris,
        &grid,
        first,
    );
    g.bench_function("shape_pair", |b| {
        b.iter(|| shape.distance(black_box(3), 90))
    });
    g.bench_function("vertex_pair", |b| {
        b.iter(|| vertex.distance(black_box(3), 90))
    });
    g.bench_function("skeleton_pair", |b| {
        b.iter(|| skel.distance(black_box(3), 90))
    });
    g.sample_size(10);
    g.bench_function("shape_all_pairs_175", |b| {
        b.iter(|| all_pairs(black_box(&shape), &|_| ()))
    });
    let m = SimilarityMatrix::new(
        vec![Span {
            name: "samba".into(),
            start: 0,
            len: frames,
        }],
        all_pairs(&shape, &|_| ()),
    )
    .unwrap();
    g.bench_function("transitions_175x175", |b| {
        let c = |r: usize, s: usize| m.get(r, s);
        b.iter(|| {
            find(
                &c,
                frames,
                frames,
                true,
                black_box(&TransitionOptions::default()),
            )
        })
    });
    g.finish();
    c.final_summary();
}

/// A binning's signature: `describe` and the first version's, each with
/// its own scratch.
type Describe<S> =
    fn(&[DVec3], &[[u32; 3]], &ShapeGrid, &mut S, &mut [f32], &mut [f64; PHI_SUB]) -> f64;

/// Benchmarks one binning of the frame `pts` (the set-up both describe
/// benches share: output, norms and scratch made once).
fn bench_describe<S: Default>(
    g: &mut BenchmarkGroup<'_, WallTime>,
    name: &str,
    pts: &[DVec3],
    tris: &[[u32; 3]],
    grid: &ShapeGrid,
    describe: Describe<S>,
) {
    g.bench_function(name, |b| {
        let mut out = vec![0.0; DESCRIPTOR_LEN];
        let mut norms = [0.0; PHI_SUB];
        let mut scratch = S::default();
        b.iter(|| {
            describe(
                black_box(pts),
                tris,
                grid,
                &mut scratch,
                &mut out,
                &mut norms,
            )
        })
    });
}
