//! Bodies cut at the neck rigged from their motion alone (issue 41,
//! `embed::auto::neck`): the SMPL template and MakeHuman's body driven by
//! the procedural turn through their fixtures' rigs, and samba's capture
//! (its first 60 frames), each cut at the neck twice (the landmark rig's
//! head part dropped; the torso cut across the neck 40 % up the neck→head
//! bone too; samba also at its neck joint, 0 %), as cut, mirrored, turned
//! Z-up and in centimetres: no chin, no head top, the file says
//! `"absent": ["head"]` and reads back, "no head" said once, the head
//! joint within 3 % of the height of the rim's centre, the limb joints
//! near the whole body's rig. The whole
//! bodies keep their heads. Samba headless through `db init` (no
//! landmarks) → `db build` → `retarget` CMU 02_02: no error, the head
//! checks skipped and said once, no head-to-torso line.

use super::auto::{Variant, capture};
use super::auto_kit::{Frames, keep_only, rig_as_db_init, scan_driven, variant};
use super::partial::init_build_retarget;
use crate::common;

use glam::DVec3;
use std::path::Path;
use surfmotion::embed::Embedding;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::mesh::Mesh;
use surfmotion::rig::Canonical;
use surfmotion::tools::autorig_headless::Cut;

/// The limb joints compared with the whole body's rig.
const LIMB: [Canonical; 8] = [
    Canonical::LKnee,
    Canonical::RKnee,
    Canonical::LAnkle,
    Canonical::RAnkle,
    Canonical::LElbow,
    Canonical::RElbow,
    Canonical::LWrist,
    Canonical::RWrist,
];

/// Mean distance of the limb joints from the whole body's rig (% of its
/// height; a mirror swaps the sides).
fn limb_percent(got: &Embedding, truth: &Embedding, v: Variant) -> f64 {
    let side = |c: Canonical| {
        let n = c.name();
        let m = match (v, n.split_at(2)) {
            (Variant::Mirrored, ("l_", r)) => format!("r_{r}"),
            (Variant::Mirrored, ("r_", r)) => format!("l_{r}"),
            _ => n.to_string(),
        };
        Canonical::from_name(&m).unwrap_or(c)
    };
    let h = truth.height() * if v == Variant::Cm { 100.0 } else { 1.0 };
    let s: f64 = LIMB
        .iter()
        .map(|&c| {
            let want = DVec3::from_array(v.point(truth.joints()[c.index()]));
            DVec3::from_array(got.joints()[side(c).index()]).distance(want)
        })
        .sum();
    100.0 * s / LIMB.len() as f64 / h
}

/// `mesh` (rigged by `truth`) and its frames cut by `cut`, in each variant:
/// rigged headless (whole: with a head), said once, the file reads back,
/// the limbs within `bound` % of the height of `truth`'s.
fn rigs_as_cut(what: &str, mesh: &Mesh, frames: &Frames, truth: &Embedding, cut: Cut, bound: f64) {
    let (m, f, _) = keep_only(mesh, frames, &cut.keep(mesh.positions(), truth));
    let whole = cut == Cut::Whole;
    for v in [
        Variant::AsCaptured,
        Variant::Mirrored,
        Variant::ZUp,
        Variant::Cm,
    ] {
        let (m, f) = variant(v, &m, &f);
        let what = format!("{what}, {cut:?}, {v:?}");
        let r = rig_as_db_init(&m, &f).unwrap_or_else(|e| panic!("{what}: {e}"));
        let said = r.notes.iter().filter(|n| n.starts_with("no head")).count();
        eprintln!(
            "{what}: {} vertices, trunk {:.1}% below the top, headless {}",
            m.vertex_count(),
            100.0 * r.trunk_depth,
            r.headless
        );
        assert_eq!(r.headless, !whole, "{what}: {:?}", r.notes);
        assert_eq!(said, usize::from(!whole), "{what}: {:?}", r.notes);
        assert_eq!(r.landmarks.headless(), !whole, "{what}");
        let n = m.vertex_count();
        let json = r.landmarks_json(n);
        assert_eq!(json.contains("\"absent\": [\"head\"]"), !whole, "{what}");
        let back = Landmarks::parse(&json, Path::new("auto.landmarks.json"), n).unwrap();
        assert_eq!(back.headless(), !whole, "{what}");
        let e = match r.rest_frame {
            None => Embedding::new(&m, &r.landmarks, None),
            Some(k) => Embedding::new_on_frame(&m, &f[k], &r.landmarks, None),
        }
        .unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(e.absent().is_empty(), whole, "{what}");
        if !whole {
            head_on_the_stump(&what, &e, &m, rim_centre(mesh, truth, cut, v));
        }
        let off = limb_percent(&e, truth, v);
        eprintln!("{what}: limb joints {off:.2}% of the height from the whole body's rig");
        assert!(off <= bound, "{what}: {off:.2}%");
    }
}

/// The centre of the cut's rim (the kept vertices of `mesh`, rigged by
/// `truth`, next to one `cut` removes), where variant `v` puts it.
fn rim_centre(mesh: &Mesh, truth: &Embedding, cut: Cut, v: Variant) -> DVec3 {
    let keep = cut.keep(mesh.positions(), truth);
    let nb = surfmotion::embed::parts::neighbours(mesh.vertex_count(), mesh.triangles());
    let rim: Vec<DVec3> = (0..keep.len())
        .filter(|&u| keep[u] && nb[u].iter().any(|&x| !keep[x as usize]))
        .map(|u| DVec3::from_array(mesh.positions()[u]))
        .collect();
    assert!(!rim.is_empty(), "{cut:?} removed nothing");
    DVec3::from_array(v.point((rim.iter().sum::<DVec3>() / rim.len() as f64).to_array()))
}

/// How far a headless body's head joint may lie from the centre of the
/// cut's rim (% of the height): it is put on the rim's centroid when the
/// cut is open (`embed::stump::pick_rim`, session 41); session 40's
/// centre of the highest 1.5 % ring near the axis lay 0.9-2.7 from it on
/// the head-part and 40 % cuts and 4.5 on samba cut at its neck joint
/// (its slanted rim reaches lower at the back); session 37's lay 3 %
/// above the stump, 2.9-4.8 from the rim's centre, which the check "not
/// above the top" refuses.
const HEAD_TO_RIM: f64 = 3.0;

/// A headless rig's head joint on its stump (`m`): not above the body's
/// top and within [`HEAD_TO_RIM`] of the rim's centre `rim`.
fn head_on_the_stump(what: &str, e: &Embedding, m: &Mesh, rim: DVec3) {
    let up = DVec3::from_array(e.up());
    let head = DVec3::from_array(e.joints()[Canonical::Head.index()]);
    let top = m
        .positions()
        .iter()
        .map(|q| DVec3::from_array(*q).dot(up))
        .fold(f64::NEG_INFINITY, f64::max);
    let h = e.height();
    let over = 100.0 * (head.dot(up) - top) / h;
    let off = 100.0 * head.distance(rim) / h;
    eprintln!(
        "{what}: head joint {over:.2}% of the height above the top, {off:.2}% from the rim's centre"
    );
    assert!(
        over <= 0.0,
        "{what}: the head joint {over:.2}% above the body"
    );
    assert!(
        off <= HEAD_TO_RIM,
        "{what}: the head joint {off:.2}% from the rim's centre"
    );
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn bodies_cut_at_the_neck_rig_without_a_head_and_whole_ones_with_one() {
    let Some(d) = common::data_dir() else { return };
    let (smpl, smpl_frames, smpl_rig) =
        scan_driven(&d, "scans/smpl-template/human_man.obj", None, "smpl");
    let (mh, mh_frames, mh_rig) =
        scan_driven(&d, "scans/makehuman/base.obj", Some("body"), "makehuman");
    let c = capture(&d, "samba");
    let samba: Frames = c.frames.iter().take(60).cloned().collect();
    for cut in [Cut::Whole, Cut::HeadPart, Cut::Plane(0.4)] {
        rigs_as_cut("SMPL", &smpl, &smpl_frames, &smpl_rig, cut, LIMB_BOUND);
        rigs_as_cut("MakeHuman", &mh, &mh_frames, &mh_rig, cut, LIMB_BOUND);
        rigs_as_cut("samba", &c.mesh, &samba, &c.truth, cut, LIMB_BOUND);
    }
    // Samba cut at its neck joint: the cut slants into the trapezius
    // (the body 11-15 % of the height across at the rim's centre), where
    // the top ring put the head joint 4.5 % from the rim's centre
    // (`autorig_eval … headless`, session 40).
    let cut = Cut::Plane(0.0);
    rigs_as_cut("samba", &c.mesh, &samba, &c.truth, cut, LIMB_BOUND);
}

/// The limb joints' bound (% of the whole body's height) from its rig.
const LIMB_BOUND: f64 = 5.0;

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_headless_capture_rigs_automatically_and_retargets_without_head_checks() {
    let Some(d) = common::data_dir() else { return };
    let t = tempfile::tempdir().unwrap();
    let c = capture(&d, "samba");
    let keep = Cut::HeadPart.keep(c.mesh.positions(), &c.truth);
    let (mesh, frames, _) = keep_only(&c.mesh, &c.frames, &keep);
    let p = init_build_retarget(
        &d,
        t.path(),
        "samba_headless",
        &mesh,
        &frames.concat(),
        None,
    );
    let lm = std::fs::read_to_string(p.db.join("auto.landmarks.json")).unwrap();
    assert!(lm.contains("\"absent\": [\"head\"]"), "{lm}");
    let (init, run) = (p.init, p.retarget);
    eprintln!("--- db init:\n{}\n--- retarget:\n{run}", init);
    let said = |s: &str, what: &str| s.matches(what).count();
    // Said once (session 36: three lines, the rig's note, the
    // embedding's chin and the skipped checks).
    assert_eq!(said(&init, "no head:"), 1, "{init}");
    assert_eq!(said(&init, "skips the head checks"), 1, "{init}");
    assert_eq!(said(&run, "no head: head checks skipped"), 1, "{run}");
    assert_eq!(said(&run, "head-to-torso"), 0, "{run}");
}

/// How far from the cut rim's centre a headless rig's head part may reach
/// (% of the height): the stump and the shoulders' tops, not the arms.
/// The SMPL template cut at its neck joint had its left forearm and hand,
/// 25-45 % of the height off, rigged as the head (sessions 36-38's highest
/// tip as the head); with the tip on the axis its head part is 19-22
/// vertices at the stump and the left shoulder's top (which the fixture
/// calls upper arm), 15.5 % off at most.
const HEAD_PART_REACH: f64 = 20.0;

/// The automatic embedding `e` of a headless body keeps its head part on
/// its stump and out of the arms: every vertex the embedding calls head
/// within [`HEAD_PART_REACH`] of the rim's centre `rim`, and none that
/// the whole body's rig calls a forearm (`truth_of` gives the whole
/// body's label of a vertex of `e`).
fn head_part_on_the_stump(
    what: &str,
    e: &Embedding,
    m: &Mesh,
    rim: DVec3,
    truth_of: &dyn Fn(usize) -> u8,
) {
    use surfmotion::embed::parts::Part;
    let head = Part::Head.index() as u8;
    let arm = [Part::LForearm, Part::RForearm].map(|p| p.index() as u8);
    let part: Vec<usize> = (0..m.vertex_count())
        .filter(|&v| e.labels()[v] == head)
        .collect();
    let reach = part
        .iter()
        .map(|&v| 100.0 * DVec3::from_array(m.positions()[v]).distance(rim) / e.height())
        .fold(0.0, f64::max);
    let forearm = part.iter().filter(|&&v| arm.contains(&truth_of(v))).count();
    eprintln!(
        "{what}: head part {} vertices, reaching {reach:.1}% of the height from the rim's centre, {forearm} of a forearm",
        part.len()
    );
    assert!(
        reach <= HEAD_PART_REACH,
        "{what}: the head part reaches {reach:.1}% from the stump"
    );
    assert_eq!(
        forearm, 0,
        "{what}: the head part holds {forearm} forearm vertices"
    );
}

/// Cut at the neck joint (0 % of the neck→head bone left), the SMPL
/// template's T-pose keeps five branch tips: the feet, the hands and the
/// stump, the stump 0.05 mm below the left hand. The head is the tip on
/// the body's axis (`AutoOptions::head_axis`), not the highest: in each
/// variant (as cut, mirrored, Z-up, centimetres, vertices renumbered) no
/// head, the head part on the stump and out of the arms, the head joint
/// within [`HEAD_TO_RIM`] of the rim's centre (session 40's top ring put
/// it 4.2 % of the height from it on SMPL: the ring took in the
/// shoulders' tops), the limbs near the whole body's rig, and the same
/// rig in every variant moved. MakeHuman's body cut so too.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn bodies_cut_at_the_neck_joint_rig_the_stump_not_a_hand_as_the_head() {
    let Some(d) = common::data_dir() else { return };
    let (smpl, smpl_frames, smpl_rig) =
        scan_driven(&d, "scans/smpl-template/human_man.obj", None, "smpl");
    let (mh, mh_frames, mh_rig) =
        scan_driven(&d, "scans/makehuman/base.obj", Some("body"), "makehuman");
    for (what, mesh, frames, truth) in [
        ("SMPL", &smpl, &smpl_frames, &smpl_rig),
        ("MakeHuman", &mh, &mh_frames, &mh_rig),
    ] {
        neck_joint_cut(what, mesh, frames, truth);
    }
}

/// [`bodies_cut_at_the_neck_joint_rig_the_stump_not_a_hand_as_the_head`]
/// on one body.
fn neck_joint_cut(what: &str, mesh: &Mesh, frames: &Frames, truth: &Embedding) {
    use super::renumber::{EVAL_SEED, renumbered, xorshift_order};
    let cut = Cut::Plane(0.0);
    let (m, f, old) = keep_only(mesh, frames, &cut.keep(mesh.positions(), truth));
    let mut limbs = Vec::new();
    let order = xorshift_order(m.vertex_count(), EVAL_SEED);
    for (v, renumber) in [
        (Variant::AsCaptured, false),
        (Variant::Mirrored, false),
        (Variant::ZUp, false),
        (Variant::Cm, false),
        (Variant::AsCaptured, true),
    ] {
        let (m, f) = variant(v, &m, &f);
        let (m, f) = match renumber {
            true => renumbered(&m, &f, &order),
            false => (m, f),
        };
        let what = format!(
            "{what}, neck at 0%, {v:?}{}",
            if renumber { ", renumbered" } else { "" }
        );
        let r = rig_as_db_init(&m, &f).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert!(r.headless, "{what}: {:?}", r.notes);
        let e = match r.rest_frame {
            None => Embedding::new(&m, &r.landmarks, None),
            Some(k) => Embedding::new_on_frame(&m, &f[k], &r.landmarks, None),
        }
        .unwrap_or_else(|e| panic!("{what}: {e}"));
        let rim = rim_centre(mesh, truth, cut, v);
        let old_of = |k: usize| old[if renumber { order[k] } else { k }];
        head_part_on_the_stump(&what, &e, &m, rim, &|k| truth.labels()[old_of(k)]);
        head_on_the_stump(&what, &e, &m, rim);
        let off = limb_percent(&e, truth, v);
        eprintln!("{what}: limb joints {off:.2}% of the height from the whole body's rig");
        assert!(off <= LIMB_BOUND, "{what}: {off:.2}%");
        if !renumber {
            limbs.push((what, off));
        }
    }
    // The same rig in every variant moved (the limbs as far from the
    // truth); renumbered, the decomposition's draws differ (MakeHuman's
    // limbs 1.28 % against 1.40 %), within the bounds above.
    let (lo, hi) = limbs
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x.1), b.max(x.1)));
    assert!(hi - lo < 0.05, "{limbs:?}");
}

/// The SMPL template driven by `autorig_eval`'s motions (the gait turn,
/// CMU 02_05 and 05_06 through its fixture's rig) and cut at its neck
/// joint, rigged as `db init` rigs it (`tools::autorig_cut`): the head
/// part on the stump and holding no forearm vertex. With the highest tip
/// as the head (`SURFMOTION_AUTORIG=head=highest`) the gait turn's head
/// part was 906 vertices of the left forearm and hand.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn smpl_cut_at_the_neck_joint_in_the_evaluations_motions_rigs_no_arm_as_the_head() {
    use surfmotion::tools::autorig::AutorigReport;
    use surfmotion::tools::autorig_cut::{Outcome, each_cut_rig};
    let Some(d) = common::data_dir() else { return };
    let mut w = AutorigReport::default();
    let mut rigged = 0;
    each_cut_rig(
        &d,
        &[Cut::Plane(0.0)],
        Some("SMPL"),
        &mut w,
        |_, case, rest, nb| {
            let what = format!("SMPL, {}, neck at 0%", case.motion);
            let (Outcome::Rigged(b), Some(m)) = (&case.outcome, &case.mesh) else {
                panic!("{what}: not rigged");
            };
            let rim = case.rim(rest, nb);
            let rim = rim.iter().sum::<DVec3>() / rim.len().max(1) as f64;
            let truth = case.truth();
            head_part_on_the_stump(&what, &b.1, m, rim, &|k| truth[k]);
            rigged += 1;
        },
    )
    .unwrap();
    assert_eq!(rigged, 3, "{}", w.tables);
}
