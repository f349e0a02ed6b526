//! Measures of a clip retargeted onto a character that a result is held
//! to: the per-frame heights of the ground under the character's feet
//! (read by the plausibility checks and by retrieval), the clip's own foot
//! glide and head-to-trunk angle.

use super::anchor::placement_from_env;
use super::feet::Toes;
use super::feet::{foot_soles, sole_height};
use super::ground::{
    Given, Support, clip_support_given, clip_support_given_into, interpolate_gaps,
    interpolate_gaps_into,
};
use super::kernel::{Retargeted, retarget, retarget_placed_into};
use super::level::level_from_env;
use super::reference::{ClipNeutral, angle, leg_length};
use super::torso::{clip_rotations, neck_carriage, upright};
use super::workspace::KernelWorkspace;
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

use Canonical as C;

/// A clip on the character's skeleton from one run of the pose kernel
/// ([`on_character_with_grounds`]): what the per-clip analysed value
/// (`drive::Analysed`) keeps for synthesis and the plausibility checks,
/// so that neither runs the kernel again (issue 40).
#[derive(Debug, Clone, Default)]
pub struct OnCharacter {
    /// Per frame, the character's joint positions and global joint
    /// rotations (metres, Y-up, standing on the character's floor:
    /// [`super::retarget_with_neutral`]'s result).
    pub frames: Vec<(Pose, [DQuat; Canonical::COUNT])>,
    /// The height of the ground under each foot (left, right) above the
    /// character's floor per frame, gaps interpolated
    /// ([`foot_ground_offsets`]).
    pub foot_grounds: [Vec<f64>; 2],
    /// With the feet on the clip's footfalls (issue 44,
    /// [`Footfalls::Targets`](super::Footfalls::Targets)), the joint
    /// positions before they were put there (the feet where the limbs'
    /// directions put them, standing on the ground): what retrieval
    /// compares, so that the database frames chosen are the clip's
    /// pose's whatever the placement. `None` otherwise (`frames` is
    /// compared).
    pub free_feet: Option<Vec<Pose>>,
}

/// The clip `mocap` on the character's skeleton `character` measured from
/// its neutral pose `neutral` ([`super::retarget_with_neutral`], rigid
/// toes) and the ground under each foot, from one run of the kernel.
/// With `neutral` = `character` its parts are [`retarget`]'s result and
/// [`foot_ground_offsets`], bit for bit.
pub fn on_character_with_grounds(
    character: &Pose,
    neutral: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
) -> OnCharacter {
    on_character_given(character, neutral, reference, mocap, &Given::default())
}

/// [`on_character_with_grounds`] with what the caller decides (the
/// levelling, the floor, the supports: [`Given`]).
pub fn on_character_given(
    character: &Pose,
    neutral: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    given: &Given<'_>,
) -> OnCharacter {
    on_character_in(
        character,
        neutral,
        reference,
        mocap,
        given,
        &mut KernelWorkspace::new(),
    )
}

/// [`on_character_given`] with `ws` the buffers of the kernel's
/// clip-level steps (a live session's, reused from frame to frame: the
/// result is the same whatever it held).
pub fn on_character_in(
    character: &Pose,
    neutral: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    given: &Given<'_>,
    ws: &mut KernelWorkspace,
) -> OnCharacter {
    let mut out = OnCharacter::default();
    on_character_into(character, neutral, reference, mocap, given, ws, &mut out);
    out
}

/// [`on_character_in`] into `out` (every part cleared and refilled): no
/// allocation once `out` and `ws` hold the clip's frames (issue 45: a
/// live session keeps both from frame to frame).
pub fn on_character_into(
    character: &Pose,
    neutral: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    given: &Given<'_>,
    ws: &mut KernelWorkspace,
    out: &mut OnCharacter,
) {
    let mut run = Retargeted {
        frames: std::mem::take(&mut out.frames),
        grounds: std::mem::take(&mut ws.grounds),
        free: out.free_feet.take(),
    };
    let how = (Toes::Rigid, placement_from_env(), level_from_env());
    let poses = (character, neutral);
    retarget_placed_into(poses, reference, mocap, how, given, ws, &mut run);
    for (g, o) in run.grounds.iter().zip(out.foot_grounds.iter_mut()) {
        interpolate_gaps_into(g, &mut ws.known, o);
    }
    (out.frames, ws.grounds, out.free_feet) = (run.frames, run.grounds, run.free);
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
/// Runs the kernel; [`foot_glide_cm`] reads a run already made.
pub fn clip_foot_glide_cm(character: &Pose, reference: &ClipNeutral, mocap: &[Pose]) -> f64 {
    if mocap.len() < 2 {
        return 0.0;
    }
    foot_glide_cm(
        character,
        &on_character_with_grounds(character, character, reference, mocap),
    )
}

/// [`clip_foot_glide_cm`] of the clip already on the character's skeleton
/// `character` (`on`, [`on_character_with_grounds`]): no kernel run.
pub fn foot_glide_cm(character: &Pose, on: &OnCharacter) -> f64 {
    let (out, raised) = (&on.frames, &on.foot_grounds);
    if out.len() < 2 {
        return 0.0;
    }
    let rest = sole_height(character, character, &[DQuat::IDENTITY; Canonical::COUNT]);
    let (mut travel, mut touching) = (0.0, 0usize);
    for (foot, (ankle, toe)) in [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)]
        .into_iter()
        .enumerate()
    {
        let (a, k) = (ankle.index(), toe.index());
        let touch = |t: usize| {
            let (p, g) = &out[t];
            let ground = raised[foot].get(t).copied().unwrap_or(0.0);
            foot_soles(character, p, g)[foot] <= rest + ground + 0.03
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

/// The clip's own head-to-trunk angle per frame (degrees, signed): the
/// angle `∠(neck→head, pelvis→neck)` of each pose minus its value in the
/// clip's neutral (the reference pose with the neck turned to the clip's
/// typical carriage relative to the chest, which the retargeting maps onto
/// the character's rest). The skeleton analogue of the mesh measure
/// [`crate::eval::HeadTorso`]: what a result's head should do relative to
/// the character's rest when it follows the clip's head.
pub fn clip_head_trunk_deg(reference: &ClipNeutral, mocap: &[Pose]) -> Vec<f64> {
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
pub fn ground_offsets(character: &Pose, reference: &ClipNeutral, mocap: &[Pose]) -> Vec<f64> {
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
/// [`place_feet_into`](super::feet::place_feet_into); interpolated across frames where the foot has none).
/// The plausibility checks measure penetration as any foot below its
/// ground, floating as the foot nearest its ground above it.
pub fn foot_ground_offsets(
    character: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
) -> [Vec<f64>; 2] {
    on_character_with_grounds(character, character, reference, mocap).foot_grounds
}

/// The height the character's body stands raised above its floor per
/// frame, in the character's metres: the lowest support a foot of the
/// clip touches ([`Support::ground`]), interpolated across frames in the
/// air. Retrieval takes it off the query, comparing poses as they stand
/// on the database's floor.
pub fn stance_offsets(character: &Pose, reference: &ClipNeutral, mocap: &[Pose]) -> Vec<f64> {
    stance_offsets_given(character, reference, mocap, &Given::default())
}

/// [`stance_offsets`] with what the caller decides (as
/// [`on_character_given`]).
pub fn stance_offsets_given(
    character: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    given: &Given<'_>,
) -> Vec<f64> {
    let mut ws = KernelWorkspace::new();
    stance_offsets_in(character, reference, mocap, given, &mut ws);
    ws.offsets
}

/// [`stance_offsets_given`] with `ws` the buffers of its steps (a live
/// session's), the offsets left in it: no allocation once they have
/// held the clip's frames.
pub fn stance_offsets_in<'w>(
    character: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    given: &Given<'_>,
    ws: &'w mut KernelWorkspace,
) -> &'w [f64] {
    ws.offsets.clear();
    if mocap.is_empty() {
        return &ws.offsets;
    }
    let tilt = given.tilt_with(mocap, &mut ws.tilt);
    ws.levelled.clear();
    ws.levelled
        .extend(mocap.iter().map(|m| m.map(|p| tilt * p)));
    let r = leg_length(&reference.pose).max(1e-12);
    let s = leg_length(character) / r;
    let support = &mut ws.found;
    clip_support_given_into(&ws.levelled, r, given, &mut ws.support, support);
    ws.raised.clear();
    ws.raised.extend(
        support
            .ground
            .iter()
            .map(|g| g.map(|y| (y - support.floor) * s)),
    );
    interpolate_gaps_into(&ws.raised, &mut ws.known, &mut ws.offsets);
    &ws.offsets
}

/// One per-frame height of the clip's [`Support`] (chosen by `pick`)
/// above its floor, scaled onto the character, gaps interpolated.
pub(super) fn offsets(
    character: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    pick: impl Fn(&Support) -> Vec<Option<f64>>,
) -> Vec<f64> {
    offsets_on(character, reference, mocap, &Given::default(), pick)
}

/// [`offsets`] with what the caller decides.
fn offsets_on(
    character: &Pose,
    reference: &ClipNeutral,
    mocap: &[Pose],
    given: &Given<'_>,
    pick: impl Fn(&Support) -> Vec<Option<f64>>,
) -> Vec<f64> {
    if mocap.is_empty() {
        return Vec::new();
    }
    let tilt = given.tilt_of(mocap);
    let levelled: Vec<Pose> = mocap.iter().map(|m| m.map(|p| tilt * p)).collect();
    let r = leg_length(&reference.pose).max(1e-12);
    let s = leg_length(character) / r;
    let support = clip_support_given(&levelled, r, given);
    let raised: Vec<Option<f64>> = pick(&support)
        .iter()
        .map(|g| g.map(|y| (y - support.floor) * s))
        .collect();
    interpolate_gaps(&raised)
}
