//! `db build`: similarity matrix, transitions and Surface Motion Graph of a
//! database, cached (Huang et al. 2015, Sec. 4).
//!
//! Sequences are loaded one at a time and reduced to per-frame descriptors
//! straight away, so a build holds the descriptors and the matrix, never
//! every mesh of the database at once.

use super::cache::{self, KeyHasher, add_rig, cache_dir, frames_key};
use super::manifest::{DbError, Manifest};
use super::skeletons::embed_rig;
use crate::embed::frames::{SkeletonKind, poses};
use crate::graph::SurfaceMotionGraph;
use crate::mocap::units::y_up;
use crate::similarity::scan::{self, ScanChoice};
use crate::similarity::sparse::{Features, SparseOptions, sparse_pairs};
use crate::similarity::vertex::VertexOptions;
use crate::similarity::{
    ColourSet, Measure, PairDistance, ShapeSet, Similarity, SimilarityMatrix, SkeletonSet, Span,
    VertexSet, all_pairs,
};
use crate::util::fsutil::{read_text, write_bytes_atomic};
use crate::util::stages::Stages;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of [`build`].
#[derive(Debug, Clone, Default)]
pub struct BuildOptions {
    /// Measure; default: the manifest's `[graph] measure`, else colour when
    /// the manifest names vertex colours, else shape.
    pub measure: Option<Measure>,
    /// Recompute even when the cache is current.
    pub force: bool,
    /// Dense (every pair) or sparse (the candidate pairs of a
    /// nearest-neighbour index, issue 43) similarity; default: a current
    /// cache of either, else sparse from [`SPARSE_FRAMES`] frames (shape
    /// measure only), dense below.
    pub method: Option<Method>,
    /// Also make the rig, frame and skeleton caches a default load reads
    /// current, while the frames are compared
    /// ([`super::frames::prepare_frame_caches`]; `db build` of a
    /// database with a rig, issue 43). Only when the similarity is
    /// computed (a current cache leaves them to the load). Default: false.
    pub prepare: bool,
}

/// How the frame similarity is computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Every pair of frames: the `n²` matrix.
    Dense,
    /// The pairs near each frame's nearest neighbours and their windows
    /// ([`crate::similarity::sparse`]).
    Sparse,
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Method, String> {
        match s {
            "dense" => Ok(Method::Dense),
            "sparse" => Ok(Method::Sparse),
            _ => Err(format!("'{s}': the similarity method is dense or sparse")),
        }
    }
}

/// Databases of at least this many frames get the sparse similarity by
/// default (the dense matrix of 5,000 frames is 100 MB and about a minute
/// on two cores; it grows with `n²`).
pub(crate) const SPARSE_FRAMES: usize = 5000;

/// Progress callbacks of a build (the library does not print).
pub trait BuildProgress: Sync {
    /// A stage of `total` steps begins.
    fn start(&self, _what: &str, _total: u64) {}
    /// `k` more steps are done.
    fn advance(&self, _k: u64) {}
    /// The stage is done.
    fn finish(&self) {}
}

/// Progress that goes nowhere.
pub struct Quiet;
impl BuildProgress for Quiet {}

/// What a build did.
#[derive(Debug, Clone, Serialize)]
pub struct BuildReport {
    /// Measure used.
    pub measure: Measure,
    /// `dense` or `sparse`.
    pub method: &'static str,
    /// Unit of the dissimilarities.
    pub unit: &'static str,
    /// Frames in the database.
    pub frames: usize,
    /// Sequences.
    pub sequences: Vec<Span>,
    /// True if the similarity matrix came from the cache.
    pub similarity_cached: bool,
    /// Seconds spent on descriptors (0 when cached).
    pub describe_seconds: f64,
    /// Seconds spent on all pairs (0 when cached).
    pub pairs_seconds: f64,
    /// Frame pairs evaluated (0 when cached).
    pub pairs: u64,
    /// Frame pairs stored (`n (n + 1) / 2` when dense).
    pub stored_pairs: u64,
    /// True if the graph came from the cache.
    pub graph_cached: bool,
    /// Seconds spent finding transitions and building the graph.
    pub graph_seconds: f64,
    /// Transitions in the graph.
    pub transitions: usize,
    /// Sequence edges in the graph.
    pub edges: usize,
    /// The cache folder.
    pub cache: PathBuf,
    /// A sparse similarity's sequence-pair scan: the full scan or a reach,
    /// and the estimates it was chosen from ([`scan_options`]; absent for
    /// the dense method).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scan: Option<ScanChoice>,
    /// Seconds the rig, frame and skeleton caches took, made while the
    /// frames were compared ([`BuildOptions::prepare`]; absent when not).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub caches_beside_seconds: Option<f64>,
}

#[derive(Serialize, Deserialize)]
struct GraphFile {
    key: u64,
    graph: SurfaceMotionGraph,
    /// Each frame's dissimilarity to the next frame of its sequence
    /// ([`successor_steps`]; `None` for a sequence's last frame), each an
    /// f32 of the similarity written as an f64 (exact in JSON). Absent in a
    /// graph cache of session 44 and before, which a load then completes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    steps: Option<Vec<Option<f64>>>,
}

impl GraphFile {
    /// The steps when there is one a frame of `n`.
    fn steps(&self, n: usize) -> Option<Vec<f32>> {
        let s = self.steps.as_ref().filter(|s| s.len() == n)?;
        Some(s.iter().map(|v| v.map_or(f32::NAN, |v| v as f32)).collect())
    }
}

/// The graph cache's text: `graph` and its `steps` under `key`.
fn graph_text(key: u64, graph: &SurfaceMotionGraph, steps: &[f32]) -> serde_json::Result<String> {
    let steps = steps
        .iter()
        .map(|v| (!v.is_nan()).then_some(f64::from(*v)))
        .collect();
    serde_json::to_string(&GraphFile {
        key,
        graph: graph.clone(),
        steps: Some(steps),
    })
}

/// The graph cache file at `path`: `None` when there is none, and also,
/// with a warning naming the file and why, when it cannot be read or is
/// not a graph cache (truncated, garbage: it was rebuilt silently). A file
/// of another key is returned for the caller to compare.
fn read_graph(path: &Path) -> Option<GraphFile> {
    if std::fs::symlink_metadata(path).is_err_and(|e| e.kind() == std::io::ErrorKind::NotFound) {
        return None;
    }
    let parsed = read_text(path)
        .map_err(|e| e.source.to_string())
        .and_then(|t| serde_json::from_str::<GraphFile>(&t).map_err(|e| e.to_string()));
    match parsed {
        Ok(g) => Some(g),
        Err(why) => {
            tracing::warn!(
                "{}: the cached graph cannot be used ({why}); rebuilding it",
                path.display()
            );
            None
        }
    }
}

/// The measure `db build` uses without `--measure`: the manifest's `[graph]
/// measure`, else the paper's 6D colour measure when the database names
/// vertex colours, else 3D shape.
pub(crate) fn default_measure(m: &Manifest) -> Measure {
    m.graph.measure.unwrap_or(if m.colors.is_some() {
        Measure::Colour
    } else {
        Measure::Shape
    })
}

fn vertex_options(m: &Manifest) -> VertexOptions {
    VertexOptions {
        velocity_weight: m.graph.velocity_weight.unwrap_or(1.0),
    }
}

/// The similarity cache file of `measure` in the database `dir`.
pub fn similarity_path(dir: &Path, measure: Measure) -> PathBuf {
    cache_dir(dir).join(format!("similarity-{}.bin", measure.name()))
}

/// The sparse similarity cache file of `measure` in the database `dir`.
pub fn sparse_path(dir: &Path, measure: Measure) -> PathBuf {
    cache_dir(dir).join(format!("sparse-{}.bin", measure.name()))
}

/// The key of a sparse similarity: the dense one's and the options.
pub(crate) fn sparse_key(similarity_key: u64, opts: &SparseOptions) -> u64 {
    let mut k = KeyHasher::default();
    k.text("similarity", &similarity_key.to_string());
    let mut text = format!(
        "{} {} {} {} {} {}",
        opts.neighbours, opts.dims, opts.band, opts.min_gap, opts.stride, opts.per_sequence
    );
    // The per-pair options only when the scan is on: the caches of
    // databases built without it keep their key.
    if opts.per_pair > 0 {
        text += &format!(" {} {} {}", opts.per_pair, opts.spread, opts.min_window);
    }
    // The re-ranking likewise only when on.
    if opts.per_pair > 0 && opts.rerank > 0 {
        text += &format!(" rerank {}", opts.rerank);
    }
    // The per-sequence candidates from one index's pool (session 28) only
    // when on: a cache of the per-sequence trees keeps its key.
    if opts.per_sequence > 0 && opts.pool > 0 {
        text += &format!(" pool {}", opts.pool);
    }
    // The cover rule (session 29) likewise.
    if opts.per_sequence > 0 && opts.pool > 0 && opts.cover > 0 {
        text += &format!(" cover {}", opts.cover);
    }
    // The sequence pairs reached (session 33) likewise.
    if opts.reach > 0 {
        text += &format!(" reach {}", opts.reach);
        // The far search (session 34) with a reach only.
        if opts.far > 0 && opts.per_pair > 0 {
            text += &format!(" far {} {}", opts.far, opts.far_rerank);
        }
    }
    // The closure (session 39) likewise: a cache built before it (or
    // with it off) keeps its key; one built with it never reads as one
    // without.
    if opts.closure > 0 {
        text += &format!(" closure {}", opts.closure);
    }
    k.text("sparse", &text);
    k.finish()
}

/// The environment variable whose `name=value` pairs override the sparse
/// options of `db build` (measurements of issue 43;
/// [`SparseOptions::with_overrides`]), e.g.
/// `SURFMOTION_SPARSE=neighbours=12,rerank=0`. The cache key follows the
/// options, so a build with other options never reads another's cache.
pub(crate) const SPARSE_ENV: &str = "SURFMOTION_SPARSE";

/// The sparse options for a manifest's transition options: the band the
/// longest window needs, its `min_gap`; then [`SPARSE_ENV`]'s overrides
/// (a warning, and none taken, when they cannot be read).
pub fn sparse_options(m: &Manifest) -> SparseOptions {
    let t = m.graph.transition_options();
    let o = SparseOptions {
        band: t.max_window.max(t.min_window) + 1,
        min_gap: t.min_gap,
        min_window: t.min_window,
        ..SparseOptions::default()
    };
    match std::env::var(SPARSE_ENV) {
        Ok(text) => o.with_overrides(&text).unwrap_or_else(|why| {
            // Once a process: `db build` reads the options again when it
            // prepares the character (and a load reads them per database).
            static WARNED: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
            let mut seen = WARNED.lock().unwrap_or_else(|e| e.into_inner());
            if !seen.contains(&why) {
                tracing::warn!("{SPARSE_ENV}: {why}; the default sparse options are used");
                seen.push(why);
            }
            o
        }),
        Err(_) => o,
    }
}

/// Whether [`SPARSE_ENV`] gives a reach (`reach=N`, read): a reach given
/// explicitly wins over the scan rule.
fn reach_given() -> bool {
    std::env::var(SPARSE_ENV).is_ok_and(|text| {
        SparseOptions::default().with_overrides(&text).is_ok()
            && text
                .split(',')
                .any(|p| p.split_once('=').is_some_and(|(n, _)| n.trim() == "reach"))
    })
}

/// The sparse options of a database of `frames` frames: [`sparse_options`]
/// with the reach the scan rule chooses from its estimate of the full
/// scan (issue 43, session 40: [`scan::choose`]; a reach given in
/// [`SPARSE_ENV`] wins), and the choice. The cache key follows the options:
/// a database built with a chosen reach is never read as a full-scan one,
/// nor the other way round.
pub fn scan_options(m: &Manifest, frames: usize) -> (SparseOptions, ScanChoice) {
    let base = sparse_options(m);
    let choice = scan::choose(frames, m.sequences.len(), &base, reach_given());
    (choice.options(&base), choice)
}

/// The frame count the sparse similarity cache of `measure` in `dir` says
/// it holds (0 without one): what the scan rule reads to judge a cache
/// before anything is described. Trusted through the key only: a cache of
/// other frames carries another similarity key.
pub(crate) fn cached_frames(dir: &Path, measure: Measure) -> usize {
    cache::sparse_frames(&sparse_path(dir, measure)).unwrap_or(0)
}

/// The graph cache file of `measure` in the database `dir`.
pub fn graph_path(dir: &Path, measure: Measure) -> PathBuf {
    cache_dir(dir).join(format!("graph-{}.json", measure.name()))
}

/// The key a current similarity cache of `measure` carries: the hash of
/// the frames, the measure and its parameters (reads every sequence file).
pub fn similarity_key(dir: &Path, m: &Manifest, measure: Measure) -> Result<u64, DbError> {
    let mut key = frames_key(dir, m)?;
    key.text("measure", measure.name());
    match measure {
        Measure::Shape => {
            key.text("voxels", &ShapeSet::VOXELS_PER_HEIGHT.to_string());
        }
        Measure::Vertex => {
            key.text(
                "velocity_weight",
                &vertex_options(m).velocity_weight.to_string(),
            );
        }
        Measure::Skeleton => add_rig(&mut key, dir, m)?,
        Measure::Colour => {
            if let Some(c) = &m.colors {
                key.path(&Manifest::resolve(dir, c))?;
            }
        }
    }
    key.save();
    Ok(key.finish())
}

/// The key a current graph cache carries: the similarity matrix's key,
/// the transition options and the graph edits of the manifest.
pub(crate) fn graph_key(m: &Manifest, similarity_key: u64) -> u64 {
    let mut gk = KeyHasher::default();
    gk.text("similarity", &similarity_key.to_string());
    gk.text(
        "options",
        &serde_json::to_string(&m.graph.transition_options()).unwrap_or_default(),
    );
    gk.text(
        "edits",
        &serde_json::to_string(&m.graph.edits()).unwrap_or_default(),
    );
    gk.finish()
}

/// The key and graph of a graph cache file, without checking either:
/// `Err` naming why it cannot be read.
pub fn read_graph_cache(path: &Path) -> Result<(u64, SurfaceMotionGraph), String> {
    read_text(path)
        .map_err(|e| e.to_string())
        .and_then(|t| {
            serde_json::from_str::<GraphFile>(&t).map_err(|e| format!("{}: {e}", path.display()))
        })
        .map(|g| (g.key, g.graph))
}

/// Where the time of a similarity computation went.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Timing {
    /// Seconds loading sequences and computing descriptors.
    pub describe_seconds: f64,
    /// Seconds comparing all pairs.
    pub pairs_seconds: f64,
    /// Pairs compared (with the diagonal).
    pub pairs: u64,
    /// Seconds of [`BuildOptions::prepare`]'s caches, made beside the
    /// pairs (`None`: not asked for, or they failed: the load says why).
    pub beside_seconds: Option<f64>,
}

/// The similarity matrix of a database for one measure, from the cache if
/// current. Returns the matrix, its key and the report fields.
pub fn similarity(
    dir: &Path,
    m: &Manifest,
    measure: Measure,
    force: bool,
    progress: &dyn BuildProgress,
) -> Result<(SimilarityMatrix, u64, Option<Timing>), DbError> {
    let (sim, key, t) = similarity_with(
        dir,
        m,
        measure,
        (Some(Method::Dense), false),
        force,
        progress,
    )?;
    match sim {
        Similarity::Dense(mat) => Ok((mat, key, t)),
        Similarity::Sparse(_) => unreachable!("the dense method was asked for"),
    }
}

/// The sparse similarity of `key` in the cache, if current and of the
/// manifest's sequences; a warning naming the file when it is there but
/// cannot be used.
fn cached_sparse(dir: &Path, m: &Manifest, measure: Measure, key: u64) -> Option<Similarity> {
    let path = sparse_path(dir, measure);
    let s = cache::read_sparse(&path, key).unwrap_or_else(|why| {
        tracing::warn!(
            "{}: the cached sparse similarity cannot be used ({why}); recomputing it",
            path.display()
        );
        None
    })?;
    let names_match = s.spans.len() == m.sequences.len()
        && s.spans
            .iter()
            .zip(&m.sequences)
            .all(|(a, b)| a.name == b.name);
    if !names_match {
        tracing::warn!(
            "{}: the cached sparse similarity disagrees with the database (other sequences); recomputing it",
            path.display()
        );
        return None;
    }
    Some(Similarity::Sparse(s))
}

/// The similarity of a database for one measure by `method` (`None`: a
/// current cache of either method, else sparse from [`SPARSE_FRAMES`]
/// frames for the shape measure, dense otherwise), from the cache if
/// current. With `prepare` ([`BuildOptions::prepare`]) the caches a load
/// reads are made beside the comparison. Returns the similarity, its key
/// (the graph cache's input) and the report fields.
pub(crate) fn similarity_with(
    dir: &Path,
    m: &Manifest,
    measure: Measure,
    (method, prepare): (Option<Method>, bool),
    force: bool,
    progress: &dyn BuildProgress,
) -> Result<(Similarity, u64, Option<Timing>), DbError> {
    let key = similarity_key(dir, m, measure)?;
    let (sopts, _) = scan_options(m, cached_frames(dir, measure));
    let skey = sparse_key(key, &sopts);
    tracing::debug!(
        "{}: cache keys: similarity ({}) {key:016x}, sparse {skey:016x}",
        dir.display(),
        measure.name()
    );
    if method == Some(Method::Sparse) && measure != Measure::Shape {
        return Err(DbError::Manifest {
            path: dir.join(super::MANIFEST),
            msg: format!(
                "the sparse similarity needs the shape measure (the {} measure has no cheap descriptor yet); build with the dense method",
                measure.name()
            ),
        });
    }
    if let Some(found) = cached_similarity(dir, m, measure, method, force, (key, skey)) {
        return Ok(found);
    }
    let t0 = Instant::now();
    let c0 = crate::similarity::candidates::process_cpu_seconds();
    let (sets, spans) = describe(dir, m, measure, progress)?;
    let describe = t0.elapsed().as_secs_f64();
    let describe_cpu = crate::similarity::candidates::process_cpu_seconds() - c0;
    let lens: Vec<usize> = spans.iter().map(|s| s.len).collect();
    let times = (describe, describe_cpu);
    let compare = || {
        compare_described(
            dir,
            m,
            measure,
            (method, key),
            &sets,
            spans,
            times,
            progress,
        )
    };
    let (sim, key, timing) = if prepare {
        beside_caches(dir, m, &lens, compare)?
    } else {
        compare()?
    };
    Ok((sim, key, Some(timing)))
}

/// Runs `work` while the caches a default load reads are made current
/// beside it ([`super::frames::prepare_frame_caches`]) on a thread of
/// their own; returns `work`'s result with their seconds in its timing. A
/// failure there is only logged: the load after the build makes them
/// again and says why it cannot.
fn beside_caches(
    dir: &Path,
    m: &Manifest,
    lens: &[usize],
    work: impl FnOnce() -> Result<(Similarity, u64, Timing), DbError>,
) -> Result<(Similarity, u64, Timing), DbError> {
    std::thread::scope(|scope| {
        let side = scope.spawn(|| {
            let t = Instant::now();
            let prepare = || super::frames::prepare_frame_caches(dir, m, lens);
            // A pool of its own: its parallel loops (the skeletons of each
            // sequence's frames) queued on the global pool would wait
            // until the pairs' blocks are done, putting this thread after
            // the comparison instead of beside it (measured at 10⁴ frames).
            match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
                Ok(pool) => pool.install(prepare),
                Err(_) => prepare(),
            }
            .map(|()| t.elapsed().as_secs_f64())
        });
        let out = work();
        let seconds = match side.join() {
            Ok(Ok(s)) => Some(s),
            Ok(Err(e)) => {
                tracing::debug!("{}: caches not made beside the pairs: {e}", dir.display());
                None
            }
            Err(_) => {
                tracing::warn!(
                    "{}: making the caches beside the pairs failed (a panic); the load makes them",
                    dir.display()
                );
                None
            }
        };
        out.map(|(sim, key, timing)| {
            let beside_seconds = seconds;
            (
                sim,
                key,
                Timing {
                    beside_seconds,
                    ..timing
                },
            )
        })
    })
}

/// The similarity of the described frames `sets` (sequences `spans`) by
/// `method` ([`similarity_with`]'s choice), saved to the cache under `key`
/// (a sparse one under the sparse key derived from it); returns it with
/// the key it was saved under.
#[allow(clippy::too_many_arguments)]
fn compare_described(
    dir: &Path,
    m: &Manifest,
    measure: Measure,
    (method, key): (Option<Method>, u64),
    sets: &Sets,
    spans: Vec<Span>,
    (describe, describe_cpu): (f64, f64),
    progress: &dyn BuildProgress,
) -> Result<(Similarity, u64, Timing), DbError> {
    let path = similarity_path(dir, measure);
    let set = sets.pair_distance();
    let frames = set.frames();
    let sparse = match method {
        Some(Method::Sparse) => true,
        Some(Method::Dense) => false,
        None => frames >= SPARSE_FRAMES && sets.shape.is_some(),
    };
    if sparse && let Some(set) = sets.shape.as_ref() {
        notice(format!(
            "{frames} frames described in {describe:.1} s ({describe_cpu:.1} s of CPU)"
        ));
        // Said before the long work: what the full scan would take and
        // what runs.
        let (sopts, choice) = scan_options(m, frames);
        notice(format!("sequence-pair scan: {}", choice.describe()));
        let skey = sparse_key(key, &sopts);
        return sparse_similarity(dir, measure, skey, set, spans, &sopts, describe, progress);
    }
    let t1 = Instant::now();
    let (data, checkpoint) = compare_frames(dir, &path, key, set, progress)?;
    let pairs_s = t1.elapsed().as_secs_f64();
    let mat = SimilarityMatrix::new(spans, data).ok_or_else(|| DbError::Manifest {
        path: dir.join(super::MANIFEST),
        msg: "internal: frame counts disagree".into(),
    })?;
    cache::save_matrix(&path, key, &mat).map_err(|e| DbError::cache_write(dir, e))?;
    if let Some(c) = checkpoint {
        c.remove();
    }
    let pairs = (frames as u64) * (frames as u64 + 1) / 2;
    Ok((
        Similarity::Dense(mat),
        key,
        Timing {
            describe_seconds: describe,
            pairs_seconds: pairs_s,
            pairs,
            beside_seconds: None,
        },
    ))
}

/// A current cached similarity for `method`, with its key: the sparse
/// cache when sparse is asked for; else the dense matrix when it is
/// current, of the manifest's sequences and finite (a warning naming the
/// file otherwise); else, without a method, a current sparse cache of the
/// shape measure. `keys`: the dense and the sparse key.
fn cached_similarity(
    dir: &Path,
    m: &Manifest,
    measure: Measure,
    method: Option<Method>,
    force: bool,
    (key, skey): (u64, u64),
) -> Option<(Similarity, u64, Option<Timing>)> {
    if method == Some(Method::Sparse)
        && !force
        && let Some(s) = cached_sparse(dir, m, measure, skey)
    {
        return Some((s, skey, None));
    }
    let path = similarity_path(dir, measure);
    let cached = if force || method == Some(Method::Sparse) {
        None
    } else {
        cache::read_matrix(&path, key).unwrap_or_else(|why| {
            tracing::warn!(
                "{}: the cached similarity matrix cannot be used ({why}); recomputing it",
                path.display()
            );
            None
        })
    };
    if let Some(mat) = cached {
        // A valid key does not make the contents right: the spans must be
        // the manifest's sequences and every value a finite distance.
        let names_match = mat.spans.len() == m.sequences.len()
            && mat
                .spans
                .iter()
                .zip(&m.sequences)
                .all(|(s, q)| s.name == q.name);
        let finite = (0..mat.len()).all(|a| mat.row(a).iter().all(|v| v.is_finite() && *v >= 0.0));
        if names_match && finite {
            return Some((Similarity::Dense(mat), key, None));
        }
        tracing::warn!(
            "{}: the cached similarity matrix disagrees with the database ({}); recomputing it",
            path.display(),
            if names_match {
                "a value that is not a finite distance"
            } else {
                "other sequences"
            }
        );
    }
    if method.is_none()
        && !force
        && measure == Measure::Shape
        && let Some(s) = cached_sparse(dir, m, measure, skey)
    {
        return Some((s, skey, None));
    }
    None
}

/// The per-frame descriptors of one measure (one set is built).
#[derive(Default)]
struct Sets {
    shape: Option<ShapeSet>,
    vertex: Option<VertexSet>,
    skel: Option<(crate::embed::Embedding, SkeletonSet)>,
    colour: Option<ColourSet>,
}

impl Sets {
    /// The empty set of `measure` for the topology `topo`.
    fn new(
        dir: &Path,
        m: &Manifest,
        measure: Measure,
        topo: &crate::mesh::Mesh,
    ) -> Result<Sets, DbError> {
        let z_up = m.up.eq_ignore_ascii_case("z");
        let mut sets = Sets::default();
        match measure {
            Measure::Shape => {
                let rest: Vec<_> = topo.positions().iter().map(|p| y_up(*p, z_up)).collect();
                sets.shape = Some(ShapeSet::new(ShapeSet::grid_for(&rest, topo.triangles())));
            }
            Measure::Vertex => {
                sets.vertex = Some(VertexSet::new(topo.vertex_count(), vertex_options(m)))
            }
            Measure::Skeleton => {
                sets.skel = Some((embed_rig(dir, m, topo)?, SkeletonSet::default()));
            }
            Measure::Colour => {
                let colours = vertex_colours(dir, m, topo)?;
                let rest: Vec<_> = topo.positions().iter().map(|p| y_up(*p, z_up)).collect();
                sets.colour = Some(ColourSet::new(
                    ShapeSet::grid_for(&rest, topo.triangles()),
                    colours,
                ));
            }
        }
        Ok(sets)
    }

    /// Adds one sequence's frames (`n` vertices each).
    fn push(&mut self, frames: &[[f64; 3]], n: usize, triangles: &[[u32; 3]], z_up: bool) {
        if let Some(set) = self.shape.as_mut() {
            set.push_sequence(frames, n, triangles, z_up);
        }
        if let Some(set) = self.vertex.as_mut() {
            set.push_sequence(frames, z_up);
        }
        if let Some(set) = self.colour.as_mut() {
            set.push_sequence(frames, n, triangles, z_up);
        }
        if let Some((rig, set)) = self.skel.as_mut() {
            let p = poses(rig, frames, n, SkeletonKind::Regressor);
            set.poses
                .extend(p.into_iter().map(|q| q.map(|j| y_up(j.to_array(), z_up))));
        }
    }

    /// The set that was built, as pair distances.
    fn pair_distance(&self) -> &dyn PairDistance {
        match (&self.shape, &self.vertex, &self.skel, &self.colour) {
            (Some(s), _, _, _) => s,
            (_, Some(s), _, _) => s,
            (_, _, Some((_, s)), _) => s,
            (_, _, _, Some(s)) => s,
            _ => unreachable!("one set is built per measure"),
        }
    }
}

/// The shape descriptors of every frame of the database `dir` and its
/// sequences' spans: what a sparse build describes (for measurements that
/// run [`sparse_pairs`] with several options on one description).
pub fn describe_shape(
    dir: &Path,
    m: &Manifest,
    progress: &dyn BuildProgress,
) -> Result<(ShapeSet, Vec<Span>), DbError> {
    let (sets, spans) = describe(dir, m, Measure::Shape, progress)?;
    sets.shape
        .map(|s| (s, spans))
        .ok_or_else(|| DbError::Manifest {
            path: dir.join(super::MANIFEST),
            msg: "internal: no shape descriptors for the shape measure".into(),
        })
}

/// Every sequence loaded one at a time and reduced to the descriptors of
/// `measure`; returns them and the sequences' spans.
fn describe(
    dir: &Path,
    m: &Manifest,
    measure: Measure,
    progress: &dyn BuildProgress,
) -> Result<(Sets, Vec<Span>), DbError> {
    let topo = m.load_topology(dir)?;
    let n = topo.vertex_count();
    let z_up = m.up.eq_ignore_ascii_case("z");
    let mut spans = Vec::new();
    let mut sets = Sets::new(dir, m, measure, &topo)?;
    progress.start("sequences described", m.sequences.len() as u64);
    for s in &m.sequences {
        let seq = m.load_sequence(dir, s)?;
        if seq.mesh().vertex_count() != n || seq.mesh().triangles() != topo.triangles() {
            return Err(DbError::Manifest {
                path: dir.join(super::MANIFEST),
                msg: format!(
                    "sequence '{}': its connectivity differs from the topology ({} vertices, the topology {}); `surfmotion db info` lists such problems",
                    s.name,
                    seq.mesh().vertex_count(),
                    n
                ),
            });
        }
        let start = spans.iter().map(|s: &Span| s.len).sum();
        spans.push(Span {
            name: s.name.clone(),
            start,
            len: seq.frame_count(),
        });
        sets.push(seq.all_positions(), n, topo.triangles(), z_up);
        progress.advance(1);
    }
    progress.finish();
    Ok((sets, spans))
}

/// The sparse similarity of the described frames `set`, saved to the
/// cache under `key`.
#[allow(clippy::too_many_arguments)]
fn sparse_similarity(
    dir: &Path,
    measure: Measure,
    key: u64,
    set: &dyn Features,
    spans: Vec<Span>,
    opts: &SparseOptions,
    describe: f64,
    progress: &dyn BuildProgress,
) -> Result<(Similarity, u64, Timing), DbError> {
    use crate::util::budget::thousands;
    let n = set.frames();
    let t = Instant::now();
    // Each stage with its total, so that the bar shows an estimate of the
    // time left (it counted pairs against a total of 0 before).
    struct Staged<'a>(&'a dyn BuildProgress, std::sync::atomic::AtomicBool);
    impl crate::similarity::sparse::SparseProgress for Staged<'_> {
        fn stage(&self, what: &str, total: u64) {
            if self.1.swap(true, std::sync::atomic::Ordering::Relaxed) {
                self.0.finish();
            }
            self.0.start(what, total);
        }
        fn advance(&self, k: u64) {
            self.0.advance(k);
        }
    }
    let staged = Staged(progress, std::sync::atomic::AtomicBool::new(false));
    let (sim, stats) = sparse_pairs(set, spans, opts, &staged);
    if staged.1.into_inner() {
        progress.finish();
    }
    let all = (n as u128) * (n as u128 + 1) / 2;
    notice(format!(
        "sparse similarity of {} frames: {} candidate pairs from the {} nearest frames of each and the {} best cheap transitions of each sequence pair ({} of them; {:.1} s, of which the sequence pairs {:.1} s), {} pairs compared ({:.2} % of the {} of the dense matrix) in {:.1} s",
        thousands(n as u128),
        thousands(stats.candidates as u128),
        opts.neighbours,
        opts.per_pair,
        thousands(stats.pair_candidates as u128),
        stats.index_seconds,
        stats.scan_seconds,
        thousands(stats.pairs as u128),
        100.0 * stats.pairs as f64 / all.max(1) as f64,
        thousands(all),
        stats.pairs_seconds
    ));
    if opts.rerank > 0 && opts.per_pair > 0 {
        notice(format!(
            "each sequence pair's {} best cheap transitions re-ranked by the full measure: {} pairs evaluated",
            opts.rerank,
            thousands(stats.rerank_pairs as u128)
        ));
    }
    if opts.reach > 0 {
        let s = sim.spans.len() as u128;
        notice(format!(
            "sequence pairs scanned: {} of {} (each sequence with the {} it is most linked to); the far search on the other {}: {} centres kept ({} best of {} cheap each), {} pairs evaluated",
            thousands(stats.sequence_pairs as u128),
            thousands(s * (s + 1) / 2),
            opts.reach,
            thousands(stats.far_sequence_pairs as u128),
            thousands(stats.far_candidates as u128),
            opts.far,
            opts.far_rerank.max(opts.far),
            thousands(stats.far_rerank_pairs as u128)
        ));
    }
    let [p_near, p_seq, p_pair] = stats.pairs_by_source.map(|p| thousands(p as u128));
    let [c_index, c_scan, c_pairs] = stats.cpu_seconds;
    notice(format!(
        "candidates: {} nearest overall ({p_near} pairs alone), {} per sequence ({p_seq} pairs alone; {} per sequence among the {} nearest of every {}th frame), {} per sequence pair ({p_pair} pairs alone); CPU s: index {c_index:.1}, sequence-pair scan and re-ranking {c_scan:.1}, full measure {c_pairs:.1}",
        thousands(stats.near_candidates as u128),
        thousands(stats.sequence_candidates as u128),
        opts.per_sequence,
        if opts.pool > 0 && opts.cover > 0 {
            format!(
                "{} (the trees' for sequence pairs linked fewer than {} times)",
                opts.pool, opts.cover
            )
        } else if opts.pool > 0 {
            opts.pool.to_string()
        } else {
            "frames of each sequence".into()
        },
        opts.stride,
        thousands(stats.pair_candidates as u128),
    ));
    let path = sparse_path(dir, measure);
    cache::save_sparse(&path, key, &sim).map_err(|e| DbError::cache_write(dir, e))?;
    Ok((
        Similarity::Sparse(sim),
        key,
        Timing {
            describe_seconds: describe,
            pairs_seconds: t.elapsed().as_secs_f64(),
            pairs: stats.pairs,
            beside_seconds: None,
        },
    ))
}

/// Databases of at least this many frames compute their similarity matrix
/// in about 50 slices of rows, each appended to a checkpoint
/// (`cache/similarity-MEASURE.partial`) as it finishes, so that a killed
/// `db build` resumes from its last finished slice; smaller ones (seconds
/// of work) at once, as before.
pub(crate) const CHECKPOINT_FRAMES: usize = 1024;

/// A `tracing` notice (the CLI prints these as plain lines).
fn notice(msg: String) {
    tracing::info!(target: "surfmotion::notice", "{msg}");
}

/// Every pair of `set` (the upper triangle mirrored): at once below
/// [`CHECKPOINT_FRAMES`], else in checkpointed slices resumed from an
/// earlier run's checkpoint of the same key. The matrix's memory is
/// checked against the budget first, and said up front for large builds,
/// with progress and an estimate of the time left after each tenth.
fn compare_frames(
    dir: &Path,
    path: &Path,
    key: u64,
    set: &dyn PairDistance,
    progress: &dyn BuildProgress,
) -> Result<(Vec<f32>, Option<cache::Checkpoint>), DbError> {
    use crate::similarity::matrix::ROW_BLOCK;
    use crate::util::budget::{Bytes, thousands};
    let n = set.frames();
    let need = (n as u128) * (n as u128) * 4;
    crate::util::budget::check(
        || format!("the similarity matrix of {} frames", thousands(n as u128)),
        need,
    )
    .map_err(|e| DbError::Manifest {
        path: dir.join(super::MANIFEST),
        msg: e.to_string(),
    })?;
    if n < CHECKPOINT_FRAMES {
        progress.start("frames compared", n as u64);
        let data = all_pairs(set, &|k| progress.advance(k));
        progress.finish();
        return Ok((data, None));
    }
    let mut data = vec![0.0f32; n * n];
    let ck_path = cache::partial_path(path);
    let done = cache::resume_rows(&ck_path, key, n, ROW_BLOCK, &mut data);
    let pairs_of = |rows: std::ops::Range<usize>| -> u64 { rows.map(|a| (n - a) as u64).sum() };
    let total = pairs_of(0..n);
    let before = pairs_of(0..done);
    notice(format!(
        "similarity of {} frames: {} pairs; the matrix takes {} of memory (budget {}); checkpointed to {}{}",
        thousands(n as u128),
        thousands(total as u128),
        Bytes(need),
        Bytes(crate::util::budget::Budget::current().bytes as u128),
        ck_path.display(),
        if done > 0 {
            format!(
                "; resumed after row {done} of {n} ({:.0} % of the pairs done by an earlier run)",
                100.0 * before as f64 / total as f64
            )
        } else {
            String::new()
        }
    ));
    let mut ck = cache::Checkpoint::open(&ck_path, key, n, done)
        .map_err(|e| DbError::cache_write(dir, e))?;
    let threads = rayon::current_num_threads().max(1);
    let slice = (n.div_ceil(50).div_ceil(ROW_BLOCK).max(2 * threads)) * ROW_BLOCK;
    progress.start("pairs compared", total - before);
    let t = Instant::now();
    let mut first = done;
    let mut told = (100 * before / total.max(1)) / 10;
    while first < n {
        let end = (first + slice).min(n);
        crate::similarity::upper_rows(set, first, &mut data[first * n..end * n], &|_, p| {
            progress.advance(p)
        });
        ck.append(first, &data[first * n..end * n])
            .map_err(|e| DbError::cache_write(dir, e))?;
        first = end;
        let now = pairs_of(0..first);
        let tenth = (100 * now / total.max(1)) / 10;
        if tenth > told && first < n {
            told = tenth;
            let secs = t.elapsed().as_secs_f64();
            let left = secs / (now - before).max(1) as f64 * (total - now) as f64;
            notice(format!(
                "similarity: {:.0} % of the pairs ({first} of {n} rows) in {secs:.0} s, about {left:.0} s left",
                100.0 * now as f64 / total as f64
            ));
        }
    }
    progress.finish();
    crate::similarity::mirror_upper(&mut data, n);
    Ok((data, Some(ck)))
}

/// The database's per-vertex colours: the manifest's `colors` mesh, else
/// the topology's own (OBJ/PLY vertex colours).
fn vertex_colours(
    dir: &Path,
    m: &Manifest,
    topo: &crate::mesh::Mesh,
) -> Result<Vec<[f64; 3]>, DbError> {
    let err = |msg: String| DbError::Manifest {
        path: dir.join(super::MANIFEST),
        msg,
    };
    let mesh = match &m.colors {
        Some(c) => {
            let p = Manifest::resolve(dir, c);
            crate::mesh::io::load_sequence(&p.to_string_lossy(), &Default::default())?
                .mesh()
                .clone()
        }
        None => topo.clone(),
    };
    let Some(c) = mesh.colors() else {
        return Err(err(
            "the colour measure needs vertex colours: set `colors = \"MESH\"` (an OBJ or PLY with vertex colours) or use a coloured topology".into(),
        ));
    };
    if c.len() != topo.vertex_count() {
        return Err(err(format!(
            "colors: {} vertex colours, the topology has {} vertices",
            c.len(),
            topo.vertex_count()
        )));
    }
    Ok(c.to_vec())
}

/// Rows of a mapped sparse similarity read between two releases of its
/// pages by [`successor_steps`].
const STEP_ROWS: usize = 512;

/// Each frame's dissimilarity to the next frame of its sequence (NaN for
/// a sequence's last frame), the pages of a mapped similarity released
/// every [`STEP_ROWS`] rows so that the pass does not keep the whole file
/// resident.
pub(crate) fn successor_steps(matrix: &Similarity, graph: &SurfaceMotionGraph) -> Vec<f32> {
    let mut steps = vec![f32::NAN; matrix.len()];
    let sparse = match matrix {
        Similarity::Sparse(s) => Some(s),
        Similarity::Dense(_) => None,
    };
    let mut read = 0;
    for q in graph.sequences() {
        for a in q.start..(q.start + q.len).saturating_sub(1) {
            if let Some(v) = steps.get_mut(a) {
                *v = matrix.get(a, a + 1);
            }
            read += 1;
            if read % STEP_ROWS == 0
                && let Some(s) = sparse
            {
                s.release();
            }
        }
    }
    if let Some(s) = sparse {
        s.release();
    }
    steps
}

/// Builds (or loads from the cache) the similarity matrix and the Surface
/// Motion Graph of the database in `dir`.
pub fn build(
    dir: &Path,
    opts: &BuildOptions,
    progress: &dyn BuildProgress,
) -> Result<(Similarity, SurfaceMotionGraph, BuildReport), DbError> {
    build_opened(dir, &Manifest::load(dir)?, opts, progress)
}

/// [`build`] of a database whose manifest `m` is opened already
/// ([`Manifest::load`] or [`Manifest::open`]).
pub(crate) fn build_opened(
    dir: &Path,
    m: &Manifest,
    opts: &BuildOptions,
    progress: &dyn BuildProgress,
) -> Result<(Similarity, SurfaceMotionGraph, BuildReport), DbError> {
    build_opened_staged(dir, m, opts, progress, None).map(|(s, g, r, _)| (s, g, r))
}

/// The graph of `mat` from its cache at `path` when it has `key` and
/// agrees with `mat`, else built and cached; with each frame's step to its
/// successor, read from the same file (a retarget at 10⁴ frames read every
/// row of the 177 MB sparse similarity for them: session 45), or computed
/// and written into it (a cache without them, of session 44 or before, is
/// completed once; that write failing is not an error). True when cached.
fn graph_and_steps(
    dir: &Path,
    (path, key): (&Path, u64),
    mat: &Similarity,
    measure: Measure,
    m: &Manifest,
    force: bool,
) -> Result<(SurfaceMotionGraph, bool, Vec<f32>), DbError> {
    let cached = if force {
        None
    } else {
        read_graph(path)
            .filter(|g| g.key == key)
            .filter(|g| match g.graph.validate(mat) {
                Ok(()) => true,
                Err(why) => {
                    tracing::warn!(
                        "{}: the cached graph disagrees with the database ({why}); rebuilding it",
                        path.display()
                    );
                    false
                }
            })
    };
    if let Some(file) = cached {
        if let Some(steps) = file.steps(mat.len()) {
            return Ok((file.graph, true, steps));
        }
        let steps = successor_steps(mat, &file.graph);
        let written = graph_text(key, &file.graph, &steps)
            .map_err(|e| e.to_string())
            .and_then(|t| write_bytes_atomic(path, t.as_bytes()).map_err(|e| e.to_string()));
        if let Err(e) = written {
            tracing::debug!("{}: steps not added: {e}", path.display());
        }
        return Ok((file.graph, true, steps));
    }
    let g = SurfaceMotionGraph::build(
        mat,
        measure,
        &m.graph.transition_options(),
        &m.graph.edits(),
    )?;
    let steps = successor_steps(mat, &g);
    let text = graph_text(key, &g, &steps).map_err(|e| DbError::Manifest {
        path: path.to_path_buf(),
        msg: e.to_string(),
    })?;
    write_bytes_atomic(path, text.as_bytes()).map_err(|e| DbError::cache_write(dir, e))?;
    Ok((g, false, steps))
}

/// [`build_opened`], its two stages timed into `stages` when given:
/// `similarity` (the keys of the inputs and the similarity read from its
/// cache or built) and `graph` (read and checked, or built); also each
/// frame's step to its successor ([`successor_steps`], kept in the graph
/// cache).
pub(crate) fn build_opened_staged(
    dir: &Path,
    m: &Manifest,
    opts: &BuildOptions,
    progress: &dyn BuildProgress,
    mut stages: Option<&mut Stages>,
) -> Result<(Similarity, SurfaceMotionGraph, BuildReport, Vec<f32>), DbError> {
    if m.sequences.is_empty() {
        return Err(DbError::Manifest {
            path: dir.join(super::MANIFEST),
            msg:
                "no sequences: add [[sequence]] entries (`InitOptions::sequences` of `db::init`: NAME=PATH)"
                    .into(),
        });
    }
    let measure = opts.measure.unwrap_or_else(|| default_measure(m));
    let (mat, sim_key, timing) = similarity_with(
        dir,
        m,
        measure,
        (opts.method, opts.prepare),
        opts.force,
        progress,
    )?;
    if let Some(s) = stages.as_deref_mut() {
        s.lap("similarity");
    }
    let graph_key = graph_key(m, sim_key);
    let gpath = graph_path(dir, measure);
    tracing::debug!("{}: cache key {graph_key:016x}", gpath.display());
    let t = Instant::now();
    let (graph, graph_cached, steps) =
        graph_and_steps(dir, (&gpath, graph_key), &mat, measure, m, opts.force)?;
    let graph_seconds = t.elapsed().as_secs_f64();
    if let Some(s) = stages {
        s.lap("graph");
    }
    let (describe_seconds, pairs_seconds, pairs) = timing
        .map(|t| (t.describe_seconds, t.pairs_seconds, t.pairs))
        .unwrap_or((0.0, 0.0, 0));
    let stored_pairs = match &mat {
        Similarity::Dense(d) => (d.len() as u64) * (d.len() as u64 + 1) / 2,
        Similarity::Sparse(s) => s.stored_pairs() as u64,
    };
    let report = BuildReport {
        measure,
        method: mat.method(),
        unit: measure.unit(),
        frames: mat.len(),
        sequences: mat.spans().to_vec(),
        similarity_cached: timing.is_none(),
        describe_seconds,
        pairs_seconds,
        pairs,
        stored_pairs,
        graph_cached,
        graph_seconds,
        transitions: graph.transitions().len(),
        edges: graph.edges().len(),
        cache: cache_dir(dir),
        // The choice its key was made with (a cache's key vouches for it).
        scan: matches!(mat, Similarity::Sparse(_)).then(|| scan_options(m, mat.len()).1),
        caches_beside_seconds: timing.and_then(|t| t.beside_seconds),
    };
    Ok((mat, graph, report, steps))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// Frames on a line, counting the distances evaluated.
    struct Line(Vec<f64>, AtomicU64);
    impl PairDistance for Line {
        fn frames(&self) -> usize {
            self.0.len()
        }
        fn distance(&self, a: usize, b: usize) -> f64 {
            self.1.fetch_add(1, Ordering::Relaxed);
            (self.0[a] - self.0[b]).abs()
        }
    }

    /// A build killed after some slices resumes from its checkpoint: only
    /// the pairs of the rows left are evaluated, and the matrix equals the
    /// one computed at once.
    #[test]
    fn a_killed_comparison_resumes_from_its_last_slice() {
        let n = CHECKPOINT_FRAMES + 37;
        let line = || Line((0..n).map(|i| (i as f64 * 0.01).sin()).collect(), 0.into());
        let whole = all_pairs(&line(), &|_| {});
        let tmp = tempfile::tempdir().unwrap();
        // In a cache folder that does not exist yet (a first build).
        let path = tmp.path().join("cache/similarity-shape.bin");
        // An uninterrupted checkpointed run.
        let set = line();
        let (data, ck) = compare_frames(tmp.path(), &path, 7, &set, &Quiet).unwrap();
        assert_eq!(data, whole);
        let total = (n * (n + 1) / 2) as u64;
        assert_eq!(set.1.load(Ordering::Relaxed), total);
        // The checkpoint holds every row; "kill" the run after 200 rows by
        // cutting the file there plus a torn half row.
        let ck_path = cache::partial_path(&path);
        let full = std::fs::read(&ck_path).unwrap();
        drop(ck);
        let rows = 200;
        let keep = 24 + (0..rows).map(|a| (n - a) * 4).sum::<usize>();
        std::fs::write(&ck_path, &full[..keep + 2 * (n - rows)]).unwrap();
        let set = line();
        let (data, ck) = compare_frames(tmp.path(), &path, 7, &set, &Quiet).unwrap();
        assert_eq!(data, whole);
        let rest: u64 = (rows..n).map(|a| (n - a) as u64).sum();
        assert_eq!(set.1.load(Ordering::Relaxed), rest);
        assert_eq!(std::fs::read(&ck_path).unwrap(), full);
        ck.unwrap().remove();
        assert!(!ck_path.exists());
        // Another key starts again.
        std::fs::write(&ck_path, &full[..keep]).unwrap();
        let set = line();
        let (data, _) = compare_frames(tmp.path(), &path, 8, &set, &Quiet).unwrap();
        assert_eq!(data, whole);
        assert_eq!(set.1.load(Ordering::Relaxed), total);
    }
}
