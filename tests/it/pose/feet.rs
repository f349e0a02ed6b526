//! Where the retargeting kernel stands the character's feet (issue 17,
//! "feet"; `surfmotion::pose::retarget`), on generated clips (no
//! ../shared needed): each foot stands on the ground under it, not on the
//! other foot's. A foot on a block does not lift the body when the other
//! foot leaves the floor (the kernel on `main` stood the body's lowest
//! sole on the block: CMU 03_02's query jumped 10-22 cm at its
//! footfalls), and a heel striking the floor while the other foot leaves
//! on its toes does not go through it (the per-foot support reverted in
//! issue 17 stood the body on the leaving foot alone and sank Bandai
//! walk_happy 8 cm and CMU 03_01 15 cm into a synthetic database's floor).

use glam::{DQuat, DVec3};
use surfmotion::pose::Pose;
use surfmotion::pose::retarget::{choose_reference, ground_offsets, leg_length, retarget};
use surfmotion::rig::Canonical;

use Canonical as C;

/// A person standing upright, feet flat with the ankle `ankle` m above
/// the toe joint (toe joint 2 cm up, 14 cm forward), hips 0.95 m up,
/// facing +Z.
fn standing(ankle: f64) -> Pose {
    let mut p = [DVec3::ZERO; Canonical::COUNT];
    let mut set = |c: C, x: f64, y: f64, z: f64| p[c.index()] = DVec3::new(x, y, z);
    let a = 0.02 + ankle;
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
    for (hip, knee, ank, toe, x) in [
        (C::LHip, C::LKnee, C::LAnkle, C::LToe, 0.1),
        (C::RHip, C::RKnee, C::RAnkle, C::RToe, -0.1),
    ] {
        set(hip, x, 0.95, 0.0);
        set(knee, x, 0.5 * (0.95 + a), 0.0);
        set(ank, x, a, 0.0);
        set(toe, x, 0.02, 0.14);
    }
    p
}

/// The joints of one leg below the hip: knee, ankle, toe.
fn leg(left: bool) -> [C; 3] {
    if left {
        [C::LKnee, C::LAnkle, C::LToe]
    } else {
        [C::RKnee, C::RAnkle, C::RToe]
    }
}

/// The lowest sole point of a posed character with global rotations `g`
/// and rest pose `rest`: a toe joint, or a heel under an ankle at the rest
/// pose's toe height, carried by the ankle.
fn lowest_sole(rest: &Pose, p: &Pose, g: &[DQuat; Canonical::COUNT]) -> f64 {
    [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)]
        .iter()
        .map(|&(a, k)| {
            let (a, k) = (a.index(), k.index());
            let heel = DVec3::new(0.0, rest[k].y - rest[a].y, 0.0);
            p[k].y.min((p[a] + g[a] * heel).y)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The knee of a leg from hip `h` to ankle `a` with thigh and shin
/// lengths `l1`, `l2`, bent forward (+Z); the leg straight when it cannot
/// reach.
fn knee(h: DVec3, a: DVec3, l1: f64, l2: f64) -> DVec3 {
    let d = (a - h).length();
    let dir = (a - h) / d;
    let x = ((l1 * l1 - l2 * l2 + d * d) / (2.0 * d)).min(l1);
    let up = (l1 * l1 - x * x).max(0.0).sqrt();
    let fwd = (DVec3::Z - dir * dir.z).normalize();
    h + dir * x + fwd * up
}

/// Stepping up onto a block of height `block`: the right foot already on
/// it, the body rises over frames 8-20 while the left foot lifts off the
/// floor, swings up (8 cm over the block's top) and lands on it; the
/// knees bend to keep the legs' lengths.
fn step_up(block: f64) -> Vec<Pose> {
    let st = standing(0.06);
    (0..36)
        .map(|t| {
            let u = ((t as f64 - 8.0) / 12.0).clamp(0.0, 1.0);
            let mut p = st;
            for c in Canonical::ALL {
                p[c.index()].y += block * u;
            }
            let lift = if t < 8 {
                0.0
            } else if t < 20 {
                block * u + 0.08 * (std::f64::consts::PI * u).sin()
            } else {
                block
            };
            for (left, y) in [(true, lift), (false, block)] {
                let [k, a, o] = leg(left);
                let h = if left { C::LHip } else { C::RHip };
                p[a.index()] = st[a.index()] + DVec3::Y * y;
                p[o.index()] = st[o.index()] + DVec3::Y * y;
                let (l1, l2) = (
                    st[h.index()].distance(st[k.index()]),
                    st[k.index()].distance(st[a.index()]),
                );
                p[k.index()] = knee(p[h.index()], p[a.index()], l1, l2);
            }
            p
        })
        .collect()
}

/// The character's pelvis follows the clip's up the block, scaled by the
/// ratio of leg lengths: no frame-to-frame change differs from the clip's
/// by 2 cm or more. On `main` the left foot leaving the floor was stood on
/// the right foot's block (frame 9: the body jumped by the block's height,
/// scaled). Blocks of 12 and 20 cm (CMU 03_02's), characters of 0.85 to
/// 1.2 the clip's size and with a taller foot.
#[test]
fn stepping_up_onto_a_block_moves_the_body_as_the_clip_moves_it() {
    for block in [0.12, 0.2] {
        let clip = step_up(block);
        let rf = choose_reference(Some(&clip[0]), &clip).unwrap();
        for (scale, ankle) in [(1.0, 0.06), (0.85, 0.06), (1.2, 0.06), (1.0, 0.09)] {
            let ch = standing(ankle).map(|p| p * scale);
            let s = leg_length(&ch) / leg_length(&rf.pose);
            let out = retarget(&ch, &rf, &clip);
            let p = C::Pelvis.index();
            for t in 1..clip.len() {
                let want = (clip[t][p].y - clip[t - 1][p].y) * s;
                let got = out[t].0[p].y - out[t - 1].0[p].y;
                assert!(
                    (got - want).abs() < 0.02,
                    "block {block} m, character ×{scale} (ankle {ankle} m), frame {t}: \
                     the pelvis moved {:.1} cm, the clip's (scaled) {:.1} cm",
                    100.0 * got,
                    100.0 * want
                );
            }
        }
    }
}

/// While the left foot rises from the floor beside the block, the ground
/// the plausibility checks measure the result's lowest point from
/// ([`ground_offsets`]) is under that foot, the floor, not the block's
/// top the right foot stands on: the lowest sole point is never more than
/// 1 cm below it (the reverted per-foot support measured the rising foot
/// against the block: 10-20 cm of penetration on CMU 03_02), nor more than
/// 1 cm above it in frames where the left foot is on the floor or on the
/// block.
#[test]
fn the_ground_under_a_foot_leaving_the_floor_beside_a_block_is_the_floor() {
    for block in [0.12, 0.2] {
        let clip = step_up(block);
        let rf = choose_reference(Some(&clip[0]), &clip).unwrap();
        for scale in [0.85, 1.2] {
            let ch = standing(0.06).map(|p| p * scale);
            let out = retarget(&ch, &rf, &clip);
            let raised = ground_offsets(&ch, &rf, &clip);
            let floor = lowest_sole(&ch, &ch, &[DQuat::IDENTITY; Canonical::COUNT]);
            for (t, ((p, g), r)) in out.iter().zip(&raised).enumerate() {
                let above = lowest_sole(&ch, p, g) - (floor + r);
                assert!(
                    above > -0.01,
                    "block {block} m, ×{scale}, frame {t}: the lowest sole {:.1} cm \
                     below the measured ground",
                    -100.0 * above
                );
                if !(8..20).contains(&t) {
                    assert!(
                        above < 0.01,
                        "block {block} m, ×{scale}, frame {t}: standing, the lowest sole \
                         {:.1} cm above the measured ground",
                        100.0 * above
                    );
                }
            }
        }
    }
}

/// `p` with one foot (ankle and toe) turned by `angle` radians about the
/// lateral axis through `pivot` (toe-up for a positive angle).
fn pitch_foot(p: &mut Pose, left: bool, pivot: DVec3, angle: f64) {
    let q = DQuat::from_rotation_x(-angle);
    for c in &leg(left)[1..] {
        p[c.index()] = pivot + q * (p[c.index()] - pivot);
    }
}

/// A flat walk's double support: the left foot leaving, heel up and its
/// toe joint `clear` m off the floor (within the 3 cm the clip touches
/// by), while the right heel strikes the floor toe up (its ankle and toe
/// joints more than 3 cm up). The clip has no heel point, so only the
/// left foot touches by its joints; the character's right heel must still
/// not go through the floor. Standing the body on the leaving foot alone
/// (the per-foot support reverted in issue 17) lowered it by the left
/// toe's clearance, the right heel that far through the floor (Bandai
/// walk_happy: 5-7 cm at every heel strike).
#[test]
fn a_heel_striking_beside_a_foot_leaving_on_its_toes_stays_on_the_floor() {
    let st = standing(0.06);
    for (lift, strike, clear) in [
        (10f64, 20f64, 0.02),
        (15.0, 30.0, 0.028),
        (5.0, 15.0, 0.015),
    ] {
        let stride: Vec<Pose> = (0..12)
            .map(|t| {
                let u = (t as f64 / 6.0).min(1.0);
                let mut p = st.map(|q| q + DVec3::Z * 0.02 * t as f64);
                // The left foot turns heel-up about its toe joint and
                // leaves the floor.
                let toe = p[C::LToe.index()];
                pitch_foot(&mut p, true, toe, -(lift * u).to_radians());
                for c in &leg(true)[1..] {
                    p[c.index()].y += clear * u;
                }
                // The right foot turns toe-up about its heel (under the
                // ankle, at the toe joint's height).
                let heel = DVec3::new(p[C::RAnkle.index()].x, 0.02, p[C::RAnkle.index()].z);
                pitch_foot(&mut p, false, heel, (strike * u).to_radians());
                p
            })
            .collect();
        // Standing still first, so the clip's floor is its flat feet.
        let clip = [vec![st; 20], stride].concat();
        let rf = choose_reference(Some(&st), &clip).unwrap();
        for (scale, ankle) in [(1.0, 0.06), (0.9, 0.09), (1.15, 0.05)] {
            let ch = standing(ankle).map(|p| p * scale);
            let floor = lowest_sole(&ch, &ch, &[DQuat::IDENTITY; Canonical::COUNT]);
            for (t, (p, g)) in retarget(&ch, &rf, &clip).iter().enumerate() {
                let below = floor - lowest_sole(&ch, p, g);
                assert!(
                    below < 0.005,
                    "lift {lift}°, strike {strike}°, clearance {clear} m, character ×{scale} \
                     (ankle {ankle} m), frame {t}: the lowest sole {:.1} cm below the floor",
                    100.0 * below
                );
            }
        }
    }
}

/// Stepping onto a block with a foot that
/// touches the floor only on its toes: the right foot stands flat on the
/// block all along; the left foot, heel up by `heel` degrees (rising by
/// 8° more over `toe_off` frames), pivots on its toe joint on the floor,
/// then swings up, flattening, over 12 frames and stands flat on the block
/// for 16 while the right foot lifts off it. The body rises with it.
fn step_up_off_toes(block: f64, heel: f64, toe_off: usize) -> Vec<Pose> {
    let st = standing(0.06);
    let swing = toe_off + 12;
    (0..swing + 16)
        .map(|t| {
            let u = ((t as f64 - toe_off as f64) / 12.0).clamp(0.0, 1.0);
            let mut p = st;
            for c in Canonical::ALL {
                p[c.index()].y += block * u;
            }
            // The right foot lifts off the block 4 frames after the left
            // lands (the next step), leaving the left to bear the weight.
            let next = ((t as f64 - swing as f64 - 4.0) / 4.0).clamp(0.0, 1.0);
            for c in &leg(false)[1..] {
                p[c.index()] = st[c.index()] + DVec3::Y * (block + 0.05 * next);
            }
            // The left foot: heel up about its toe joint, flattening as
            // it swings, flat on the block from frame `swing`.
            let pitch = if t < toe_off {
                heel + 8.0 * t as f64 / toe_off as f64
            } else {
                (heel + 8.0) * (1.0 - u)
            };
            let lift = if t < toe_off {
                0.0
            } else {
                block * u + 0.08 * (std::f64::consts::PI * u).sin()
            };
            for c in &leg(true)[1..] {
                p[c.index()] = st[c.index()] + DVec3::Y * lift;
            }
            let toe = p[C::LToe.index()];
            pitch_foot(&mut p, true, toe, -pitch.to_radians());
            bend_knees(&mut p, &st);
            p
        })
        .collect()
}

/// The elevation (degrees) of a pose's left foot bone, ankle to toe.
fn left_foot_elevation(p: &Pose) -> f64 {
    let f = p[C::LToe.index()] - p[C::LAnkle.index()];
    (f.y / f.length()).asin().to_degrees()
}

/// A foot the clip stands flat on a block stands flat on the character,
/// though the only frames it touches the floor in are a toe-off (or,
/// stepping down, a landing on the toes): its foot bone keeps the
/// character's rest elevation within 3° while the clip's foot is flat on
/// the block. On `main` the foot's flat elevation was read off the frames
/// where its ankle and toe are lowest, the toe-off here: the character's
/// left foot stood on the block toes up by the heel's lift (CMU 03_02:
/// 50-60°, its heel 3-4 cm through the block's top on the samba
/// character). Blocks of 12 and 20 cm, toe-offs 30-55° lasting 6 to 10
/// frames, characters ×0.85 and ×1.2 with a taller foot.
#[test]
fn a_foot_flat_on_a_block_is_flat_on_the_character_though_it_only_leaves_the_floor_on_its_toes() {
    for block in [0.12, 0.2] {
        for (heel, toe_off) in [(30.0, 6), (45.0, 10), (40.0, 8)] {
            // A 30 cm block, or this clip played backwards (stepping down
            // off a 20 cm block onto the toes), still fails: there the
            // levelled clip's block footfall is not taken for a step (not
            // fixed).
            let up = step_up_off_toes(block, heel, toe_off);
            for (name, clip, flat) in [("up", &up, toe_off + 14..up.len())] {
                let rf = choose_reference(Some(&standing(0.06)), clip).unwrap();
                for (scale, ankle) in [(0.85, 0.06), (1.2, 0.09)] {
                    let ch = standing(ankle).map(|p| p * scale);
                    let rest = left_foot_elevation(&ch);
                    let out = retarget(&ch, &rf, clip);
                    for t in flat.clone() {
                        let e = left_foot_elevation(&out[t].0);
                        assert!(
                            (e - rest).abs() < 3.0,
                            "block {block} m, stepping {name}, toe-off {heel}° over \
                             {toe_off} frames, character ×{scale}, frame {t}: the left foot \
                             at {e:.1}°, flat at {rest:.1}°"
                        );
                    }
                }
            }
        }
    }
}

/// `p` mirrored left to right: x negated, left and right joints swapped.
fn mirrored(p: &Pose) -> Pose {
    let mut q = p.map(|v| DVec3::new(-v.x, v.y, v.z));
    for (l, r) in [
        (C::LShoulder, C::RShoulder),
        (C::LElbow, C::RElbow),
        (C::LWrist, C::RWrist),
        (C::LHip, C::RHip),
        (C::LKnee, C::RKnee),
        (C::LAnkle, C::RAnkle),
        (C::LToe, C::RToe),
    ] {
        q.swap(l.index(), r.index());
    }
    q
}

/// [`standing`] with the legs `legs` times as long (the hips and every
/// joint below them scaled in height, the trunk carried up on them).
fn proportioned(ankle: f64, legs: f64) -> Pose {
    let hip = 0.95;
    standing(ankle).map(|v| {
        let y = if v.y <= hip + 1e-9 {
            v.y * legs
        } else {
            v.y + hip * (legs - 1.0)
        };
        DVec3::new(v.x, y, v.z)
    })
}

/// Stepping onto a block `block` m high at `fps` frames per second with
/// the left foot from its toes: the right foot stands flat on the block
/// all along; the left, heel up by `heel` degrees (rising by 8° more over
/// `toe_off` s), pivots on its toe joint on the floor, then swings up
/// and over the block's edge, clearing its top by 5 cm and flattening,
/// over 0.4 s, and stands flat on the block for 0.55 s while the right
/// foot lifts off it 0.13 s after the landing. The body rises with the
/// swing; the knees bend to keep the legs' lengths. Played backwards, it
/// steps down off the block onto the toes.
fn block_step(block: f64, heel: f64, toe_off: f64, fps: f64) -> Vec<Pose> {
    let st = standing(0.06);
    let (swing, stand) = (0.4, 0.55);
    let n = ((toe_off + swing + stand) * fps).round() as usize;
    (0..n)
        .map(|i| {
            let t = i as f64 / fps;
            let u = ((t - toe_off) / swing).clamp(0.0, 1.0);
            let mut p = st;
            for c in Canonical::ALL {
                p[c.index()].y += block * u;
            }
            let next = ((t - toe_off - swing - 0.13) / 0.13).clamp(0.0, 1.0);
            for c in &leg(false)[1..] {
                p[c.index()] = st[c.index()] + DVec3::Y * (block + 0.05 * next);
            }
            let pitch = if t < toe_off {
                heel + 8.0 * t / toe_off
            } else {
                (heel + 8.0) * (1.0 - u)
            };
            // Up fast, then over the edge and down onto the top.
            let lift = block * (1.0 - (1.0 - u).powi(2)) + 0.05 * (std::f64::consts::PI * u).sin();
            for c in &leg(true)[1..] {
                p[c.index()] = st[c.index()] + DVec3::Y * lift;
            }
            let toe = p[C::LToe.index()];
            pitch_foot(&mut p, true, toe, -pitch.to_radians());
            bend_knees(&mut p, &st);
            p
        })
        .collect()
}

/// The elevation (degrees) of a pose's foot bone, ankle to toe.
fn foot_elevation(p: &Pose, left: bool) -> f64 {
    let [_, a, t] = leg(left);
    let f = p[t.index()] - p[a.index()];
    (f.y / f.length()).asin().to_degrees()
}

/// The lowest sole point (toe joint, or a heel under the ankle at the
/// rest pose's toe height, carried by the ankle) of one foot.
fn sole(rest: &Pose, p: &Pose, g: &[DQuat; Canonical::COUNT], left: bool) -> f64 {
    let [_, a, k] = leg(left);
    let (a, k) = (a.index(), k.index());
    let heel = DVec3::new(0.0, rest[k].y - rest[a].y, 0.0);
    p[k].y.min((p[a] + g[a] * heel).y)
}

/// A foot the clip stands flat on a block stands flat on the character,
/// its heel not in the block, whatever the block's height, the direction
/// (stepping up from the toes, or down off the block onto them: the clip
/// played backwards), the foot, the frame rate and the character: while
/// the clip's stepping foot is flat on the block, the character's keeps
/// its rest elevation within 3°, and on a block higher than 6 cm (a step
/// to the kernel) neither its heel nor its toe is more than 1 cm below
/// the block's top (scaled by the ratio of leg lengths).
/// On `main` a footfall's support was the lowest height its lowest joint
/// reached while planted, and the run of planted frames also held the
/// frames coming down onto the block or leaving it over the edge: on 30
/// and 40 cm blocks stepping up, and on every block stepping down, the
/// frames flat on the block touched nothing, the foot's flat elevation
/// was read off the toes on the floor, and the foot stood on the block
/// toes up, its heel through the top; a 5 cm block was the floor (steps
/// begins 6 cm up) and its foot touched nothing either (464 of the 640
/// cases fail on `main`, up to 56° off flat). Blocks 5-40 cm,
/// toe-offs 30-50° over 0.2-0.33 s, both feet, 24 to 120 frames per
/// second, characters ×0.85 and ×1.2, with a taller foot, longer or
/// shorter legs.
#[test]
fn a_foot_flat_on_a_block_of_any_height_stands_flat_stepping_up_or_down() {
    let mut failures = Vec::new();
    let mut checked = 0;
    for block in [0.05, 0.12, 0.2, 0.3, 0.4] {
        for (heel, toe_off) in [(30.0, 0.2), (50.0, 0.33)] {
            for fps in [24.0, 30.0, 60.0, 120.0] {
                let up = block_step(block, heel, toe_off, fps);
                let down: Vec<Pose> = up.iter().rev().copied().collect();
                for (dir, clip) in [("up", up), ("down", down)] {
                    for left in [true, false] {
                        let clip: Vec<Pose> = if left {
                            clip.clone()
                        } else {
                            clip.iter().map(mirrored).collect()
                        };
                        let st = standing(0.06);
                        let rest_e = foot_elevation(&st, true);
                        let top = block + 0.02;
                        let flat: Vec<usize> = (0..clip.len())
                            .filter(|&t| {
                                (foot_elevation(&clip[t], left) - rest_e).abs() < 0.5
                                    && (clip[t][leg(left)[2].index()].y - top).abs() < 0.005
                            })
                            .collect();
                        assert!(flat.len() >= 5, "{dir} {block}: {} flat frames", flat.len());
                        let rf = choose_reference(Some(&st), &clip).unwrap();
                        for (scale, ankle, legs) in [
                            (0.85, 0.06, 1.0),
                            (1.2, 0.09, 1.0),
                            (1.0, 0.06, 1.15),
                            (1.0, 0.08, 0.9),
                        ] {
                            let ch = proportioned(ankle, legs).map(|p| p * scale);
                            let s = leg_length(&ch) / leg_length(&rf.pose);
                            let rest = foot_elevation(&ch, left);
                            let floor = sole(&ch, &ch, &[DQuat::IDENTITY; Canonical::COUNT], left);
                            let out = retarget(&ch, &rf, &clip);
                            checked += 1;
                            let (mut worst_e, mut worst_sole) = (0.0f64, 0.0f64);
                            for &t in &flat {
                                let (p, g) = &out[t];
                                worst_e = worst_e.max((foot_elevation(p, left) - rest).abs());
                                let below = floor + block * s - sole(&ch, p, g, left);
                                worst_sole = worst_sole.max(below);
                            }
                            // A block within 6 cm of the floor is the
                            // floor to the kernel: the body is not held
                            // on it (its sole up to 2.1 cm below the top
                            // at 60-120 fps, legs ×1.15); only the foot's
                            // elevation is checked there.
                            let step = block > 0.06;
                            if worst_e >= 3.0 || (step && worst_sole >= 0.01) {
                                failures.push(format!(
                                    "block {block} m {dir}, {} foot, toe-off {heel}° over \
                                     {toe_off} s, {fps} fps, character ×{scale} (ankle {ankle} m, \
                                     legs ×{legs}): the foot {worst_e:.1}° off flat, its sole \
                                     {:.1} cm below the block's top",
                                    if left { "left" } else { "right" },
                                    100.0 * worst_sole
                                ));
                            }
                        }
                    }
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {checked} cases:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Puts each knee where the hip and ankle of `p` and the thigh and shin
/// lengths of the standing pose `st` put it.
fn bend_knees(p: &mut Pose, st: &Pose) {
    for left in [true, false] {
        let [k, a, _] = leg(left);
        let h = if left { C::LHip } else { C::RHip };
        let (l1, l2) = (
            st[h.index()].distance(st[k.index()]),
            st[k.index()].distance(st[a.index()]),
        );
        p[k.index()] = knee(p[h.index()], p[a.index()], l1, l2);
    }
}

/// A walk in place (a game's cycle): `n` frames, the feet sliding back
/// under the body on the floor, each stance short (heel strike 25° toes
/// up, flat for about one frame, then rolling onto the ball to 60°), each
/// swing kicking the shin up behind (the foot pointing down and back)
/// before it comes forward; the right leg half a cycle after the left.
/// The foot's flat elevation is steep (ankle 9 cm over the toe joint, 12
/// cm behind it: −37°, a cartoon foot), hips 0.95 m up, facing +Z. So no
/// foot stands flat for five frames or is ever planted, and the frames
/// where one leg kicks back are among the most neutral (Kenney's Maya
/// character's clip, whose heel went 7.2 cm through samba's floor).
fn walk_in_place(n: usize) -> Vec<Pose> {
    use std::f64::consts::PI;
    let st = standing(0.06);
    // The flat foot: toe joint 1 cm up, ankle and heel from it.
    let toe0 = DVec3::new(0.0, 0.01, 0.0);
    let ankle0 = toe0 + DVec3::new(0.0, 0.09, -0.12);
    let heel0 = DVec3::new(0.0, 0.01, -0.14);
    // The foot turned by `phi` (toes up) about the heel (up) or the toe
    // joint (down), the pivot on the floor at `z`: (ankle, toe).
    let stance = |phi: f64, z: f64| -> (DVec3, DVec3) {
        let q = DQuat::from_rotation_x(-phi);
        let pivot = if phi > 0.0 { heel0 } else { toe0 };
        let at = |v: DVec3| pivot + q * (v - pivot) + DVec3::Z * z;
        (at(ankle0), at(toe0))
    };
    let lerp = |a: f64, b: f64, w: f64| a + (b - a) * w;
    let piece = |u: f64, keys: &[(f64, f64)]| -> f64 {
        let k = keys
            .windows(2)
            .find(|w| u <= w[1].0)
            .unwrap_or(&keys[keys.len() - 2..]);
        lerp(
            k[0].1,
            k[1].1,
            ((u - k[0].0) / (k[1].0 - k[0].0)).clamp(0.0, 1.0),
        )
    };
    let deg = PI / 180.0;
    // Stance: u in [0, 0.3), the pivot sliding from +0.2 to -0.2 m.
    let stance_phi = [
        (0.0, 25.0),
        (0.06, 0.0),
        (0.12, -25.0),
        (0.2, -45.0),
        (0.3, -60.0),
    ];
    let (end_a, _) = stance(-60.0 * deg, -0.2);
    let (strike_a, _) = stance(25.0 * deg, 0.2);
    let foot = |u: f64| -> (DVec3, DVec3) {
        if u < 0.3 {
            return stance(piece(u, &stance_phi) * deg, lerp(0.2, -0.2, u / 0.3));
        }
        // Swing: the ankle up behind (kicked back), then forward, then down.
        let ay = piece(
            u,
            &[(0.3, end_a.y), (0.55, 0.42), (0.85, 0.2), (1.0, strike_a.y)],
        );
        let az = piece(
            u,
            &[
                (0.3, end_a.z),
                (0.55, -0.3),
                (0.85, 0.25),
                (1.0, strike_a.z),
            ],
        );
        let phi = piece(u, &[(0.3, -60.0), (0.55, -85.0), (0.85, 25.0), (1.0, 25.0)]) * deg;
        let dir = DQuat::from_rotation_x(-phi) * (toe0 - ankle0);
        let a = DVec3::new(0.0, ay, az);
        (a, a + dir)
    };
    (0..n)
        .map(|i| {
            let mut p = st;
            for (left, shift) in [(true, 0.0), (false, 0.5)] {
                let u = (i as f64 / n as f64 + shift).fract();
                let [_, a, t] = leg(left);
                let x = p[a.index()].x;
                let (fa, ft) = foot(u);
                p[a.index()] = fa + DVec3::X * x;
                p[t.index()] = ft + DVec3::X * x;
            }
            bend_knees(&mut p, &st);
            p
        })
        .collect()
}

/// Kenney's heel (issue 44): a clip that never stands a foot flat for five
/// frames and whose reference frame kicks a foot back (the foot bone
/// pointing backward) stood the character's foot toes-up by 64° at the
/// next heel strike, its heel through the floor. On the walk in place
/// ([`walk_in_place`], 26 frames at 30 fps as Kenney's), its reference
/// chosen as `retarget` chooses it and forced onto each frame where a
/// shin is kicked back, re-scaled (0.6, 1, 1.5), turned (0°, 90°, 200°) and
/// mirrored: where the clip's foot is flat (its toe joint and its heel on
/// the floor) the character's foot is within 12° of its own flat
/// elevation, and a heel point 5 cm behind the character's ankle at its
/// rest toe height, carried by the ankle, never goes more than 2.5 cm
/// under its floor (the kernel stands the body on a heel point *under*
/// the ankle: at the clip's 25° heel strike one 5 cm behind it is 2.1 cm
/// lower). At 0.6 (a clip of a 1.1 m body, legs 0.54 m) this failed
/// while the flat elevation's "near the lowest" was 2 cm whatever the
/// body's size: the frames rolling onto the ball counted, and the
/// character's foot stood 16° toes-down where the clip's was flat
/// (session 32); the band is now 2.4 % of the clip's leg.
#[test]
fn a_clip_never_flat_footed_with_a_foot_kicked_back_keeps_the_heels_above_the_floor() {
    use surfmotion::pose::retarget::{ClipNeutral, ClipNeutralSource};
    let n = 26;
    let base = walk_in_place(n);
    // The frames where a shin is kicked back (u = 0.55 of a leg's cycle),
    // and the frames where a foot is flat (u = 0.06).
    let at = |u: f64, shift: f64| ((u - shift).rem_euclid(1.0) * n as f64).round() as usize % n;
    let kicked = [at(0.55, 0.0), at(0.55, 0.5)];
    let flat = [(true, at(0.06, 0.0)), (false, at(0.06, 0.5))];
    let elev = |f: DVec3| (f.y / f.length()).asin().to_degrees();
    let mut failures = Vec::new();
    let mut checked = 0;
    for scale in [0.6, 1.0, 1.5] {
        for turn in [0.0f64, 90.0, 200.0] {
            for mirror in [false, true] {
                let q = DQuat::from_rotation_y(turn.to_radians());
                let clip: Vec<Pose> = base
                    .iter()
                    .map(|p| {
                        let p = if mirror { mirrored(p) } else { *p };
                        p.map(|v| q * v * scale)
                    })
                    .collect();
                let chosen = choose_reference(Some(&clip[0]), &clip).unwrap();
                let mut refs = vec![("chosen".to_string(), chosen)];
                for k in kicked {
                    refs.push((
                        format!("frame {k}"),
                        ClipNeutral {
                            pose: clip[k],
                            source: ClipNeutralSource::Frame(k),
                            rotations: std::sync::Arc::from(Vec::new()),
                        },
                    ));
                }
                let ch = standing(0.06);
                let floor = ch[C::LToe.index()].y;
                let rest_elev = elev(ch[C::LToe.index()] - ch[C::LAnkle.index()]);
                for (name, rf) in &refs {
                    checked += 1;
                    let out = retarget(&ch, rf, &clip);
                    let case = format!(
                        "scale {scale}, turned {turn}°, mirrored {mirror}, reference {name}"
                    );
                    let mut worst = 0.0f64;
                    for (p, g) in &out {
                        for (a, t) in [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)] {
                            let heel_rest = DVec3::new(
                                ch[a.index()].x,
                                ch[t.index()].y,
                                ch[a.index()].z - 0.05,
                            );
                            let heel = p[a.index()] + g[a.index()] * (heel_rest - ch[a.index()]);
                            worst = worst.max(floor - heel.y);
                        }
                    }
                    if worst > 0.025 {
                        failures.push(format!(
                            "{case}: a heel {:.1} cm under the floor",
                            100.0 * worst
                        ));
                    }
                    for (left, i) in flat {
                        // Mirrored, the left foot's motion is the right's.
                        let left = left != mirror;
                        let [_, a, t] = leg(left);
                        let e = elev(out[i].0[t.index()] - out[i].0[a.index()]);
                        if (e - rest_elev).abs() > 12.0 {
                            failures.push(format!(
                                "{case}: frame {i}, the clip's {} foot flat, the character's at {e:.1}° (flat {rest_elev:.1}°)",
                                if left { "left" } else { "right" }
                            ));
                        }
                    }
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures in {checked} cases:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Kenney's end hold (issue 44): a clip padded with a pose held over its
/// last frames, both feet in the air, read the hold as a step under the
/// lower foot (it rests, bears the body and lasts 5 frames), and that
/// step's foot elevation became the foot's flat one. On the walk in place
/// ([`walk_in_place`]) padded with a kicked-back frame raised by a tenth
/// of the leg and repeated 5 or 8 times, re-scaled (0.6, 1, 1.5): the
/// repeats touch no support. (The result's frames before the padding are
/// not yet those of the clip without it: at ×1 with 8 repeats a foot
/// stands at −7.2° in frame 0 against 8.9°; session 33, a gap.)
#[test]
fn a_pose_held_in_the_air_at_the_end_of_a_clip_is_no_step() {
    use surfmotion::pose::retarget::clip_support;
    let n = 26;
    let base = walk_in_place(n);
    let kicked = ((0.55 * n as f64).round() as usize) % n;
    for scale in [0.6, 1.0, 1.5] {
        let clip: Vec<Pose> = base.iter().map(|p| p.map(|v| v * scale)).collect();
        let leg = leg_length(&clip[0]);
        for repeats in [5usize, 8] {
            let hold = clip[kicked].map(|v| v + DVec3::Y * 0.1 * leg);
            let mut padded = clip.clone();
            padded.extend(std::iter::repeat_n(hold, repeats + 1));
            let s = clip_support(&padded, leg);
            for foot in 0..2 {
                for i in n..padded.len() {
                    assert_eq!(
                        s.touch[foot][i], None,
                        "×{scale}, {repeats} repeats: foot {foot} touches {:?} in held frame {i}",
                        s.touch[foot][i]
                    );
                }
            }
        }
    }
}
