//! The automatic rig does not depend on how the file numbers its
//! vertices (issue 41): samba, crane and the synthetic walk, rigged as
//! `db init` rigs them, with their vertices renumbered (reversed,
//! shuffled, interleaved) rest on the same frame, give every vertex the
//! same part (through the renumbering) and the same joints and landmarks
//! within [`BOUND`] of the height.
//!
//! The decomposition is `db init`'s default when that is numbering-free,
//! else [`PINNED`]. The main's default until session 30
//! (`Seeding::Index`) seeds its k-means at vertex `n / 2` and draws the
//! next seeds walking the vertices in index order:
//! `SURFMOTION_AUTORIG=seed=index` runs these tests with it, and they
//! fail (samba renumbered: a joint 2.0-5.6 % of the height away).
//!
//! The rest frame is chosen for each numbering (`embed::rest`), the
//! contact finder's surface patches seeded by position
//! (`ContactOptions::seed_by_position`, session 30; an option): seeded at
//! vertex 0 (the default), samba with its odd ids first finds "1 contact,
//! 4 vertices touching" on its clear frame 0 and rests on frame 27
//! (session 29).

use super::renumber::renumbered;
use crate::common;

use glam::DVec3;
use surfmotion::embed::Embedding;
use surfmotion::embed::auto::decompose::{DecomposeOptions, Seeding};
use surfmotion::embed::auto::options::{AutoOptions, automatic_setup};
use surfmotion::embed::auto::report::AutoRig;
use surfmotion::embed::auto::rig::auto_rig;
use surfmotion::embed::rest::choose_rest_frame;
use surfmotion::mesh::Mesh;

/// The decomposition tested while `db init`'s default follows the
/// numbering.
const PINNED: Seeding = Seeding::Draws(8);

/// Joints and landmarks of a renumbered capture may move by this fraction
/// of the height (the check: 0.1 %).
const BOUND: f64 = 1e-3;

/// Renumberings of `n` vertices: new vertex `k` is old vertex `order[k]`.
fn orders(n: usize) -> Vec<(&'static str, Vec<u32>)> {
    let mut shuffled: Vec<u32> = (0..n as u32).collect();
    let mut s: u64 = 0x9e37_79b9_7f4a_7c15;
    for i in (1..n).rev() {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        shuffled.swap(i, (s >> 33) as usize % (i + 1));
    }
    // Odd ids first, then even ones (a file written in two passes).
    let interleaved: Vec<u32> = (0..n as u32)
        .filter(|v| v % 2 == 1)
        .chain((0..n as u32).filter(|v| v % 2 == 0))
        .collect();
    vec![
        ("reversed", (0..n as u32).rev().collect()),
        ("shuffled", shuffled),
        ("interleaved", interleaved),
    ]
}

/// The rig `db init` makes (its options; the decomposition its default
/// when numbering-free, else [`PINNED`]; `SURFMOTION_AUTORIG` applied
/// over it), on the rest frame `db init` chooses with the contact patches
/// seeded by position (`patches=position`, not yet the default), and its
/// embedding's joints on the rest frame.
fn rig_as_db_init(mesh: &Mesh, frames: &[Vec<[f64; 3]>]) -> (AutoRig, [[f64; 3]; 19]) {
    let mut base = AutoOptions::default();
    if base.decompose.seeding == Seeding::Index {
        base.decompose = DecomposeOptions {
            seeding: PINNED,
            ..base.decompose
        };
    }
    let (mut rule, auto) = automatic_setup(&base).unwrap();
    rule.contact.seed_by_position = true;
    let f: Vec<&[[f64; 3]]> = frames.iter().map(Vec::as_slice).collect();
    let mut all = vec![mesh.positions()];
    all.extend_from_slice(&f);
    let c = choose_rest_frame(mesh, &all, &rule).unwrap();
    let rest = (c.frame > 0).then(|| c.frame - 1);
    let rig = auto_rig(
        mesh,
        &f,
        &AutoOptions {
            rest_frame: rest,
            ..auto
        },
    )
    .unwrap();
    let e = match rest {
        None => Embedding::new(mesh, &rig.landmarks, None),
        Some(r) => Embedding::new_on_frame(mesh, f[r], &rig.landmarks, None),
    }
    .unwrap();
    (rig, *e.joints())
}

/// Every renumbering against the capture's own numbering: the failures.
fn numbering_failures(name: &str, mesh: &Mesh, frames: &[Vec<[f64; 3]>]) -> Vec<String> {
    let (a, ja) = rig_as_db_init(mesh, frames);
    let h = a.height;
    let mut bad = Vec::new();
    for (what, order) in orders(mesh.vertex_count()) {
        let (m, fr) = renumbered(mesh, frames, &order);
        let (b, jb) = rig_as_db_init(&m, &fr);
        if b.rest_frame != a.rest_frame {
            bad.push(format!(
                "{name} {what}: rests on frame {:?}, as numbered on {:?}",
                b.rest_frame, a.rest_frame
            ));
            continue;
        }
        // The same part for every vertex: vertex k of b is vertex order[k]
        // of a (labels are numbered by the positions, so equal).
        let moved = order
            .iter()
            .enumerate()
            .filter(|&(k, &o)| b.labels[k] != a.labels[o as usize])
            .count();
        let dist = |p: [f64; 3], q: [f64; 3]| DVec3::from_array(p).distance(DVec3::from_array(q));
        let joints = ja
            .iter()
            .zip(&jb)
            .map(|(p, q)| dist(*p, *q))
            .fold(0.0, f64::max);
        let found = a
            .joints
            .iter()
            .zip(&b.joints)
            .map(|(p, q)| dist(p.position, q.position))
            .fold(0.0, f64::max);
        let marks = a
            .landmarks
            .marks
            .keys()
            .map(|&l| {
                match (
                    a.landmarks.point(l, mesh.positions()),
                    b.landmarks.point(l, m.positions()),
                ) {
                    (Some(p), Some(q)) => dist(p, q),
                    _ => f64::INFINITY,
                }
            })
            .fold(0.0, f64::max);
        eprintln!(
            "{name} {what}: {moved} vertices in another part ({} / {} parts), joints {:.3} %, limb joints {:.3} %, landmarks {:.3} % of the height",
            a.parts,
            b.parts,
            100.0 * joints / h,
            100.0 * found / h,
            100.0 * marks / h
        );
        if moved > 0 || a.parts != b.parts || joints.max(found).max(marks) > BOUND * h {
            bad.push(format!(
                "{name} {what}: {moved} vertices in another part, parts {} / {}, joints {:.3} %, limb joints {:.3} %, landmarks {:.3} % of the height (bound {:.1} %)",
                a.parts,
                b.parts,
                100.0 * joints / h,
                100.0 * found / h,
                100.0 * marks / h,
                100.0 * BOUND
            ));
        }
    }
    bad
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn samba_renumbered_rigs_the_same() {
    let Some(d) = common::data_dir() else { return };
    let c = super::auto::capture(&d, "samba");
    let bad = numbering_failures("samba", &c.mesh, &c.frames);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn crane_renumbered_rigs_the_same() {
    let Some(d) = common::data_dir() else { return };
    let c = super::auto::capture(&d, "crane");
    let bad = numbering_failures("crane", &c.mesh, &c.frames);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn a_synthetic_walk_renumbered_rigs_the_same() {
    let (mesh, frames) = super::auto_order::synthetic_walk();
    let bad = numbering_failures("synthetic walk", mesh, frames);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}
