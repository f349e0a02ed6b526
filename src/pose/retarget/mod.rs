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
//! (trunk nearest vertical, knees straightest), whose torso (spine, chest,
//! neck, head, hips' and shoulders' places, the file joints' rotations) is
//! then the clip's mean carriage in the body's heading frame
//! (`motion_ref`): that frame's stride is the file's, not the
//! performance's.

mod anchor;
mod feet;
mod footfall;
mod ground;
mod kernel;
mod leg_ik;
mod level;
mod measures;
mod motion_ref;
mod reference;
mod root;
mod stride;
mod torso;
mod workspace;

pub use anchor::{Anchor, Footfalls, PLACEMENT_ENV, Placement, TravelScale};
pub use feet::Toes;
pub use ground::{
    Given, Support, SupportScratch, TiltScratch, clip_floor, clip_floor_with, clip_support,
    clip_support_given, clip_support_given_into, clip_support_into, clip_support_on, contact_band,
    foot_height, ground_tilt, ground_tilt_with,
};
pub use kernel::{
    retarget, retarget_levelled, retarget_placed, retarget_toes, retarget_with_neutral,
};
pub use level::{LEVEL_ENV, Level};
pub use measures::{
    OnCharacter, clip_foot_glide_cm, clip_head_trunk_deg, foot_glide_cm, foot_ground_offsets,
    ground_offsets, on_character_given, on_character_in, on_character_into,
    on_character_with_grounds, stance_offsets, stance_offsets_given, stance_offsets_in,
};
pub use motion_ref::REFERENCE_ENV;
pub use reference::{
    CharacterNeutral, ClipNeutral, ClipNeutralSource, ClipPoses, JointRotations, NeutralSource,
    character_neutral, choose_reference, clip_poses, leg_length, neutral_score,
};
#[allow(deprecated)]
pub use reference::{Reference, ReferenceSource};
pub use workspace::KernelWorkspace; // old name

#[cfg(test)]
mod tests;
