//! The canonical skeleton and the mapping of rig conventions onto it.

mod canonical;
mod derive;
pub mod load;
mod map;
pub mod names;
pub mod structure;

pub use canonical::Canonical;
pub use derive::Derive;
pub use load::{LoadOptions, guess_up, load_clip, read_any_clip, read_rigged_character};
pub use map::{
    BY_NAMES, BY_STRUCTURE, CONVENTIONS, Convention, Detection, JointReport, RigError, RigMap,
    detect, detect_clip, normalise_name,
};
pub use structure::Provenance;
/// The old name of [`Provenance`].
#[deprecated(note = "renamed `Provenance` (issue 40: `Source` names a live input stream)")]
pub type Source = Provenance;
