//! A knee matched at a boundary that is no joint should move to the joint
//! the motion shows (issue 41): samba
//! (a dancer in a skirt) rigged with `merge=settle` draws whose left shin
//! main's rig cut at mid-shin (the upper half in one part with the
//! skirt's hem, the knee placed on the cut, 5 % of the height low in
//! `autorig_eval … spread 10 renumbered`), as captured, with its vertices
//! renumbered, mirrored and turned Z-up: both knees lie within
//! [`KNEE_BOUND`] of the landmark rig's (of the same side; the mirror
//! swaps them) and the rig gives no warning that the knees lie unequally
//! far from the toes. Ignored: it fails on main and with `knee=split`
//! (`embed::auto::straddle::split_knee`, session 33) alike; the target of
//! the next step (run it with `--ignored`).

use super::auto::{Variant, capture};
use super::auto_sides::variant;
use super::renumber::{EVAL_SEED, renumbered, xorshift_order};
use crate::common;

use glam::DVec3;
use surfmotion::embed::Embedding;
use surfmotion::embed::auto::decompose::MergeRule;
use surfmotion::embed::auto::options::{AutoOptions, automatic_setup};
use surfmotion::embed::auto::rig::auto_rig;
use surfmotion::embed::rest::choose_rest_frame;
use surfmotion::rig::Canonical;

/// Each knee's bound, in % of the height (`embed::auto_knees`'s).
const KNEE_BOUND: f64 = 3.0;

/// Samba in `v` (renumbered by the evaluation's shuffle when `renumber`)
/// rigged as `db init` rigs it with `merge=settle,salt=SALT`, and
/// embedded: the failures (refusals, knees off, the knee warning).
fn failures(d: &std::path::Path, v: Variant, renumber: bool, salt: u32) -> Vec<String> {
    let c = capture(d, "samba");
    let what = format!(
        "samba {v:?}{} settle salt {salt}",
        if renumber { " renumbered" } else { "" }
    );
    let (mut mesh, mut frames) = variant(v, &c.mesh, &c.frames);
    if renumber {
        (mesh, frames) = renumbered(
            &mesh,
            &frames,
            &xorshift_order(mesh.vertex_count(), EVAL_SEED),
        );
    }
    let f: Vec<&[[f64; 3]]> = frames.iter().map(Vec::as_slice).collect();
    let mut all = vec![mesh.positions()];
    all.extend_from_slice(&f);
    let (rule, mut auto) = automatic_setup(&AutoOptions::default()).unwrap();
    auto.split_knee = true;
    auto.decompose.merge = MergeRule::Settle;
    auto.decompose.salt = salt;
    let choice = choose_rest_frame(&mesh, &all, &rule).unwrap();
    auto.rest_frame = (choice.frame > 0).then(|| choice.frame - 1);
    let rig = match auto_rig(&mesh, &f, &auto) {
        Ok(r) => r,
        Err(e) => return vec![format!("{what}: refused: {e}")],
    };
    let mut bad: Vec<String> = rig
        .notes
        .iter()
        .filter(|n| n.contains("the knees are"))
        .map(|n| format!("{what}: {n}"))
        .collect();
    let e = match Embedding::new(&mesh, &rig.landmarks, None) {
        Ok(e) => e,
        Err(err) => {
            bad.push(format!("{what}: embedding refused: {err}"));
            return bad;
        }
    };
    let truth = |j: Canonical| DVec3::from_array(v.point(c.truth.joints()[j.index()]));
    let at = |j: Canonical| DVec3::from_array(e.joints()[j.index()]);
    let (l, r) = (Canonical::LKnee, Canonical::RKnee);
    let pairs = if v == Variant::Mirrored {
        [(l, r), (r, l)]
    } else {
        [(l, l), (r, r)]
    };
    for (j, own) in pairs {
        let off = 100.0 * at(j).distance(truth(own)) / c.truth.height();
        eprintln!(
            "{what}: {} {off:.2}% of the height from the landmark rig's",
            j.name()
        );
        if off > KNEE_BOUND {
            bad.push(format!(
                "{what}: {} {off:.1}% of the height from the landmark rig's (bound {KNEE_BOUND}%)",
                j.name()
            ));
        }
    }
    bad
}

#[test]
#[ignore = "issue 41: not solved yet; samba's left knee under merge=settle stays 5% low with knee=split (session 33)"]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn samba_settle_draws_main_cut_at_mid_shin_find_the_knee() {
    let Some(d) = common::data_dir() else { return };
    let mut bad = Vec::new();
    for (v, renumber, salt) in [
        (Variant::AsCaptured, false, 1),
        (Variant::AsCaptured, true, 4),
        (Variant::Mirrored, false, 1),
        (Variant::ZUp, false, 1),
    ] {
        bad.extend(failures(&d, v, renumber, salt));
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}
