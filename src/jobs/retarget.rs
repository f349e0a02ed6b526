//! Retargeting a clip through a database (Huang et al. 2015, Sec. 5.2):
//! load the character once ([`RetargetJob::load`]), then any number of
//! clips ([`RetargetJob::run`]); each result can be scored (Sec. 6.2,
//! [`RetargetRun::velocity_error`]), checked for plausibility and written.

use super::JobError;
use crate::batch::summary::count;
use crate::batch::{Converted, Converter};
use crate::db::{BuildProgress, Character, CharacterOptions};
use crate::deform::{DeformMode, TurnedOver};
use crate::eval::{Checker, Plausibility, PlausibilityOptions, VelocityError, velocity_error};
use crate::mesh::io::SaveOptions;
use crate::mesh::io::glb::GlbOptions;
use crate::mesh::io::stream::SequenceWriter;
use crate::pose::Pose;
use crate::pose::retarget::{clip_foot_glide_cm, clip_head_trunk_deg, foot_ground_offsets};
use crate::retarget::query::{MocapPoses, load_mocap, to_database};
use crate::retarget::{Output, Report, RetargetOptions, Timings, synthesise, synthesise_each};
use crate::rig::LoadOptions;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Options of a [`RetargetJob`].
#[derive(Debug, Clone, Default)]
pub struct RetargetJobOptions {
    /// Retrieval, timeline and deformation. Default:
    /// [`RetargetOptions::default`] (part-based deformation).
    pub retarget: RetargetOptions,
    /// How the database is loaded. Default: regressor skeletons.
    pub character: CharacterOptions,
    /// How clips are read. Default: decide from the file.
    pub load: LoadOptions,
    /// GLB output. Default: [`GlbOptions::DEFAULT`].
    pub glb: GlbOptions,
}

/// A database loaded once for retargeting many clips.
pub struct RetargetJob {
    /// The loaded character.
    pub character: Character,
    /// The options.
    pub options: RetargetJobOptions,
    /// The database folder.
    pub db: PathBuf,
}

/// One clip retargeted.
pub struct RetargetRun {
    /// The clip as read (canonical poses, metres, Y-up, the database's rate).
    pub mocap: MocapPoses,
    /// Positions, the query on the character's skeleton, and the report.
    pub output: Output,
}

impl RetargetJob {
    /// Loads the database in `db` (building its graph first if needed).
    pub fn load(
        db: &Path,
        options: RetargetJobOptions,
        progress: &dyn BuildProgress,
    ) -> Result<RetargetJob, JobError> {
        let character = Character::load_with(db, progress, &options.character)?;
        Ok(RetargetJob {
            character,
            options,
            db: db.to_path_buf(),
        })
    }

    /// The clip at `clip` at the database's frame rate, refused when it
    /// has no frames.
    fn load_clip(&self, clip: &Path) -> Result<MocapPoses, JobError> {
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
        let output = synthesise(
            ch,
            &mocap.poses,
            &mocap.reference,
            fps,
            &self.options.retarget,
        )?;
        Ok(RetargetRun { mocap, output })
    }

    /// Retargets the clip at `clip` straight to `out` (by extension), each
    /// frame written as it is made ([`synthesise_each`] into a
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
        let ch = &self.character;
        let fps = ch.manifest().fps;
        let mocap = self.load_clip(clip)?;
        let n = ch.n();
        let frames = mocap.poses.len();
        let mut writer = SequenceWriter::create(
            &ch.topology_metres(),
            out,
            frames,
            &SaveOptions {
                fps: Some(fps),
                glb: self.options.glb,
            },
        )?;
        let keep = (keep_bytes / (24 * n.max(1))).clamp(1, frames);
        let mut kept = Vec::with_capacity(keep * n);
        let mut skeletons: Vec<Pose> = Vec::with_capacity(frames);
        let s = synthesise_each(
            ch,
            &mocap.poses,
            &mocap.reference,
            fps,
            &self.options.retarget,
            |f, p| -> Result<(), JobError> {
                if f < keep {
                    kept.extend_from_slice(p);
                }
                skeletons.push(ch.rig().frame_joints(p));
                Ok(writer.push(p)?)
            },
        )?;
        let written = writer.finish()?;
        let velocity = velocity_error(&s.query, &skeletons);
        Ok(StreamedRun {
            mocap,
            report: s.report,
            written,
            kept,
            velocity,
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
        plausibility(&self.character, positions, turned_over, None)
    }

    /// [`RetargetJob::plausibility`] of the first frames `kept` of a
    /// streamed run ([`RetargetJob::run_to`]), with the clip's own head
    /// range, foot glide and ground as [`RetargetJob::plausibility_of`].
    pub fn plausibility_of_streamed(&self, run: &StreamedRun) -> Option<(Plausibility, f64)> {
        plausibility(
            &self.character,
            &run.kept,
            run.deformed().then_some(run.report.turned_over),
            Some(&run.mocap),
        )
    }

    /// [`RetargetJob::plausibility`] of a run's output, with the head held
    /// to the larger of the database's range and the clip's own
    /// ([`Plausibility::with_clip_head`]).
    pub fn plausibility_of(&self, run: &RetargetRun) -> Option<(Plausibility, f64)> {
        let out = &run.output;
        plausibility(
            &self.character,
            &out.positions,
            run.deformed().then_some(out.report.turned_over),
            Some(&run.mocap),
        )
    }

    /// Writes `positions` (the character's vertices, frame-major) to `out`
    /// (by extension); returns the files written.
    pub fn write(&self, positions: Vec<[f64; 3]>, out: &Path) -> Result<Vec<PathBuf>, JobError> {
        let ch = &self.character;
        super::write_positions(
            ch.topology_metres(),
            positions,
            ch.manifest().fps,
            self.options.glb,
            out,
        )
    }
}

/// The plausibility of `positions` made for `ch` against the database's
/// own frames (and, given the driving `clip`, its own head range), and the
/// floor; `None` (with a warning) when the rig cannot support the checks.
pub fn plausibility(
    ch: &Character,
    positions: &[[f64; 3]],
    turned_over: Option<TurnedOver>,
    clip: Option<&MocapPoses>,
) -> Option<(Plausibility, f64)> {
    let opts = PlausibilityOptions::default();
    let checked = Checker::for_character(ch, opts).and_then(|c| {
        let Some(m) = clip else {
            return Ok((c.measure(positions, ch.n(), turned_over)?.logged(), c.floor));
        };
        // Floating and penetration from the clip's own ground under each
        // foot (its floor, raised under a footfall on a step), where the
        // result stands.
        let raised = foot_ground_offsets(ch.rest_pose(), &m.reference, &m.poses);
        let p = c
            .measure_on(positions, ch.n(), turned_over, Some(&raised))?
            .with_clip_head(&clip_head_trunk_deg(&m.reference, &m.poses), &opts.limits)
            .with_clip_glide(
                clip_foot_glide_cm(ch.rest_pose(), &m.reference, &m.poses),
                &opts.limits,
            )
            .logged();
        Ok((p, c.floor))
    });
    match checked {
        Ok(p) => Some(p),
        Err(e) => {
            tracing::warn!("plausibility not measured: {e}");
            None
        }
    }
}

/// One clip retargeted straight to a file ([`RetargetJob::run_to`]).
pub struct StreamedRun {
    /// The clip as read (canonical poses, metres, Y-up, the database's rate).
    pub mocap: MocapPoses,
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
    pub fn velocity_error(&self, ch: &Character) -> VelocityError {
        let query = to_database(ch, &self.mocap.reference, &self.mocap.poses);
        let skel: Vec<Pose> = self
            .output
            .positions
            .chunks(ch.n().max(1))
            .map(|p| ch.rig().frame_joints(p))
            .collect();
        velocity_error(&query, &skel)
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
pub fn per_frame_seconds(r: &Report) -> f64 {
    (r.timings.retrieval + r.timings.timeline + r.timings.meshes + r.timings.deform)
        / r.frames.max(1) as f64
}

impl Converter for RetargetJob {
    fn describe(&self) -> String {
        format!("retarget --db {}", self.db.display())
    }

    /// Streams the frames to `out` as they are made
    /// ([`RetargetJob::run_to`]): a clip of any length converts with the
    /// memory of one chunk of frames (issue 18, item 12); only a GLB,
    /// written whole, is checked against the budget.
    fn convert(&self, clip: &Path, out: &Path) -> Result<Converted, String> {
        // The first frames are kept for the plausibility measure, as
        // `retarget` keeps them (issue 39, item 4: batch dropped every
        // warning `eval` gives).
        let keep_bytes = super::transfer::PLAUSIBILITY_BYTES
            .min((crate::budget::Budget::current().bytes / 8) as usize);
        let run = self.run_to(clip, out, keep_bytes).map_err(|e| match e {
            JobError::Input { msg, .. } => msg,
            e => e.to_string(),
        })?;
        let warnings = self
            .plausibility_of_streamed(&run)
            .map(|(p, _)| crate::batch::runner::ClipWarning::of(&p))
            .unwrap_or_default();
        Ok(Converted {
            frames: run.report.frames,
            error_cm: Some(run.velocity.mean_cm),
            warnings,
        })
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
    let query = to_database(ch, &clip.reference, &clip.poses);
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
                "{}, but {} at the database's {} fps gives {}; was it made from this clip (and with --input-fps as given)?",
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
    let e = velocity_error(&query, &out);
    let plaus = plausibility(ch, res.all_positions(), None, Some(&clip)).map(|p| p.0);
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
