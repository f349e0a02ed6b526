//! Character databases: the manifest and what it points to, per-frame
//! skeletons, the cached similarity matrix, Surface Motion Graph and rig, and
//! the [`Character`] they load into for synthesis.

pub mod build;
pub mod cache;
pub mod character;
pub mod content;
pub mod examples;
pub mod frames;
pub mod init;
pub mod manifest;
pub mod rig_cache;
pub mod skeletons;

pub use crate::graph::{FlatFrame, FrameId};
pub use build::{BuildOptions, BuildProgress, BuildReport, Quiet, build};
pub use character::{Character, CharacterOptions};
pub use manifest::{
    DbError, DbInfo, DeformSpec, GraphSpec, MANIFEST, Manifest, RigSpec, SequenceEntry, SpaceEntry,
    info,
};
