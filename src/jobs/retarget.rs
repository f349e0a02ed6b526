//! Retargeting a clip through a database (Huang et al. 2015, Sec. 5.2):
//! load the character once ([`RetargetJob::load`]), then any number of
//! clips ([`RetargetJob::run`]); each result can be scored (Sec. 6.2,
//! [`RetargetRun::velocity_error`]), checked for plausibility and written.

use super::JobError;
use crate::batch::summary::count;
use crate::batch::{Converted, Converter, Preparation};
use crate::db::{BuildProgress, Character, CharacterOptions};
use crate::deform::{DeformMode, TurnedOver};
use crate::drive::query::{ClipQuery, database_floor_lift, load_mocap};
use crate::drive::{Analysed, DriveOptions, Each, Output, Prepared, Report, Timings};
use crate::mesh::io::SaveOptions;
use crate::mesh::io::glb::GlbOptions;
use crate::mesh::io::stream::SequenceWriter;
use crate::mesh::io::usd::UsdOptions;
use crate::pose::Pose;
use crate::pose::retarget::{character_neutral, clip_head_trunk_deg, foot_glide_cm};
use crate::rig::LoadOptions;
use crate::tools::eval::{
    Checker, Plausibility, PlausibilityOptions, VelocityError, velocity_error,
};
use crate::tools::render::preview::PreviewOptions;
use crate::util::stages::{self, Stage, Stages};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Options of a [`RetargetJob`].
#[derive(Debug, Clone, Default)]
pub struct RetargetJobOptions {
    /// Retrieval, timeline and deformation. Default:
    /// [`DriveOptions::default`] (part-based deformation).
    pub retarget: DriveOptions,
    /// How the database is loaded. Default: regressor skeletons.
    pub character: CharacterOptions,
    /// How clips are read. Default: decide from the file.
    pub load: LoadOptions,
    /// GLB output. Default: [`GlbOptions::DEFAULT`].
    pub glb: GlbOptions,
    /// `.usda` output. Default: [`UsdOptions::DEFAULT`] (normals on).
    pub usd: UsdOptions,
}

/// A database loaded and prepared once for retargeting many clips: the
/// character, its preparation for synthesis ([`Prepared`]: the blender's
/// and the deformer's factorisations, the neutral pose, the floor lift)
/// and, when first asked for, the plausibility checker; every clip reads
/// them by reference.
pub struct RetargetJob {
    /// The loaded character.
    pub character: Character,
    /// The options.
    pub options: RetargetJobOptions,
    /// The database folder.
    pub db: PathBuf,
    /// The character prepared for `options.retarget`'s deformation.
    prepared: Prepared,
    /// Preparations made (one on load; one more per run whose options no
    /// longer fit it).
    preparations: AtomicUsize,
    /// The plausibility checker of the character (built on first use;
    /// `None` when the rig cannot support the checks).
    checker: OnceLock<Option<Checker>>,
    /// The stages of [`RetargetJob::load`], timed (issue 43).
    load_stages: Vec<Stage>,
}

/// One clip retargeted.
pub struct RetargetRun {
    /// The clip as read (canonical poses, metres, Y-up, the database's rate).
    pub mocap: ClipQuery,
    /// Positions, the query on the character's skeleton, and the report.
    pub output: Output,
    /// The clip analysed once ([`Prepared::analyse`]), which the
    /// plausibility checks read.
    pub analysed: Analysed,
}

impl RetargetJob {
    /// Loads the database in `db` (building its graph first if needed).
    pub fn load(
        db: &Path,
        options: RetargetJobOptions,
        progress: &dyn BuildProgress,
    ) -> Result<RetargetJob, JobError> {
        let mut stages = Stages::start();
        let character = Character::load_staged(db, progress, &options.character, &mut stages)?;
        let prepared = Prepared::new_staged(&character, &options.retarget, &mut stages)?;
        Ok(RetargetJob {
            character,
            options,
            db: db.to_path_buf(),
            prepared,
            preparations: AtomicUsize::new(1),
            checker: OnceLock::new(),
            load_stages: stages.into_stages(),
        })
    }

    /// The stages of the load ([`Character::load_staged`],
    /// [`Prepared::new_staged`]), each with its wall and CPU seconds: what
    /// the job spent before its first clip.
    pub fn load_stages(&self) -> &[Stage] {
        &self.load_stages
    }

    /// The stages of the load and of the clip `c` (issue 43: the per-clip
    /// fixed cost separated), with their sums and the process's CPU
    /// seconds so far (what the stages leave out: the program's start, the
    /// options read, the outputs checked), for a `--report`.
    pub fn stages_json(&self, c: &ClipResult) -> serde_json::Value {
        let (load_wall, load_cpu) = stages::sum(&self.load_stages);
        let (clip_wall, clip_cpu) = stages::sum(&c.stages);
        serde_json::json!({
            "load": self.load_stages,
            "clip": c.stages,
            "load_wall": load_wall,
            "load_cpu": load_cpu,
            "clip_wall": clip_wall,
            "clip_cpu": clip_cpu,
            "process_cpu": stages::process_cpu(),
        })
    }

    /// The report file of clip `c` (`retarget --report`):
    /// [`ClipResult::report_json`] with [`Self::stages_json`] under
    /// `stages`, as pretty JSON written to `path` atomically.
    pub fn write_report(&self, c: &ClipResult, path: &Path) -> Result<(), JobError> {
        let mut v = c.report_json()?;
        v["stages"] = self.stages_json(c);
        let json = serde_json::to_string_pretty(&v)?;
        Ok(crate::util::fsutil::write_bytes_atomic(
            path,
            json.as_bytes(),
        )?)
    }

    /// The prepared character (made on load with the options then given).
    pub fn prepared(&self) -> &Prepared {
        &self.prepared
    }

    /// How many times the character was prepared (its blender and deformer
    /// factored): 1 for a job whose options did not change after
    /// [`RetargetJob::load`], whatever the number of clips.
    pub(crate) fn preparations(&self) -> usize {
        self.preparations.load(Ordering::Relaxed)
    }

    /// A new preparation when `options.retarget`'s deformation was changed
    /// since [`RetargetJob::load`] (the one made on load no longer fits);
    /// `None` when that one serves.
    fn fresh_preparation(&self) -> Result<Option<Prepared>, JobError> {
        if self.prepared.fits(&self.character, &self.options.retarget) {
            return Ok(None);
        }
        self.preparations.fetch_add(1, Ordering::Relaxed);
        Ok(Some(Prepared::new(
            &self.character,
            &self.options.retarget,
        )?))
    }

    /// The character's plausibility checker, built once.
    fn checker(&self) -> Option<&Checker> {
        self.checker
            .get_or_init(|| {
                Checker::for_character_with(
                    &self.character,
                    self.prepared.neutral(),
                    PlausibilityOptions::default(),
                )
                .map_err(|e| tracing::warn!("plausibility not measured: {e}"))
                .ok()
            })
            .as_ref()
    }

    /// The clip at `clip` at the database's frame rate, refused when it
    /// has no frames.
    fn load_clip(&self, clip: &Path) -> Result<ClipQuery, JobError> {
        let mocap = load_mocap(clip, &self.options.load, self.character.manifest().fps)?;
        if mocap.poses.is_empty() {
            return Err(JobError::Input {
                path: clip.to_path_buf(),
                msg: "the clip has no frames".into(),
            });
        }
        Ok(mocap)
    }

    /// Retargets the clip at `clip` (BVH or AMC, any detected rig).
    pub fn run(&self, clip: &Path) -> Result<RetargetRun, JobError> {
        let ch = &self.character;
        let fps = ch.manifest().fps;
        let mocap = self.load_clip(clip)?;
        // One output frame per query frame, each holding the character's
        // vertices: refuse before allocating (issue 18, item 12).
        crate::util::budget::check_frames(
            &format!("the retarget at {fps} fps"),
            mocap.poses.len(),
            ch.n(),
            1,
        )
        .map_err(crate::drive::DriveError::from)?;
        let fresh = self.fresh_preparation()?;
        let prepared = fresh.as_ref().unwrap_or(&self.prepared);
        let analysed = prepared.analyse(ch, &mocap.reference, &mocap.poses);
        let mut positions = Vec::with_capacity(mocap.poses.len() * ch.n());
        let report = prepared.synthesise::<_, crate::drive::DriveError>(
            ch,
            &analysed,
            mocap.reference.source,
            fps,
            &self.options.retarget,
            &mut positions,
        )?;
        let output = Output {
            positions,
            query: analysed.query.clone(),
            report,
        };
        Ok(RetargetRun {
            mocap,
            output,
            analysed,
        })
    }

    /// Retargets the clip at `clip` straight to `out` (by extension), each
    /// frame written as it is made ([`Prepared::synthesise`] into a
    /// [`SequenceWriter`]), so a clip of any length needs the memory of one
    /// chunk of frames, not of every frame (issue 18, item 12): point caches
    /// and OBJ folders stream; a GLB, written whole, is checked against the
    /// memory budget and its format's size before the first frame is made.
    /// The first frames, up to `keep_bytes` of positions, are kept (for a
    /// plausibility measure); the joint-velocity error is measured on every
    /// frame. The bytes written are those of [`RetargetJob::run`] then
    /// [`RetargetJob::write`].
    pub fn run_to(
        &self,
        clip: &Path,
        out: &Path,
        keep_bytes: usize,
    ) -> Result<StreamedRun, JobError> {
        let mut stages = Stages::start();
        let ch = &self.character;
        let fps = ch.manifest().fps;
        let mocap = self.load_clip(clip)?;
        stages.lap("clip read");
        let n = ch.n();
        let frames = mocap.poses.len();
        let fresh = self.fresh_preparation()?;
        let prepared = fresh.as_ref().unwrap_or(&self.prepared);
        let mut writer = SequenceWriter::create(
            prepared.topology_metres(),
            out,
            frames,
            &SaveOptions {
                fps: Some(fps),
                glb: self.options.glb,
                usd: self.options.usd,
            },
        )?;
        let keep = (keep_bytes / (24 * n.max(1))).clamp(1, frames);
        let mut kept = Vec::with_capacity(keep * n);
        let mut skeletons: Vec<Pose> = Vec::with_capacity(frames);
        stages.lap("output opened");
        let analysed = prepared.analyse(ch, &mocap.reference, &mocap.poses);
        stages.lap("clip analysed");
        let mut sink_seconds = 0.0;
        let report = prepared.synthesise::<_, JobError>(
            ch,
            &analysed,
            mocap.reference.source,
            fps,
            &self.options.retarget,
            Each(|p: &[[f64; 3]]| -> Result<(), JobError> {
                let t = Instant::now();
                if skeletons.len() < keep {
                    kept.extend_from_slice(p);
                }
                skeletons.push(ch.rig().frame_joints(p));
                writer.push(p)?;
                sink_seconds += t.elapsed().as_secs_f64();
                Ok(())
            }),
        )?;
        stages.lap("synthesis");
        let t = Instant::now();
        let written = writer.finish()?;
        sink_seconds += t.elapsed().as_secs_f64();
        stages.lap("output finished");
        let velocity = velocity_error(&analysed.query, &skeletons);
        stages.lap("velocity error");
        Ok(StreamedRun {
            mocap,
            analysed,
            report,
            written,
            kept,
            velocity,
            sink_seconds,
            stages,
        })
    }

    /// The plausibility of `positions` (metres, Y-up, frame-major) against
    /// the database's own frames, and the floor height; `None` (with a
    /// warning) when the rig cannot support the checks.
    pub fn plausibility(
        &self,
        positions: &[[f64; 3]],
        turned_over: Option<TurnedOver>,
    ) -> Option<(Plausibility, f64)> {
        plausibility_with(
            self.checker()?,
            &self.character,
            positions,
            turned_over,
            None,
        )
    }

    /// [`RetargetJob::plausibility`] of the first frames `kept` of a
    /// streamed run ([`RetargetJob::run_to`]), with the clip's own head
    /// range, foot glide and ground as [`RetargetJob::plausibility_of`].
    pub fn plausibility_of_streamed(&self, run: &StreamedRun) -> Option<(Plausibility, f64)> {
        plausibility_with(
            self.checker()?,
            &self.character,
            &run.kept,
            run.deformed().then_some(run.report.turned_over),
            Some((&run.mocap, &run.analysed)),
        )
    }

    /// [`RetargetJob::plausibility`] of a run's output, with the head held
    /// to the larger of the database's range and the clip's own
    /// ([`Plausibility::with_clip_head`]).
    pub fn plausibility_of(&self, run: &RetargetRun) -> Option<(Plausibility, f64)> {
        let out = &run.output;
        plausibility_with(
            self.checker()?,
            &self.character,
            &out.positions,
            run.deformed().then_some(out.report.turned_over),
            Some((&run.mocap, &run.analysed)),
        )
    }

    /// Writes `positions` (the character's vertices, frame-major) to `out`
    /// (by extension); returns the files written.
    pub fn write(&self, positions: Vec<[f64; 3]>, out: &Path) -> Result<Vec<PathBuf>, JobError> {
        let ch = &self.character;
        super::write_positions(
            self.prepared.topology_metres().clone(),
            positions,
            ch.manifest().fps,
            self.options.glb,
            self.options.usd,
            out,
        )
    }
}

/// The plausibility of `positions` made for `ch` against the database's
/// own frames (and, given the driving `clip` and its analysis, its own
/// head range, foot glide and ground), and the floor; `None` (with a
/// warning) when the rig cannot support the checks.
pub fn plausibility(
    ch: &Character,
    positions: &[[f64; 3]],
    turned_over: Option<TurnedOver>,
    clip: Option<(&ClipQuery, &Analysed)>,
) -> Option<(Plausibility, f64)> {
    match Checker::for_character(ch, PlausibilityOptions::default()) {
        Ok(c) => plausibility_with(&c, ch, positions, turned_over, clip),
        Err(e) => {
            tracing::warn!("plausibility not measured: {e}");
            None
        }
    }
}

/// [`plausibility`] with the character's checker `c` built already
/// ([`Checker::for_character`]; a [`RetargetJob`] builds it once).
pub(crate) fn plausibility_with(
    c: &Checker,
    ch: &Character,
    positions: &[[f64; 3]],
    turned_over: Option<TurnedOver>,
    clip: Option<(&ClipQuery, &Analysed)>,
) -> Option<(Plausibility, f64)> {
    match measure(c, ch, positions, turned_over, clip) {
        Ok(p) => Some(p),
        Err(e) => {
            tracing::warn!("plausibility not measured: {e}");
            None
        }
    }
}

/// [`plausibility_with`]'s measure, its error kept. The clip's ground
/// and foot glide are read off its analysis (`a`, the pose kernel's one
/// run for the clip; issue 40: the checks ran it three more times).
fn measure(
    c: &Checker,
    ch: &Character,
    positions: &[[f64; 3]],
    turned_over: Option<TurnedOver>,
    clip: Option<(&ClipQuery, &Analysed)>,
) -> Result<(Plausibility, f64), crate::tools::eval::EvalError> {
    let opts = c.opts;
    let Some((m, a)) = clip else {
        return Ok((c.measure(positions, ch.n(), turned_over)?.logged(), c.floor));
    };
    // Floating and penetration from the clip's own ground under each
    // foot (its floor, raised under a footfall on a step), where the
    // result stands.
    let raised = &a.on_character.foot_grounds;
    let p = c
        .measure_on(positions, ch.n(), turned_over, Some(raised))?
        .with_clip_head(&clip_head_trunk_deg(&m.reference, &m.poses), &opts.limits)
        .with_clip_glide(foot_glide_cm(ch.rest_pose(), &a.on_character), &opts.limits)
        .logged();
    Ok((p, c.floor))
}

/// One clip retargeted straight to a file ([`RetargetJob::run_to`]).
pub struct StreamedRun {
    /// The clip as read (canonical poses, metres, Y-up, the database's rate).
    pub mocap: ClipQuery,
    /// The clip analysed once ([`Prepared::analyse`]), which the
    /// plausibility checks read.
    pub analysed: Analysed,
    /// What was done.
    pub report: Report,
    /// Files written.
    pub written: Vec<PathBuf>,
    /// The first output frames (frame-major), as many as the `keep_bytes`
    /// given allow (at least one).
    pub kept: Vec<[f64; 3]>,
    /// The joint-velocity error (Huang et al. 2015, Sec. 6.2) over every
    /// frame, as [`RetargetRun::velocity_error`].
    pub velocity: VelocityError,
    /// Seconds handing frames on (skeletons read, frames written).
    pub sink_seconds: f64,
    /// The run's stages so far (the clock still running: a caller laps
    /// what it does next).
    pub stages: Stages,
}

impl StreamedRun {
    /// True when the deformation ran (its repair counts are meaningful).
    pub fn deformed(&self) -> bool {
        matches!(self.report.deform, DeformMode::Part | DeformMode::Global)
    }
}

impl RetargetRun {
    /// The joint-velocity error (Huang et al. 2015, Sec. 6.2) between the
    /// query on the character's bones and the skeleton read off the result.
    /// The query is the run's own ([`Output::query`], the clip analysed
    /// once), bit for bit what [`crate::drive::query::to_database`] gives.
    pub fn velocity_error(&self, ch: &Character) -> VelocityError {
        let query = &self.output.query;
        let skel: Vec<Pose> = self
            .output
            .positions
            .chunks(ch.n().max(1))
            .map(|p| ch.rig().frame_joints(p))
            .collect();
        velocity_error(query, &skel)
    }

    /// True when the deformation ran (its repair counts are meaningful).
    pub fn deformed(&self) -> bool {
        matches!(
            self.output.report.deform,
            DeformMode::Part | DeformMode::Global
        )
    }
}

/// The summary `retarget --json` prints.
#[derive(Debug, Clone, Serialize)]
pub struct RetargetSummary {
    /// Files written.
    pub output: Vec<PathBuf>,
    /// Output frames.
    pub frames: usize,
    /// Frame rate.
    pub fps: f64,
    /// The skeleton threshold used (metres, summed over 19 joints).
    pub t_skel: f64,
    /// Trellis nodes.
    pub trellis_nodes: usize,
    /// Transitions taken.
    pub transitions: usize,
    /// Cuts (jumps along no edge).
    pub cuts: usize,
    /// Query frames whose candidate set was widened.
    pub widened: usize,
    /// Summed node cost of the path.
    pub node_cost: f64,
    /// Summed edge cost of the path.
    pub edge_cost: f64,
    /// Timings (seconds).
    pub timings: Timings,
    /// Retrieval, timeline, meshes and deformation per output frame (ms).
    pub ms_per_frame: f64,
    /// The deformation mode.
    pub deformation: DeformMode,
    /// Triangle-frames turned over before and after the repair.
    pub turned_over: TurnedOver,
    /// Plausibility against the database's frames.
    pub plausibility: Option<Plausibility>,
}

impl RetargetSummary {
    /// The summary of report `r`, written to `output`.
    pub fn new(output: Vec<PathBuf>, r: &Report, plausibility: Option<Plausibility>) -> Self {
        RetargetSummary {
            output,
            frames: r.frames,
            fps: r.fps,
            t_skel: r.retrieval.t_skel,
            trellis_nodes: r.retrieval.nodes,
            transitions: r.jumps.iter().filter(|j| j.transition).count(),
            cuts: r.retrieval.cuts.len(),
            widened: r.retrieval.widened.len(),
            node_cost: r.retrieval.node_cost,
            edge_cost: r.retrieval.edge_cost,
            timings: r.timings,
            ms_per_frame: 1e3 * per_frame_seconds(r),
            deformation: r.deform,
            turned_over: r.turned_over,
            plausibility,
        }
    }
}

/// Retrieval, timeline, meshes and deformation time per output frame (s).
pub(crate) fn per_frame_seconds(r: &Report) -> f64 {
    (r.timings.retrieval + r.timings.timeline + r.timings.meshes + r.timings.deform)
        / r.frames.max(1) as f64
}

impl Converter for RetargetJob {
    fn describe(&self) -> String {
        format!("retarget onto {}", self.db.display())
    }

    /// Streams the frames to `out` as they are made
    /// ([`RetargetJob::run_to`]): a clip of any length converts with the
    /// memory of one chunk of frames (issue 18, item 12); only a GLB,
    /// written whole, is checked against the budget.
    fn convert(&self, clip: &Path, out: &Path) -> Result<Converted, String> {
        let t = Instant::now();
        // The first frames are kept for the plausibility measure, as
        // `retarget` keeps them (issue 39, item 4: batch dropped every
        // warning `eval` gives).
        let keep_bytes = super::transfer::PLAUSIBILITY_BYTES
            .min((crate::util::budget::Budget::current().bytes / 8) as usize);
        let run = self.run_to(clip, out, keep_bytes).map_err(|e| match e {
            JobError::Input { msg, .. } => msg,
            e => e.to_string(),
        })?;
        let checks = Instant::now();
        let warnings = self
            .plausibility_of_streamed(&run)
            .map(|(p, _)| crate::batch::runner::ClipWarning::of(&p))
            .unwrap_or_default();
        let checks = checks.elapsed().as_secs_f64();
        // The per-frame work: retrieval, timeline, meshes, deformation, the
        // frames handed on and measured; the rest (the clip read, its rig
        // mapped, the pose kernel, the output opened; before issue 40 also
        // the factorisations and the checker) is the clip's fixed cost.
        let per_frame =
            per_frame_seconds(&run.report) * run.report.frames as f64 + run.sink_seconds + checks;
        Ok(Converted {
            frames: run.report.frames,
            error_cm: Some(run.velocity.mean_cm),
            warnings,
            fixed_seconds: Some((t.elapsed().as_secs_f64() - per_frame).max(0.0)),
        })
    }

    fn preparation(&self) -> Preparation {
        Preparation {
            factorisations: self.preparations(),
            seconds: self.prepared.timings().total(),
        }
    }
}

/// The score of a retargeted result (the `eval` verb): the joint-velocity
/// error of Huang et al. 2015, Sec. 6.2, and the plausibility of the result
/// against the database's own frames.
#[derive(Debug, Serialize)]
pub struct EvalReport {
    /// The clip that drove the result.
    pub mocap: PathBuf,
    /// The result.
    pub result: PathBuf,
    /// Frames of the clip at the database's frame rate.
    pub query_frames: usize,
    /// Frames of the result.
    pub result_frames: usize,
    /// Mean joint-velocity error (cm per frame).
    pub velocity_error_cm_per_frame: f64,
    /// Its standard deviation (cm per frame).
    pub std_cm_per_frame: f64,
    /// Per frame (cm).
    pub per_frame_cm: Vec<f64>,
    /// Plausibility of the result.
    pub plausibility: Option<Plausibility>,
    /// Frames the velocity error is measured over.
    #[serde(skip)]
    pub velocity_frames: usize,
}

/// Scores `result` (a sequence on `ch`'s vertices, metres, Y-up, as
/// [`RetargetJob`] writes it) against the clip at `mocap` (read with
/// `load` at the database's frame rate): the joint-velocity error of Huang
/// et al. 2015, Sec. 6.2, and the plausibility against the database's
/// frames. The result must have one frame per clip frame.
pub fn evaluate_result(
    ch: &Character,
    mocap: &Path,
    result: &Path,
    load: &LoadOptions,
) -> Result<EvalReport, JobError> {
    use crate::mesh::io::{LoadOptions as SeqLoad, load_sequence};
    let fps = ch.manifest().fps;
    let clip = load_mocap(mocap, load, fps)?;
    // The clip analysed once (the query of `to_database`, bit for bit),
    // the neutral pose found once for it and the checker.
    let neutral = character_neutral(ch.rest_pose(), ch.poses());
    let analysed = Analysed::new(
        ch,
        &neutral.pose,
        database_floor_lift(ch),
        &clip.reference,
        &clip.poses,
    );
    let query = &analysed.query;
    // The reader's errors name the file already (a context of its path
    // printed it twice: "out: out: no .obj files in the folder").
    let res = load_sequence(&result.to_string_lossy(), &SeqLoad::default())?;
    if res.mesh().vertex_count() != ch.n() {
        return Err(JobError::Input {
            path: result.to_path_buf(),
            msg: format!(
                "{} vertices, the character has {}",
                res.mesh().vertex_count(),
                ch.n()
            ),
        });
    }
    // A result of another clip (or another frame rate) would give a number
    // that means nothing: the frames must pair one to one (issue 18, item 8).
    if res.frame_count() != query.len() {
        return Err(JobError::Input {
            path: result.to_path_buf(),
            msg: format!(
                "{}, but {} at the database's {} fps gives {}; was it made from this clip (and with `LoadOptions::fps` as given)?",
                count(res.frame_count(), "frame"),
                mocap.display(),
                fps,
                count(query.len(), "frame")
            ),
        });
    }
    let out: Vec<Pose> = (0..res.frame_count())
        .map(|f| ch.rig().frame_joints(res.frame(f)))
        .collect();
    let e = velocity_error(query, &out);
    let plaus = match Checker::for_character_with(ch, &neutral, PlausibilityOptions::default()) {
        Ok(c) => plausibility_with(&c, ch, res.all_positions(), None, Some((&clip, &analysed))),
        Err(e) => {
            tracing::warn!("plausibility not measured: {e}");
            None
        }
    }
    .map(|p| p.0);
    Ok(EvalReport {
        mocap: mocap.to_path_buf(),
        result: result.to_path_buf(),
        query_frames: query.len(),
        result_frames: out.len(),
        velocity_error_cm_per_frame: e.mean_cm,
        std_cm_per_frame: e.std_cm,
        per_frame_cm: e.per_frame,
        plausibility: plaus,
        velocity_frames: e.frames,
    })
}

/// One clip retargeted to a file by [`RetargetJob::run_clip`]: what the
/// `retarget` verb reports.
#[derive(Debug, Clone)]
pub struct ClipResult {
    /// What was done.
    pub report: Report,
    /// Files written.
    pub written: Vec<PathBuf>,
    /// The clip's rig convention.
    pub convention: String,
    /// Plausibility against the database's frames.
    pub plausibility: Option<Plausibility>,
    /// The plausibility was measured on this many first frames (streamed
    /// output); `None` when on every frame.
    pub partial: Option<usize>,
    /// The clip's stages, timed (issue 43).
    pub stages: Vec<Stage>,
}

impl RetargetJob {
    /// Retargets `clip` to the file `out`. Without a `preview` the frames
    /// go to the output as they are made (issue 18, item 12) and the
    /// plausibility is measured on the first frames, as `transfer` does;
    /// with one, every frame is held, the contact sheet drawn (each panel
    /// faced from its own body, `render`'s rule), then the output written.
    pub fn run_clip(
        &self,
        clip: &Path,
        out: &Path,
        preview: Option<(&Path, &PreviewOptions)>,
    ) -> Result<ClipResult, JobError> {
        let ch = &self.character;
        let Some((path, opts)) = preview else {
            let keep_bytes = super::transfer::PLAUSIBILITY_BYTES
                .min((crate::util::budget::Budget::current().bytes / 4) as usize);
            let mut run = self.run_to(clip, out, keep_bytes)?;
            let measured = run.kept.len() / ch.n().max(1);
            // Built on the first clip of a job (made once, then read).
            let _ = self.checker();
            run.stages.lap("plausibility checker");
            let plausibility = self.plausibility_of_streamed(&run).map(|p| p.0);
            run.stages.lap("plausibility");
            let partial = (measured < run.report.frames).then_some(measured);
            if let Some(k) = partial {
                tracing::info!(
                    "plausibility measured on the first {k} of {} frames (streamed output)",
                    run.report.frames
                );
            }
            return Ok(ClipResult {
                report: run.report,
                written: run.written,
                convention: run.mocap.convention,
                plausibility,
                partial,
                stages: run.stages.into_stages(),
            });
        };
        let mut stages = Stages::start();
        let run = self.run(clip)?;
        stages.lap("clip retargeted");
        let plaus = self.plausibility_of(&run);
        stages.lap("plausibility");
        crate::tools::render::preview::write_preview(
            path,
            &run.output.positions,
            ch.n(),
            ch.topology().triangles(),
            Some(ch.rig()),
            None,
            plaus.as_ref().map(|p| p.1),
            opts,
        )?;
        stages.lap("preview");
        let written = self.write(run.output.positions, out)?;
        stages.lap("output written");
        Ok(ClipResult {
            report: run.output.report,
            written,
            convention: run.mocap.convention,
            plausibility: plaus.map(|p| p.0),
            partial: None,
            stages: stages.into_stages(),
        })
    }
}

impl ClipResult {
    /// The `--report` file's JSON: the report, its plausibility and (when
    /// measured on the first frames only) their number.
    pub fn report_json(&self) -> Result<serde_json::Value, JobError> {
        let mut v = serde_json::to_value(&self.report)?;
        v["plausibility"] = serde_json::to_value(&self.plausibility)?;
        if let Some(k) = self.partial {
            v["plausibility_frames"] = serde_json::to_value(k)?;
        }
        Ok(v)
    }

    /// The summary `retarget --json` prints.
    pub fn summary(&self) -> RetargetSummary {
        RetargetSummary::new(
            self.written.clone(),
            &self.report,
            self.plausibility.clone(),
        )
    }
}
