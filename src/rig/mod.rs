//! The canonical skeleton and the mapping of rig conventions onto it.

mod canonical;
pub mod embed;
mod map;
pub mod retarget;

pub use canonical::Canonical;
pub use map::{CONVENTIONS, Convention, Detection, RigError, RigMap, detect, normalise_name};
