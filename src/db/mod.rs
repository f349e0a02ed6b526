//! Character databases: the manifest and what it points to, per-frame
//! skeletons, the cached similarity matrix and Surface Motion Graph, and
//! the [`Character`] they load into for synthesis.

pub mod build;
pub mod cache;
pub mod character;
pub mod content;
pub mod frames;
pub mod init;
pub mod manifest;
pub mod skeletons;

pub use crate::graph::{FlatFrame, FrameId};
pub use build::{BuildOptions, BuildProgress, BuildReport, Quiet, build};
pub use character::{Character, CharacterOptions};
pub use manifest::{
    DbError, DbInfo, DeformSpec, GraphSpec, MANIFEST, Manifest, RigSpec, SequenceEntry, SpaceEntry,
    info,
};
