//! Building and loading a character database: the all-frames similarity
//! matrix and the Surface Motion Graph (Huang et al. 2015, Sec. 4, cached
//! in `DIR/cache`), and the [`Character`] that synthesis reads.

use super::JobError;
use crate::db::{BuildOptions, BuildProgress, BuildReport, Character, CharacterOptions, DbError};
use crate::graph::SurfaceMotionGraph;
use crate::parametric::space::SpaceSummary;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// What [`build_database`] did: the graph's report ([`BuildReport`], which
/// this derefs to) and the parametric motion spaces of the manifest's
/// `[[space]]` entries (Casas et al. 2013).
#[derive(Debug, Clone, Serialize)]
pub struct DatabaseReport {
    /// Similarity matrix and graph.
    #[serde(flatten)]
    pub build: BuildReport,
    /// The parametric motion spaces built (empty without any).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub spaces: Vec<SpaceSummary>,
    /// True if the parametric model came from the cache (absent without
    /// spaces).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spaces_cached: Option<bool>,
    /// Seconds spent on the parametric model (absent without spaces).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spaces_seconds: Option<f64>,
    /// Seconds spent loading the character as `retarget` does and writing
    /// what its first load would (frames, skeletons, rig, the deformation's
    /// examples, the plausibility reference); absent without a `[rig]`, for
    /// a measure other than the one a retarget loads and for a build of a
    /// given similarity method.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prepared_seconds: Option<f64>,
    /// Why the character could not be prepared (the graph is built; a
    /// `retarget` will say the same).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prepare_failed: Option<String>,
}

impl std::ops::Deref for DatabaseReport {
    type Target = BuildReport;
    fn deref(&self) -> &BuildReport {
        &self.build
    }
}

/// Builds (or reads from the cache) the similarity matrix and graph of the
/// database in `dir`, and the parametric motion spaces of its `[[space]]`
/// entries; returns the graph and the typed report ([`DatabaseReport`]:
/// frames, pairs, transitions, timings, cache state, spaces).
/// Options: [`BuildOptions`] (default: the manifest's measure, cache used).
pub fn build_database(
    dir: &Path,
    opts: &BuildOptions,
    progress: &dyn BuildProgress,
) -> Result<(SurfaceMotionGraph, DatabaseReport), JobError> {
    let m = crate::db::Manifest::load(dir)?;
    // Only for the measure and method a retarget loads: another measure's
    // build would otherwise make the default measure's graph too, and a
    // build of a given method (`--similarity`) could have its graph cache
    // replaced by the one the load's own choice of method makes.
    let default = opts.method.is_none()
        && opts
            .measure
            .is_none_or(|k| k == crate::db::build::default_measure(&m));
    let prepare = default && (m.rig.landmarks.is_some() || m.rig.gltf_skin.is_some());
    // The rig, frame and skeleton caches made while the frames are
    // compared (issue 43); the load below finds them current.
    let build_opts = BuildOptions {
        prepare,
        ..opts.clone()
    };
    let (_, graph, build) = crate::db::build::build_opened(dir, &m, &build_opts, progress)?;
    let t = Instant::now();
    let (spaces, spaces_cached) = if m.spaces.is_empty() {
        (Vec::new(), None)
    } else {
        let popts = crate::parametric::MotionOptions::default();
        let (motion, cached) = crate::parametric::store::load_or_build(dir, &popts, opts.force)
            .map_err(|e| match e {
                crate::parametric::ParamError::Db(e) => e,
                crate::parametric::ParamError::Space { path, space, msg } => DbError::Manifest {
                    path,
                    msg: format!("space '{space}': {msg}"),
                },
                other => DbError::Manifest {
                    path: dir.join(crate::db::MANIFEST),
                    msg: other.to_string(),
                },
            })?;
        (motion.summary(), Some(cached))
    };
    let spaces_seconds = spaces_cached.map(|_| t.elapsed().as_secs_f64());
    // Every cache a `retarget` reads, written here (issue 43): a database
    // built once serves every later retarget read-only.
    let (mut prepared_seconds, mut prepare_failed) = (None, None);
    if prepare {
        let t = Instant::now();
        match prepare_for_retarget(dir, progress) {
            Ok(()) => prepared_seconds = Some(t.elapsed().as_secs_f64()),
            Err(e) => {
                tracing::warn!("{}: not prepared for retargeting: {e}", dir.display());
                prepare_failed = Some(e.to_string());
            }
        }
    }
    Ok((
        graph,
        DatabaseReport {
            build,
            spaces,
            spaces_cached,
            spaces_seconds,
            prepared_seconds,
            prepare_failed,
        },
    ))
}

/// Loads the database in `dir` and prepares it as a default `retarget`
/// does ([`super::RetargetJob::load`], the plausibility checker), so that
/// every cache that load reads is current: the frame and skeleton caches,
/// the rig, the part deformation's examples (`db::examples`) and the
/// plausibility reference.
fn prepare_for_retarget(dir: &Path, progress: &dyn BuildProgress) -> Result<(), String> {
    let job =
        super::RetargetJob::load(dir, Default::default(), progress).map_err(|e| e.to_string())?;
    crate::tools::eval::Checker::for_character_with(
        &job.character,
        job.prepared().neutral(),
        crate::tools::eval::PlausibilityOptions::default(),
    )
    .map_err(|e| e.to_string())?;
    Ok(())
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
