//! The body's extremities are the tips of its branches (issue 41,
//! `embed::auto::branches`): a point half way down a limb is no sixth
//! extremity, so SMPL, MakeHuman and bodies without hands rig, while a
//! grown tail or a third arm is still refused. Generated variants: the
//! procedural body (plain, mirrored, turned Z-up, in centimetres), its
//! hands cut, a tail or a third arm grafted on; SMPL and MakeHuman driven
//! by the procedural turn, SMPL with a tail; samba with its hands cut.

use crate::common;

use super::auto::{Variant, mean_percent};
use super::auto_kit::{
    Frames, driven, graft, keep_only, mid_vertex, rig_as_db_init, rig_with, scan_driven, variant,
    without_feet, without_feet_of, without_hands,
};
use glam::DVec3;
use std::path::Path;
use surfmotion::embed::Embedding;
use surfmotion::embed::auto::centre::TipSeed;
use surfmotion::embed::auto::options::{AutoError, AutoOptions, automatic_setup};
use surfmotion::embed::auto::report::AutoRig;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::mesh::Mesh;
use surfmotion::synth::humanoid::{HumanoidShape, humanoid_landmarks_with, humanoid_mesh_with};

/// Refused as a body with a sixth extremity (else printed, false).
fn refused_for_a_sixth(what: &str, r: Result<AutoRig, AutoError>) -> bool {
    match r {
        Err(AutoError::NotHumanoid(why)) if why.contains("sixth extremity") => {
            eprintln!("{what}: refused: {why}");
            true
        }
        Err(e) => {
            eprintln!("{what}: NOT AS WANTED: refused for another reason: {e}");
            false
        }
        Ok(a) => {
            eprintln!("{what}: NOT AS WANTED: rigged ({})", a.summary());
            false
        }
    }
}

/// Rigged, its joints within `bound` % of the height of the rig that
/// drove it (moved as the variant moves it).
fn rigs_near(
    what: &str,
    v: Variant,
    mesh: &Mesh,
    frames: &Frames,
    truth: &Embedding,
    bound: f64,
    how: TipSeed,
) {
    let auto =
        rig_with(mesh, frames, |o| o.tip_seed = how).unwrap_or_else(|e| panic!("{what}: {e}"));
    let e = Embedding::new(mesh, &auto.landmarks, None).unwrap();
    let want = truth.joints().map(|p| v.point(p));
    let scale = if v == Variant::Cm { 100.0 } else { 1.0 };
    let err = mean_percent(
        e.joints(),
        &want,
        truth.height() * scale,
        v == Variant::Mirrored,
    );
    eprintln!("{what}: joints {err:.2}% of the height from the rig that drove it");
    assert!(err <= bound, "{what}: {err:.2}%");
}

const VARIANTS: [Variant; 4] = [
    Variant::AsCaptured,
    Variant::Mirrored,
    Variant::ZUp,
    Variant::Cm,
];

#[test]
#[ignore = "fails: the procedural body with a tail of 20 % of its height is rigged from the centroid's vertex (session 35; from the geodesic centre it is refused: the next test)"]
fn a_grown_tail_or_third_arm_is_refused_and_the_body_without_them_rigs() {
    grown_limbs_are_refused(TipSeed::Centroid);
}

/// Measured (session 36): from the geodesic centre, farther from the
/// lower back than the centroid's vertex, the tail of 20 % of the height
/// reaches 91 % of the fifth branch's reach (limit 68 %).
#[test]
fn a_grown_tail_or_third_arm_is_refused_from_the_geodesic_centre() {
    grown_limbs_are_refused(TipSeed::Centre);
}

/// Measured (session 37): guarded ([`surfmotion::embed::auto::guard`]),
/// the tail of 20 % of the height is refused as from the centre.
#[test]
fn a_grown_tail_or_third_arm_is_refused_guarded() {
    grown_limbs_are_refused(TipSeed::Guarded);
}

/// The procedural body, as it is and without hands, rigs from the seed
/// `how` in every variant; with a tail of 20 % or 45 % of the height or a
/// third arm it is refused for a sixth extremity.
fn grown_limbs_are_refused(how: TipSeed) {
    let shape = HumanoidShape::default();
    let body = humanoid_mesh_with(0.025, &shape);
    let lm = humanoid_landmarks_with(&body, &shape);
    let h = 1.75;
    let tail = |len: f64| {
        let dir = DVec3::new(0.0, -0.5, -1.0).normalize();
        graft(&body, mid_vertex(&body, 0.52, false), dir, len * h)
    };
    let arm = graft(
        &body,
        mid_vertex(&body, 0.72, true),
        DVec3::new(0.2, 0.0, 1.0).normalize(),
        0.35 * h,
    );
    let (frames, truth) = driven(&body, &lm);
    let (no_hands, cut_frames, _) =
        keep_only(&body, &frames, &without_hands(&truth, body.positions()));
    five_tips_from(how, "body turned", &body, &frames, truth.labels());
    let mut missed = Vec::new();
    for v in VARIANTS {
        let (m, f) = variant(v, &body, &frames);
        rigs_near(&format!("body {v:?}"), v, &m, &f, &truth, 3.0, how);
        let (m, f) = variant(v, &no_hands, &cut_frames);
        let r = rig_with(&m, &f, |o| o.tip_seed = how);
        assert!(r.is_ok(), "handless {v:?}: {}", r.err().unwrap());
        for (what, grown) in [
            ("tail 0.2", tail(0.2)),
            ("tail 0.45", tail(0.45)),
            ("third arm", arm.clone()),
        ] {
            let lm = humanoid_landmarks_with(&grown, &shape);
            let (gf, _) = driven(&grown, &lm);
            let (m, f) = variant(v, &grown, &gf);
            let r = rig_with(&m, &f, |o| o.tip_seed = how);
            if !refused_for_a_sixth(&format!("{what} {v:?}"), r) {
                missed.push(format!("{what} {v:?}"));
            }
        }
    }
    assert!(missed.is_empty(), "not refused: {missed:?}");
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn smpl_makehuman_and_handless_samba_rig_and_smpl_with_a_tail_is_refused() {
    let Some(d) = common::data_dir() else { return };
    let (smpl, smpl_frames, smpl_rig) =
        scan_driven(&d, "scans/smpl-template/human_man.obj", None, "smpl");
    let (mh, mh_frames, mh_rig) =
        scan_driven(&d, "scans/makehuman/base.obj", Some("body"), "makehuman");
    let seed = automatic_setup(&AutoOptions::default()).unwrap().1.tip_seed;
    for v in [Variant::AsCaptured, Variant::Mirrored, Variant::ZUp] {
        let (m, f) = variant(v, &smpl, &smpl_frames);
        rigs_near(&format!("SMPL {v:?}"), v, &m, &f, &smpl_rig, 2.5, seed);
        let (m, f) = variant(v, &mh, &mh_frames);
        rigs_near(&format!("MakeHuman {v:?}"), v, &m, &f, &mh_rig, 2.5, seed);
    }
    every_frame_has_five_tips("SMPL turned", &smpl, &smpl_frames, smpl_rig.labels());
    every_frame_has_five_tips("MakeHuman turned", &mh, &mh_frames, mh_rig.labels());
    let h = smpl_rig.height();
    let tailed = graft(
        &smpl,
        mid_vertex(&smpl, 0.52, false),
        DVec3::new(0.0, -0.5, -1.0).normalize(),
        0.45 * h,
    );
    let lm = Landmarks::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/smpl.landmarks.json"),
        tailed.vertex_count(),
    )
    .unwrap();
    let (f, _) = driven(&tailed, &lm);
    assert!(refused_for_a_sixth(
        "SMPL with a tail",
        rig_as_db_init(&tailed, &f)
    ));
    handless_captures_rig_near_their_landmark_rigs(&d);
    footless_captures_rig_near_their_landmark_rigs(&d);
    one_foot_cut_gets_the_other_mirrored(&d);
}

/// Samba and crane without hands (their first 60 frames; the cut left
/// open, as a script leaves it), as captured and mirrored: rigged, the
/// arm matched from the cut (`embed::auto::cut_ends`), the joints within
/// the real captures' figure of the landmark rig's, each elbow within 5 %
/// of the height. Matched from the missing fingertips, samba's elbows
/// were put at the shoulders (18 % of the height off) and its upper arms'
/// parts were empty.
fn handless_captures_rig_near_their_landmark_rigs(d: &Path) {
    use surfmotion::rig::Canonical as C;
    let cut = |c: &super::auto::Capture| without_hands(&c.truth, c.mesh.positions());
    cut_captures_rig(d, "hands", cut, "no hand: the left and right arm", |r| {
        let (l, r2) = (r.off(C::LElbow, C::RElbow), r.off(C::RElbow, C::LElbow));
        eprintln!("{}: elbows {l:.2} / {r2:.2}%", r.what);
        assert!(
            r.err <= super::auto::BOUND_PERCENT,
            "{}: {:.2}%",
            r.what,
            r.err
        );
        assert!(
            l <= 5.0 && r2 <= 5.0,
            "{}: elbows {l:.2} / {r2:.2}%",
            r.what
        );
    });
}

/// One rig of a cut capture: its embedding against the landmark rig's
/// joints (carried by the variant).
struct CutRig {
    what: String,
    e: Embedding,
    want: [[f64; 3]; surfmotion::rig::Canonical::COUNT],
    h: f64,
    mirrored: bool,
    /// The mean joint distance, % of the height.
    err: f64,
}

impl CutRig {
    /// Joint `j`'s distance from the landmark rig's (its `twin`'s when
    /// mirrored), % of the height.
    fn off(&self, j: surfmotion::rig::Canonical, twin: surfmotion::rig::Canonical) -> f64 {
        let k = if self.mirrored { twin } else { j };
        100.0
            * DVec3::from_array(self.e.joints()[j.index()])
                .distance(DVec3::from_array(self.want[k.index()]))
            / self.h
    }
}

/// Samba and crane with `cut` (the vertices kept) applied to their first
/// 60 frames, as captured and mirrored, rigged as `db init` does: the
/// note starting `note` said, then `check` on each rig.
fn cut_captures_rig(
    d: &Path,
    without: &str,
    cut: impl Fn(&super::auto::Capture) -> Vec<bool>,
    note: &str,
    check: impl Fn(&CutRig),
) {
    for name in ["samba", "crane"] {
        let c = super::auto::capture(d, name);
        let keep = cut(c);
        let frames: Frames = c.frames.iter().take(60).cloned().collect();
        let (m, f, _) = keep_only(&c.mesh, &frames, &keep);
        assert!(m.vertex_count() + 100 < c.mesh.vertex_count());
        for v in [Variant::AsCaptured, Variant::Mirrored] {
            let (m, f) = variant(v, &m, &f);
            let what = format!("{name} without {without} {v:?}");
            let a = rig_as_db_init(&m, &f).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert!(
                a.notes.iter().any(|n| n.starts_with(note)),
                "{what}: {:?}",
                a.notes
            );
            let e = Embedding::new(&m, &a.landmarks, None).unwrap();
            let want = c.truth.joints().map(|p| v.point(p));
            let (h, mirrored) = (c.truth.height(), v == Variant::Mirrored);
            let err = mean_percent(e.joints(), &want, h, mirrored);
            eprintln!(
                "{what}: joints {err:.2}% of the height from the landmark rig; {}",
                a.summary()
            );
            check(&CutRig {
                what,
                e,
                want,
                h,
                mirrored,
                err,
            });
        }
    }
}

/// Samba and crane without feet (their first 60 frames; cut 2 % of the
/// height above the landmark rig's ankles, left open), as captured and
/// mirrored: rigged with each leg matched from its cut
/// (`embed::auto::cut_ends`) and the floor found from the knees
/// (`embed::auto::floor`), facing the capture's way (each knee near its
/// own side's), each knee within 5 % of the height of the landmark rig's
/// and the joints within 4 % on average (the ankles are at the cuts, 2 %
/// up the shins, and the toes of a missing foot are the embedding's
/// guess). Matched from the missing toes, samba's knees went to the
/// skirt's hem, 11-13 % of the height high. The pelvis is printed, not
/// bounded: it follows the hips the decomposition finds, whose spread from
/// draw to draw on the whole capture is as large (samba's groin 0.76-0.92
/// m over `SURFMOTION_AUTORIG=salt=0..4`; 0.79-0.91 m without feet).
fn footless_captures_rig_near_their_landmark_rigs(d: &Path) {
    use surfmotion::rig::Canonical as C;
    let cut = |c: &super::auto::Capture| without_feet(&c.truth, c.mesh.positions(), 0.02);
    cut_captures_rig(d, "feet", cut, "no foot: the left and right leg", |r| {
        let (l, r2) = (r.off(C::LKnee, C::RKnee), r.off(C::RKnee, C::LKnee));
        let pelvis = r.off(C::Pelvis, C::Pelvis);
        eprintln!("{}: knees {l:.2} / {r2:.2}%, pelvis {pelvis:.2}%", r.what);
        assert!(
            r.e.absent().iter().any(|x| x == "feet"),
            "{}: the embedding must say the feet are absent: {:?}",
            r.what,
            r.e.absent()
        );
        assert!(r.err <= 4.0, "{}: {:.2}%", r.what, r.err);
        assert!(l <= 5.0 && r2 <= 5.0, "{}: knees {l:.2} / {r2:.2}%", r.what);
    });
}

/// Samba and crane with the left foot cut (2 % of the height above the
/// landmark rig's ankle; first 60 frames), as captured and mirrored: the
/// embedding says that one foot is absent (`l_foot`, or `r_foot` on the
/// mirror), and the cut leg's toe lies on its own side, ahead of its own
/// ankle as the other foot's toe is of its ankle (`embed::footless`: the
/// other foot mirrored; the embedding's guess put samba's towards the
/// other foot, the toes 8.6 % of the height apart from the mid-plane);
/// the joints and knees within the bounds of both feet cut.
fn one_foot_cut_gets_the_other_mirrored(d: &Path) {
    use surfmotion::rig::Canonical as C;
    let cut = |c: &super::auto::Capture| {
        without_feet_of(&c.truth, c.mesh.positions(), 0.02, [true, false])
    };
    cut_captures_rig(d, "the left foot", cut, "no foot: the ", |r| {
        let (gone, kept) = match r.mirrored {
            false => ("l_foot", [C::LAnkle, C::LToe, C::RAnkle, C::RToe]),
            true => ("r_foot", [C::RAnkle, C::RToe, C::LAnkle, C::LToe]),
        };
        assert!(
            r.e.absent().iter().any(|x| x == gone),
            "{}: the embedding must say {gone} is absent: {:?}",
            r.what,
            r.e.absent()
        );
        let j = |c: C| DVec3::from_array(r.e.joints()[c.index()]);
        let [ankle, toe, other_ankle, other_toe] = kept.map(j);
        // On its own side: nearer its own ankle than the other's.
        assert!(
            toe.distance(ankle) < toe.distance(other_ankle),
            "{}: the cut leg's toe {toe} is nearer the other ankle",
            r.what
        );
        // As long as the other foot's, and pointing the same way forward.
        let (a, b) = (toe - ankle, other_toe - other_ankle);
        assert!((a.length() - b.length()).abs() < 1e-9 * r.h.max(1.0));
        let up = DVec3::from_array(r.e.joints()[C::Neck.index()]) - j(C::Pelvis);
        let flat = |v: DVec3| v - v.dot(up.normalize()) * up.normalize();
        assert!(
            flat(a).normalize().dot(flat(b).normalize()) > 0.5,
            "{}: the feet point apart ({a} and {b})",
            r.what
        );
        let (l, r2) = (r.off(C::LKnee, C::RKnee), r.off(C::RKnee, C::LKnee));
        eprintln!("{}: knees {l:.2} / {r2:.2}%", r.what);
        // The bounds of the feet cut both (measured: joints 2.3-2.8 %,
        // knees 0.6-4.2 %, samba's cut one the farthest).
        assert!(r.err <= 4.0, "{}: {:.2}%", r.what, r.err);
        assert!(l <= 5.0 && r2 <= 5.0, "{}: knees {l:.2} / {r2:.2}%", r.what);
    });
}

/// Every frame of `frames` taken as the rest: five branches, on the two
/// feet, the two forearms (the hands or the stumps) and the head of
/// `labels` (the landmark rig's parts) on at least 90 % of the frames,
/// and no sixth on any. The frames whose five tips are other parts are
/// counted and printed: with a hand held at the body's centre (samba's
/// frames from 127, the hands going to the hips) the seed, the vertex
/// nearest the centroid, lies near the hand, which is then no extremity.
/// (The geodesic centre, `TipSeed::Centre`, lies in the trunk however
/// the hands are held.) The tips are sought from the seed `how`.
/// Returns the greatest score (detour less disc ratio) of a candidate that
/// is no branch and the least of a branch.
fn five_tips_from(
    how: TipSeed,
    what: &str,
    mesh: &Mesh,
    frames: &[Vec<[f64; 3]>],
    labels: &[u8],
) -> (f64, f64) {
    use surfmotion::embed::auto::branches::{body_tips, sixth_limit};
    use surfmotion::embed::parts::neighbours;
    let nb = neighbours(mesh.vertex_count(), mesh.triangles());
    let want = surfmotion::tools::autorig_tips::five_on_extremities();
    let (mut no, mut yes) = (f64::MIN, f64::MAX);
    let (mut skipped, mut centre_kept) = (Vec::new(), Vec::new());
    for (f, rest) in frames.iter().enumerate() {
        let t = body_tips(rest, mesh.triangles(), &nb, sixth_limit, how);
        let mut parts: Vec<u8> = t.five.iter().map(|&(v, _)| labels[v as usize]).collect();
        parts.sort_unstable();
        if parts != want {
            skipped.push(f);
        }
        if t.guard.is_some_and(|g| g.kept_centre) {
            centre_kept.push(f);
        }
        assert!(t.sixth.is_none(), "{what} frame {f}: {:?}", t.sixth);
        for c in &t.candidates {
            let s = c.detour - c.sheet;
            if c.is_branch() {
                yes = yes.min(s);
            } else {
                no = no.max(s);
            }
        }
    }
    eprintln!(
        "{what} ({how:?}): {} frames as the rest, the five tips not the limbs' and the head's on {skipped:?}; scores: not a tip up to {no:.2}, tips from {yes:.2}; the guard kept the centre's on {centre_kept:?}",
        frames.len()
    );
    assert!(skipped.len() * 10 < frames.len(), "{what}: {skipped:?}");
    (no, yes)
}

/// [`five_tips_from`] the default seed (`db init`'s).
fn every_frame_has_five_tips(
    what: &str,
    mesh: &Mesh,
    frames: &[Vec<[f64; 3]>],
    labels: &[u8],
) -> (f64, f64) {
    let how = automatic_setup(&AutoOptions::default()).unwrap().1.tip_seed;
    five_tips_from(how, what, mesh, frames, labels)
}

/// Every frame of samba and crane (mirrored and in centimetres every 25th)
/// has five tips from the seed `how`; with `handless`, every frame of
/// samba without hands too.
fn captures_have_five_tips(d: &Path, how: TipSeed, handless: bool) {
    for name in ["samba", "crane"] {
        let c = super::auto::capture(d, name);
        five_tips_from(how, name, &c.mesh, &c.frames, c.truth.labels());
        // Mirrored and in centimetres: the same.
        for v in [Variant::Mirrored, Variant::Cm] {
            let some: Frames = c.frames.iter().step_by(25).cloned().collect();
            let (m, f) = variant(v, &c.mesh, &some);
            five_tips_from(how, &format!("{name} {v:?}"), &m, &f, c.truth.labels());
        }
    }
    if !handless {
        return;
    }
    // Samba without hands: the arms' stumps are the tips.
    let c = super::auto::capture(d, "samba");
    let keep = without_hands(&c.truth, c.mesh.positions());
    let (m, f, old) = keep_only(&c.mesh, &c.frames, &keep);
    let labels: Vec<u8> = old.iter().map(|&v| c.truth.labels()[v]).collect();
    five_tips_from(how, "samba without hands", &m, &f, &labels);
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
#[ignore = "fails: samba's frames 127-173 (hands at the body's centre) give other tips from the centroid's vertex (session 35; from the geodesic centre they do not: the next test)"]
fn every_frame_of_the_captures_has_five_tips_and_no_sixth() {
    let Some(d) = common::data_dir() else { return };
    captures_have_five_tips(&d, TipSeed::Centroid, true);
}

/// Measured (session 36): from the geodesic centre every frame of samba
/// and crane has the limbs' and the head's tips (from the centroid's
/// vertex 47 of samba's did not), the candidates that are no tip score
/// up to −0.45 and the tips from 0.07.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn every_frame_of_the_captures_has_five_tips_from_the_geodesic_centre() {
    let Some(d) = common::data_dir() else { return };
    captures_have_five_tips(&d, TipSeed::Centre, false);
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
#[ignore = "fails: from the geodesic centre samba without hands has a sixth branch on frame 48 (vertex 2737, 41 % of the height out, score -0.28 against the margin -0.3; session 36)"]
fn every_frame_of_samba_without_hands_has_five_tips_from_the_geodesic_centre() {
    let Some(d) = common::data_dir() else { return };
    let c = super::auto::capture(&d, "samba");
    let keep = without_hands(&c.truth, c.mesh.positions());
    let (m, f, old) = keep_only(&c.mesh, &c.frames, &keep);
    let labels: Vec<u8> = old.iter().map(|&v| c.truth.labels()[v]).collect();
    five_tips_from(TipSeed::Centre, "samba without hands", &m, &f, &labels);
}

/// Measured (session 37): guarded, every frame of samba, crane and samba
/// without hands has the limbs' and the head's tips and no sixth.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn every_frame_of_the_captures_has_five_tips_guarded() {
    let Some(d) = common::data_dir() else { return };
    captures_have_five_tips(&d, TipSeed::Guarded, true);
}
