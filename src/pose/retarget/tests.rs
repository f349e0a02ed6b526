//! The kernel's unit tests: small synthetic skeletons and clips.

use super::feet::*;
use super::ground::*;
use super::kernel::*;
use super::measures::*;
use super::reference::*;
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

use Canonical as C;

/// A standing rest pose (metres, Y-up, facing +z, left at +x).
fn standing() -> Pose {
    let mut p = [DVec3::ZERO; Canonical::COUNT];
    let mut set = |c: C, x: f64, y: f64, z: f64| p[c.index()] = DVec3::new(x, y, z);
    set(C::Pelvis, 0.0, 1.0, 0.0);
    set(C::Spine, 0.0, 1.15, 0.0);
    set(C::Chest, 0.0, 1.35, 0.0);
    set(C::Neck, 0.0, 1.5, 0.0);
    set(C::Head, 0.0, 1.6, 0.0);
    set(C::LShoulder, 0.18, 1.45, 0.0);
    set(C::LElbow, 0.2, 1.18, 0.0);
    set(C::LWrist, 0.21, 0.93, 0.0);
    set(C::RShoulder, -0.18, 1.45, 0.0);
    set(C::RElbow, -0.2, 1.18, 0.0);
    set(C::RWrist, -0.21, 0.93, 0.0);
    set(C::LHip, 0.1, 0.95, 0.0);
    set(C::LKnee, 0.1, 0.52, 0.0);
    set(C::LAnkle, 0.1, 0.08, 0.0);
    set(C::LToe, 0.1, 0.02, 0.14);
    set(C::RHip, -0.1, 0.95, 0.0);
    set(C::RKnee, -0.1, 0.52, 0.0);
    set(C::RAnkle, -0.1, 0.08, 0.0);
    set(C::RToe, -0.1, 0.02, 0.14);
    p
}

fn map(p: &Pose, f: impl Fn(DVec3) -> DVec3) -> Pose {
    p.map(f)
}

/// The neck → head bone's angle to the pelvis → neck axis.
fn head_tilt(p: &Pose) -> f64 {
    angle(
        p[C::Head.index()] - p[C::Neck.index()],
        p[C::Neck.index()] - p[C::Pelvis.index()],
    )
}

#[test]
fn a_neutral_clip_gives_the_character_as_captured() {
    let ch = standing();
    // A clip whose skeleton defines the head joint further back (a
    // constant anatomical difference), scaled, turned and moved.
    let mut clip = standing();
    clip[C::Head.index()] += DVec3::new(0.0, 0.0, -0.05);
    let q = DQuat::from_rotation_y(1.1);
    let clip = map(&clip, |p| q * p * 1.7 + DVec3::new(3.0, 0.0, -2.0));
    let rf = choose_reference(Some(&clip), &[clip]).unwrap();
    assert_eq!(rf.source, ClipNeutralSource::Rest);
    let out = retarget(&ch, &rf, &[clip, clip]);
    for (p, _) in &out {
        assert!((head_tilt(p) - head_tilt(&ch)).abs() < 1e-9);
        // Upright, the character's own bone lengths.
        assert!(trunk_tilt(p) < 1e-9);
        for (a, b) in bone_lengths(p).zip(bone_lengths(&ch)) {
            assert!((a - b).abs() < 1e-9);
        }
        // Facing the clip's way: left-right axis turned by q.
        let l = p[C::LHip.index()] - p[C::RHip.index()];
        assert!(l.normalize().distance(q * DVec3::X) < 1e-9);
    }
}

#[test]
fn limbs_follow_the_clip_and_the_head_keeps_its_attitude_plus_motion() {
    let ch = standing();
    let rest = standing();
    // Frame: the arm raised to the side, the head nodding 20° forward.
    let mut m = rest;
    let (s, e) = (C::LShoulder.index(), C::LElbow.index());
    m[e] = m[s] + DVec3::new(0.27, 0.0, 0.0);
    m[C::LWrist.index()] = m[e] + DVec3::new(0.25, 0.0, 0.0);
    let nod = DQuat::from_rotation_x(20f64.to_radians());
    m[C::Head.index()] = m[C::Neck.index()] + nod * (rest[C::Head.index()] - rest[C::Neck.index()]);
    let rf = choose_reference(Some(&rest), &[rest, m]).unwrap();
    let out = retarget(&ch, &rf, &[rest, m]);
    let p = &out[1].0;
    let arm = (p[C::LElbow.index()] - p[C::LShoulder.index()]).normalize();
    assert!(arm.distance(DVec3::X) < 1e-9, "{arm}");
    // The nod comes across (20° between the frames), around the
    // character's own carriage (the clip's typical carriage, 10°, maps
    // onto the character's rest: ±10° either side of it).
    let neck = |p: &Pose| p[C::Head.index()] - p[C::Neck.index()];
    assert!((angle(neck(&out[0].0), neck(p)) - 20f64.to_radians()).abs() < 1e-9);
    for (q, _) in &out {
        assert!((head_tilt(q) - 10f64.to_radians()).abs() < 1e-9);
    }
}

#[test]
fn a_head_held_off_its_rest_joint_is_carried_as_the_character_carries_it() {
    // A clip whose neck bone sits 15° back from its rest skeleton's in
    // every frame (a calibration pose unlike the motion): the character
    // keeps its captured carriage.
    let ch = standing();
    let rest = standing();
    let mut m = rest;
    let back = DQuat::from_rotation_x(-15f64.to_radians());
    m[C::Head.index()] =
        m[C::Neck.index()] + back * (rest[C::Head.index()] - rest[C::Neck.index()]);
    let rf = choose_reference(Some(&rest), &[m, m, m]).unwrap();
    assert_eq!(rf.source, ClipNeutralSource::Rest);
    for (p, _) in retarget(&ch, &rf, &[m, m, m]) {
        assert!(head_tilt(&p) < 1e-9, "{}", head_tilt(&p).to_degrees());
    }
}

#[test]
fn a_lying_rest_skeleton_falls_back_to_the_most_neutral_frame() {
    let st = standing();
    let lying = map(&st, |p| DQuat::from_rotation_x(1.5) * p);
    let crouch = map(&st, |p| DQuat::from_rotation_x(0.4) * p);
    let rf = choose_reference(Some(&lying), &[crouch, st, crouch]).unwrap();
    assert_eq!(rf.source, ClipNeutralSource::Frame(1));
}

#[test]
fn degenerate_skeletons_are_refused() {
    let z = [DVec3::ZERO; Canonical::COUNT];
    assert!(choose_reference(Some(&z), &[z, z]).is_err());
    assert!(choose_reference(None, &[]).is_err());
    let nan = [DVec3::NAN; Canonical::COUNT];
    assert!(choose_reference(None, &[nan]).is_err());
}

#[test]
fn feet_stand_on_the_floor_as_the_clip_stands() {
    let ch = standing();
    // The clip: twice as big, its floor 5 m below the origin.
    let clip = map(&standing(), |p| p * 2.0 - DVec3::Y * 5.0);
    let rf = choose_reference(Some(&clip), &[clip]).unwrap();
    let (p, _) = &retarget(&ch, &rf, &[clip])[0];
    assert!((foot_height(p) - foot_height(&ch)).abs() < 1e-9);
}

/// A rest skeleton with the bone lengths of `lengths_of`, standing as
/// [`standing`] with the upper arms and forearms `arm` radians below
/// the horizontal (0: a T-pose).
fn rest_with(lengths_of: &Pose, arm: f64) -> Pose {
    let shape = standing();
    let mut r = shape;
    for c in Canonical::ALL {
        let Some(p) = c.parent() else { continue };
        let (j, q) = (c.index(), p.index());
        let side = match c {
            C::LElbow | C::LWrist => Some(1.0),
            C::RElbow | C::RWrist => Some(-1.0),
            _ => None,
        };
        let dir = match side {
            Some(s) => DVec3::new(s * arm.cos(), -arm.sin(), 0.0),
            None => (shape[j] - shape[q]).normalize(),
        };
        r[j] = r[q] + dir * lengths_of[j].distance(lengths_of[q]);
    }
    r
}

#[test]
fn t_and_a_pose_versions_of_a_clip_give_the_same_result() {
    use crate::pose::measure::pose_clip;
    use crate::synth::{Gait, gait_clip};
    let clip = gait_clip(Gait::Walk, 2.0, 30.0);
    let poses = crate::rig::detect(&clip.point_names())
        .map
        .poses(&clip)
        .unwrap();
    let character = standing();
    let mut results = Vec::new();
    for arm in [0.0, 45f64.to_radians()] {
        let rest = rest_with(&poses[0], arm);
        let version = pose_clip(&rest, &poses, 30.0).unwrap();
        let map = crate::rig::detect(&version.point_names()).map;
        let cp = clip_poses(&version, &map).unwrap();
        assert_eq!(cp.reference.source, ClipNeutralSource::Rest, "arm {arm}");
        results.push(retarget(&character, &cp.reference, &cp.poses));
    }
    let worst = results[0]
        .iter()
        .zip(&results[1])
        .flat_map(|((p, _), (q, _))| p.iter().zip(q).map(|(a, b)| a.distance(*b)))
        .fold(0.0, f64::max);
    assert!(worst < 1e-9, "T and A versions {worst} m apart");
}

/// The joints above the pelvis (spine, chest, neck, head, arms).
fn upper(c: C) -> bool {
    !matches!(
        c,
        C::Pelvis
            | C::LHip
            | C::LKnee
            | C::LAnkle
            | C::LToe
            | C::RHip
            | C::RKnee
            | C::RAnkle
            | C::RToe
    )
}

/// `p` bowed forward by `bow` at the pelvis and the head bent down a
/// further `nod` at the neck (radians).
fn bowed(p: &Pose, bow: f64, nod: f64) -> Pose {
    let mut out = *p;
    let (pv, n, h) = (C::Pelvis.index(), C::Neck.index(), C::Head.index());
    let q = DQuat::from_rotation_x(bow);
    for c in Canonical::ALL {
        if upper(c) {
            out[c.index()] = p[pv] + q * (p[c.index()] - p[pv]);
        }
    }
    out[h] = out[n] + DQuat::from_rotation_x(nod) * (out[h] - out[n]);
    out
}

#[test]
fn the_neck_carriage_is_read_on_the_upright_frames() {
    // Three upright frames and seven bowed 40° with the head down a
    // further 30° (CMU 131_02): the upright frames carry the head as
    // the character does, not thrown back by the bowed frames' carriage.
    let ch = standing();
    let up = standing();
    let down = bowed(&up, 0.7, 0.5);
    let mut clip = vec![up; 3];
    clip.extend(std::iter::repeat_n(down, 7));
    let rf = choose_reference(Some(&up), &clip).unwrap();
    let out = retarget(&ch, &rf, &clip);
    for (p, _) in &out[..3] {
        assert!(
            (head_tilt(p) - head_tilt(&ch)).abs() < 1e-9,
            "{}",
            head_tilt(p).to_degrees()
        );
    }
    // The clip's own head-to-trunk angle: 0 upright, the nod when bowed.
    let own = clip_head_trunk_deg(&rf, &clip);
    assert!(
        own[0].abs() < 1e-9 && (own[5] - 0.5f64.to_degrees()).abs() < 1e-6,
        "{own:?}"
    );
}

#[test]
fn a_tilted_capture_floor_is_levelled() {
    use crate::synth::{Gait, gait_clip};
    let clip = gait_clip(Gait::Walk, 3.0, 30.0);
    let map = crate::rig::detect(&clip.point_names()).map;
    let cp = clip_poses(&clip, &map).unwrap();
    // The capture's floor rises 1.5° along every axis through the origin.
    let q =
        DQuat::from_rotation_x(-1.5f64.to_radians()) * DQuat::from_rotation_z(1.5f64.to_radians());
    let tilted: Vec<Pose> = cp.poses.iter().map(|p| p.map(|x| q * x)).collect();
    let rise = tilted.last().unwrap()[0].y - tilted[0][0].y;
    assert!(rise.abs() > 0.05, "the test clip rises {rise} m");
    let ch = standing();
    let flat = retarget(&ch, &cp.reference, &cp.poses);
    let levelled = retarget(&ch, &cp.reference, &tilted);
    for ((a, _), (b, _)) in flat.iter().zip(&levelled) {
        let d = (a[0].y - b[0].y).abs();
        assert!(d < 0.01, "pelvis heights {} and {} m", a[0].y, b[0].y);
    }
    // Feet on the character's floor: the lowest sole point of every
    // frame within 1 cm of the rest's (the clip walks: always a foot down).
    let rest = sole_height(&ch, &ch, &[DQuat::IDENTITY; Canonical::COUNT]);
    let mut lows: Vec<f64> = cp.poses.iter().map(foot_height).collect();
    lows.sort_by(f64::total_cmp);
    let floor = lows[lows.len() / 20];
    let mut standing_frames = 0;
    for ((p, g), m) in levelled.iter().zip(&cp.poses) {
        if foot_height(m) <= floor + 0.03 {
            standing_frames += 1;
            assert!((sole_height(&ch, p, g) - rest).abs() < 0.01);
        }
    }
    assert!(standing_frames * 2 > levelled.len());
}

#[test]
fn a_bent_rest_skeleton_falls_back_to_the_most_neutral_frame() {
    use crate::pose::measure::pose_clip;
    use crate::synth::{Gait, gait_clip};
    let clip = gait_clip(Gait::Walk, 2.0, 30.0);
    let poses = crate::rig::detect(&clip.point_names())
        .map
        .poses(&clip)
        .unwrap();
    // The rest skeleton bowed 50° at the pelvis with the knees bent:
    // not a T- or A-pose.
    let mut shape = bowed(&standing(), 50f64.to_radians(), 0.0);
    for (k, a, t) in [
        (C::LKnee, C::LAnkle, C::LToe),
        (C::RKnee, C::RAnkle, C::RToe),
    ] {
        let (k, a, t) = (k.index(), a.index(), t.index());
        let bend = DQuat::from_rotation_x(-1.0);
        let (da, dt) = (shape[a] - shape[k], shape[t] - shape[a]);
        shape[a] = shape[k] + bend * da;
        shape[t] = shape[a] + dt;
    }
    let mut rest = shape;
    for c in Canonical::ALL {
        let Some(p) = c.parent() else { continue };
        let (j, q) = (c.index(), p.index());
        let len = poses[0][j].distance(poses[0][q]);
        rest[j] = rest[q] + (shape[j] - shape[q]).normalize() * len;
    }
    let version = pose_clip(&rest, &poses, 30.0).unwrap();
    let map = crate::rig::detect(&version.point_names()).map;
    let cp = clip_poses(&version, &map).unwrap();
    let ClipNeutralSource::Frame(i) = cp.reference.source else {
        panic!("a bent rest skeleton was taken as the reference");
    };
    // The most neutral frame is as upright as the walk gets, and in it
    // the character's trunk (pelvis → chest, upright at rest) leans as the
    // clip's does: the torso is measured from the reference stood upright
    // on that line (the lean a reference stands with is the file's, not
    // the performance's; `level_torso`), so a frame chosen as the
    // reference no longer stands the character as at rest. The reference's
    // torso is the walk's mean carriage (`motion_ref`), whose line leans
    // within a hundredth of a degree of this frame's: 6.957° against the
    // clip's 6.964° (exactly the clip's when the frame itself was the
    // torso's reference).
    let least = poses.iter().map(trunk_tilt).fold(f64::INFINITY, f64::min);
    assert!(trunk_tilt(&cp.poses[i]) < least + 5f64.to_radians());
    let out = retarget(&standing(), &cp.reference, &cp.poses);
    let lean = |p: &Pose| angle(p[C::Chest.index()] - p[C::Pelvis.index()], DVec3::Y);
    let tilt = ground_tilt(&cp.poses);
    let clip_lean = lean(&cp.poses[i].map(|p| tilt * p));
    assert!(
        (lean(&out[i].0) - clip_lean).abs() < 0.1f64.to_radians(),
        "{} vs the clip's {}",
        lean(&out[i].0).to_degrees(),
        clip_lean.to_degrees()
    );
    assert!((head_tilt(&out[i].0) - head_tilt(&standing())).abs() < 0.1);
}

#[test]
fn a_bent_character_rest_frame_gives_way_to_its_most_neutral_database_frame() {
    // The character's rest frame leaning 40° forward from its feet (a
    // database whose mesh was captured mid-fall); its frames: leaning,
    // upright, bowed.
    let up = standing();
    let lean = DQuat::from_rotation_x(40f64.to_radians());
    let bowed_rest = map(&up, |p| lean * p);
    let crouch = bowed(&up, 20f64.to_radians(), 0.0);
    let n = character_neutral(&bowed_rest, &[bowed_rest, up, crouch]);
    assert_eq!(n.source, NeutralSource::Frame(1));
    // An upright rest frame is kept.
    assert_eq!(
        character_neutral(&up, &[bowed_rest, crouch]).source,
        NeutralSource::Rest
    );
    // A clip standing neutrally: measured from the rest frame the
    // character stands bowed; from the neutral frame, upright.
    let clip = standing();
    let rf = choose_reference(Some(&clip), &[clip]).unwrap();
    let (from_rest, _) = &retarget(&bowed_rest, &rf, &[clip])[0];
    assert!(trunk_tilt(from_rest) > 35f64.to_radians());
    let (p, _) = &retarget_with_neutral(&bowed_rest, &n.pose, &rf, &[clip])[0];
    assert!(trunk_tilt(p) < 1e-6, "{}", trunk_tilt(p).to_degrees());
    // Still the character's own bones.
    for (a, b) in bone_lengths(p).zip(bone_lengths(&bowed_rest)) {
        assert!((a - b).abs() < 1e-9);
    }
}

#[test]
fn a_clip_walking_on_a_block_stands_the_character_on_it_at_every_footfall() {
    // The clip stands on a 20 cm block (CMU 03_01 starts on one), its
    // knees bent a little, then steps down 40 cm forward onto the floor
    // and stands straight.
    let st = map(&standing(), |p| p * 1.1);
    let mut bent = st;
    for c in Canonical::ALL {
        if !matches!(c, C::LAnkle | C::LToe | C::RAnkle | C::RToe) {
            bent[c.index()] += DVec3::new(0.0, -0.03, 0.0);
        }
    }
    for k in [C::LKnee, C::RKnee] {
        bent[k.index()] += DVec3::new(0.0, 0.0, 0.1);
    }
    let mut clip: Vec<Pose> = vec![bent.map(|p| p + DVec3::Y * 0.2); 12];
    clip.extend(vec![st.map(|p| p + DVec3::Z * 0.4); 12]);
    let rf = choose_reference(Some(&st), &clip).unwrap();
    let leg = leg_length(&rf.pose);
    let support = clip_support(&clip, leg);
    for (t, g) in support.ground.iter().enumerate() {
        let want = if t < 12 { 0.2 } else { 0.0 };
        let g = g.expect("standing: every frame on its ground");
        assert!((g - support.floor - want).abs() < 1e-9, "frame {t}: {g}");
    }
    // The character's lowest sole point on the block, scaled.
    let ch = standing();
    let s = leg_length(&ch) / leg;
    let rest = sole_height(&ch, &ch, &[DQuat::IDENTITY; Canonical::COUNT]);
    for (t, (p, g)) in retarget(&ch, &rf, &clip).iter().enumerate() {
        let want = if t < 12 { rest + 0.2 * s } else { rest };
        let h = sole_height(&ch, p, g);
        assert!((h - want).abs() < 1e-6, "frame {t}: {h} vs {want}");
    }
    // And the plausibility's ground follows it.
    let raised = ground_offsets(&ch, &rf, &clip);
    for (t, r) in raised.iter().enumerate() {
        let want = if t < 12 { 0.2 * s } else { 0.0 };
        assert!((r - want).abs() < 1e-9, "frame {t}: {r}");
    }
}

#[test]
fn a_leg_held_still_in_the_air_is_no_step() {
    // The body glides 3 cm per frame on its right foot (not planted),
    // the left foot held 15 cm up and still in the air (a knee lift
    // held); in frames 10-13 the right heel and toe rise 4 cm. The
    // still left foot bears no weight: it is no step to stand on.
    let st = standing();
    let clip: Vec<Pose> = (0..20)
        .map(|t| {
            let mut p = st.map(|q| q + DVec3::X * 0.03 * t as f64);
            for c in [C::LKnee, C::LAnkle, C::LToe] {
                p[c.index()] = st[c.index()] + DVec3::new(0.0, 0.15, 0.1);
            }
            if (10..14).contains(&t) {
                for c in [C::RAnkle, C::RToe] {
                    p[c.index()] += DVec3::Y * 0.04;
                }
            }
            p
        })
        .collect();
    let support = clip_support(&clip, leg_length(&st));
    for (t, g) in support.ground.iter().enumerate() {
        assert!(
            g.is_none_or(|g| g < support.floor + 0.05),
            "frame {t}: ground {g:?}, floor {}",
            support.floor
        );
    }
}

#[test]
fn the_clip_foot_glide_reads_zero_standing_and_the_drag_when_dragged() {
    let ch = standing();
    let st = map(&standing(), |p| p * 2.0);
    let rf = choose_reference(Some(&st), &[st]).unwrap();
    let still = vec![st; 20];
    assert!(clip_foot_glide_cm(&ch, &rf, &still) < 1e-9);
    // Dragged 2 cm per frame along x, feet on the floor: 1 cm per
    // frame at the character's half size.
    let dragged: Vec<Pose> = (0..20)
        .map(|t| st.map(|p| p + DVec3::X * 0.02 * t as f64))
        .collect();
    let g = clip_foot_glide_cm(&ch, &rf, &dragged);
    // 19 of 20 touching frames move.
    assert!((g - 0.95).abs() < 1e-6, "{g}");
    // A foot swinging in the air (knee raised 60°) does not touch the
    // floor: one foot moving in the air, the other planted, reads 0.
    let lifted: Vec<Pose> = (0..20)
        .map(|t| {
            let mut p = st;
            let (h, k, a, o) = (
                C::LHip.index(),
                C::LKnee.index(),
                C::LAnkle.index(),
                C::LToe.index(),
            );
            let (thigh, shin) = (p[h].distance(p[k]), p[k].distance(p[a]));
            let foot = p[o] - p[a];
            let drift = DVec3::X * 0.02 * t as f64;
            p[k] = p[h] + DVec3::new(0.0, -0.5, 0.866) * thigh + drift;
            p[a] = p[k] - DVec3::Y * shin;
            p[o] = p[a] + foot;
            p
        })
        .collect();
    let g = clip_foot_glide_cm(&ch, &rf, &lifted);
    assert!(g < 1e-9, "{g}");
}

/// The frames each foot touches its ground (`Support::touch`), per foot.
fn touches(s: &Support) -> [Vec<bool>; 2] {
    s.touch
        .each_ref()
        .map(|t| t.iter().map(|g| g.is_some()).collect())
}

#[test]
fn a_clip_scaled_touches_the_ground_in_the_same_frames() {
    // The project's generated walk and run (metres), and the same clips
    // scaled as a child's, a giant's or a file in other units would be:
    // the contact band is a fraction of the leg, so the same frames touch
    // and the supports scale with the clip (with the fixed 3 cm band it
    // replaces, the walk scaled by 0.6 touched in other frames).
    for g in [crate::synth::Gait::Walk, crate::synth::Gait::Run] {
        let clip = crate::synth::gait_clip(g, 2.0, 30.0);
        let poses = crate::rig::detect_clip(&clip)
            .unwrap()
            .map
            .poses(&clip)
            .unwrap();
        let leg = leg_length(&poses[0]);
        let base = clip_support(&poses, leg);
        assert!(touches(&base).iter().flatten().any(|&t| t));
        for k in [0.6, 1.37, 2.5] {
            let scaled: Vec<Pose> = poses.iter().map(|p| p.map(|x| x * k)).collect();
            let s = clip_support(&scaled, leg * k);
            assert_eq!(touches(&s), touches(&base), "{g:?} scaled by {k}");
            assert!((s.floor - k * base.floor).abs() < 1e-9 * k);
            assert!((s.band - k * base.band).abs() < 1e-12 * k);
        }
    }
}
