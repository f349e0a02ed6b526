//! Transferring mocap clips onto a scan (Confluent Motion, de Aguiar et al.
//! 2007): the scan is repaired, its markers placed and its system factored
//! once ([`ScanTransferJob::prepare`]); each clip is then one marker motion
//! and one transfer ([`ScanTransferJob::run`]). A moving template source is
//! a one-off ([`crate::transfer::Job::new`]).

use super::JobError;
use crate::batch::{ClipWarning, Converted, Converter, Preparation};
use crate::drive::Each;
use crate::drive::query::{ClipQuery, load_mocap, to_character};
use crate::embed::landmarks::Landmarks;
use crate::mesh::Mesh;
use crate::mesh::io::SaveOptions;
use crate::mesh::io::glb::GlbOptions;
use crate::mesh::io::stream::SequenceWriter;
use crate::mesh::io::usd::UsdOptions;
use crate::pose::Pose;
use crate::rig::LoadOptions;
use crate::tools::eval::{Checker, PlausibilityOptions, VelocityError, velocity_error};
use crate::transfer::{
    Confluent, MarkerOptions, MarkerSpec, PreparedScan, TransferOptions, TransferStats,
    mocap_motion, prepare, transfer, transfer_into,
};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::Instant;

/// Options of a [`ScanTransferJob`].
#[derive(Debug, Clone)]
pub struct ScanTransferOptions {
    /// Generated markers. Default: [`MarkerOptions::default`] (180, margin
    /// 0.25).
    pub markers: MarkerOptions,
    /// Output frame rate (clips are resampled). Default: 30.
    pub fps: f64,
    /// The transfer (quaternion signs). Default: consistent signs.
    pub transfer: TransferOptions,
    /// How clips are read. Default: decide from the file.
    pub load: LoadOptions,
    /// GLB output. Default: [`GlbOptions::DEFAULT`].
    pub glb: GlbOptions,
    /// `.usda` output. Default: [`UsdOptions::DEFAULT`] (normals on).
    pub usd: UsdOptions,
}

impl ScanTransferOptions {
    /// Checked options with the defaults but `markers` ([`MarkerOptions::new`]
    /// checks them) and `fps` (a frame rate the CLI accepts,
    /// [`crate::util::budget::is_frame_rate`]).
    pub fn new(markers: MarkerOptions, fps: f64) -> Result<ScanTransferOptions, JobError> {
        use crate::util::budget::{MAX_FPS, MIN_FPS, is_frame_rate};
        if !is_frame_rate(fps) {
            return Err(JobError::Usage(format!(
                "`ScanTransferOptions::fps` {fps}: expected a frame rate in [{MIN_FPS}, {MAX_FPS}]"
            )));
        }
        let markers = MarkerOptions::new(markers.count, markers.margin)
            .map_err(|e| JobError::Usage(e.to_string()))?;
        Ok(ScanTransferOptions {
            markers,
            fps,
            ..ScanTransferOptions::default()
        })
    }
}

impl Default for ScanTransferOptions {
    fn default() -> Self {
        ScanTransferOptions {
            markers: MarkerOptions::default(),
            fps: 30.0,
            transfer: TransferOptions::default(),
            load: LoadOptions::default(),
            glb: GlbOptions::DEFAULT,
            usd: UsdOptions::DEFAULT,
        }
    }
}

/// A scan prepared and factored once for any number of clips.
pub struct ScanTransferJob {
    /// The repaired scan with its markers and rig.
    pub prepared: PreparedScan,
    /// The factored system of the bone markers.
    pub confluent: Confluent,
    /// The options.
    pub options: ScanTransferOptions,
    /// What the job is, for reports (`transfer onto SCAN`).
    pub what: String,
    /// Seconds repairing, placing markers and factoring (once).
    prepare_seconds: f64,
    /// The plausibility checker of the scan (built on first use; `None`
    /// without a rig or when the checks cannot run), as `transfer`
    /// measures its result.
    checker: OnceLock<Option<Checker>>,
}

/// One clip transferred.
pub struct ScanTransferRun {
    /// The clip as read.
    pub mocap: ClipQuery,
    /// Positions, frame-major (the scan's units).
    pub positions: Vec<[f64; 3]>,
    /// What the transfer did.
    pub stats: TransferStats,
}

impl ScanTransferJob {
    /// Repairs `scan`, places markers from `landmarks` and factors the
    /// system once; `name` names the scan in reports.
    pub fn prepare(
        scan: &Mesh,
        landmarks: &Landmarks,
        name: &str,
        options: ScanTransferOptions,
    ) -> Result<ScanTransferJob, JobError> {
        let t = Instant::now();
        let prepared = prepare(scan, MarkerSpec::Landmarks(landmarks, options.markers))?;
        let (confluent, _) = crate::transfer::Job::factor_mocap(&prepared)?;
        Ok(ScanTransferJob {
            prepared,
            confluent,
            options,
            what: format!("transfer onto {name}"),
            prepare_seconds: t.elapsed().as_secs_f64(),
            checker: OnceLock::new(),
        })
    }

    /// The scan's plausibility checker, built once: against the scan's
    /// rest frame (floor: its lowest point), in metres guessed from the
    /// rig's height, as `transfer` measures its result.
    fn checker(&self) -> Option<&Checker> {
        self.checker
            .get_or_init(|| {
                let rig = self.prepared.rig.as_ref()?;
                let up = crate::transfer::up_axis(rig);
                let opts = PlausibilityOptions::default();
                Checker::new(&self.prepared.mesh, rig, up, None, self.options.fps, opts)
                    .map(|mut c| {
                        c.metres_per_unit = guess_metres_per_unit(rig.height);
                        c
                    })
                    .map_err(|e| tracing::warn!("plausibility not measured: {e}"))
                    .ok()
            })
            .as_ref()
    }

    /// Transfers the clip at `clip` onto the scan.
    pub fn run(&self, clip: &Path) -> Result<ScanTransferRun, JobError> {
        let mocap = load_mocap(clip, &self.options.load, self.options.fps)?;
        if mocap.poses.is_empty() {
            return Err(JobError::Input {
                path: clip.to_path_buf(),
                msg: "the clip has no frames".into(),
            });
        }
        // Every output frame is held: refuse what cannot fit before
        // anything is allocated ([`Converter::convert`] streams instead).
        crate::util::budget::check_frames(
            "the transfer",
            mocap.poses.len(),
            self.prepared.mesh.vertex_count(),
            1,
        )?;
        let mut motion = mocap_motion(&self.prepared, &mocap.poses, &mocap.reference)?;
        motion.set_fps(self.options.fps);
        let (positions, stats) = transfer(
            &self.confluent,
            &mut motion,
            &self.options.transfer,
            &|_| {},
        );
        Ok(ScanTransferRun {
            mocap,
            positions,
            stats,
        })
    }

    /// The joint-velocity error of a result against its clip (on the
    /// scan's embedded skeleton); `None` without a rig.
    pub fn velocity_error(&self, run: &ScanTransferRun) -> Option<VelocityError> {
        let rig = self.prepared.rig.as_ref()?;
        let n = self.prepared.mesh.vertex_count();
        let rest: Pose = rig.joints.map(glam::DVec3::from_array);
        let query = to_character(&rest, &run.mocap.reference, &run.mocap.poses);
        let skel: Vec<Pose> = run
            .positions
            .chunks(n.max(1))
            .map(|p| rig.frame_joints(p))
            .collect();
        Some(velocity_error(&query, &skel))
    }

    /// Writes `positions` (the repaired scan's vertices, frame-major) to
    /// `out` (by extension); returns the files written.
    pub fn write(&self, positions: Vec<[f64; 3]>, out: &Path) -> Result<Vec<PathBuf>, JobError> {
        super::write_positions(
            self.prepared.mesh.clone(),
            positions,
            self.options.fps,
            self.options.glb,
            self.options.usd,
            out,
        )
    }
}

impl Converter for ScanTransferJob {
    fn describe(&self) -> String {
        self.what.clone()
    }

    /// Streams the frames to `out` as they are solved ([`transfer_into`]
    /// a [`SequenceWriter`]): a clip of any length converts with the
    /// memory of its marker motion and one chunk of frames (issue 18, item
    /// 12); only a GLB, written whole, is checked against the budget. The
    /// first frames are kept for the plausibility measure, whose warnings
    /// the report records as `transfer` prints them (issue 39: they were
    /// dropped).
    fn convert(&self, clip: &Path, out: &Path) -> Result<Converted, String> {
        let t0 = Instant::now();
        let msg = |e: JobError| match e {
            JobError::Input { msg, .. } => msg,
            e => e.to_string(),
        };
        let rig = self.prepared.rig.as_ref().ok_or("no rig")?;
        let mocap =
            load_mocap(clip, &self.options.load, self.options.fps).map_err(|e| msg(e.into()))?;
        if mocap.poses.is_empty() {
            return Err("the clip has no frames".into());
        }
        let mut motion = mocap_motion(&self.prepared, &mocap.poses, &mocap.reference)
            .map_err(|e| msg(e.into()))?;
        motion.set_fps(self.options.fps);
        let fps = self.options.fps;
        let mut writer = SequenceWriter::create(
            &self.prepared.mesh,
            out,
            motion.frames(),
            &SaveOptions {
                fps: Some(fps),
                glb: self.options.glb,
                usd: self.options.usd,
            },
        )
        .map_err(|e| e.to_string())?;
        let n = self.prepared.mesh.vertex_count();
        let keep_bytes =
            PLAUSIBILITY_BYTES.min((crate::util::budget::Budget::current().bytes / 8) as usize);
        let keep = (keep_bytes / (24 * n.max(1))).clamp(1, motion.frames().max(1));
        let mut kept: Vec<[f64; 3]> = Vec::with_capacity(keep * n);
        let mut skel: Vec<Pose> = Vec::with_capacity(motion.frames());
        let mut sink_seconds = 0.0;
        let stats = transfer_into(
            &self.confluent,
            &mut motion,
            &self.options.transfer,
            &|_| {},
            Each(|p: &[[f64; 3]]| {
                let t = Instant::now();
                if skel.len() < keep {
                    kept.extend_from_slice(p);
                }
                skel.push(rig.frame_joints(p));
                let r = writer.push(p);
                sink_seconds += t.elapsed().as_secs_f64();
                r
            }),
        )
        .map_err(|e| e.to_string())?;
        let t = Instant::now();
        writer.finish().map_err(|e| e.to_string())?;
        sink_seconds += t.elapsed().as_secs_f64();
        let rest: Pose = rig.joints.map(glam::DVec3::from_array);
        let query = to_character(&rest, &mocap.reference, &mocap.poses);
        let checks = Instant::now();
        let warnings = self
            .checker()
            .and_then(|c| {
                let opts = c.opts;
                c.measure(&kept, n, None)
                    .map(|p| {
                        p.with_clip_head(
                            &crate::pose::retarget::clip_head_trunk_deg(
                                &mocap.reference,
                                &mocap.poses,
                            ),
                            &opts.limits,
                        )
                        .logged()
                    })
                    .map_err(|e| tracing::warn!("plausibility not measured: {e}"))
                    .ok()
            })
            .map(|p| ClipWarning::of(&p))
            .unwrap_or_default();
        let per_frame = stats.solve_seconds + sink_seconds + checks.elapsed().as_secs_f64();
        Ok(Converted {
            frames: stats.frames,
            error_cm: Some(velocity_error(&query, &skel).mean_cm),
            warnings,
            fixed_seconds: Some((t0.elapsed().as_secs_f64() - per_frame).max(0.0)),
        })
    }

    fn preparation(&self) -> Preparation {
        Preparation {
            factorisations: 1,
            seconds: self.prepare_seconds,
        }
    }
}

/// What drives a [`transfer_onto_scan`] job.
#[derive(Debug, Clone)]
pub enum TransferSource {
    /// A mocap clip (BVH, AMC), resampled to [`ScanTransferOptions::fps`].
    Mocap(PathBuf),
    /// A moving template mesh sequence (played at its own frame rate, else
    /// [`ScanTransferOptions::fps`]).
    Template {
        /// The template sequence (a mesh-sequence spec).
        spec: String,
        /// Its markers (a marker file); else generated from `landmarks`.
        markers: Option<PathBuf>,
        /// Its landmarks; default: the scan's landmarks when the template
        /// has the scan's topology.
        landmarks: Option<PathBuf>,
        /// Its reference frame (the one matching the scan's pose). Default 0.
        frame: usize,
    },
}

/// A one-off transfer onto a scan (the `transfer` verb): where the scan's
/// markers come from, the source, and what to measure.
#[derive(Debug, Clone)]
pub struct TransferSpec {
    /// The scan's name in messages (its spec as given).
    pub scan_name: String,
    /// The scan's landmarks (generated markers and the embedded rig).
    /// Without them and without `markers`: found automatically
    /// ([`AutoScanLandmarks`]).
    pub landmarks: Option<PathBuf>,
    /// The automatic landmarks, when neither `landmarks` nor `markers`
    /// are given.
    pub automatic: AutoScanLandmarks,
    /// A marker file for the scan (takes precedence over generated ones).
    pub markers: Option<PathBuf>,
    /// Save the scan's markers to this file.
    pub save_markers: Option<PathBuf>,
    /// What drives the scan.
    pub source: TransferSource,
    /// A ground-truth sequence on the scan's vertices to measure against.
    pub truth: Option<String>,
    /// Markers, frame rate, signs, clip reading and GLB output.
    pub options: ScanTransferOptions,
}

/// The scan's landmarks found from its geometry (issue 41,
/// [`crate::embed::scan_landmarks`]) when no landmark or marker file is
/// given.
#[derive(Debug, Clone)]
pub struct AutoScanLandmarks {
    /// Refused below this confidence (0..1). Default 0.5 (the CLI's
    /// `--min-confidence`).
    pub min_confidence: f64,
    /// Write them as a landmark file (to edit and give back). Default: no.
    pub write: Option<PathBuf>,
}

impl Default for AutoScanLandmarks {
    fn default() -> Self {
        AutoScanLandmarks {
            min_confidence: crate::embed::scan_landmarks::ScanOptions::default().min_confidence,
            write: None,
        }
    }
}

impl AutoScanLandmarks {
    /// Checked options: `min_confidence` in [0, 1].
    pub fn new(min_confidence: f64, write: Option<PathBuf>) -> Result<AutoScanLandmarks, JobError> {
        if !(0.0..=1.0).contains(&min_confidence) {
            return Err(JobError::Usage(format!(
                "`AutoScanLandmarks::min_confidence` {min_confidence}: expected 0 to 1"
            )));
        }
        Ok(AutoScanLandmarks {
            min_confidence,
            write,
        })
    }
}

/// The automatic landmarks of `scan` (named `name`) as `o` says, written
/// if asked.
fn automatic_landmarks(
    scan: &Mesh,
    name: &str,
    o: &AutoScanLandmarks,
) -> Result<crate::embed::scan_landmarks::AutoLandmarks, JobError> {
    use crate::embed::scan_landmarks::{ScanOptions, find};
    let opts = ScanOptions {
        min_confidence: o.min_confidence,
    };
    let a = find(scan.positions(), scan.triangles(), &opts).map_err(|e| JobError::Input {
        path: PathBuf::from(name),
        msg: e.to_string(),
    })?;
    if let Some(p) = &o.write {
        let text = a.to_json();
        crate::util::fsutil::write_atomic(p, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    }
    Ok(a)
}

/// The vertex error against a ground truth (% of the scan's height), as
/// reported.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TruthError {
    /// Mean over frames and vertices.
    pub mean_pct: f64,
    /// 95th percentile.
    pub p95_pct: f64,
    /// Largest.
    pub max_pct: f64,
    /// Mean per frame (only in the full report).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub per_frame_pct: Option<Vec<f64>>,
}

/// A transfer computed by [`transfer_onto_scan`], not yet written.
pub struct TransferOutcome {
    /// The repaired scan with its markers and rig.
    pub prepared: PreparedScan,
    /// Positions, frame-major (the repaired scan's vertices).
    pub positions: Vec<[f64; 3]>,
    /// Frame rate of the result.
    pub fps: f64,
    /// Frames of the result.
    pub frames: usize,
    /// The source, for messages.
    pub what: String,
    /// Names of the markers used.
    pub used: Vec<String>,
    /// Scan markers without a counterpart in the source.
    pub unpaired: usize,
    /// What the transfer did.
    pub stats: TransferStats,
    /// Error against the ground truth, when one was given.
    pub truth_error: Option<crate::tools::eval::VertexError>,
    /// Metres per scan unit assumed for the plausibility measure.
    pub metres_per_unit: Option<f64>,
    /// Plausibility against the scan's rest frame (with a rig).
    pub plausibility: Option<crate::tools::eval::Plausibility>,
    /// Seconds from the start to the factorisation.
    pub setup_seconds: f64,
    /// Seconds to set up the job (factor the system, build the motion).
    pub factor_seconds: f64,
    /// The automatic landmarks, when neither landmarks nor markers were
    /// given.
    pub automatic_landmarks: Option<crate::embed::scan_landmarks::AutoLandmarks>,
}

/// The report of a transfer written by [`TransferOutcome::write`] (keys
/// as the `transfer` verb's `--json` and `--report`).
#[derive(serde::Serialize)]
pub struct TransferReport {
    /// Files written.
    pub output: Vec<PathBuf>,
    /// The source.
    pub source: String,
    /// Frames.
    pub frames: usize,
    /// Frame rate.
    pub fps: f64,
    /// Vertices of the repaired scan.
    pub vertices: usize,
    /// Triangles of the repaired scan.
    pub triangles: usize,
    /// Markers used.
    pub markers: usize,
    /// Scan markers without a counterpart.
    pub unpaired_markers: usize,
    /// What the repair of the scan did.
    pub scan: crate::transfer::scan::ScanReport,
    /// What the transfer did.
    pub transfer: TransferStats,
    /// Seconds of setup.
    pub setup_seconds: f64,
    /// Seconds to factor.
    pub factor_seconds: f64,
    /// Milliseconds per frame of the solve.
    pub ms_per_frame: f64,
    /// Frames per second of the solve.
    pub frames_per_second: f64,
    /// Error against the ground truth.
    pub truth_error: Option<TruthError>,
    /// Names of the markers used.
    pub markers_used: Vec<String>,
    /// Metres per scan unit assumed.
    pub metres_per_unit_assumed: Option<f64>,
    /// Plausibility of the result.
    pub plausibility: Option<crate::tools::eval::Plausibility>,
    /// The automatic landmarks used (none given).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub automatic_landmarks: Option<crate::embed::scan_landmarks::AutoLandmarks>,
}

/// Metres per unit of a scan whose rig is `height` units tall, assuming a
/// person of 0.5-2.5 m: 1 (m), 0.1 (dm), 0.01 (cm) or 0.001 (mm).
fn guess_metres_per_unit(height: f64) -> f64 {
    [1.0, 0.1, 0.01, 0.001]
        .into_iter()
        .find(|m| (0.5..=2.5).contains(&(height * m)))
        .unwrap_or(1.0)
}

fn context(what: String) -> impl FnOnce(JobError) -> JobError {
    move |e| JobError::Context {
        what,
        source: Box::new(e),
    }
}

/// Progress of the solve of a [`transfer_onto_scan`] job.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameProgress {
    /// Frames solved so far.
    pub done: usize,
    /// Frames to solve in all (known once the source is read).
    pub total: usize,
}

/// Animates `scan` from `spec.source` (Confluent Motion, de Aguiar et al.
/// 2007, Sec. 4): prepares the scan, pairs its markers with the source's,
/// factors once and solves every frame (`progress` is called once per
/// frame solved, from any thread, with the frames done and the total);
/// measures the result against `spec.truth` and its plausibility. Write the
/// result with [`TransferOutcome::write`].
pub fn transfer_onto_scan(
    scan: &Mesh,
    spec: &TransferSpec,
    progress: &(dyn Fn(FrameProgress) + Sync),
) -> Result<TransferOutcome, JobError> {
    Ok(transfer_inner(scan, spec, progress, None)?.0)
}

/// Frames of a streamed transfer kept for its plausibility measure, in
/// bytes of positions (the first frames up to this size, and up to a
/// quarter of the memory budget, are measured).
pub(crate) const PLAUSIBILITY_BYTES: usize = 256 << 20;

/// [`transfer_onto_scan`] writing each frame to `out` as it is solved
/// (GLB options `glb`, USD options `usd`), so a clip of any length needs the memory of its
/// marker motion and one chunk of frames, not of every frame (issue 18,
/// item 12): point caches and OBJ folders stream; a GLB, written whole, is
/// checked against the memory budget and its format's size before the
/// first frame. The plausibility is measured on the first frames, up to
/// [`PLAUSIBILITY_BYTES`] of positions (the report says how many). A
/// ground truth (`spec.truth`) needs every frame held: use
/// [`transfer_onto_scan`].
pub fn transfer_onto_scan_to(
    scan: &Mesh,
    spec: &TransferSpec,
    out: &Path,
    glb: GlbOptions,
    usd: UsdOptions,
    per_frame: bool,
    progress: &(dyn Fn(FrameProgress) + Sync),
) -> Result<TransferReport, JobError> {
    if spec.truth.is_some() {
        return Err(JobError::Usage(
            "a ground truth needs every frame held: use transfer_onto_scan".into(),
        ));
    }
    let (outcome, output) = transfer_inner(scan, spec, progress, Some((out, glb, usd)))?;
    Ok(outcome.report(output.unwrap_or_default(), per_frame))
}

/// The transfer: frames held in the outcome (`stream` `None`), or written
/// to `stream`'s path as they are solved (the files written returned).
/// Steps: the scan's marks, the prepared scan, the driving source, the job
/// (factored once), the solve, the truth error, the plausibility.
fn transfer_inner(
    scan: &Mesh,
    spec: &TransferSpec,
    progress: &(dyn Fn(FrameProgress) + Sync),
    stream: Option<(&Path, GlbOptions, UsdOptions)>,
) -> Result<(TransferOutcome, Option<Vec<PathBuf>>), JobError> {
    let t0 = std::time::Instant::now();
    let marks = scan_marks(scan, spec)?;
    let prepared = prepare_scan(scan, spec, &marks)?;
    let height = scan_height(&prepared);
    let driving = load_driving(scan, spec, &prepared)?;
    let t_setup = std::time::Instant::now();
    let mut job = crate::transfer::Job::new(&prepared, driving.source())?;
    let factor_seconds = t_setup.elapsed().as_secs_f64();
    let frames = job.motion.frames();
    let fps = driving.fps;
    let progress = &|done| {
        progress(FrameProgress {
            done,
            total: frames,
        })
    };
    let (positions, stats, output) = solve(&mut job, &prepared, spec, fps, progress, stream)?;
    let truth_error = truth_error(spec, &prepared, &positions, height)?;
    let (metres_per_unit, plausibility) =
        plausibility(&prepared, &positions, fps, driving.clip_head.as_deref());
    let outcome = TransferOutcome {
        used: std::mem::take(&mut job.used),
        unpaired: job.unpaired,
        prepared,
        positions,
        fps,
        frames,
        what: driving.what,
        stats,
        truth_error,
        metres_per_unit,
        plausibility,
        setup_seconds: t_setup.duration_since(t0).as_secs_f64(),
        factor_seconds,
        automatic_landmarks: marks.automatic,
    };
    Ok((outcome, output))
}

/// The scan's marks as a [`TransferSpec`] gives them: a marker file, its
/// landmarks (from a file or, without either, found automatically).
struct ScanMarks {
    file: Option<crate::transfer::MarkerFile>,
    landmarks: Option<Landmarks>,
    automatic: Option<crate::embed::scan_landmarks::AutoLandmarks>,
}

/// Reads the scan's marker file and landmarks, or finds its landmarks.
fn scan_marks(scan: &Mesh, spec: &TransferSpec) -> Result<ScanMarks, JobError> {
    use crate::transfer::MarkerFile;
    let file = match &spec.markers {
        Some(p) => Some(MarkerFile::load(p, scan.triangle_count())?),
        None => None,
    };
    let mut automatic = None;
    let landmarks = match &spec.landmarks {
        Some(p) => Some(Landmarks::load(p, scan.vertex_count())?),
        None if file.is_none() => {
            let a = automatic_landmarks(scan, &spec.scan_name, &spec.automatic)?;
            let l = a.landmarks();
            automatic = Some(a);
            Some(l)
        }
        None => None,
    };
    Ok(ScanMarks {
        file,
        landmarks,
        automatic,
    })
}

/// The scan repaired with its markers (and rig), its markers saved if
/// asked.
fn prepare_scan(
    scan: &Mesh,
    spec: &TransferSpec,
    marks: &ScanMarks,
) -> Result<PreparedScan, JobError> {
    use crate::transfer::MarkerFile;
    let mopts = spec.options.markers;
    // Errors of the preparation (a flat or face-less mesh, markers of
    // another mesh) name the files they came from.
    let prepared = match (&marks.file, &marks.landmarks) {
        (Some(f), l) => prepare(scan, MarkerSpec::File(f, l.as_ref()))
            .map_err(JobError::from)
            .map_err(context(format!(
                "{} with markers {}",
                spec.scan_name,
                spec.markers.as_deref().unwrap_or(Path::new("?")).display()
            )))?,
        (None, Some(l)) => prepare(scan, MarkerSpec::Landmarks(l, mopts))
            .map_err(JobError::from)
            .map_err(context(format!(
                "{} with landmarks {}",
                spec.scan_name,
                spec.landmarks
                    .as_deref()
                    .unwrap_or(Path::new("(automatic)"))
                    .display()
            )))?,
        (None, None) => {
            return Err(JobError::Usage(
                "give `TransferSpec::landmarks` or `TransferSpec::markers`".into(),
            ));
        }
    };
    if let Some(p) = &spec.save_markers {
        MarkerFile {
            triangle_count: Some(prepared.mesh.triangle_count()),
            markers: prepared.markers.clone(),
        }
        .save(p)?;
    }
    Ok(prepared)
}

/// The scan's height: its rig's, else its bounds' largest side.
fn scan_height(prepared: &PreparedScan) -> f64 {
    match &prepared.rig {
        Some(r) => r.height,
        None => {
            let b = prepared.mesh.bounds();
            (0..3).map(|k| b.max[k] - b.min[k]).fold(0.0, f64::max)
        }
    }
}

/// What drives the scan, read and owned (a [`crate::transfer::Driving`]
/// borrows it).
enum OwnedDriving {
    /// A clip's canonical poses.
    Mocap(Box<ClipQuery>),
    /// A template sequence with its markers.
    Template {
        frames: crate::mesh::MeshSequence,
        markers: Vec<crate::transfer::Marker>,
        reference: usize,
        align: glam::DQuat,
    },
}

/// The driving source read, its frame rate, its description and (a clip)
/// its own head-to-trunk angles.
struct LoadedDriving {
    driving: OwnedDriving,
    fps: f64,
    what: String,
    /// The driving clip's own head-to-trunk angles: its head line
    /// (Plausibility::with_clip_head), as in retarget, eval and synth.
    clip_head: Option<Vec<f64>>,
}

impl LoadedDriving {
    fn source(&self) -> crate::transfer::Driving<'_> {
        use crate::transfer::Driving;
        match &self.driving {
            OwnedDriving::Mocap(clip) => Driving::Mocap(&clip.poses, &clip.reference),
            OwnedDriving::Template {
                frames,
                markers,
                reference,
                align,
            } => Driving::Template {
                frames,
                markers,
                reference: *reference,
                align: *align,
            },
        }
    }
}

/// Reads `spec.source`: a clip (refused without frames) or a template
/// sequence with its markers.
fn load_driving(
    scan: &Mesh,
    spec: &TransferSpec,
    prepared: &PreparedScan,
) -> Result<LoadedDriving, JobError> {
    match &spec.source {
        TransferSource::Mocap(m) => {
            let clip = load_mocap(m, &spec.options.load, spec.options.fps)?;
            if clip.poses.is_empty() {
                return Err(JobError::Input {
                    path: m.clone(),
                    msg: "the clip has no frames".into(),
                });
            }
            let clip_head = Some(crate::pose::retarget::clip_head_trunk_deg(
                &clip.reference,
                &clip.poses,
            ));
            let what = format!("{} ({} rig)", m.display(), clip.convention);
            Ok(LoadedDriving {
                driving: OwnedDriving::Mocap(Box::new(clip)),
                fps: spec.options.fps,
                what,
                clip_head,
            })
        }
        TransferSource::Template {
            spec: tspec,
            markers,
            landmarks,
            frame,
        } => load_template(
            scan,
            spec,
            prepared,
            tspec,
            markers.as_deref(),
            landmarks.as_deref(),
            *frame,
        ),
    }
}

/// Reads a template sequence and its markers (from a marker file, else
/// generated from its landmarks' rig, aligned to the scan's rig).
fn load_template(
    scan: &Mesh,
    spec: &TransferSpec,
    prepared: &PreparedScan,
    tspec: &str,
    markers: Option<&Path>,
    landmarks: Option<&Path>,
    frame: usize,
) -> Result<LoadedDriving, JobError> {
    use crate::mesh::io::{LoadOptions as SeqLoad, load_sequence};
    use crate::transfer::MarkerFile;
    let mut align = glam::DQuat::IDENTITY;
    let template = load_sequence(tspec, &SeqLoad::default())?;
    // The range first: a frame past the end used to reach the
    // landmark check on the last frame and fail there.
    if frame >= template.frame_count() {
        return Err(JobError::Input {
            path: tspec.into(),
            msg: format!(
                "`TransferSource::Template` frame {frame} is past the end: the template has {} (0..={})",
                crate::batch::summary::count(template.frame_count(), "frame"),
                template.frame_count().saturating_sub(1)
            ),
        });
    }
    let tmesh = template.frame_mesh(frame);
    let template_markers = if let Some(p) = markers {
        MarkerFile::load(p, tmesh.triangle_count())?.markers
    } else {
        let tl = match (landmarks, &spec.landmarks) {
            (Some(p), _) => Landmarks::load(p, tmesh.vertex_count())?,
            (None, Some(p))
                if tmesh.vertex_count() == scan.vertex_count()
                    && tmesh.triangles() == scan.triangles() =>
            {
                Landmarks::load(p, tmesh.vertex_count())?
            }
            _ => {
                return Err(JobError::Usage(
                    "the template needs markers: give the `TransferSource::Template` markers or landmarks"
                        .into(),
                ));
            }
        };
        let rig = crate::embed::Embedding::new(&tmesh, &tl, None)?;
        if let Some(scan_rig) = &prepared.rig {
            align = crate::transfer::alignment(&rig, scan_rig);
        }
        crate::transfer::markers::generate(&tmesh, &rig, &spec.options.markers)
    };
    let fps = template.fps.unwrap_or(spec.options.fps);
    Ok(LoadedDriving {
        driving: OwnedDriving::Template {
            frames: template,
            markers: template_markers,
            reference: frame,
            align,
        },
        fps,
        what: tspec.to_string(),
        clip_head: None,
    })
}

/// What [`solve`] returns: the positions (held or kept), what the
/// transfer did, the files written (streamed).
type Solved = (Vec<[f64; 3]>, TransferStats, Option<Vec<PathBuf>>);

/// Solves every frame: held (checked against the memory budget first), or
/// written to `stream` as solved with the first frames kept for the
/// plausibility measure. Returns the positions (held or kept), what the
/// transfer did and the files written (streamed).
fn solve(
    job: &mut crate::transfer::Job,
    prepared: &PreparedScan,
    spec: &TransferSpec,
    fps: f64,
    progress: &(dyn Fn(usize) + Sync),
    stream: Option<(&Path, GlbOptions, UsdOptions)>,
) -> Result<Solved, JobError> {
    let frames = job.motion.frames();
    let n = prepared.mesh.vertex_count();
    Ok(match stream {
        None => {
            // Every output frame is held: refuse what cannot fit before
            // anything is allocated (issue 18, item 12).
            crate::util::budget::check_frames("the transfer", frames, n, 1)?;
            let (positions, stats) = transfer(
                &job.confluent,
                &mut job.motion,
                &spec.options.transfer,
                progress,
            );
            (positions, stats, None)
        }
        Some((out, glb, usd)) => {
            let mut writer = SequenceWriter::create(
                &prepared.mesh,
                out,
                frames,
                &SaveOptions {
                    fps: Some(fps),
                    glb,
                    usd,
                },
            )?;
            // The first frames, for the plausibility measure.
            let keep_bytes =
                PLAUSIBILITY_BYTES.min((crate::util::budget::Budget::current().bytes / 4) as usize);
            let keep = (keep_bytes / (24 * n.max(1))).clamp(1, frames);
            let mut kept = Vec::with_capacity(keep * n);
            let stats = transfer_into(
                &job.confluent,
                &mut job.motion,
                &spec.options.transfer,
                progress,
                Each(|p: &[[f64; 3]]| {
                    if kept.len() < keep * n {
                        kept.extend_from_slice(p);
                    }
                    writer.push(p)
                }),
            )?;
            if keep < frames {
                tracing::info!(
                    "plausibility measured on the first {keep} of {frames} frames (streamed output)"
                );
            }
            (kept, stats, Some(writer.finish()?))
        }
    })
}

/// The vertex error against `spec.truth` (% of `height`), if given.
fn truth_error(
    spec: &TransferSpec,
    prepared: &PreparedScan,
    positions: &[[f64; 3]],
    height: f64,
) -> Result<Option<crate::tools::eval::VertexError>, JobError> {
    use crate::mesh::io::{LoadOptions as SeqLoad, load_sequence};
    Ok(match &spec.truth {
        Some(tspec) => {
            let t = load_sequence(tspec, &SeqLoad::default())?;
            if t.mesh().vertex_count() != prepared.mesh.vertex_count() {
                return Err(JobError::Input {
                    path: tspec.into(),
                    msg: format!(
                        "{} vertices, the (repaired) scan has {}",
                        t.mesh().vertex_count(),
                        prepared.mesh.vertex_count()
                    ),
                });
            }
            Some(crate::tools::eval::vertex_error(
                positions,
                t.all_positions(),
                prepared.mesh.vertex_count(),
                height,
            ))
        }
        None => None,
    })
}

/// Plausibility against the scan's rest frame (floor: its lowest point),
/// with the metres per unit assumed; `None` without a rig or when it cannot
/// be measured (logged).
fn plausibility(
    prepared: &PreparedScan,
    positions: &[[f64; 3]],
    fps: f64,
    clip_head: Option<&[f64]>,
) -> (Option<f64>, Option<crate::tools::eval::Plausibility>) {
    let mut metres_per_unit = None;
    let plausibility = prepared.rig.as_ref().and_then(|rig| {
        let mpu = guess_metres_per_unit(rig.height);
        metres_per_unit = Some(mpu);
        let rest = prepared.mesh.positions();
        // The axis the scan stands along, as the transfer stood it.
        let up = crate::transfer::up_axis(rig);
        let opts = crate::tools::eval::PlausibilityOptions::default();
        crate::tools::eval::Checker::new(&prepared.mesh, rig, up, None, fps, opts)
            .and_then(|mut c| {
                c.metres_per_unit = mpu;
                c.measure(positions, rest.len(), None)
            })
            .map(|p| match clip_head {
                Some(h) => p.with_clip_head(h, &opts.limits),
                None => p,
            })
            .map(crate::tools::eval::Plausibility::logged)
            .map_err(|e| tracing::warn!("plausibility not measured: {e}"))
            .ok()
    });
    (metres_per_unit, plausibility)
}

impl TransferOutcome {
    /// Writes the result to `out` (by extension, GLB options `glb`, USD
    /// options `usd`) and
    /// returns its report; `per_frame` keeps the per-frame truth error.
    pub fn write(
        mut self,
        out: &Path,
        glb: GlbOptions,
        usd: UsdOptions,
        per_frame: bool,
    ) -> Result<TransferReport, JobError> {
        let output = super::write_positions(
            self.prepared.mesh.clone(),
            std::mem::take(&mut self.positions),
            self.fps,
            glb,
            usd,
            out,
        )?;
        Ok(self.report(output, per_frame))
    }

    /// The report of the outcome written to `output`.
    fn report(self, output: Vec<PathBuf>, per_frame: bool) -> TransferReport {
        let frames = self.frames;
        let ms_per_frame = 1e3 * self.stats.solve_seconds / frames.max(1) as f64;
        TransferReport {
            output,
            source: self.what,
            frames,
            fps: self.fps,
            vertices: self.prepared.mesh.vertex_count(),
            triangles: self.prepared.mesh.triangle_count(),
            markers: self.used.len(),
            unpaired_markers: self.unpaired,
            scan: self.prepared.report,
            transfer: self.stats,
            setup_seconds: self.setup_seconds,
            factor_seconds: self.factor_seconds,
            ms_per_frame,
            frames_per_second: 1e3 / ms_per_frame.max(1e-12),
            truth_error: self.truth_error.map(|e| TruthError {
                mean_pct: e.mean_pct,
                p95_pct: e.p95_pct,
                max_pct: e.max_pct,
                per_frame_pct: per_frame.then_some(e.per_frame),
            }),
            markers_used: self.used,
            metres_per_unit_assumed: self.metres_per_unit,
            plausibility: self.plausibility,
            automatic_landmarks: self.automatic_landmarks,
        }
    }
}

impl TransferOutcome {
    /// Draws the contact sheet of the result to `path`: each panel faced
    /// from its own body (`render`'s rule) on its floor when the scan
    /// stands Y-up, else faced by the rig's rest facing.
    pub fn write_preview(
        &self,
        path: &Path,
        opts: &crate::tools::render::preview::PreviewOptions,
    ) -> Result<(), JobError> {
        let prepared = &self.prepared;
        let up = prepared.rig.as_ref().map(crate::transfer::up_axis);
        let y_up = up.is_none_or(|u| u == glam::DVec3::Y);
        crate::tools::render::preview::write_preview(
            path,
            &self.positions,
            prepared.mesh.vertex_count(),
            prepared.mesh.triangles(),
            prepared.rig.as_ref(),
            prepared
                .rig
                .as_ref()
                .filter(|_| !y_up)
                .map(|r| glam::DVec3::from_array(r.facing)),
            self.plausibility
                .as_ref()
                .filter(|_| y_up)
                .map(|p| p.floor_m / self.metres_per_unit.unwrap_or(1.0)),
            opts,
        )?;
        Ok(())
    }
}

impl TransferReport {
    /// The report `transfer --json` prints: without the markers used and
    /// the per-frame truth error (the `--report` file keeps them).
    pub fn short_json(&self) -> Result<serde_json::Value, JobError> {
        let mut short = serde_json::to_value(self)?;
        short.as_object_mut().map(|o| o.remove("markers_used"));
        if let Some(t) = short.get_mut("truth_error").and_then(|t| t.as_object_mut()) {
            t.remove("per_frame_pct");
        }
        Ok(short)
    }
}
