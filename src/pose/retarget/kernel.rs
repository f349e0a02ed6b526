//! The kernel: a clip's poses onto the character's skeleton, bone by bone
//! (torso, neck and head, limbs, feet, toes), the root placed by the feet
//! on their grounds. See the [module docs](super) for what is matched.

use super::anchor::{Footfalls, Placement, place_anchor, placement_from_env};
use super::feet::{Toes, flat_feet_with, place_feet_into};
use super::footfall::plant_feet;
use super::ground::{Given, clip_support_given_into, foot_height};
use super::level::{Level, level_from_env, levelling_line};
use super::motion_ref::{carriage_for_rest, torso_reference};
use super::reference::{ClipNeutral, ClipNeutralSource, leg_length};
use super::root::root_from_legs;
use super::torso::{clip_rotations_into, neck_carriage, upright_into};
use super::workspace::KernelWorkspace;
use crate::pose::{Pose, pose_rotations};
use crate::rig::Canonical;
use glam::{DQuat, DVec3};
use rayon::prelude::*;

use Canonical as C;

pub(super) const TORSO: [Canonical; 5] = [C::Pelvis, C::Spine, C::Chest, C::Neck, C::Head];

pub(super) fn is_torso(c: Canonical) -> bool {
    TORSO.contains(&c)
}

/// The feet turn by the clip's rotation since its reference, like the
/// torso: a flat foot in the clip is the character's flat foot, whatever
/// the angle each skeleton's ankle-to-toe bone makes with the sole.
pub(super) fn is_foot(c: Canonical) -> bool {
    matches!(c, C::LAnkle | C::RAnkle)
}

/// Turn about the vertical taking `from`'s left-right axis (hips and
/// shoulders) onto `to`'s.
pub(super) fn heading_between(from: &Pose, to: &Pose) -> DQuat {
    let lateral = |p: &Pose| {
        let v = (p[C::LHip.index()] - p[C::RHip.index()])
            + (p[C::LShoulder.index()] - p[C::RShoulder.index()]);
        DVec3::new(v.x, 0.0, v.z).normalize_or_zero()
    };
    let (a, b) = (lateral(from), lateral(to));
    if a == DVec3::ZERO || b == DVec3::ZERO {
        return DQuat::IDENTITY;
    }
    DQuat::from_rotation_y(a.z.atan2(a.x) - b.z.atan2(b.x))
}

/// The character's joint positions and global joint rotations (taking its
/// rest bones, `character`, onto the posed ones) in every clip pose
/// (metres, Y-up). See the module docs for what is matched. Skinning with
/// these rotations and positions is consistent: every joint sits where its
/// parent's rotation carries the rest bone.
pub fn retarget(
    character: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
) -> Vec<(Pose, [DQuat; Canonical::COUNT])> {
    retarget_with_neutral(character, character, reference, mocap)
}

/// [`retarget`] with the character's neutral pose `neutral` (a pose of its
/// skeleton in its rest frame's space, e.g. [`character_neutral`](super::character_neutral)'s)
/// standing for its rest pose `character`: a clip standing neutrally
/// gives the character's torso, neck, head and feet as in `neutral`
/// (`G_j(t) = A_j(t) H N_j`, with `N` the rotations taking the rest bones
/// onto the neutral's and `H` the turn facing the neutral the reference's
/// way); bone lengths, the floor and the soles stay the rest pose's.
///
/// With the clip's joint rotations ([`ClipNeutral::rotations`], one per pose
/// of `mocap`) the chest turns by the rotation of the file joint mapped
/// to it rather than by the fit to its children's bones. Those children
/// (the neck, the shoulders) are carried by other file joints (the neck's
/// base, the clavicles), so the fit depended on where each sits on the
/// chest: CMU 01_01's cgspeed BVH conversion drops the thorax's length and
/// hangs the neck and shoulders 11.7 cm lower on the same rotations than
/// the AMC, and its chest, then its neck, head and arms, turned
/// differently. The pelvis keeps the fit to its hips and spine bones: the
/// root's own rotation leaves out the lower back's (CMU `lowerback`, a
/// bone off the root in the ASF, a zero-length joint on `Hips` in the
/// BVH, carries the spine), and the character's trunk then leaned up to
/// 12° less than the clip's in CMU 131_01's lunges while its chest and
/// head followed the clip (the head 3° past the clip's own line); the
/// pelvis's bones sit alike in an AMC and its conversions.
pub fn retarget_with_neutral(
    character: &Pose,
    neutral: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
) -> Vec<(Pose, [DQuat; Canonical::COUNT])> {
    retarget_toes(character, neutral, reference, mocap, Toes::Rigid)
}

/// A retargeted clip (per frame the character's joint positions and global
/// rotations), each foot's ground per frame ([`retarget_on_grounds`]) and,
/// with the feet on the clip's footfalls ([`Footfalls::Targets`]), the
/// joint positions as they were before (the feet where the limbs' directions put
/// them, standing on the ground as the result does): what retrieval
/// compares (`drive::Analysed::on_floor`).
pub(super) type RetargetedOnGrounds = (
    Vec<(Pose, [DQuat; Canonical::COUNT])>,
    [Vec<Option<f64>>; 2],
    Option<Vec<Pose>>,
);

/// [`retarget_with_neutral`] with the character's toes moving as `toes`
/// says: [`Toes::Rigid`] is [`retarget_with_neutral`]; with
/// [`Toes::Bending`] a foot pitched down onto its ball stands on the ball,
/// not on a rigid toe tip below it, and the toes' rotation
/// (`G_toe`, the ankle's without bending) turns them up about the ball.
pub fn retarget_toes(
    character: &Pose,
    neutral: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    toes: Toes,
) -> Vec<(Pose, [DQuat; Canonical::COUNT])> {
    retarget_on_grounds(
        character,
        neutral,
        reference,
        mocap,
        toes,
        &Given::default(),
        &mut KernelWorkspace::new(),
    )
    .0
}

/// [`retarget_toes`] and the ground each foot of the result stands on or
/// above per frame, raised above the character's floor (character's
/// metres; `None` for a foot that never touches): see [`place_feet_into`].
/// `given` holds what the caller decides instead of the kernel (the
/// levelling, the floor, the supports: [`Given`]): a live session's
/// decisions over the stream, where `mocap` is only its recent window;
/// `Given::default()` decides nothing. `ws` holds the buffers of the
/// kernel's clip-level steps ([`KernelWorkspace`]: the result is the
/// same whatever it held).
pub(super) fn retarget_on_grounds(
    character: &Pose,
    neutral: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    toes: Toes,
    given: &Given<'_>,
    ws: &mut KernelWorkspace,
) -> RetargetedOnGrounds {
    let how = (toes, placement_from_env(), level_from_env());
    retarget_placed_on_grounds(character, neutral, reference, mocap, how, given, ws)
}

/// [`retarget_toes`] with the body placed as `placement` says (issue 44;
/// [`Placement::default`] is the kernel's own rule, what every other
/// entry point uses unless [`PLACEMENT_ENV`](super::PLACEMENT_ENV) says
/// otherwise).
pub fn retarget_placed(
    character: &Pose,
    neutral: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    toes: Toes,
    placement: Placement,
) -> Vec<(Pose, [DQuat; Canonical::COUNT])> {
    retarget_levelled(
        character,
        neutral,
        reference,
        mocap,
        toes,
        placement,
        level_from_env(),
    )
}

/// [`retarget_placed`] with the torso's reference stood upright on the
/// line `level` names (issue 44; [`Level::default`] is the kernel's own,
/// what every other entry point uses unless
/// [`LEVEL_ENV`](super::LEVEL_ENV) says otherwise).
pub fn retarget_levelled(
    character: &Pose,
    neutral: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    toes: Toes,
    placement: Placement,
    level: Level,
) -> Vec<(Pose, [DQuat; Canonical::COUNT])> {
    let how = (toes, placement, level);
    let ws = &mut KernelWorkspace::new();
    retarget_placed_on_grounds(
        character,
        neutral,
        reference,
        mocap,
        how,
        &Given::default(),
        ws,
    )
    .0
}

/// [`retarget_on_grounds`] with the placement given.
fn retarget_placed_on_grounds(
    character: &Pose,
    neutral: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    how: (Toes, Placement, Level),
    given: &Given<'_>,
    ws: &mut KernelWorkspace,
) -> RetargetedOnGrounds {
    let mut out = Retargeted::default();
    let poses = (character, neutral);
    retarget_placed_into(poses, reference, mocap, how, given, ws, &mut out);
    (out.frames, out.grounds, out.free)
}

/// What one run of the kernel over a clip gives ([`RetargetedOnGrounds`]
/// as buffers): refilled by [`retarget_placed_into`], so a live session
/// that keeps it makes no allocation for them once they hold its window
/// (issue 45).
#[derive(Debug, Clone, Default)]
pub(super) struct Retargeted {
    /// Per frame, the character's joint positions and global rotations.
    pub(super) frames: Vec<(Pose, [DQuat; Canonical::COUNT])>,
    /// Each foot's ground per frame ([`place_feet_into`]).
    pub(super) grounds: [Vec<Option<f64>>; 2],
    /// With the feet on the clip's footfalls, the joints before.
    pub(super) free: Option<Vec<Pose>>,
}

/// [`retarget_placed_on_grounds`] into `out` (every part cleared and
/// refilled; `(character, neutral)` the character's rest and neutral
/// poses), the clip levelled and its rotations in the buffers of `ws`.
pub(super) fn retarget_placed_into(
    (character, neutral): (&Pose, &Pose),
    reference: &ClipNeutral,
    mocap: &[Pose],
    (toes, placement, level): (Toes, Placement, Level),
    given: &Given<'_>,
    ws: &mut KernelWorkspace,
    out: &mut Retargeted,
) {
    // Counted by the tests of issue 40's "analysed once per clip".
    let _run = tracing::debug_span!("pose_kernel", frames = mocap.len()).entered();
    out.frames.clear();
    out.grounds.iter_mut().for_each(Vec::clear);
    if mocap.is_empty() {
        out.free = None;
        return;
    }
    // A clip whose root carries no vertical motion stood on its legs.
    let from_legs = root_from_legs(mocap);
    let mocap = from_legs.as_deref().unwrap_or(mocap);
    // The clip's ground made level (a capture volume's floor is often a
    // degree or two off its vertical axis; CMU subject 02's rises 8 cm
    // over a 4 m walk), so that one floor height holds for every frame.
    let tilt = given.tilt_with(mocap, &mut ws.tilt);
    ws.levelled.clear();
    ws.levelled
        .extend(mocap.iter().map(|m| m.map(|p| tilt * p)));
    let mocap = &ws.levelled[..];
    let first = &mocap[0];
    let level_ref;
    let r = match reference.source {
        ClipNeutralSource::Frame(i) if i < mocap.len() => {
            level_ref = mocap[i];
            &level_ref
        }
        _ => &reference.pose,
    };
    // A frame standing in for the rest: the torso from the clip's mean
    // carriage (see [`torso_reference`]); an upright rest's too when
    // [`REFERENCE_ENV`](super::REFERENCE_ENV) says `carriage`.
    let (carriage, at_ref) = torso_reference(r, mocap, reference, tilt, carriage_for_rest());
    let r = &carriage;
    // The clip's floor and the support under each of its footfalls (the
    // leg's length does not depend on the feet).
    let support = &mut ws.found;
    clip_support_given_into(mocap, leg_length(r), given, &mut ws.support, support);
    let support = &*support;
    // The feet measured from how the clip holds them flat on its ground.
    let stance_ref = flat_feet_with(r, mocap, support, &mut ws.flat);
    let r = &stance_ref;
    let s = leg_length(character) / leg_length(r).max(1e-12);
    let face = heading_between(neutral, r);
    // The rest bones onto the neutral's (identity when it is the rest).
    let held = pose_rotations(character, neutral);
    let root = C::Pelvis.index();
    let clip_floor = support.floor;
    let char_floor = foot_height(character);
    let rotations = &mut ws.rotations;
    clip_rotations_into(r, mocap, reference, (tilt, at_ref), rotations);
    level_torso(rotations, r, level);
    let rotations = &*rotations;
    upright_into(mocap, rotations, &mut ws.trunk, &mut ws.upright);
    let carriage_inv = neck_carriage(&ws.upright).inverse();
    let (chest, neck) = (C::Chest.index(), C::Neck.index());
    let unset = (
        [DVec3::ZERO; Canonical::COUNT],
        [DQuat::IDENTITY; Canonical::COUNT],
    );
    out.frames.resize(mocap.len(), unset);
    out.frames
        .par_iter_mut()
        .zip(mocap.par_iter().zip(rotations.par_iter()))
        .for_each(|(o, (m, a))| {
            let mut g = [DQuat::IDENTITY; Canonical::COUNT];
            let mut t = [DVec3::ZERO; Canonical::COUNT];
            let d = (m[root] - first[root]) * s;
            t[root] = DVec3::new(
                character[root].x + d.x,
                char_floor + (m[root].y - clip_floor) * s,
                character[root].z + d.z,
            );
            // The neck's turn relative to the chest, around the clip's
            // typical carriage.
            let neck_g = a[chest] * carriage_inv * a[chest].inverse() * a[neck];
            for c in Canonical::ALL {
                let j = c.index();
                if let Some(p) = c.parent() {
                    t[j] = t[p.index()] + g[p.index()] * (character[j] - character[p.index()]);
                }
                g[j] = match c {
                    C::Neck | C::Head => (neck_g * face * held[j]).normalize(),
                    _ if is_torso(c) || is_foot(c) => (a[j] * face * held[j]).normalize(),
                    _ => limb_rotation(character, m, &g, c),
                };
            }
            *o = (t, g);
        });
    // Feet on the ground: in every frame where a foot of the clip touches
    // its ground (planted, its lowest joint within the contact band, 3.6 %
    // of the clip's leg, of that footfall's support, or of the floor), the body is lifted (or
    // lowered) so that each character foot stands on or above the ground
    // under it ([`Support::under`]: the support the foot touches, raised
    // above the character's floor by its height above the clip's floor,
    // scaled; for a foot in the air, the lower of the supports it left
    // and lands on unless its sole is above the higher's top:
    // [`place_feet_into`]); the foot that
    // needs the body highest stands on its
    // ground. Between such frames (a run's flight) the correction is
    // interpolated. Whatever the two skeletons' hip offsets and foot
    // lengths. Each foot is held to its own ground: CMU 03_02 stands one
    // foot on a block while the other leaves the floor, and the body's
    // lowest sole put on the block stood the character 10-22 cm up for a
    // frame or more at each footfall. A foot the clip does not touch with
    // still counts (its ground is [`Support::under`]'s): the
    // clip has no heel point, so a heel strike's foot is off the ground
    // by its joints, and standing the body on the other foot alone (its
    // toes, leaving) sank the striking heel 5-7 cm through the floor.
    // The body's anchor following the clip's (issue 44; the root already
    // does with the default placement: see [`place_anchor`]).
    let floors = (clip_floor, char_floor);
    let how = (toes, given.open_end);
    let k = place_anchor(character, mocap, placement, s, floors, &mut out.frames);
    // The feet on the clip's footfalls, mapped by the same travel scale
    // (issue 44, an option: [`plant_feet`]); the poses as they were kept,
    // grounded, for retrieval to compare.
    if placement.footfalls == Footfalls::Targets {
        let was = &mut ws.was;
        was.clear();
        was.extend_from_slice(&out.frames);
        let feet = (&mut ws.feet, &mut out.grounds);
        place_feet_into(character, support, s, how, was, feet);
        let free = out.free.get_or_insert_with(Vec::new);
        free.clear();
        free.extend(was.iter().map(|(p, _)| *p));
        plant_feet(mocap, support, (k, leg_length(r)), &mut out.frames);
    } else {
        out.free = None;
    }
    let feet = (&mut ws.feet, &mut out.grounds);
    place_feet_into(character, support, s, how, &mut out.frames, feet);
}

/// The torso's rotations (pelvis, spine, chest, neck, head) measured from
/// the reference `r` stood upright: each turned by `L⁻¹` on the right, `L`
/// the least rotation taking the reference's pelvis → chest line onto the
/// vertical (the reference's own bones turned by `L` are then taken onto
/// the frame's by the result). The lean a reference stands with is the
/// file's, not the performance's: CMU 02_03's ASF rest skeleton stands
/// 2.8° off the vertical on this line, the CC-rig BVH conversion's most
/// neutral frame 5.4° (knees bent 37°), and with the reference as it
/// stood the two drove the character's chest, neck and head 1.7-2.6 % of
/// its height apart about the pelvis. The line is the pelvis → chest one
/// (not → neck or shoulders): a conversion that drops the thorax's length
/// (CMU 01_01's cgspeed BVH) moves the neck and shoulders, not the chest.
/// `level` chooses another line ([`Level`]: the pelvis is the root joint,
/// and a rig that puts its root elsewhere turns this one).
pub(super) fn level_torso(rotations: &mut [[DQuat; Canonical::COUNT]], r: &Pose, level: Level) {
    let line = levelling_line(r, level);
    if line == DVec3::ZERO {
        return;
    }
    let undo = DQuat::from_rotation_arc(line, DVec3::Y).inverse();
    for a in rotations {
        for c in TORSO {
            a[c.index()] = (a[c.index()] * undo).normalize();
        }
    }
}

/// A limb joint's global rotation: the least rotation from where its
/// parent carries the character's rest bone onto the clip's bone direction,
/// composed on the parent's (an end joint keeps its parent's).
pub(super) fn limb_rotation(
    character: &Pose,
    m: &Pose,
    g: &[DQuat; Canonical::COUNT],
    c: Canonical,
) -> DQuat {
    let pr = c.parent().map_or(DQuat::IDENTITY, |p| g[p.index()]);
    let Some(child) = Canonical::ALL.iter().find(|k| k.parent() == Some(c)) else {
        return pr;
    };
    let (j, k) = (c.index(), child.index());
    let from = (pr * (character[k] - character[j])).normalize_or_zero();
    let to = (m[k] - m[j]).normalize_or_zero();
    if from == DVec3::ZERO || to == DVec3::ZERO {
        return pr;
    }
    (DQuat::from_rotation_arc(from, to) * pr).normalize()
}
