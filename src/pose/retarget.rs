//! Rest-pose-aware retargeting: a clip's canonical poses onto a character's
//! own skeleton (used by `synth`, `retarget`, `transfer` and everything
//! after them).
//!
//! Copying every bone's *direction* from the clip (the retargeting of
//! Huang et al. 2015, Sec. 5.2, taken literally) gives the character the
//! clip's anatomy wherever the two skeletons define a joint differently: a
//! CMU "head" joint sits at the base of the skull, a character's at the top
//! of its neck region, and the difference became a permanent 15-30° tilt of
//! the head. Here the skeleton is split by what matters where:
//!
//! - **Torso** (pelvis, spine, chest): each joint turns by the clip's
//!   rotation *since a neutral reference pose of the clip*,
//!   `G_j(t) = A_j(t) H` with `A(t)` the rotations taking the reference's
//!   bones onto frame `t`'s ([`pose_rotations`]) and `H` the turn about the
//!   vertical that faces the character's rest frame the reference's way. A
//!   clip standing neutrally gives the character standing as captured; the
//!   clip's motion comes on top.
//! - **Neck and head**: the neck's turn relative to the chest is taken
//!   around the clip's *typical carriage* (the mean over the clip of
//!   `L(t) = A_chest⁻¹ A_neck`, call it `M`):
//!   `G_neck(t) = A_chest(t) M⁻¹ L(t) H`. Mocap suites place the neck and
//!   head joints differently and calibration poses rarely hold the head as
//!   the subject carries it: measured on CMU 02_02 (a walk), the neck bone
//!   sits 11° (median) back from the ASF rest skeleton's relative to the
//!   trunk, which left the character looking up. So the character carries
//!   its head as captured on average, and nods, turns and looks down as
//!   the clip does around that.
//! - **Limbs** (upper arms, forearms, thighs, shins, feet): each bone takes
//!   the clip's direction at `t` (the least rotation from where the parent
//!   carries the character's rest bone, so twist follows the parent), so
//!   hands and feet reach where the clip's do, scaled; T- versus A-pose arms
//!   make no difference.
//! - **Feet** (ankles) turn by the clip's rotation since the reference,
//!   as the torso does, with the reference's foot bones set to the
//!   elevation the clip's feet have when flat on its floor: a flat foot
//!   gives the character's flat foot.
//! - **Toes** ([`Toes`]): rigid with the foot for a surface whose foot
//!   part turns with the ankle (the part-based deformation); for one that
//!   turns the toes by the toe joint (`transfer`'s markers) they bend at
//!   the ball where the ground stops them, and the body stands on the
//!   ball or the heel rather than on a rigid toe tip below the ball
//!   ([`retarget_toes`]).
//! - **Root**: horizontal travel from the clip's first frame scaled by the
//!   ratio of leg lengths (character / reference); height above the floor
//!   scaled the same way. The clip's ground is first levelled
//!   ([`ground_tilt`]); then in every frame where the clip stands on its
//!   ground ([`clip_support`]: its floor, or the support under a planted
//!   foot's footfall, a step) the character's lowest sole point (toe
//!   joint, heel, toe tip) is put on the character's floor (its rest
//!   frame's) raised by that support, scaled; the correction is
//!   interpolated across frames where the clip does not (a run's flight).
//! - **The character's neutral** ([`character_neutral`]): its rest frame
//!   when that stands upright, else the database frame nearest neutral;
//!   [`retarget_with_neutral`] turns the torso, neck, head and feet from
//!   it (`G_j(t) = A_j(t) H N_j`).
//! - The neck's carriage is read on the clip's upright frames (trunk
//!   within 10° of its most upright), so a clip mostly bent over does not
//!   make head-down its neutral.
//!
//! The clip's reference ([`choose_reference`]) is its rest skeleton when
//! that stands upright (a T- or A-pose: trunk within 20° of vertical, legs
//! within 30°, bones as long as in the motion), else its most neutral frame
//! (trunk nearest vertical, knees straightest).

use crate::mocap::Clip;
use crate::pose::{Pose, pose_rotations};
use crate::rig::{Canonical, RigError, RigMap};
use glam::{DQuat, DVec3};
use rayon::prelude::*;
use serde::Serialize;
use std::sync::Arc;

/// Where a clip's neutral reference pose comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ReferenceSource {
    /// The clip's rest (bind) skeleton, which stands upright.
    Rest,
    /// The clip's most neutral frame (the rest skeleton was not upright).
    Frame(usize),
}

impl std::fmt::Display for ReferenceSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReferenceSource::Rest => write!(f, "rest skeleton"),
            ReferenceSource::Frame(i) => write!(f, "most neutral frame ({i})"),
        }
    }
}

/// A clip's neutral reference pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// Canonical joint positions (the clip's units and axes).
    pub pose: Pose,
    /// Where it came from.
    pub source: ReferenceSource,
    /// The clip's own joint rotations per frame ([`JointRotations`], one
    /// per pose the reference was chosen among, in the clip's axes; empty
    /// when not known). [`retarget`] turns the chest by them
    /// when it is given that many poses, those the reference came with:
    /// poses changed since (moved, turned, resampled) must take a reference
    /// without them ([`Reference::without_rotations`]).
    pub rotations: Arc<[JointRotations]>,
}

impl Reference {
    /// The reference with no joint rotations: [`retarget`] turns the torso
    /// by the fit to the poses' bones alone.
    pub fn without_rotations(&self) -> Reference {
        Reference {
            rotations: Arc::from(Vec::new()),
            ..self.clone()
        }
    }
}

/// Per canonical joint, the world rotation of the clip's file joint mapped
/// to it (the rotation carrying that joint's own bones), `None` for a
/// joint the map derives; the clip's axes. See [`RigMap::poses_and_rotations`].
pub type JointRotations = [Option<DQuat>; Canonical::COUNT];

/// A clip as canonical poses with its neutral reference.
#[derive(Debug, Clone)]
pub struct ClipPoses {
    /// One pose per frame (the clip's units and axes).
    pub poses: Vec<Pose>,
    /// The neutral reference the retargeting measures rotations from
    /// (with the file joints' rotations of every frame).
    pub reference: Reference,
}

/// Canonical poses of every frame of `clip` and its neutral reference.
/// Convert the clip to metres, Y-up, first (`Clip::to_metres_y_up`): the
/// reference is chosen against the vertical.
pub fn clip_poses(clip: &Clip, map: &RigMap) -> Result<ClipPoses, RigError> {
    let (poses, rotations) = map.poses_and_rotations(clip)?;
    let rest = map.rest_pose(clip)?;
    let mut reference = choose_reference(Some(&rest), &poses)?;
    reference.rotations = Arc::from(rotations);
    Ok(ClipPoses { poses, reference })
}

use Canonical as C;

const TORSO: [Canonical; 5] = [C::Pelvis, C::Spine, C::Chest, C::Neck, C::Head];

fn is_torso(c: Canonical) -> bool {
    TORSO.contains(&c)
}

/// The feet turn by the clip's rotation since its reference, like the
/// torso: a flat foot in the clip is the character's flat foot, whatever
/// the angle each skeleton's ankle-to-toe bone makes with the sole.
fn is_foot(c: Canonical) -> bool {
    matches!(c, C::LAnkle | C::RAnkle)
}

/// Mean length of the two legs (hip to knee to ankle).
pub fn leg_length(p: &Pose) -> f64 {
    let d = |a: C, b: C| p[a.index()].distance(p[b.index()]);
    0.5 * (d(C::LHip, C::LKnee)
        + d(C::LKnee, C::LAnkle)
        + d(C::RHip, C::RKnee)
        + d(C::RKnee, C::RAnkle))
}

fn angle(a: DVec3, b: DVec3) -> f64 {
    let (a, b) = (a.normalize_or_zero(), b.normalize_or_zero());
    if a == DVec3::ZERO || b == DVec3::ZERO {
        return std::f64::consts::PI;
    }
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// Trunk tilt from the vertical (pelvis → neck), radians.
fn trunk_tilt(p: &Pose) -> f64 {
    angle(p[C::Neck.index()] - p[C::Pelvis.index()], DVec3::Y)
}

/// Knee bend of one leg (0 = straight), radians.
fn knee_bend(p: &Pose, hip: C, knee: C, ankle: C) -> f64 {
    let (h, k, a) = (p[hip.index()], p[knee.index()], p[ankle.index()]);
    angle(k - h, a - k)
}

/// How far `p` is from standing neutrally: trunk tilt plus the mean knee
/// bend (radians).
fn neutrality(p: &Pose) -> f64 {
    trunk_tilt(p)
        + 0.5
            * (knee_bend(p, C::LHip, C::LKnee, C::LAnkle)
                + knee_bend(p, C::RHip, C::RKnee, C::RAnkle))
}

/// Canonical bones (child, parent) of the torso and legs, whose lengths the
/// rest skeleton must share with the motion to stand in for it.
fn bone_lengths(p: &Pose) -> impl Iterator<Item = f64> + '_ {
    Canonical::ALL
        .iter()
        .filter_map(move |c| c.parent().map(|q| p[c.index()].distance(p[q.index()])))
}

/// Whether the rest skeleton stands upright (a T- or A-pose) with the
/// motion's bone lengths.
fn rest_is_neutral(rest: &Pose, poses: &[Pose]) -> bool {
    let leg_ok = |hip: C, ankle: C| {
        angle(rest[ankle.index()] - rest[hip.index()], -DVec3::Y) < 30f64.to_radians()
    };
    if trunk_tilt(rest) >= 20f64.to_radians()
        || !leg_ok(C::LHip, C::LAnkle)
        || !leg_ok(C::RHip, C::RAnkle)
    {
        return false;
    }
    // Bone lengths as in the motion (a file whose position channels replace
    // the offsets has a rest skeleton of other proportions).
    let Some(mid) = poses.get(poses.len() / 2) else {
        return true;
    };
    let scale = leg_length(rest).max(1e-12);
    bone_lengths(rest)
        .zip(bone_lengths(mid))
        .all(|(a, b)| (a - b).abs() <= 0.1 * b.max(a) + 0.02 * scale)
}

/// Chooses the clip's neutral reference: its rest skeleton when given and
/// upright with the motion's proportions, else its most neutral frame.
/// Refuses a degenerate skeleton (legs or trunk of no length, non-finite
/// joints), which could only retarget to garbage.
pub fn choose_reference(rest: Option<&Pose>, poses: &[Pose]) -> Result<Reference, RigError> {
    let Some(first) = poses.first() else {
        return Err(RigError::Degenerate {
            reason: "the clip has no frames".into(),
        });
    };
    if let Some(r) = rest
        && r.iter().all(|p| p.is_finite())
        && leg_length(r) > 0.0
        && rest_is_neutral(r, poses)
    {
        return Ok(Reference {
            pose: *r,
            source: ReferenceSource::Rest,
            rotations: Arc::from(Vec::new()),
        });
    }
    let mut best: Option<(f64, usize)> = None;
    for (i, p) in poses.iter().enumerate() {
        if !p.iter().all(|x| x.is_finite()) {
            continue;
        }
        let s = neutrality(p);
        if best.is_none_or(|(b, _)| s < b) {
            best = Some((s, i));
        }
    }
    let (_, i) = best.ok_or_else(|| RigError::Degenerate {
        reason: "every frame has a non-finite joint".into(),
    })?;
    let pose = poses[i];
    let size = leg_length(&pose)
        .max(pose[C::Neck.index()].distance(pose[C::Pelvis.index()]))
        .max(leg_length(first));
    let trunk = pose[C::Neck.index()].distance(pose[C::Pelvis.index()]);
    if !(leg_length(&pose) > 1e-6 * size.max(1e-300) && trunk > 1e-6 * size.max(1e-300)) {
        return Err(RigError::Degenerate {
            reason: format!(
                "legs {:.3e} and trunk {:.3e} long at frame {i}: the skeleton has no extent",
                leg_length(&pose),
                trunk
            ),
        });
    }
    Ok(Reference {
        pose,
        source: ReferenceSource::Frame(i),
        rotations: Arc::from(Vec::new()),
    })
}

/// Where a character's neutral pose comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NeutralSource {
    /// Its rest frame (the mesh the rig was embedded on), which stands
    /// upright.
    Rest,
    /// The database frame nearest neutral (the rest frame did not stand
    /// upright).
    Frame(usize),
}

/// The character's neutral pose: what a clip standing neutrally gives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CharacterNeutral {
    /// Canonical joint positions (the character's rest frame's space).
    pub pose: Pose,
    /// Where it came from.
    pub source: NeutralSource,
}

/// How far a character's pose is from standing neutrally (radians): the
/// trunk's tilt from the vertical, plus the mean knee bend, plus the mean
/// angle of the thighs from the vertical (legs under the body, feet
/// together), plus half the neck's bend from the trunk's line. 0 for a
/// body standing straight with its legs under it and its head over its
/// trunk, whatever its arms do (the limbs take the clip's directions).
pub fn neutral_score(p: &Pose) -> f64 {
    let thigh = |hip: C, knee: C| angle(p[knee.index()] - p[hip.index()], -DVec3::Y);
    let neck = angle(
        p[C::Head.index()] - p[C::Neck.index()],
        p[C::Neck.index()] - p[C::Pelvis.index()],
    );
    neutrality(p) + 0.5 * (thigh(C::LHip, C::LKnee) + thigh(C::RHip, C::RKnee)) + 0.5 * neck
}

/// Chooses the character's neutral pose: its rest frame `rest` when that
/// stands upright (trunk within 20° of the vertical, each hip → ankle
/// within 30° of straight down), else the frame of `frames` (the
/// database's per-frame skeletons, the rest frame's space) with the least
/// [`neutral_score`]; the rest frame when no frame is finite.
pub fn character_neutral(rest: &Pose, frames: &[Pose]) -> CharacterNeutral {
    let leg_ok = |hip: C, ankle: C| {
        angle(rest[ankle.index()] - rest[hip.index()], -DVec3::Y) < 30f64.to_radians()
    };
    let upright = trunk_tilt(rest) < 20f64.to_radians()
        && leg_ok(C::LHip, C::LAnkle)
        && leg_ok(C::RHip, C::RAnkle);
    let as_rest = CharacterNeutral {
        pose: *rest,
        source: NeutralSource::Rest,
    };
    if upright {
        return as_rest;
    }
    frames
        .iter()
        .enumerate()
        .filter(|(_, p)| p.iter().all(|x| x.is_finite()))
        .map(|(i, p)| (neutral_score(p), i))
        .filter(|(s, _)| s.is_finite())
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .map_or(as_rest, |(_, i)| CharacterNeutral {
            pose: frames[i],
            source: NeutralSource::Frame(i),
        })
}

/// Turn about the vertical taking `from`'s left-right axis (hips and
/// shoulders) onto `to`'s.
fn heading_between(from: &Pose, to: &Pose) -> DQuat {
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

/// Lowest ankle or toe joint height of a pose.
fn foot_height(p: &Pose) -> f64 {
    [C::LAnkle, C::LToe, C::RAnkle, C::RToe]
        .iter()
        .map(|c| p[c.index()].y)
        .fold(f64::INFINITY, f64::min)
}

/// The character's joint positions and global joint rotations (taking its
/// rest bones, `character`, onto the posed ones) in every clip pose
/// (metres, Y-up). See the module docs for what is matched. Skinning with
/// these rotations and positions is consistent: every joint sits where its
/// parent's rotation carries the rest bone.
pub fn retarget(
    character: &Pose,
    reference: &Reference,
    mocap: &[Pose],
) -> Vec<(Pose, [DQuat; Canonical::COUNT])> {
    retarget_with_neutral(character, character, reference, mocap)
}

/// [`retarget`] with the character's neutral pose `neutral` (a pose of its
/// skeleton in its rest frame's space, e.g. [`character_neutral`]'s)
/// standing for its rest pose `character`: a clip standing neutrally
/// gives the character's torso, neck, head and feet as in `neutral`
/// (`G_j(t) = A_j(t) H N_j`, with `N` the rotations taking the rest bones
/// onto the neutral's and `H` the turn facing the neutral the reference's
/// way); bone lengths, the floor and the soles stay the rest pose's.
///
/// With the clip's joint rotations ([`Reference::rotations`], one per pose
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
    reference: &Reference,
    mocap: &[Pose],
) -> Vec<(Pose, [DQuat; Canonical::COUNT])> {
    retarget_toes(character, neutral, reference, mocap, Toes::Rigid)
}

/// A retargeted clip (per frame the character's joint positions and global
/// rotations) and each foot's ground per frame ([`retarget_on_grounds`]).
type RetargetedOnGrounds = (
    Vec<(Pose, [DQuat; Canonical::COUNT])>,
    [Vec<Option<f64>>; 2],
);

/// How the surface a result drives moves its toes, which decides the
/// sole the kernel stands on the ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Toes {
    /// The toes move with the foot (the part-based deformation's foot
    /// part turns with the ankle): the sole's toe tip, a quarter of the
    /// foot's horizontal length beyond the toe joint, is carried by the
    /// ankle and dips below the toe joint when the foot pitches down
    /// onto its ball, so the body stands on it.
    #[default]
    Rigid,
    /// The toes bend at the toe joint (the ball) where the ground stops
    /// them, as a foot's do: the body stands on the toe joint or the heel
    /// alone, and the toe joint's rotation turns the toes up about the
    /// ball just enough to keep their tip on the foot's ground (level
    /// at most). A foot in the air keeps its toes in line with it. For a
    /// deformation that turns the toes by the toe joint's rotation (the
    /// Confluent Motion markers of `transfer`).
    Bending,
}

/// [`retarget_with_neutral`] with the character's toes moving as `toes`
/// says: [`Toes::Rigid`] is [`retarget_with_neutral`]; with
/// [`Toes::Bending`] a foot pitched down onto its ball stands on the ball,
/// not on a rigid toe tip below it, and the toes' rotation
/// (`G_toe`, the ankle's without bending) turns them up about the ball.
pub fn retarget_toes(
    character: &Pose,
    neutral: &Pose,
    reference: &Reference,
    mocap: &[Pose],
    toes: Toes,
) -> Vec<(Pose, [DQuat; Canonical::COUNT])> {
    retarget_on_grounds(character, neutral, reference, mocap, toes).0
}

/// [`retarget_toes`] and the ground each foot of the result stands on or
/// above per frame, raised above the character's floor (character's
/// metres; `None` for a foot that never touches): see [`place_feet`].
fn retarget_on_grounds(
    character: &Pose,
    neutral: &Pose,
    reference: &Reference,
    mocap: &[Pose],
    toes: Toes,
) -> RetargetedOnGrounds {
    if mocap.is_empty() {
        return (Vec::new(), [Vec::new(), Vec::new()]);
    }
    // The clip's ground made level (a capture volume's floor is often a
    // degree or two off its vertical axis; CMU subject 02's rises 8 cm
    // over a 4 m walk), so that one floor height holds for every frame.
    let tilt = ground_tilt(mocap);
    let levelled: Vec<Pose> = mocap.iter().map(|m| m.map(|p| tilt * p)).collect();
    let mocap = &levelled[..];
    let first = &mocap[0];
    let level_ref;
    let r = match reference.source {
        ReferenceSource::Frame(i) if i < mocap.len() => {
            level_ref = mocap[i];
            &level_ref
        }
        _ => &reference.pose,
    };
    // The clip's floor and the support under each of its footfalls (the
    // leg's length does not depend on the feet).
    let support = clip_support(mocap, leg_length(r));
    // The feet measured from how the clip holds them flat on its ground.
    let stance_ref = flat_feet(r, mocap, &support);
    let r = &stance_ref;
    let s = leg_length(character) / leg_length(r).max(1e-12);
    let face = heading_between(neutral, r);
    // The rest bones onto the neutral's (identity when it is the rest).
    let held = pose_rotations(character, neutral);
    let root = C::Pelvis.index();
    let clip_floor = support.floor;
    let char_floor = foot_height(character);
    let rotations = clip_rotations(r, mocap, reference, tilt);
    let carriage_inv = neck_carriage(&upright(mocap, &rotations)).inverse();
    let (chest, neck) = (C::Chest.index(), C::Neck.index());
    let mut out: Vec<(Pose, [DQuat; Canonical::COUNT])> = mocap
        .par_iter()
        .zip(&rotations)
        .map(|(m, a)| {
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
            (t, g)
        })
        .collect();
    // Feet on the ground: in every frame where a foot of the clip touches
    // its ground (planted, its lowest joint within 3 cm of that footfall's
    // support, or within 3 cm of the floor), the body is lifted (or
    // lowered) so that each character foot stands on or above the ground
    // under it ([`Support::under`]: the support the foot touches, raised
    // above the character's floor by its height above the clip's floor,
    // scaled; for a foot in the air, the lower of the supports it left
    // and lands on unless its sole is above the higher's top:
    // [`place_feet`]); the foot that
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
    let grounds = place_feet(character, &support, s, toes, &mut out);
    (out, grounds)
}

/// Lifts (or lowers) every pose of `out` (the character's, before its
/// vertical correction) so that each foot stands on or above its ground,
/// and with [`Toes::Bending`] turns the toes up onto it; returns each
/// foot's ground per frame (raised above the character's floor by its
/// height above the clip's floor `support.floor`, scaled by `s`; `None`
/// where the foot has none). See [`retarget_toes`].
///
/// A foot in the air between two supports is over the higher one's top
/// only when the character's own sole is above it, the body placed by the
/// feet on their grounds and the air feet over their lower ones; else it
/// is over the lower ground ([`Support::under`] decides by the clip's
/// joints, which sit above the character's sole: a toe tip pitched down
/// reaches 5 cm below them). So a foot in the air never lifts the body
/// onto a higher top: CMU 03_02's left foot, swinging up from the floor
/// beside the block the right foot stands on, passed the next block's top
/// (24 cm) by its joints in frame 8 while the character's toe tip was 5
/// cm lower, and stood on that top the whole body lifted 7.6 cm in one
/// frame (samba) while the clip's root rose 1.6 cm. On flat ground both
/// supports are the floor and nothing changes.
///
/// So does a foot touching a step it is arriving on or leaving, not at
/// rest on it ([`Support::rests`]), the step higher than the lower of the
/// supports the foot rests on before and after, while the other foot
/// stands on a support as high (the floor, or a step it rests on, within
/// the contact band of the step or above it): with a footfall's support the
/// height the foot holds at rest ([`clip_support`]), the frames it comes
/// up onto a block in, its lowest joint within the contact band below
/// the top, touch the top, and the character's sole there is lower than
/// the clip's joints (a heel pitched down is 6 cm under the ankle): the
/// generated step up onto 20 cm at 30 fps lifted the body 2.7 cm in one
/// frame more than the clip's 1.7 cm. A foot that holds the body alone
/// (the other in the air) or above a lower support stays on the step it
/// touches: stepping down off a block (CMU 03_01 on samba, frame 90),
/// the rear foot on its toes on the block holds the body up while the
/// front one strikes the floor; counted in the air, its toes went 4 cm
/// into the block for that frame.
fn place_feet(
    character: &Pose,
    support: &Support,
    s: f64,
    toes: Toes,
    out: &mut [(Pose, [DQuat; Canonical::COUNT])],
) -> [Vec<Option<f64>>; 2] {
    let clip_floor = support.floor;
    let rest_soles = foot_soles(character, character, &[DQuat::IDENTITY; Canonical::COUNT]);
    let soles: Vec<[f64; 2]> = out
        .iter()
        .map(|(t, g)| soles_of(character, t, g, toes))
        .collect();
    // How far frame `i` must be lifted for foot `f` to stand on ground
    // `y` (the clip's height).
    let need = |f: usize, i: usize, y: f64| rest_soles[f] + (y - clip_floor) * s - soles[i][f];
    let n = out.len();
    // The supports each foot is settled on: the floor, or a step while
    // the foot rests on it.
    let settled: [Vec<Option<f64>>; 2] = [0, 1].map(|f| {
        (0..n)
            .map(|i| support.touch[f][i].filter(|&u| u <= clip_floor || support.rests[f][i]))
            .collect()
    });
    let settled_sides = settled.each_ref().map(|t| grounds_either_side(t));
    // A foot touching a step it is arriving on or leaving (not at rest on
    // it, and the step above the lower of the supports it settles on
    // before and after) while the other foot is settled on a support as
    // high (within the contact band) counts as in the air: the step is its
    // ground only once its sole is above the top.
    let touch: [Vec<Option<f64>>; 2] = [0, 1].map(|f| {
        (0..n)
            .map(|i| {
                let t = support.touch[f][i];
                let (Some(u), None) = (t, settled[f][i]) else {
                    return t;
                };
                let lo = match settled_sides[f][i] {
                    (Some(a), Some(b)) => a.min(b),
                    (a, b) => a.or(b).unwrap_or(u),
                };
                if u > lo && settled[1 - f][i].is_some_and(|o| o >= u - CONTACT) {
                    None
                } else {
                    t
                }
            })
            .collect()
    });
    let sides = touch.each_ref().map(|t| grounds_either_side(t));
    // A foot's ground when touching; in the air, the lower of the
    // supports it left and lands on.
    let lower = |f: usize, i: usize| -> Option<f64> {
        touch[f][i].or(match sides[f][i] {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        })
    };
    let fix: Vec<Option<f64>> = (0..out.len())
        .map(|i| {
            if touch.iter().all(|f| f[i].is_none()) {
                return None;
            }
            (0..2)
                .filter_map(|f| Some(need(f, i, lower(f, i)?)))
                .filter(|d| d.is_finite())
                .reduce(f64::max)
        })
        .collect();
    let mut lift = interpolate_gaps(&fix);
    // A foot leaving a support for a lower one (stepping down off a
    // block) held the body up to the frame it left; from then until it
    // lands the lift comes down to the landing frame's at an even rate,
    // never below what the feet need: its ground switching to the floor
    // dropped the body in one frame while the clip's came down a few
    // millimetres (CMU 03_01 on samba, frame 89: 3.8 cm; synth3 03_02,
    // frame 39: 9.2 cm). Only raises the body, so no foot goes under its
    // ground.
    for t in &touch {
        let mut i = 1;
        while i < n {
            if let (Some(u), None) = (t[i - 1], t[i])
                && let Some(j) = (i..n).find(|&j| t[j].is_some())
            {
                if t[j].is_some_and(|v| v < u - CONTACT) {
                    let (a, b) = (lift[i - 1], lift[j]);
                    for (k, l) in lift.iter_mut().enumerate().take(j).skip(i) {
                        let w = (k + 1 - i) as f64 / (j + 1 - i) as f64;
                        *l = l.max(a + (b - a) * w);
                    }
                }
                i = j;
                continue;
            }
            i += 1;
        }
    }
    // The higher top under a foot in the air where the clip's joints are
    // above it and the character's sole, lifted, is too.
    let grounds: [Vec<Option<f64>>; 2] = [0, 1].map(|f| {
        (0..out.len())
            .map(|i| {
                let lo = lower(f, i)?;
                match support.under[f][i] {
                    Some(u) if u > lo && need(f, i, u) <= lift[i] + 1e-9 => Some(u),
                    _ => Some(lo),
                }
            })
            .collect()
    });
    if toes == Toes::Bending {
        for (i, (t, g)) in out.iter_mut().enumerate() {
            let d = lift[i];
            for (f, sole) in rest_soles.iter().enumerate() {
                let Some(u) = grounds[f][i] else {
                    continue;
                };
                let ground = sole + (u - clip_floor) * s - d;
                bend_toes(character, t, g, f, ground);
            }
        }
    }
    for ((t, _), d) in out.iter_mut().zip(&lift) {
        for p in t.iter_mut() {
            p.y += d;
        }
    }
    grounds.map(|g| {
        g.into_iter()
            .map(|y| y.map(|y| (y - clip_floor) * s))
            .collect()
    })
}

/// The lowest sole point of the character posed as `t` with global
/// rotations `g`: its toe joints; under each ankle a heel point at the
/// height of the toe in the rest pose `character`; and a toe tip a quarter of the
/// foot's horizontal length beyond the toe joint at its height (a foot
/// pivoting on its toes dips the tips); both carried by the ankle.
fn sole_height(character: &Pose, t: &Pose, g: &[DQuat; Canonical::COUNT]) -> f64 {
    let [l, r] = foot_soles(character, t, g);
    l.min(r)
}

/// The lowest sole point of each foot (left, right) of the character
/// posed as `t` with global rotations `g` (see [`sole_height`]).
fn foot_soles(character: &Pose, t: &Pose, g: &[DQuat; Canonical::COUNT]) -> [f64; 2] {
    soles_of(character, t, g, Toes::Rigid)
}

/// The ankle and toe joints of each foot (left, right).
const FEET: [(C, C); 2] = [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)];

/// The sole's toe tip of a foot of `character` in its rest pose, from its
/// toe joint: a quarter of the foot's horizontal length (ankle → toe
/// joint) beyond it, at its height.
fn toe_tip(character: &Pose, foot: usize) -> DVec3 {
    let (a, k) = FEET[foot];
    let f = character[k.index()] - character[a.index()];
    DVec3::new(0.25 * f.x, 0.0, 0.25 * f.z)
}

/// The lowest sole point of each foot (left, right) of the character
/// posed as `t` with global rotations `g`, its toes moving as `toes`
/// says: the toe joint, a heel point under the ankle at the rest pose's
/// toe height, and for rigid toes the toe tip ([`toe_tip`]) carried by
/// the ankle (bending toes never take their tip below the toe joint's
/// ground: [`bend_toes`]).
fn soles_of(character: &Pose, t: &Pose, g: &[DQuat; Canonical::COUNT], toes: Toes) -> [f64; 2] {
    [0, 1].map(|foot| {
        let (a, k) = FEET[foot];
        let (a, k) = (a.index(), k.index());
        let heel = DVec3::new(
            0.0,
            character[k].y.min(character[a].y) - character[a].y,
            0.0,
        );
        let tip = match toes {
            Toes::Rigid => (t[k] + g[a] * toe_tip(character, foot)).y,
            Toes::Bending => f64::INFINITY,
        };
        [t[k].y, (t[a] + g[a] * heel).y, tip]
            .into_iter()
            .fold(f64::INFINITY, f64::min)
    })
}

/// Turns foot `foot`'s toes (its toe joint's rotation in `g`, the
/// ankle's until now) up about the toe joint of `t` so that the toe tip
/// ([`toe_tip`], carried by the ankle) is no lower than `ground` (the
/// foot's ground, the character's metres): by the least angle in the
/// vertical plane through the tip, and no further than level (a toe joint
/// below its ground leaves the toes level). Toes whose tip is on or above
/// the ground are left with the foot.
fn bend_toes(
    character: &Pose,
    t: &Pose,
    g: &mut [DQuat; Canonical::COUNT],
    foot: usize,
    ground: f64,
) {
    let (a, k) = FEET[foot];
    let (a, k) = (a.index(), k.index());
    let v = g[a] * toe_tip(character, foot);
    let len = v.length();
    if len.is_nan() || len <= 1e-12 || !ground.is_finite() || t[k].y + v.y >= ground {
        return;
    }
    let axis = v.cross(DVec3::Y).normalize_or_zero();
    if axis == DVec3::ZERO {
        return;
    }
    let now = (v.y / len).clamp(-1.0, 1.0).asin();
    let wanted = ((ground - t[k].y) / len).clamp(-1.0, 0.0).asin();
    if wanted > now {
        g[k] = (DQuat::from_axis_angle(axis, wanted - now) * g[a]).normalize();
    }
}

/// Where a clip stands: its floor and, per frame, the height of the
/// ground its planted foot stands on.
#[derive(Debug, Clone, PartialEq)]
pub struct Support {
    /// The clip's floor: the 5th percentile of its lowest ankle or toe
    /// joint over the frames.
    pub floor: f64,
    /// Per frame, the support under the clip's lowest planted foot when it
    /// touches it (its lowest joint within 3 cm); `None` in the air. The
    /// lowest of the two feet's [`Support::touch`].
    pub ground: Vec<Option<f64>>,
    /// Per foot (left, right) and frame, the support the foot touches: its
    /// footfall's when its lowest joint is within 3 cm of it, the floor
    /// when within 3 cm of the floor; `None` otherwise.
    pub touch: [Vec<Option<f64>>; 2],
    /// Per foot and frame, the ground under the foot: the support it
    /// touches; in the air, the higher of the last support it touched and
    /// the next when its lowest joint is above that one's top (a heel
    /// striking a block, a heel rising on it), else the lower (a foot
    /// stepping down from a block, or leaving the floor beside one, is
    /// over the floor); the only one before its first touch or after its
    /// last; `None` for a foot that never touches.
    pub under: [Vec<Option<f64>>; 2],
    /// Per foot and frame, whether the foot stands on a footfall's
    /// support: its lowest joint within the contact band of the height
    /// the footfall holds, on the floor, a step, or a block too low to
    /// be told from the floor (3-6 cm, which it does not touch).
    pub held: [Vec<bool>; 2],
    /// Per foot and frame, whether the foot is at rest: its ankle and toe
    /// joints both moving less than 0.5 % of the leg's length from the
    /// frame before (the first frame: to the next).
    pub rests: [Vec<bool>; 2],
}

/// The ground under a foot per frame (see [`Support::under`]) from the
/// supports it touches, `touch`, and its lowest joint's height, `low`:
/// where it touches, that support; in the air, the higher of the last
/// support it touched and the next that the foot is not below (a foot
/// above a block's top may be over it: at a heel strike on it, or its
/// heel rising on it), else the lower.
fn ground_under(touch: &[Option<f64>], low: &[f64]) -> Vec<Option<f64>> {
    grounds_either_side(touch)
        .into_iter()
        .enumerate()
        .map(|(i, (last, next))| match (touch[i], last, next) {
            (Some(t), _, _) => Some(t),
            (None, Some(a), Some(b)) => {
                let (lo, hi) = (a.min(b), a.max(b));
                Some(if low[i] >= hi { hi } else { lo })
            }
            (None, a, b) => a.or(b),
        })
        .collect()
}

/// Per frame, the last support a foot touched (this frame's when it
/// touches one) and the next, from the supports it touches, `touch`.
fn grounds_either_side(touch: &[Option<f64>]) -> Vec<(Option<f64>, Option<f64>)> {
    let mut out = vec![(None, None); touch.len()];
    let mut l: Option<f64> = None;
    for (o, t) in out.iter_mut().zip(touch) {
        l = t.or(l);
        o.0 = l;
    }
    let mut n: Option<f64> = None;
    for (o, t) in out.iter_mut().zip(touch).rev() {
        n = t.or(n);
        o.1 = n;
    }
    out
}

/// The contact band (m): a foot whose lowest joint is within it of a
/// support touches that support.
const CONTACT: f64 = 0.03;

/// The height a footfall holds its lowest joint at, from its heights
/// `h` in the frames the foot is at rest (metres, sorted ascending): the
/// lowest of the largest set of them within the contact band of one
/// another (the first such set). `INFINITY` for no heights.
fn held_height(h: &[f64]) -> f64 {
    let (mut best, mut lo, mut j) = (0, f64::INFINITY, 0);
    for i in 0..h.len() {
        while h[i] - h[j] > CONTACT {
            j += 1;
        }
        if i + 1 - j > best {
            (best, lo) = (i + 1 - j, h[j]);
        }
    }
    lo
}

/// The clip's support per footfall (poses levelled, Y-up, metres; `leg`
/// the clip's leg length). A foot is planted while its ankle or its toe
/// joint moves less than 2 % of the leg length per frame (a heel rising
/// about a planted toe, or a toe lowering about a planted heel); a
/// footfall is a run of planted frames, and its support is the height
/// its lowest joint holds in it while the foot is at rest, its ankle and
/// toe both moving less than 0.5 % of the leg length per frame
/// ([`held_height`]: the lowest of the largest set of those heights
/// within the 3 cm contact band; of all its heights when it never rests). A support
/// within twice the contact band of the clip's floor is the floor (a flat
/// capture keeps one plane); a higher one is a step the clip stands on
/// (CMU subject 03 walks over blocks 11-25 cm high) when the footfall
/// lasts at least 5 frames, the foot rests in some and bears weight (it
/// is the lower foot in some frame of it). A frame touches the ground when any foot
/// joint is within 3 cm of the floor (as on a flat capture), or a planted
/// foot's lowest joint is within 3 cm of its footfall's support; the
/// lowest such support is the frame's ground.
///
/// The support was the lowest height the footfall's lowest joint
/// reached, and steps began 6 cm above the floor. A run of planted frames
/// also holds the frames where the foot comes down onto a block toe
/// first, or leaves it over the edge onto its toes, its ankle moving
/// slowly (more such frames the higher the frame rate, the bound being
/// per frame): on a 30 cm block the toe was 5 cm below the top when the
/// run began, stepping down off 20 cm it dropped 4 cm past the edge, and
/// the frames flat on the block, more than 3 cm above that lowest
/// height, touched nothing (the foot's flat elevation was then read off
/// its toe-off, [`flat_feet`], and it stood toes up on the block). On the
/// README's walks at 30 frames per second the resting frames' lowest
/// height is the footfall's lowest. A block 3-6 cm high is still the
/// floor (CMU 131_02 holds a foot 3.8 cm above its floor for 6 frames;
/// as a step it raised samba's penetration maximum 0.50 → 1.18 cm),
/// which the foot on it does not touch; [`Support::held`] has it.
pub fn clip_support(mocap: &[Pose], leg: f64) -> Support {
    let mut lows: Vec<f64> = mocap
        .iter()
        .map(foot_height)
        .filter(|h| h.is_finite())
        .collect();
    lows.sort_by(f64::total_cmp);
    let floor = lows
        .get(lows.len() / 20)
        .copied()
        .unwrap_or_else(|| mocap.first().map_or(0.0, |p| p[C::Pelvis.index()].y));
    let mut touch: [Vec<Option<f64>>; 2] = [vec![None; mocap.len()], vec![None; mocap.len()]];
    let mut held: [Vec<bool>; 2] = [vec![false; mocap.len()], vec![false; mocap.len()]];
    let mut rests: [Vec<bool>; 2] = [vec![false; mocap.len()], vec![false; mocap.len()]];
    let still = 0.02 * leg.max(1e-9);
    for (foot, (ankle, toe)) in [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)]
        .into_iter()
        .enumerate()
    {
        let (a, k) = (ankle.index(), toe.index());
        let low = |p: &Pose| if p[a].y <= p[k].y { p[a] } else { p[k] };
        // Per frame, how far the ankle and the toe joint moved from the
        // frame before (the first frame: to the next).
        let moved: Vec<(f64, f64)> = (0..mocap.len())
            .map(|t| {
                let (i, j) = if t > 0 {
                    (t - 1, t)
                } else {
                    (0, 1.min(mocap.len() - 1))
                };
                (
                    (mocap[j][a] - mocap[i][a]).length(),
                    (mocap[j][k] - mocap[i][k]).length(),
                )
            })
            .collect();
        let planted: Vec<bool> = (0..mocap.len())
            .map(|t| moved[t].0.min(moved[t].1) <= still && low(&mocap[t]).is_finite())
            .collect();
        // At rest: the whole foot, ankle and toe, still (a quarter of the
        // planted bound).
        let resting = |t: usize| moved[t].0.max(moved[t].1) <= 0.25 * still;
        for (t, r) in rests[foot].iter_mut().enumerate() {
            *r = resting(t);
        }
        let mut t = 0;
        while t < mocap.len() {
            if !planted[t] {
                t += 1;
                continue;
            }
            let start = t;
            while t < mocap.len() && planted[t] {
                t += 1;
            }
            let run = start..t;
            let height = |i: usize| low(&mocap[i]).y;
            let mut rests: Vec<f64> = run.clone().filter(|&i| resting(i)).map(height).collect();
            rests.sort_by(f64::total_cmp);
            let sup = if rests.is_empty() {
                let mut lows: Vec<f64> = run.clone().map(height).collect();
                lows.sort_by(f64::total_cmp);
                held_height(&lows)
            } else {
                held_height(&rests)
            };
            // A step is twice the contact band above the floor (6 cm; a
            // kerb or a block), held at least 5 frames with the foot at
            // rest in some, and bears weight: the foot is the lower of
            // the two in some frame of the footfall (a leg held still in
            // the air, the other foot on the floor, is no step; nor a
            // gliding foot hovering over it).
            let bears = run
                .clone()
                .any(|i| low(&mocap[i]).y <= foot_height(&mocap[i]) + 1e-9);
            if sup > floor + 2.0 * CONTACT && !(bears && !rests.is_empty() && run.len() >= 5) {
                continue;
            }
            for i in run.clone() {
                if (low(&mocap[i]).y - sup).abs() <= CONTACT {
                    held[foot][i] = true;
                }
            }
            let sup = if sup <= floor + 2.0 * CONTACT {
                floor
            } else {
                sup
            };
            // The frames within the contact band of it: not those where
            // the foot, still counted planted, has dropped past the
            // block's edge (stepping down) or not yet come down onto it.
            for i in run {
                if (low(&mocap[i]).y - sup).abs() <= CONTACT {
                    touch[foot][i] = Some(sup);
                }
            }
        }
        // On the floor, as on a flat capture: the foot within 3 cm of it.
        for (i, p) in mocap.iter().enumerate() {
            if low(p).y <= floor + CONTACT {
                touch[foot][i] = Some(floor);
            }
        }
    }
    let ground = (0..mocap.len())
        .map(|i| match (touch[0][i], touch[1][i]) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        })
        .collect();
    let lows = |a: C, k: C| -> Vec<f64> {
        mocap
            .iter()
            .map(|p| p[a.index()].y.min(p[k.index()].y))
            .collect()
    };
    let under = [
        ground_under(&touch[0], &lows(C::LAnkle, C::LToe)),
        ground_under(&touch[1], &lows(C::RAnkle, C::RToe)),
    ];
    Support {
        floor,
        ground,
        touch,
        under,
        held,
        rests,
    }
}

/// The height of the ground under the character's lower foot above its
/// floor per frame, in the character's metres: the clip retargeted onto
/// the character's skeleton `character` ([`retarget`]), then per frame
/// the [`Support::under`] of the foot whose lowest sole point is lower
/// (the clip levelled as [`retarget`] levels it, scaled by the ratio of
/// leg lengths, interpolated across frames where no foot has a ground):
/// where the lowest point of a result of [`retarget`] stands. The
/// plausibility checks measure floating and penetration from the
/// character's floor raised by it. With one foot on a block and the other
/// lower, in the air over the floor, it is the floor.
pub fn ground_offsets(character: &Pose, reference: &Reference, mocap: &[Pose]) -> Vec<f64> {
    let out = retarget(character, reference, mocap);
    offsets(character, reference, mocap, |s| {
        out.iter()
            .enumerate()
            .map(|(i, (t, g))| {
                let [l, r] = foot_soles(character, t, g);
                let (a, b) = if r < l { (1, 0) } else { (0, 1) };
                s.under[a][i].or(s.under[b][i])
            })
            .collect()
    })
}

/// The height of the ground under each foot (left, right) above the
/// character's floor per frame, in the character's metres: the ground
/// [`retarget`] stands that foot on or above (the clip's
/// [`Support::under`] of that foot, levelled as [`retarget`] levels the
/// clip and scaled by the ratio of leg lengths, except that a foot in the
/// air is over a higher top only when the character's sole is above it:
/// [`place_feet`]; interpolated across frames where the foot has none).
/// The plausibility checks measure penetration as any foot below its
/// ground, floating as the foot nearest its ground above it.
pub fn foot_ground_offsets(
    character: &Pose,
    reference: &Reference,
    mocap: &[Pose],
) -> [Vec<f64>; 2] {
    retarget_on_grounds(character, character, reference, mocap, Toes::Rigid)
        .1
        .map(|g| interpolate_gaps(&g))
}

/// The height the character's body stands raised above its floor per
/// frame, in the character's metres: the lowest support a foot of the
/// clip touches ([`Support::ground`]), interpolated across frames in the
/// air. Retrieval takes it off the query, comparing poses as they stand
/// on the database's floor.
pub fn stance_offsets(character: &Pose, reference: &Reference, mocap: &[Pose]) -> Vec<f64> {
    offsets(character, reference, mocap, |s| s.ground.clone())
}

/// One per-frame height of the clip's [`Support`] (chosen by `pick`)
/// above its floor, scaled onto the character, gaps interpolated.
fn offsets(
    character: &Pose,
    reference: &Reference,
    mocap: &[Pose],
    pick: impl Fn(&Support) -> Vec<Option<f64>>,
) -> Vec<f64> {
    if mocap.is_empty() {
        return Vec::new();
    }
    let tilt = ground_tilt(mocap);
    let levelled: Vec<Pose> = mocap.iter().map(|m| m.map(|p| tilt * p)).collect();
    let r = leg_length(&reference.pose).max(1e-12);
    let s = leg_length(character) / r;
    let support = clip_support(&levelled, r);
    let raised: Vec<Option<f64>> = pick(&support)
        .iter()
        .map(|g| g.map(|y| (y - support.floor) * s))
        .collect();
    interpolate_gaps(&raised)
}

/// The clip's own foot glide while touching its ground, on the
/// character (cm per touching foot-frame): the clip retargeted onto the
/// character's skeleton `character` ([`retarget`]), then per foot the
/// horizontal travel from frame `t-1` to `t` of the midpoint of its ankle
/// and toe joints while the foot's lowest sole point (toe joint, heel, toe
/// tip, as the kernel puts on the floor) is within 3 cm of the character's
/// floor raised by the clip's ground under that foot
/// ([`foot_ground_offsets`]) at both; summed
/// and divided by the touching foot-frames. The skeleton analogue of the
/// mesh measure [`crate::eval::Sliding::touching_mean_cm_per_frame`], on
/// the same feet and floor: a walk's feet pass through the touching band
/// at heel strike and toe-off, which a mostly planted capture (the samba
/// dance) never does, so a result is held to its own clip's figure.
pub fn clip_foot_glide_cm(character: &Pose, reference: &Reference, mocap: &[Pose]) -> f64 {
    if mocap.len() < 2 {
        return 0.0;
    }
    let out = retarget(character, reference, mocap);
    let raised = foot_ground_offsets(character, reference, mocap);
    let rest = sole_height(character, character, &[DQuat::IDENTITY; Canonical::COUNT]);
    let (mut travel, mut touching) = (0.0, 0usize);
    for (foot, (ankle, toe)) in [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)]
        .into_iter()
        .enumerate()
    {
        let (a, k) = (ankle.index(), toe.index());
        let touch = |t: usize| {
            let (p, g) = &out[t];
            foot_soles(character, p, g)[foot] <= rest + raised[foot][t] + 0.03
        };
        let mid = |t: usize| {
            let p = &out[t].0;
            let m = 0.5 * (p[a] + p[k]);
            DVec3::new(m.x, 0.0, m.z)
        };
        for t in 0..out.len() {
            if touch(t) {
                touching += 1;
                if t > 0 && touch(t - 1) {
                    let d = mid(t).distance(mid(t - 1));
                    if d.is_finite() {
                        travel += d;
                    }
                }
            }
        }
    }
    100.0 * travel / touching.max(1) as f64
}

/// Fills the `None`s of `v` linearly between their known neighbours (the
/// nearest known value past either end; all zeros when none is known).
fn interpolate_gaps(v: &[Option<f64>]) -> Vec<f64> {
    let known: Vec<(usize, f64)> = v
        .iter()
        .enumerate()
        .filter_map(|(i, x)| x.map(|x| (i, x)))
        .collect();
    let (Some(&first), Some(&last)) = (known.first(), known.last()) else {
        return vec![0.0; v.len()];
    };
    let mut out = Vec::with_capacity(v.len());
    let mut k = 0;
    for i in 0..v.len() {
        while k + 1 < known.len() && known[k + 1].0 <= i {
            k += 1;
        }
        out.push(if i <= first.0 {
            first.1
        } else if i >= last.0 {
            last.1
        } else {
            let ((i0, a), (i1, b)) = (known[k], known[k + 1]);
            if i1 == i0 {
                a
            } else {
                a + (b - a) * (i - i0) as f64 / (i1 - i0) as f64
            }
        });
    }
    out
}

/// `r` with each foot bone (ankle → toe) turned about its lateral axis to
/// the elevation the clip's foot has when flat on its ground: the median
/// over the frames where both the foot's ankle and toe are within 2 cm of
/// their lowest (5th percentile) heights, unless it is more than 5° off
/// the elevation the foot holds longest while planted on a support
/// ([`held_elevation`] over the frames where it touches the floor or a
/// block it stands on, `support`'s [`Support::touch`], or stands on a
/// block too low to be told from the floor, [`Support::held`], with its ankle and
/// toe joints each moving less than 2 % of the leg's length from the
/// frame before), which is then taken. A rest skeleton's foot bone need
/// not point as the standing foot's does (CMU's ASF rest skeleton points
/// it 15° further down than the walks' stance, and copying that left the
/// character's heels 2 cm up); `r` unchanged for a foot never flat. The
/// lowest heights alone are not enough on uneven ground: CMU 03_02's left
/// foot touches the floor only while leaving it on its toes, then stands
/// on blocks, and that toe-off (−82° against the −14° it holds on the
/// blocks) was taken for flat: on the blocks the character's left foot
/// stood toes up by 50-60°, its heel 3-4 cm through the block's top. On
/// a flat capture the two agree (within 3° on the README's walks and
/// runs) and the lowest heights are kept.
fn flat_feet(r: &Pose, mocap: &[Pose], support: &Support) -> Pose {
    let mut out = *r;
    let low = |c: C| {
        let mut h: Vec<f64> = mocap
            .iter()
            .map(|p| p[c.index()].y)
            .filter(|y| y.is_finite())
            .collect();
        h.sort_by(f64::total_cmp);
        h.get(h.len() / 20).copied()
    };
    let elevation = |f: DVec3| (f.y / f.length()).clamp(-1.0, 1.0).asin();
    let still = 0.02 * leg_length(r).max(1e-9);
    for (foot, (ankle, toe)) in [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)]
        .into_iter()
        .enumerate()
    {
        let (a, t) = (ankle.index(), toe.index());
        let moved = |i: usize, j: usize| {
            mocap[i][a]
                .distance(mocap[j][a])
                .max(mocap[i][t].distance(mocap[j][t]))
        };
        let planted = |i: usize| {
            let j = if i > 0 { i - 1 } else { 1.min(mocap.len() - 1) };
            let on = support.touch[foot].get(i).is_some_and(|g| g.is_some())
                || support.held[foot].get(i).is_some_and(|&h| h);
            on && moved(i, j) <= still
        };
        let mut held: Vec<f64> = (0..mocap.len())
            .filter(|&i| planted(i))
            .map(|i| elevation(mocap[i][t] - mocap[i][a]))
            .filter(|e| e.is_finite())
            .collect();
        held.sort_by(f64::total_cmp);
        let held = (held.len() >= 5).then(|| held_elevation(&held));
        let lowest = match (low(ankle), low(toe)) {
            (Some(la), Some(lt)) => {
                let mut e: Vec<f64> = mocap
                    .iter()
                    .filter(|p| p[a].y <= la + 0.02 && p[t].y <= lt + 0.02)
                    .map(|p| elevation(p[t] - p[a]))
                    .filter(|e| e.is_finite())
                    .collect();
                e.sort_by(f64::total_cmp);
                (e.len() >= 5).then(|| e[e.len() / 2])
            }
            _ => None,
        };
        let flat = match (lowest, held) {
            (Some(l), Some(h)) if (l - h).abs() > 5f64.to_radians() => h,
            (Some(l), _) => l,
            (None, Some(h)) => h,
            (None, None) => continue,
        };
        let f = r[t] - r[a];
        let axis = f.cross(DVec3::Y).normalize_or_zero();
        if axis == DVec3::ZERO || !f.is_finite() {
            continue;
        }
        let turn = DQuat::from_axis_angle(axis, flat - elevation(f));
        out[t] = r[a] + turn * f;
    }
    out
}

/// The elevation a foot holds longest among `e` (radians, sorted
/// ascending): the median of the largest set of them within 3° of one of
/// them. A foot at rest on its support holds one elevation; rolling onto
/// it (a heel strike) or off it (a heel rising about the toe, slowly
/// enough to count as planted) passes through the others.
fn held_elevation(e: &[f64]) -> f64 {
    let band = 3f64.to_radians();
    let (mut best, mut lo, mut hi) = (0, 0, 0);
    let mut j = 0;
    for i in 0..e.len() {
        while e[i] - e[j] > band {
            j += 1;
        }
        // e[j..=i] all within `band` below e[i].
        if i + 1 - j > best {
            (best, lo, hi) = (i + 1 - j, j, i + 1);
        }
    }
    let w = &e[lo..hi];
    w.get(w.len() / 2).copied().unwrap_or(0.0)
}

/// The rotation that makes a clip's ground level: a plane
/// `y = a + b·x + c·z` fitted to the lowest ankle or toe joint of every
/// frame (least squares, then three times on the lower half of the
/// residuals, so that lifted feet and jumps do not count), its slope
/// shrunk by a ridge of (0.22 m)² so that a clip standing in place has
/// none, turned onto the horizontal. Identity for a clip of fewer than 10
/// frames or a slope past 5° (a ramp or stairs, not a tilted floor).
pub fn ground_tilt(mocap: &[Pose]) -> DQuat {
    let feet = [C::LAnkle, C::LToe, C::RAnkle, C::RToe];
    let samples: Vec<DVec3> = mocap
        .iter()
        .filter_map(|p| {
            feet.iter()
                .map(|c| p[c.index()])
                .filter(|q| q.is_finite())
                .min_by(|a, b| a.y.total_cmp(&b.y))
        })
        .collect();
    if samples.len() < 10 {
        return DQuat::IDENTITY;
    }
    const RIDGE: f64 = 0.05;
    let fit = |keep: &[DVec3]| -> Option<(f64, f64, f64, DVec3)> {
        let n = keep.len() as f64;
        let mean = keep.iter().copied().sum::<DVec3>() / n;
        let (mut sxx, mut sxz, mut szz, mut sxy, mut szy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for q in keep {
            let d = *q - mean;
            sxx += d.x * d.x;
            sxz += d.x * d.z;
            szz += d.z * d.z;
            sxy += d.x * d.y;
            szy += d.z * d.y;
        }
        let (sxx, szz) = (sxx + n * RIDGE, szz + n * RIDGE);
        let det = sxx * szz - sxz * sxz;
        if !(det.is_finite() && det > 0.0) {
            return None;
        }
        let b = (sxy * szz - szy * sxz) / det;
        let c = (szy * sxx - sxy * sxz) / det;
        Some((mean.y, b, c, mean))
    };
    let Some(mut plane) = fit(&samples) else {
        return DQuat::IDENTITY;
    };
    for _ in 0..3 {
        let (a, b, c, m) = plane;
        let res = |q: &DVec3| q.y - (a + b * (q.x - m.x) + c * (q.z - m.z));
        let mut r: Vec<f64> = samples.iter().map(res).collect();
        r.sort_by(f64::total_cmp);
        let cut = r[r.len() / 2];
        let low: Vec<DVec3> = samples.iter().copied().filter(|q| res(q) <= cut).collect();
        if low.len() < 5 {
            break;
        }
        match fit(&low) {
            Some(p) => plane = p,
            None => break,
        }
    }
    let (_, b, c, _) = plane;
    let normal = DVec3::new(-b, 1.0, -c).normalize();
    if normal.angle_between(DVec3::Y) > 5f64.to_radians() || !normal.is_finite() {
        return DQuat::IDENTITY;
    }
    DQuat::from_rotation_arc(normal, DVec3::Y)
}

/// The clip's own head-to-trunk angle per frame (degrees, signed): the
/// angle `∠(neck→head, pelvis→neck)` of each pose minus its value in the
/// clip's neutral (the reference pose with the neck turned to the clip's
/// typical carriage relative to the chest, which the retargeting maps onto
/// the character's rest). The skeleton analogue of the mesh measure
/// [`crate::eval::HeadTorso`]: what a result's head should do relative to
/// the character's rest when it follows the clip's head.
pub fn clip_head_trunk_deg(reference: &Reference, mocap: &[Pose]) -> Vec<f64> {
    // The neck → head bone in a frame attached to the trunk (up pelvis →
    // neck, lateral from the hips and shoulders).
    let local = |p: &Pose| {
        let y = (p[C::Neck.index()] - p[C::Pelvis.index()]).normalize_or_zero();
        let l = (p[C::LHip.index()] - p[C::RHip.index()])
            + (p[C::LShoulder.index()] - p[C::RShoulder.index()]);
        let x = (l - y * l.dot(y)).normalize_or_zero();
        let z = x.cross(y);
        let h = p[C::Head.index()] - p[C::Neck.index()];
        DVec3::new(h.dot(x), h.dot(y), h.dot(z))
    };
    let r = &reference.pose;
    let rotations = clip_rotations(r, mocap, reference, DQuat::IDENTITY);
    let mut neutral = *r;
    let (n, h) = (C::Neck.index(), C::Head.index());
    neutral[h] = r[n] + neck_carriage(&upright(mocap, &rotations)) * (r[h] - r[n]);
    let zero = local(&neutral);
    mocap
        .iter()
        .map(|p| angle(local(p), zero).to_degrees())
        .collect()
}

/// The rotations of the clip's upright frames: those whose trunk (pelvis
/// → chest) is within 10° of the clip's most upright. The neck's carriage is read on them: a
/// clip that spends most of its time bent over, head down (CMU 131_02),
/// would otherwise make head-down its neutral, and its upright frames
/// would throw the character's head back.
fn upright(
    mocap: &[Pose],
    rotations: &[[DQuat; Canonical::COUNT]],
) -> Vec<[DQuat; Canonical::COUNT]> {
    // The trunk as the pelvis → chest line: where the neck sits on the
    // chest (a conversion drops the thorax's length) must not choose them.
    let tilt: Vec<f64> = mocap
        .iter()
        .map(|p| angle(p[C::Chest.index()] - p[C::Pelvis.index()], DVec3::Y))
        .collect();
    let least = tilt
        .iter()
        .copied()
        .filter(|t| t.is_finite())
        .fold(f64::INFINITY, f64::min);
    rotations
        .iter()
        .zip(&tilt)
        .filter(|&(_, &t)| t <= least + 10f64.to_radians())
        .map(|(a, _)| *a)
        .collect()
}

/// The clip's typical carriage of the neck: the mean (sign-aligned,
/// normalised) over frames of the neck's rotation relative to the chest
/// since the reference, `A_chest⁻¹ A_neck`.
fn neck_carriage(rotations: &[[DQuat; Canonical::COUNT]]) -> DQuat {
    let (chest, neck) = (C::Chest.index(), C::Neck.index());
    let mut sum = glam::DVec4::ZERO;
    let mut sign_ref: Option<glam::DVec4> = None;
    for a in rotations {
        let l = glam::DVec4::from(a[chest].inverse() * a[neck]);
        if !l.is_finite() {
            continue;
        }
        let f = *sign_ref.get_or_insert(l);
        sum += if l.dot(f) < 0.0 { -l } else { l };
    }
    let q = DQuat::from_vec4(sum);
    if q.length_squared() > 1e-24 {
        q.normalize()
    } else {
        DQuat::IDENTITY
    }
}

/// The clip's global joint rotations since its reference per pose of
/// `mocap` (the poses turned by `tilt`, `r` the reference's pose as the
/// kernel uses it): the fit to the bones ([`pose_rotations`]), with the
/// chest (and the spine and neck on it) from the clip's own
/// joint rotations when the reference carries one per pose
/// ([`Reference::rotations`], [`torso_from_file`]).
fn clip_rotations(
    r: &Pose,
    mocap: &[Pose],
    reference: &Reference,
    tilt: DQuat,
) -> Vec<[DQuat; Canonical::COUNT]> {
    let mut rotations: Vec<[DQuat; Canonical::COUNT]> =
        mocap.par_iter().map(|m| pose_rotations(r, m)).collect();
    let file = &reference.rotations;
    // The reference's own file rotations: the rest skeleton's are the
    // identity; a frame's, turned as the poses are.
    let at_ref: Option<JointRotations> = match reference.source {
        ReferenceSource::Rest => Some([Some(DQuat::IDENTITY); Canonical::COUNT]),
        ReferenceSource::Frame(i) => file.get(i).map(|w| w.map(|q| q.map(|q| tilt * q))),
    };
    if let Some(at_ref) = at_ref
        && file.len() == mocap.len()
    {
        rotations
            .par_iter_mut()
            .zip(mocap.par_iter().zip(file.par_iter()))
            .for_each(|(a, (m, w))| {
                torso_from_file(a, r, m, &w.map(|q| q.map(|q| tilt * q)), &at_ref)
            });
    }
    rotations
}

/// Replaces the chest's rotation in `a` (the rotations taking the
/// reference `r`'s bones onto `m`'s) by its file joint's rotation since
/// the reference (`w · w_ref⁻¹`, when both are known) with its twist about
/// the spine taken from the shoulders ([`shoulder_twist`]), and re-derives the
/// single-child spine and neck (the least rotation of their bone,
/// composed on the parent's, as [`pose_rotations`] does). The pelvis keeps
/// the fit to its hips and spine bones (see [`retarget_with_neutral`]).
fn torso_from_file(
    a: &mut [DQuat; Canonical::COUNT],
    r: &Pose,
    m: &Pose,
    w: &JointRotations,
    w_ref: &JointRotations,
) {
    for c in [C::Pelvis, C::Spine, C::Chest, C::Neck] {
        let j = c.index();
        if c == C::Pelvis {
            continue;
        }
        if c == C::Chest {
            if let (Some(q), Some(q0)) = (w[j], w_ref[j])
                && (q * q0.inverse()).is_finite()
            {
                a[j] = shoulder_twist((q * q0.inverse()).normalize(), r, m);
            }
            continue;
        }
        let pr = c.parent().map_or(DQuat::IDENTITY, |p| a[p.index()]);
        let k = if c == C::Spine { C::Chest } else { C::Head }.index();
        let from = (pr * (r[k] - r[j])).normalize_or_zero();
        let to = (m[k] - m[j]).normalize_or_zero();
        a[j] = if from == DVec3::ZERO || to == DVec3::ZERO {
            pr
        } else {
            (DQuat::from_rotation_arc(from, to) * pr).normalize()
        };
    }
}

/// The chest's file rotation `f` (since the reference `r`) turned about
/// the chest's own axis (the reference's spine → chest bone, carried by
/// `f`) so that it carries the reference's shoulder line
/// (right → left shoulder) onto `m`'s, seen along that axis: the swing
/// from the file, the twist from the shoulders.
///
/// A file joint's rotation states the chest's twist only when whatever
/// wrote the file knew it. `db skeleton`'s BVH turns `Spine1` by the
/// fitted chest → neck bone alone (the shoulders hang from zero-offset
/// clavicles of their own), a lone bone whose twist no joint observes;
/// on the samba dancer's own skeleton it sat 20° (mean over the frames)
/// off the chest's fit to its neck and shoulders, all of it about the
/// spine, and the self-transfer's vertex error rose from 3.55 to 3.81 %
/// of the height (20 markers). The shoulder line is the same whichever
/// joint carries the neck and clavicles and wherever they sit on the
/// chest (an AMC clip and its cgspeed BVH conversion, which drops the
/// thorax's length), so the two still drive the character alike.
/// `f` unchanged when the axis or either shoulder line (seen along it) has
/// no length.
fn shoulder_twist(f: DQuat, r: &Pose, m: &Pose) -> DQuat {
    let (spine, chest) = (C::Spine.index(), C::Chest.index());
    let (l, rt) = (C::LShoulder.index(), C::RShoulder.index());
    let up = (f * (r[chest] - r[spine])).normalize_or_zero();
    if up == DVec3::ZERO {
        return f;
    }
    let across = |v: DVec3| (v - up * v.dot(up)).normalize_or_zero();
    let from = across(f * (r[l] - r[rt]));
    let to = across(m[l] - m[rt]);
    if from == DVec3::ZERO || to == DVec3::ZERO {
        return f;
    }
    let turn = from.cross(to).dot(up).atan2(from.dot(to));
    (DQuat::from_axis_angle(up, turn) * f).normalize()
}

/// A limb joint's global rotation: the least rotation from where its
/// parent carries the character's rest bone onto the clip's bone direction,
/// composed on the parent's (an end joint keeps its parent's).
fn limb_rotation(character: &Pose, m: &Pose, g: &[DQuat; Canonical::COUNT], c: Canonical) -> DQuat {
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

#[cfg(test)]
mod tests {
    use super::*;

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
        assert_eq!(rf.source, ReferenceSource::Rest);
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
        m[C::Head.index()] =
            m[C::Neck.index()] + nod * (rest[C::Head.index()] - rest[C::Neck.index()]);
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
        assert_eq!(rf.source, ReferenceSource::Rest);
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
        assert_eq!(rf.source, ReferenceSource::Frame(1));
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
            assert_eq!(cp.reference.source, ReferenceSource::Rest, "arm {arm}");
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
        let q = DQuat::from_rotation_x(-1.5f64.to_radians())
            * DQuat::from_rotation_z(1.5f64.to_radians());
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
        let ReferenceSource::Frame(i) = cp.reference.source else {
            panic!("a bent rest skeleton was taken as the reference");
        };
        // The most neutral frame is as upright as the walk gets, and in it
        // the character stands as at rest (trunk vertical).
        let least = poses.iter().map(trunk_tilt).fold(f64::INFINITY, f64::min);
        assert!(trunk_tilt(&cp.poses[i]) < least + 5f64.to_radians());
        let out = retarget(&standing(), &cp.reference, &cp.poses);
        assert!(
            trunk_tilt(&out[i].0) < 1e-6,
            "{}",
            trunk_tilt(&out[i].0).to_degrees()
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
}
