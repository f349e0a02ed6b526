//! Character databases: the manifest and what it points to, per-frame
//! skeletons, and the cached similarity matrix and Surface Motion Graph.

pub mod build;
pub mod cache;
pub mod manifest;
pub mod rigid;
pub mod skeletons;

pub use build::{BuildOptions, BuildProgress, BuildReport, Quiet, build};
pub use manifest::{
    DbError, DbInfo, DeformSpec, GraphSpec, MANIFEST, Manifest, RigSpec, SequenceEntry, SpaceEntry,
    info,
};
