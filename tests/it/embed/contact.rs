//! Contact-proof rigging (issue 41) on generated variants of the real
//! captures: each capture re-ordered so that a frame with both hands on
//! the hips (samba, frames 120-174) or a hand against the hip (crane,
//! frames 35-38) comes first, its topology that frame, and the landmark
//! fixtures carried onto it as a user would have marked them there. The
//! rest frame chosen must be clear, and the rig embedded on it is compared
//! with the rig of the original (clear) first frame: joints over the frames
//! in % of the height, parts agreeing (issue 41's target, 1 % and 95 %, is
//! not reached yet: see the figures in the test).

use crate::common;

use std::path::{Path, PathBuf};
use surfmotion::embed::Embedding;
use surfmotion::embed::contact::{ContactFinder, ContactOptions};
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::embed::rest::{RestOptions, choose_rest_frame};
use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::{LoadOptions, load_sequence};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

struct Case {
    name: &'static str,
    pc2: &'static str,
    landmarks: &'static str,
    /// A frame with a contact, put first.
    contact: usize,
}

const CASES: [Case; 2] = [
    Case {
        name: "samba",
        pc2: "4d/samba/samba.pc2",
        landmarks: "samba.landmarks.json",
        contact: 130,
    },
    Case {
        name: "crane",
        pc2: "4d/crane/crane.pc2",
        landmarks: "crane.landmarks.json",
        contact: 37,
    },
];

/// The sequence re-ordered to start at `first` (a rotation of its frames).
fn reordered(seq: &MeshSequence, first: usize) -> MeshSequence {
    let n = seq.mesh().vertex_count();
    let nf = seq.frame_count();
    let mut frames = Vec::with_capacity(nf * n);
    for k in 0..nf {
        frames.extend_from_slice(seq.frame((first + k) % nf));
    }
    let mesh = seq.frame_mesh(first);
    MeshSequence::new(mesh, frames, seq.fps).unwrap()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_original_first_frames_are_clear_and_the_contact_frames_are_not() {
    let Some(d) = common::data_dir() else { return };
    for c in &CASES {
        let seq = load_sequence(d.join(c.pc2).to_str().unwrap(), &LoadOptions::default()).unwrap();
        let f = ContactFinder::new(&seq.frame_mesh(0), ContactOptions::default());
        let first = f.find(seq.frame(0));
        assert!(
            first.contacts.is_empty(),
            "{}: {:?}",
            c.name,
            first.contacts
        );
        let touch = f.find(seq.frame(c.contact));
        assert!(
            !touch.contacts.is_empty() && touch.touching >= 50,
            "{}: frame {} {:?}",
            c.name,
            c.contact,
            touch
        );
        // Every side of every contact is one connected set apart from the
        // other sides along the surface.
        for k in &touch.contacts {
            assert!(k.sides.len() >= 2, "{}: {k:?}", c.name);
            assert!(k.gap < 0.015 * f.height());
        }
        // Contacts do not depend on where the body stands (translated).
        let moved: Vec<[f64; 3]> = seq
            .frame(c.contact)
            .iter()
            .map(|p| [p[0] + 3.0, p[1], p[2] - 1.5])
            .collect();
        let again = f.find(&moved);
        assert_eq!(again.touching, touch.touching, "{}", c.name);
    }
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_capture_starting_in_contact_rigs_as_well_as_from_a_clear_frame() {
    let Some(d) = common::data_dir() else { return };
    for c in &CASES {
        let seq = load_sequence(d.join(c.pc2).to_str().unwrap(), &LoadOptions::default()).unwrap();
        let n = seq.mesh().vertex_count();
        let clear_mesh = seq.frame_mesh(0);
        let lm = Landmarks::load(&fixture(c.landmarks), n).unwrap();
        let truth = Embedding::new(&clear_mesh, &lm, None).unwrap();

        // The variant: a contact frame first, the landmarks marked on it.
        let var = reordered(&seq, c.contact);
        let topo = var.mesh().clone();
        let lm_var = lm.moved(clear_mesh.positions(), topo.positions(), topo.triangles());
        let mut frames: Vec<&[[f64; 3]]> = vec![topo.positions()];
        frames.extend((0..var.frame_count()).map(|f| var.frame(f)));
        let choice = choose_rest_frame(&topo, &frames, &RestOptions::default()).unwrap();
        assert!(
            !choice.first.contacts.is_empty(),
            "{}: frame 0 has a contact",
            c.name
        );
        assert!(choice.frame > 0, "{}: {}", c.name, choice.why);
        assert!(
            choice.contacts.contacts.is_empty(),
            "{}: the rest frame chosen is clear: {}",
            c.name,
            choice.why
        );
        let rest = frames[choice.frame];
        let rig = Embedding::new_on_frame(&topo, rest, &lm_var, None).unwrap();
        // What the rig was before: embedded on the contact frame itself
        // (refused outright on samba's hands-on-hips frame).
        let naive = Embedding::new(&topo, &lm_var, None);

        let agree = |e: &Embedding| {
            e.labels()
                .iter()
                .zip(truth.labels())
                .filter(|(a, b)| a == b)
                .count() as f64
                / n as f64
        };
        // Joints over every 5th original frame, in % of the height.
        let joint_err = |e: &Embedding| {
            let (mut sum, mut count, mut worst) = (0.0, 0usize, 0.0f64);
            for f in (0..seq.frame_count()).step_by(5) {
                let a = e.frame_joints(seq.frame(f));
                let b = truth.frame_joints(seq.frame(f));
                for (x, y) in a.iter().zip(&b) {
                    let d = x.distance(*y) / truth.height() * 100.0;
                    sum += d;
                    worst = worst.max(d);
                    count += 1;
                }
            }
            (sum / count as f64, worst)
        };
        let (mean, worst) = joint_err(&rig);
        let before = match &naive {
            Ok(e) => {
                let (m, w) = joint_err(e);
                format!(
                    "parts {:.1} %, joints {m:.2} % (worst {w:.2} %)",
                    100.0 * agree(e)
                )
            }
            Err(e) => format!("refused: {e}"),
        };
        eprintln!(
            "{}: rest frame {} of {} ({}); chosen: parts {:.1} % agree, joints {mean:.2} % (worst {worst:.2} %) of the height; \
             on the contact frame: {before}",
            c.name,
            choice.frame,
            frames.len(),
            choice.why,
            100.0 * agree(&rig),
        );
        // Issue 41's target is parts >= 95 % and joints <= 1 % of the
        // height; NOT reached yet: samba measured 91.9 % and 1.56 % (worst
        // 5.1 %) with the rest frame chosen (original frame 29, arms out,
        // a leg stepping). Guarded at the measured level so it does not get
        // worse; crane's figures are printed, not yet measured at this
        // commit.
        if c.name == "samba" {
            assert!(agree(&rig) >= 0.91, "{}: parts {}", c.name, agree(&rig));
            assert!(mean <= 1.6, "{}: joints {mean} % of the height", c.name);
        }
        // The stored rest joints are the topology's (the contact frame's).
        let on_topo = rig.frame_joints(topo.positions());
        for (j, p) in rig.joints().iter().enumerate() {
            assert!(
                glam::DVec3::from_array(*p).distance(on_topo[j]) < 1e-9,
                "{}: joint {j}",
                c.name
            );
        }
    }
}
