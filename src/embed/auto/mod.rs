//! A character's rig from its capture alone (issue 41): which vertices
//! move together ([`decompose`], a rigid skinning decomposition after Le &
//! Deng 2012/2014), the joints where the parts meet ([`joints`]), and the
//! canonical humanoid read off the parts and the surface ([`humanoid`],
//! [`up`], [`facing`], [`limbs`]); [`rig::auto_rig`] runs them in order.
//!
//! The result is a set of landmarks on the rest frame ([`report::AutoRig`],
//! written by `db init` as `auto.landmarks.json` beside the manifest):
//! the existing pipeline ([`crate::embed::Embedding::new`]: joints from
//! landmarks, bone heat, parts, regressors) then runs unchanged, a user
//! can look at and edit the file as an override, and every check the
//! landmarks get (`Landmarks::validate`) applies to the automatic ones.
//! Writing a `JointEstimate` directly would have skipped those checks and
//! left nothing to edit.

pub mod body;
pub mod branches;
pub mod candidates;
pub mod centre;
pub mod consensus;
pub(crate) mod cut_ends;
pub mod decompose;
pub mod facing;
mod floor;
pub mod guard;
pub mod hips;
pub mod humanoid;
pub mod joints;
pub mod limbs;
pub mod neck;
pub mod options;
pub mod report;
pub mod rig;
pub mod seeding;
pub mod sides;
pub mod straddle;
pub mod up;
