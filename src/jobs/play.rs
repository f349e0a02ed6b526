//! `jobs::play`: a scripted session of parametric motion (Casas et al.
//! 2013, Sec. 3): the database's `[[space]]` motion spaces steered by
//! timed requests, written to a mesh output frame by frame.

use crate::db::Manifest;
use crate::mesh::io::SaveOptions;
use crate::mesh::io::stream::SequenceWriter;
use crate::parametric::script::{
    SessionReport, parse_script, parse_script_for, play, session_frames,
};
use crate::parametric::store::load_or_build;
use crate::parametric::{MotionOptions, Parameter};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of [`play_session`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlayOptions {
    /// Length of the session in seconds, in (0, 3600]
    /// ([`crate::parametric::script::MAX_SECONDS`]). Default: none (the
    /// last request + 2 s).
    pub seconds: Option<f64>,
    /// How the parametric model is built when it is not cached. Default:
    /// [`MotionOptions::default`] (that of `db build`).
    pub motion: MotionOptions,
    /// GLB output (normals, quantisation). Default: [`GlbOptions::DEFAULT`](crate::mesh::io::glb::GlbOptions::DEFAULT).
    pub glb: crate::mesh::io::glb::GlbOptions,
    /// `.usda` output (normals). Default: [`UsdOptions::DEFAULT`](crate::mesh::io::usd::UsdOptions::DEFAULT).
    pub usd: crate::mesh::io::usd::UsdOptions,
}

/// What can go wrong in [`play_session`].
#[derive(Debug, thiserror::Error)]
pub enum PlayError {
    /// The script could not be read, or a report written.
    #[error(transparent)]
    Fs(#[from] crate::util::fsutil::FsError),
    /// The database has no `[[space]]`, or its manifest is wrong.
    #[error(transparent)]
    Db(#[from] crate::db::DbError),
    /// The script is malformed or names what the database does not have.
    #[error(transparent)]
    Script(#[from] crate::parametric::script::ScriptError),
    /// The parametric model could not be built or read.
    #[error(transparent)]
    Param(#[from] crate::parametric::ParamError),
    /// The output could not be written.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
}

/// The stage [`play_session`] is at.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlayStage {
    /// Loading the parametric model, or building and caching it.
    Model,
    /// Playing the script into the output.
    Playing,
}

/// A session played ([`play_session`]).
#[derive(Debug, Clone, Serialize)]
pub struct PlayRun {
    /// What the session did (per second, transitions, notices).
    #[serde(flatten)]
    pub report: SessionReport,
    /// The files written.
    pub output: Vec<PathBuf>,
    /// The model was read from the cache (not built).
    pub model_cached: bool,
    /// Seconds loading or building the model.
    pub model_seconds: f64,
    /// Seconds writing the output.
    pub write_seconds: f64,
    /// Vertices of the character.
    #[serde(skip)]
    pub vertices: usize,
}

/// Reads the script at `script` and checks it against the spaces the
/// manifest of `db` declares, before any model is built (a typo was
/// reported only after the build: 7.5 s on the demo database, minutes on
/// a real one). A database without spaces is refused as such, not as a
/// script error. A manifest that cannot be read is left to the model's
/// loader.
pub(crate) fn read_script(db: &Path, script: &Path) -> Result<String, PlayError> {
    let text = crate::util::fsutil::read_small_text(script)?;
    if let Ok(m) = Manifest::load(db) {
        m.require_spaces(db)?;
        let params: Vec<Vec<Parameter>> = m
            .spaces
            .iter()
            .map(|s| {
                s.parameters
                    .iter()
                    .filter_map(|p| Parameter::parse(p))
                    .collect()
            })
            .collect();
        let spaces: Vec<(&str, &[Parameter])> = m
            .spaces
            .iter()
            .zip(&params)
            .map(|(s, p)| (s.name.as_str(), p.as_slice()))
            .collect();
        parse_script_for(&text, script, &spaces)?;
    }
    Ok(text)
}

/// Plays the script at `script` on the database in `db` into `out` (by
/// extension): the script checked ([`read_script`]), the parametric model
/// loaded or built and cached ([`load_or_build`]), then every frame
/// written as it is made (point caches and OBJ folders stream; a GLB,
/// written whole, is checked against the memory budget before the first
/// frame: every frame was held, then the whole file's bytes, 1.1 GB for a
/// 100 s session, attack s14, item 3). `progress` is told each stage.
pub fn play_session(
    db: &Path,
    script: &Path,
    out: &Path,
    opts: &PlayOptions,
    progress: &mut dyn FnMut(PlayStage),
) -> Result<PlayRun, PlayError> {
    let text = read_script(db, script)?;
    let t0 = Instant::now();
    progress(PlayStage::Model);
    let built = load_or_build(db, &opts.motion, false);
    progress(PlayStage::Playing);
    let (motion, model_cached) = built?;
    let model_seconds = t0.elapsed().as_secs_f64();
    let requests = parse_script(&text, script, &motion)?;
    let seconds = opts
        .seconds
        .unwrap_or_else(|| requests.last().map_or(0.0, |r| r.t) + 2.0);
    let frames = session_frames(&requests, Some(seconds), motion.fps);
    let save = SaveOptions {
        fps: Some(motion.fps),
        glb: opts.glb,
        usd: opts.usd,
    };
    let mut writer = SequenceWriter::create(&motion.topology, out, frames, &save)?;
    let mut write_seconds = 0.0;
    let report = play(&motion, &requests, Some(seconds), |p| {
        let t = Instant::now();
        let r = writer.push(p);
        write_seconds += t.elapsed().as_secs_f64();
        r
    })?;
    let t1 = Instant::now();
    let output = writer.finish()?;
    Ok(PlayRun {
        report,
        output,
        model_cached,
        model_seconds,
        write_seconds: write_seconds + t1.elapsed().as_secs_f64(),
        vertices: motion.topology.vertex_count(),
    })
}
