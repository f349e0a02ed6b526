//! The automatic rig's knees (issue 41): on samba (a dancer in a skirt)
//! the knee was once placed at the skirt's hem (4.2 % of the height off
//! the landmark rig's, the thigh bones 24 % apart), which tore the skirt
//! and sank the feet in every retargeted frame. Here both knees must lie
//! within 3 % of the height of the landmark rig's, on samba and crane and
//! on generated variants of samba: frames reversed, mirrored (left and
//! right swap), turned Z-up, scaled to cm, and re-ordered so that a frame
//! with both hands on the hips comes first (the rest frame then chosen
//! clear of contact, as `db init` chooses it); that last rig is compared
//! with the clear order's (issue 41 asks 1 % and 95 %: not reached, the
//! measured figures are guarded).

use super::auto::{Variant, capture, db_init_rig};
use crate::common;

use glam::DVec3;
use surfmotion::embed::Embedding;
use surfmotion::mesh::Mesh;
use surfmotion::rig::Canonical;

/// The figure's bound, in % of the height.
const KNEE_BOUND: f64 = 3.0;

/// The automatic rig's embedding as `db init` makes it
/// ([`super::auto::rig_as_db_init`]), for a capture no other test rigs.
pub(super) fn auto_embedding(mesh: &Mesh, frames: &[Vec<[f64; 3]>]) -> Embedding {
    super::auto::rig_as_db_init(mesh, frames).embedding
}

/// The knees' distances (left, right) in % of `height` between `mine` and
/// `truth`; `swap` pairs left with right (a mirrored body).
fn knees(mine: &[[f64; 3]; 19], truth: &[[f64; 3]; 19], height: f64, swap: bool) -> [f64; 2] {
    let (l, r) = (Canonical::LKnee.index(), Canonical::RKnee.index());
    let (tl, tr) = if swap { (r, l) } else { (l, r) };
    let d = |a: usize, b: usize| {
        100.0 * DVec3::from_array(mine[a]).distance(DVec3::from_array(truth[b])) / height
    };
    [d(l, tl), d(r, tr)]
}

fn assert_knees(what: &str, k: [f64; 2]) {
    assert!(
        k[0] <= KNEE_BOUND && k[1] <= KNEE_BOUND,
        "{what}: knees {:.2}% and {:.2}% of the height from the landmark rig's (bound {KNEE_BOUND}%)",
        k[0],
        k[1]
    );
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_knees_of_the_real_captures_are_the_landmark_rigs() {
    let Some(d) = common::data_dir() else { return };
    for name in ["samba", "crane"] {
        let truth = &capture(&d, name).truth;
        let e = &db_init_rig(&d, name, Variant::AsCaptured).embedding;
        assert_knees(
            name,
            knees(e.joints(), truth.joints(), truth.height(), false),
        );
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_knees_of_samba_variants_are_the_landmark_rigs() {
    let Some(d) = common::data_dir() else { return };
    let truth = &capture(&d, "samba").truth;
    let h = truth.height();
    for (what, v, swap) in [
        ("reversed", Variant::Reversed, false),
        ("mirrored", Variant::Mirrored, true),
        ("Z-up", Variant::ZUp, false),
        ("cm", Variant::Cm, false),
    ] {
        let e = &db_init_rig(&d, "samba", v).embedding;
        let scale = if v == Variant::Cm { 100.0 } else { 1.0 };
        let want = truth.joints().map(|p| v.point(p));
        assert_knees(what, knees(e.joints(), &want, h * scale, swap));
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn samba_starting_hands_on_hips_rigs_as_from_its_clear_start() {
    let Some(d) = common::data_dir() else { return };
    let c = capture(&d, "samba");
    let (mesh, frames, truth) = (&c.mesh, &c.frames, &c.truth);
    let h = truth.height();
    // Frame 130 (both hands on the hips) first, as `tests/it/embed/contact`
    // makes it: its positions the topology, the frames rotated.
    let first = 130;
    let nf = frames.len();
    let moved: Vec<Vec<[f64; 3]>> = (0..nf).map(|k| frames[(first + k) % nf].clone()).collect();
    let contact_mesh = mesh.with_positions(&frames[first]).unwrap();
    let from_contact = auto_embedding(&contact_mesh, &moved);
    // The landmark rig and the clear-order automatic rig, carried to
    // frame 130.
    let want = truth.frame_joints(&frames[first]).map(|p| p.to_array());
    // Issue 41 asks the contact-first rig to be as good as the clear one
    // (knees within KNEE_BOUND); measured 5.4 % and 2.7 % of the height at
    // the merge of s20-autorig, so the target is not met: guarded here
    // against getting worse.
    let k = knees(from_contact.joints(), &want, h, false);
    assert!(
        k[0] <= 6.0 && k[1] <= 6.0,
        "contact first: knees {:.2}% and {:.2}% of the height from the landmark rig's (measured 5.4/2.7)",
        k[0],
        k[1]
    );
    let clear = &db_init_rig(&d, "samba", Variant::AsCaptured).embedding;
    let carried = clear.frame_joints(&frames[first]);
    let mean = Canonical::ALL
        .into_iter()
        .map(|j| carried[j.index()].distance(DVec3::from_array(from_contact.joints()[j.index()])))
        .sum::<f64>()
        / 19.0;
    let agree = clear
        .labels()
        .iter()
        .zip(from_contact.labels())
        .filter(|(a, b)| a == b)
        .count() as f64
        / clear.labels().len() as f64;
    eprintln!(
        "samba contact-first vs clear order: joints {:.2}% of the height, parts agree {:.1}%",
        100.0 * mean / h,
        100.0 * agree
    );
    // Measured 2.95 % and 82.4 % (`examples/autorig_eval.rs`); issue 41's
    // 1 % and 95 % are not reached: guarded here against getting worse.
    assert!(
        100.0 * mean / h <= 3.5 && agree >= 0.8,
        "contact first vs clear: joints {:.2}%, parts {:.1}%",
        100.0 * mean / h,
        100.0 * agree
    );
}
