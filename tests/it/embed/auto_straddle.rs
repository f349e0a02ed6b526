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
use super::auto_sides::rigged;
use crate::common;

use glam::DVec3;
use surfmotion::embed::auto::decompose::MergeRule;
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
    let (mut bad, e) = rigged(
        c,
        v,
        renumber,
        |o| {
            o.split_knee = true;
            o.decompose.merge = MergeRule::Settle;
            o.decompose.salt = salt;
        },
        "the knees are",
        &what,
    );
    let Some(e) = e else { return bad };
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
