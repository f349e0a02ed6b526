//! Building and loading a character database: the all-frames similarity
//! matrix and the Surface Motion Graph (Huang et al. 2015, Sec. 4, cached
//! in `DIR/cache`), and the [`Character`] that synthesis reads.

use super::JobError;
use crate::db::{BuildOptions, BuildProgress, BuildReport, Character, CharacterOptions};
use crate::graph::SurfaceMotionGraph;
use std::path::Path;

/// Builds (or reads from the cache) the similarity matrix and graph of the
/// database in `dir`; returns the graph and the typed report
/// ([`BuildReport`]: frames, pairs, transitions, timings, cache state).
/// Options: [`BuildOptions`] (default: the manifest's measure, cache used).
pub fn build_database(
    dir: &Path,
    opts: &BuildOptions,
    progress: &dyn BuildProgress,
) -> Result<(SurfaceMotionGraph, BuildReport), JobError> {
    let (_, graph, report) = crate::db::build(dir, opts, progress)?;
    Ok((graph, report))
}

/// Loads the database in `dir` for synthesis (building its graph first if
/// needed): frames and skeletons in metres, Y-up. Options:
/// [`CharacterOptions`] (default: regressor skeletons).
pub fn load_database(
    dir: &Path,
    opts: &CharacterOptions,
    progress: &dyn BuildProgress,
) -> Result<Character, JobError> {
    Ok(Character::load_with(dir, progress, opts)?)
}
