//! Character stage on real data: embedding a rig in samba from the landmark
//! fixture, extracting skeletons for all 175 samba frames (measured joints,
//! and the rigid skeleton fitted to them), and synthesising
//! a 1,000-frame database sequence (a procedural walk driving samba).

mod common;

use criterion::Criterion;
use std::hint::black_box;
use surfmotion::embed::Embedding;
use surfmotion::embed::frames::{SkeletonKind, poses};
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::pose::retarget::clip_poses;
use surfmotion::synth::database::{Dynamics, drive};
use surfmotion::synth::{Gait, gait_clip};

fn main() {
    let Some(d) = common::data() else { return };
    let seq = common::samba(&d);
    let rest = seq.frame_mesh(0);
    let n = rest.vertex_count();
    let fixture = common::samba_landmarks();
    let lm = Landmarks::load(&fixture, n).unwrap();
    let mut c = Criterion::default().configure_from_args();
    let mut g = c.benchmark_group("character/samba");
    g.sample_size(10);
    g.bench_function("embed_rig", |b| {
        b.iter(|| Embedding::new(black_box(&rest), &lm, None).unwrap())
    });
    let rig = Embedding::new(&rest, &lm, None).unwrap();
    g.bench_function("skeletons_175_frames", |b| {
        b.iter(|| {
            poses(
                &rig,
                black_box(seq.all_positions()),
                n,
                SkeletonKind::Regressor,
            )
        })
    });
    // The rigid skeleton: regressor joints, calibration and 175 fits.
    g.bench_function("rigid_skeletons_175_frames", |b| {
        b.iter(|| poses(&rig, black_box(seq.all_positions()), n, SkeletonKind::Rigid))
    });
    let clip = gait_clip(Gait::Walk, 1000.0 / 30.0, 30.0);
    let names = clip.point_names();
    let map = surfmotion::rig::detect(&names).map;
    let mocap = clip_poses(&clip, &map).unwrap();
    assert_eq!(mocap.poses.len(), 1000);
    g.bench_function("synthesise_1000_frames", |b| {
        b.iter(|| {
            drive(
                &rest,
                &rig,
                black_box(&mocap.poses),
                &mocap.reference,
                30.0,
                Dynamics::default(),
            )
        })
    });
    g.finish();
    c.final_summary();
}
