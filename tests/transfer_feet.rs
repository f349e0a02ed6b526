//! The transferred surface stands on the ground where the clip's feet do
//! (Confluent Motion, de Aguiar et al. 2007, Sec. 5, driven by the
//! retargeting kernel): generated clips of the scan's own skeleton.

mod common;

use glam::{DQuat, DVec3};
use surfmotion::mesh::io::{LoadOptions, load_sequence};
use surfmotion::rig::Canonical as C;
use surfmotion::rig::embed::landmarks::Landmarks;
use surfmotion::rig::embed::parts::Part;
use surfmotion::rig::retarget::choose_reference;
use surfmotion::skeleton::Pose;
use surfmotion::transfer::{Job, MarkerOptions, MarkerSpec, Source, prepare, transfer};

/// The scan's own skeleton standing as at rest for `still` frames, then
/// rising onto the ball of its left foot by `deg` (the ankle turned up
/// about the toe joint, the knee following it) and holding that for
/// `held` frames: the foot's held elevation is then the ball's, not the
/// rest's (the samba dancer's left foot, frames 130-175), and the kernel
/// takes its flat stance from it.
fn on_the_ball(rest: &Pose, deg: f64, still: usize, held: usize) -> Vec<Pose> {
    let (a, k, kn) = (C::LAnkle.index(), C::LToe.index(), C::LKnee.index());
    let f = rest[k] - rest[a];
    let axis = f.cross(DVec3::Y).normalize();
    let q = DQuat::from_axis_angle(axis, -deg.to_radians());
    let mut up = *rest;
    up[a] = rest[k] + q * (rest[a] - rest[k]);
    up[kn] = rest[kn] + (up[a] - rest[a]);
    let mut out = vec![*rest; still];
    out.extend(std::iter::repeat_n(up, held));
    out
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_surface_stands_on_the_ground_where_the_clip_does() {
    let Some(d) = common::data_dir() else { return };
    let seq = load_sequence(
        d.join("4d/samba/samba.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    let scan = seq.frame_mesh(0);
    let lm = Landmarks::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/samba.landmarks.json"),
        scan.vertex_count(),
    )
    .unwrap();
    let opts = MarkerOptions {
        count: 20,
        ..Default::default()
    };
    let prepared = prepare(&scan, MarkerSpec::Landmarks(&lm, opts)).unwrap();
    let rig = prepared.rig.as_ref().unwrap();
    let rest: Pose = rig.joints.map(DVec3::from_array);
    let n = prepared.mesh.vertex_count();
    let p0 = prepared.mesh.positions();
    let feet = [Part::LFoot, Part::RFoot].map(|part| {
        (0..n)
            .filter(|&v| rig.labels[v] as usize == part.index())
            .collect::<Vec<_>>()
    });
    let low = |p: &[[f64; 3]], f: usize| {
        feet[f]
            .iter()
            .map(|&v| p[v][1])
            .fold(f64::INFINITY, f64::min)
    };
    let rest_low = [low(p0, 0), low(p0, 1)];
    for deg in [12.0, 25.0, 40.0] {
        for (still, held) in [(6, 24), (10, 40)] {
            let poses = on_the_ball(&rest, deg, still, held);
            let reference = choose_reference(Some(&rest), &poses).unwrap();
            let mut job = Job::new(&prepared, Source::Mocap(&poses, &reference)).unwrap();
            let (out, _) = transfer(
                &job.confluent,
                &mut job.motion,
                &Default::default(),
                &|_| {},
            );
            for (i, p) in out.chunks(n).enumerate() {
                // Both feet stand on the floor in every frame: none below
                // it, the lower on it (1 mm; the surface moves with the
                // skeleton, so a lifted body stands every foot above).
                let gaps = [low(p, 0) - rest_low[0], low(p, 1) - rest_low[1]];
                let lower = gaps[0].min(gaps[1]);
                assert!(
                    lower.abs() < 1e-3,
                    "{deg}°, {still}+{held} frames, frame {i}: the lower foot is {:.2} cm off the floor (left {:.2}, right {:.2})",
                    100.0 * lower,
                    100.0 * gaps[0],
                    100.0 * gaps[1]
                );
            }
        }
    }
}
