//! Mocap stage: parse + forward kinematics of every frame, on real CMU data
//! (cgspeed BVH 01_01, 2,752 frames; the largest AMC, 02_10, 2,645 frames).
//! Throughput is reported in frames per second.

mod common;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{DQuat, DVec3};
use std::hint::black_box;
use std::path::Path;
use surfmotion::mocap::Clip;
use surfmotion::mocap::asfamc::{AmcOptions, parse_amc, parse_asf};
use surfmotion::mocap::bvh::{BvhOptions, parse_bvh};

use common::data;

/// FK of every frame into reused buffers; returns a checksum.
fn fk_all(c: &Clip, pos: &mut [DVec3], rot: &mut [DQuat]) -> f64 {
    let mut s = 0.0;
    for f in 0..c.frame_count() {
        c.world_into(f, pos, rot);
        s += pos[pos.len() - 1].x;
    }
    s
}

fn bench(cr: &mut Criterion) {
    let Some(d) = data() else { return };
    let mut g = cr.benchmark_group("mocap");
    g.sample_size(20);

    let bvh_path = d.join("mocap/cmu-bvh/01_01.bvh");
    let text = std::fs::read_to_string(&bvh_path).unwrap();
    let clip = parse_bvh(&text, &bvh_path, &BvhOptions::default()).unwrap();
    let n = clip.joint_count();
    let (mut pos, mut rot) = (vec![DVec3::ZERO; n], vec![DQuat::IDENTITY; n]);
    g.throughput(Throughput::Elements(clip.frame_count() as u64));
    g.bench_function("bvh_parse_01_01", |b| {
        b.iter(|| parse_bvh(black_box(&text), Path::new("b"), &BvhOptions::default()).unwrap())
    });
    g.bench_function("bvh_fk_01_01", |b| {
        b.iter(|| fk_all(black_box(&clip), &mut pos, &mut rot))
    });
    g.bench_function("bvh_parse_fk_01_01", |b| {
        b.iter(|| {
            let c = parse_bvh(black_box(&text), Path::new("b"), &BvhOptions::default()).unwrap();
            fk_all(&c, &mut pos, &mut rot)
        })
    });

    let asf = std::fs::read_to_string(d.join("mocap/cmu-amc/02/02.asf")).unwrap();
    let amc_path = d.join("mocap/cmu-amc/02/02_10.amc");
    let amc = std::fs::read_to_string(&amc_path).unwrap();
    let skel = parse_asf(&asf, Path::new("02.asf")).unwrap();
    let clip = parse_amc(&amc, &amc_path, &skel, &AmcOptions::default()).unwrap();
    let n = clip.joint_count();
    let (mut pos, mut rot) = (vec![DVec3::ZERO; n], vec![DQuat::IDENTITY; n]);
    g.throughput(Throughput::Elements(clip.frame_count() as u64));
    g.bench_function("amc_parse_fk_02_10", |b| {
        b.iter(|| {
            let s = parse_asf(black_box(&asf), Path::new("a")).unwrap();
            let c = parse_amc(black_box(&amc), Path::new("m"), &s, &AmcOptions::default()).unwrap();
            fk_all(&c, &mut pos, &mut rot)
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
