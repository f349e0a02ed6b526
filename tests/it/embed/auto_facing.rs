//! The automatic rig's facing (issue 41) turns with the body: on samba,
//! crane and the synthetic humanoid walking, turned about the vertical by
//! 30°, 90°, 180° and 270°, mirrored (x → −x), and with the vertices
//! re-ordered, the facing `auto_rig` reports lies within [`BOUND_DEG`] of
//! the landmark rig's (knees, elbows and wrists: `embed::joints`) turned
//! and mirrored the same way. Main's rule (square to the line through the
//! hips found on the legs' paths) put samba's 31° off, (0.86, 0, −0.51):
//! one hip was found at a band of the skirt, 12 cm behind the other
//! (`SURFMOTION_AUTORIG=facing=hips` runs these tests with it).

use crate::common;

use glam::{DMat3, DVec3};
use std::borrow::Cow;
use surfmotion::embed::Embedding;
use surfmotion::embed::auto::options::{AutoOptions, automatic_setup};
use surfmotion::embed::auto::report::AutoRig;
use surfmotion::embed::auto::rig::auto_rig;
use surfmotion::mesh::Mesh;

/// The bound (degrees) between the automatic rig's facing and the
/// landmark rig's. Measured (session 28): samba, crane and the synthetic
/// walk within 1.2° in every variant.
const BOUND_DEG: f64 = 5.0;

/// A variant: turned by `yaw` degrees about +Y, then mirrored across
/// x = 0 when `mirror`; the vertices re-ordered when `shuffle`.
#[derive(Debug, Clone, Copy)]
struct Variant {
    yaw: f64,
    mirror: bool,
    shuffle: bool,
}

impl Variant {
    fn map(&self) -> DMat3 {
        let turn = DMat3::from_rotation_y(self.yaw.to_radians());
        let flip = DMat3::from_diagonal(DVec3::new(if self.mirror { -1.0 } else { 1.0 }, 1.0, 1.0));
        flip * turn
    }
}

const VARIANTS: [Variant; 6] = [
    Variant {
        yaw: 0.0,
        mirror: false,
        shuffle: false,
    },
    Variant {
        yaw: 30.0,
        mirror: false,
        shuffle: false,
    },
    Variant {
        yaw: 90.0,
        mirror: true,
        shuffle: false,
    },
    Variant {
        yaw: 180.0,
        mirror: false,
        shuffle: true,
    },
    Variant {
        yaw: 270.0,
        mirror: false,
        shuffle: false,
    },
    Variant {
        yaw: 30.0,
        mirror: true,
        shuffle: true,
    },
];

/// A fixed shuffle of `0..n` (a linear congruential generator).
fn shuffled(n: usize) -> Vec<u32> {
    let mut p: Vec<u32> = (0..n as u32).collect();
    let mut s: u64 = 0x2545_f491_4f6c_dd1d;
    for i in (1..n).rev() {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        p.swap(i, (s >> 33) as usize % (i + 1));
    }
    p
}

/// `mesh` and `frames` as `v` makes them.
fn variant(mesh: &Mesh, frames: &[Vec<[f64; 3]>], v: Variant) -> (Mesh, Vec<Vec<[f64; 3]>>) {
    let m = v.map();
    let n = mesh.vertex_count();
    // New vertex k is old vertex order[k].
    let order: Vec<u32> = if v.shuffle {
        shuffled(n)
    } else {
        (0..n as u32).collect()
    };
    let mut new_of = vec![0u32; n];
    for (k, &o) in order.iter().enumerate() {
        new_of[o as usize] = k as u32;
    }
    let place = |f: &[[f64; 3]]| -> Vec<[f64; 3]> {
        order
            .iter()
            .map(|&o| (m * DVec3::from_array(f[o as usize])).to_array())
            .collect()
    };
    let tris = mesh
        .triangles()
        .iter()
        .map(|t| {
            let t = t.map(|i| new_of[i as usize]);
            if v.mirror { [t[0], t[2], t[1]] } else { t }
        })
        .collect();
    let out = Mesh::new(place(mesh.positions()), tris).unwrap();
    (out, frames.iter().map(|f| place(f)).collect())
}

/// Each variant's automatic facing against `truth`'s facing moved by the
/// variant: the angles (degrees), and the variants past [`BOUND_DEG`].
/// `as_captured`: the rig of the first variant (the capture as it is),
/// when another test has made it with these options
/// (`embed::auto::db_init_rig` with the topology as its rest frame).
fn facing_errors(
    name: &str,
    mesh: &Mesh,
    frames: &[Vec<[f64; 3]>],
    truth: &Embedding,
    as_captured: Option<&AutoRig>,
) -> Vec<String> {
    let mut bad = Vec::new();
    for v in VARIANTS {
        let plain = v.yaw == 0.0 && !v.mirror && !v.shuffle;
        let rig = match as_captured.filter(|_| plain) {
            Some(rig) => Cow::Borrowed(rig),
            None => {
                let (m, fr) = variant(mesh, frames, v);
                let f: Vec<&[[f64; 3]]> = fr.iter().map(Vec::as_slice).collect();
                // `db init`'s options (`SURFMOTION_AUTORIG` applied:
                // `facing=hips` is main's rule), the parts found on the
                // mesh's positions.
                let (_, opts) = automatic_setup(&AutoOptions::default()).unwrap();
                Cow::Owned(auto_rig(&m, &f, &opts).unwrap())
            }
        };
        let want = v.map() * DVec3::from_array(truth.facing());
        let got = DVec3::from_array(rig.facing);
        let deg = got.dot(want).clamp(-1.0, 1.0).acos().to_degrees();
        eprintln!("{name} {v:?}: facing {got:.3} against {want:.3}: {deg:.1}°");
        let up = v.map() * DVec3::from_array(truth.up());
        let left_ok = DVec3::from_array(rig.left).dot(up.cross(got)) > 0.999;
        if deg > BOUND_DEG || !left_ok {
            bad.push(format!(
                "{name} {v:?}: facing {got:.3}, the landmark rig's {want:.3}: {deg:.1}° apart (bound {BOUND_DEG}°); left {:?}",
                rig.left
            ));
        }
    }
    bad
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn samba_faces_as_its_landmark_rig_turned_mirrored_and_reordered() {
    let Some(d) = common::data_dir() else { return };
    let c = super::auto::capture(&d, "samba");
    let r = super::auto::db_init_rig(&d, "samba", super::auto::Variant::AsCaptured);
    let cached = r.rest.is_none().then_some(&r.rig);
    let bad = facing_errors("samba", &c.mesh, &c.frames, &c.truth, cached);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn crane_faces_as_its_landmark_rig_turned_mirrored_and_reordered() {
    let Some(d) = common::data_dir() else { return };
    let c = super::auto::capture(&d, "crane");
    let r = super::auto::db_init_rig(&d, "crane", super::auto::Variant::AsCaptured);
    let cached = r.rest.is_none().then_some(&r.rig);
    let bad = facing_errors("crane", &c.mesh, &c.frames, &c.truth, cached);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn a_synthetic_walk_faces_as_its_rig_turned_mirrored_and_reordered() {
    use surfmotion::synth::humanoid::{HumanoidShape, humanoid_landmarks_with};
    let (mesh, frames) = super::auto_order::synthetic_walk();
    let lm = humanoid_landmarks_with(mesh, &HumanoidShape::default());
    let truth = Embedding::new(mesh, &lm, None).unwrap();
    let bad = facing_errors("synthetic walk", mesh, frames, &truth, None);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}
