//! Character databases: the manifest and what it points to.

pub mod manifest;
pub mod skeletons;

pub use manifest::{DbError, DbInfo, MANIFEST, Manifest, RigSpec, SequenceEntry, info};
