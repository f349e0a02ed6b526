//! Surface synthesis of one clip (Huang et al. 2015, Sec. 5.2): retrieval,
//! timeline, placement, blending and deformation, frame by frame.

use super::options::{DriveError, DriveOptions};
use super::placement::{BlendScratch, Floor, blend_placed, placements};
use super::prepared::{Analysed, Prepared};
use super::sink::FrameSink;
use super::timeline::{Jump, OutFrame, timeline};
use super::trellis::{DatabaseLinks, Retrieval, retrieve};
use crate::db::Character;
use crate::deform::{DeformMode, Deformer, TurnedOver};
use crate::mesh::blend::FrameGradients;
use crate::pose::Pose;
use crate::pose::retarget::{ClipNeutral, ClipNeutralSource};
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// One output frame in the report.
#[derive(Debug, Clone, Serialize)]
pub struct Step {
    /// Sequence of the retrieved frame.
    pub sequence: String,
    /// Retrieved frame in that sequence.
    pub frame: usize,
    /// `c_skel` to the query (metres, summed over joints).
    pub skeleton_cost: f64,
    /// What the output frame blends: `(sequence, frame, weight)`.
    pub blend: Vec<(String, usize, f64)>,
}

/// Seconds per stage.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Timings {
    /// Retargeting the query to the character.
    pub query: f64,
    /// The trellis search.
    pub retrieval: f64,
    /// Interpolation and blending weights.
    pub timeline: f64,
    /// Factoring the blender (once per character).
    pub factor: f64,
    /// Placing and blending the meshes.
    pub meshes: f64,
    /// Prefactoring the deformation (once per character).
    pub deform_factor: f64,
    /// Deforming every frame.
    pub deform: f64,
}

/// What [`synthesise`] reports.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Output frames.
    pub frames: usize,
    /// Frames per second.
    pub fps: f64,
    /// The clip's neutral reference pose the retargeting measured the
    /// torso's rotations from (see [`crate::pose::retarget`]).
    pub reference: ClipNeutralSource,
    /// The retrieval (path, threshold, costs, widened rows, cuts).
    pub retrieval: Retrieval,
    /// Jumps (transitions and cuts) with their blend windows.
    pub jumps: Vec<Jump>,
    /// Per output frame.
    pub steps: Vec<Step>,
    /// Seconds per stage.
    pub timings: Timings,
    /// The deformation applied.
    pub deform: DeformMode,
    /// Triangle-frames turned over by the deformation, before and after
    /// its repair (summed over frames; zero for `lbs` and `none`).
    pub turned_over: TurnedOver,
}

/// The synthesised sequence.
pub struct Output {
    /// Positions, frame-major (metres, Y-up).
    pub positions: Vec<[f64; 3]>,
    /// The query on the character's skeleton (metres, Y-up).
    pub query: Vec<Pose>,
    /// What was done.
    pub report: Report,
}

/// Output frames made at once by [`Prepared::synthesise`]: blended and
/// deformed in parallel, then handed on in order. A chunk holds two copies
/// of the character's vertices per frame (64 × 6,304 vertices × 48 B ≈ 19
/// MB).
pub const CHUNK_FRAMES: usize = 64;

/// Drives the character by the mocap poses (metres, Y-up, the clip's own
/// skeleton at the database frame rate) and the clip's neutral `reference`
/// ([`super::query::load_mocap`] gives both): Sec. 5.2 up to interpolation. A
/// one-off: the character is prepared ([`Prepared::new`]) for this call
/// and every output frame is held (the memory is checked against
/// [`crate::util::budget`] first). A job driving several clips prepares once and
/// calls [`Prepared::synthesise`] with any [`FrameSink`].
pub fn synthesise(
    ch: &Character,
    mocap: &[Pose],
    reference: &ClipNeutral,
    fps: f64,
    opts: &DriveOptions,
) -> Result<Output, DriveError> {
    // One output frame per query frame, each holding the character's
    // vertices: refuse before allocating (issue 18, item 12).
    crate::util::budget::check_frames(
        &format!("the retarget at {fps} fps"),
        mocap.len(),
        ch.n(),
        1,
    )?;
    let prepared = Prepared::new(ch, opts)?;
    let clip = prepared.analyse(ch, reference, mocap);
    let mut positions = Vec::with_capacity(mocap.len() * ch.n());
    let report = prepared.synthesise::<_, DriveError>(
        ch,
        &clip,
        reference.source,
        fps,
        opts,
        &mut positions,
    )?;
    Ok(Output {
        positions,
        query: clip.query,
        report,
    })
}

impl Prepared {
    /// The clip `clip` ([`Prepared::analyse`]) driving the character, each
    /// output frame (the character's vertices, metres, Y-up) handed to
    /// `sink` in order, so a clip of any length needs the memory of
    /// [`CHUNK_FRAMES`] frames when the sink streams (issue 18, item 12).
    /// The placements on the root trajectory (Sec. 5.2) are computed for
    /// every frame first (they are smoothed over time), then chunks of
    /// frames are blended (Sec. 4.4) and deformed (Sec. 5.2.3) in
    /// parallel, each frame independently, with per-worker scratch reused
    /// from chunk to chunk. The report's timings count the blending and
    /// deformation, not the sink, and give the preparation's factoring
    /// times (made once). The first error of the sink stops the job and is
    /// returned. `reference` is the source of the clip's neutral pose, for
    /// the report.
    pub fn synthesise<S: FrameSink, E: From<DriveError> + From<S::Error>>(
        &self,
        ch: &Character,
        clip: &Analysed,
        reference: ClipNeutralSource,
        fps: f64,
        opts: &DriveOptions,
        mut sink: S,
    ) -> Result<Report, E> {
        if !self.fits(ch, opts) {
            return Err(DriveError::Unprepared(format!(
                "prepared for {} vertices, {:?} deformation; asked for {} vertices, {:?} deformation",
                self.topology_metres().vertex_count(),
                self.deform(),
                ch.n(),
                opts.deform
            ))
            .into());
        }
        let query = &clip.query;
        let prepared = self.timings();
        let mut timings = Timings {
            query: clip.seconds,
            factor: prepared.factor,
            deform_factor: prepared.deform_factor,
            ..Timings::default()
        };
        let (retrieval, frames, jumps, placed) =
            self.retrieve_and_place(ch, clip, opts, &mut timings);
        let deformer = self.deformer();
        let n = ch.n().max(1);
        let chunk = CHUNK_FRAMES.min(frames.len()).max(1);
        // The chunk's blended frames, then (when deforming) its deformed ones.
        let mut blended = vec![[0.0; 3]; chunk * n];
        let mut deformed = if deformer.is_some() {
            vec![[0.0; 3]; chunk * n]
        } else {
            Vec::new()
        };
        // Per-worker scratch, taken and given back frame by frame (allocated
        // once per worker, not per frame).
        let blend_pool = std::sync::Mutex::new(Vec::<BlendWorker>::new());
        let deform_pool = std::sync::Mutex::new(Vec::<crate::deform::DeformWorkspace>::new());
        let mut turned_over = TurnedOver::default();
        for start in (0..frames.len()).step_by(chunk) {
            let m = chunk.min(frames.len() - start);
            let t = Instant::now();
            self.blend_chunk(
                ch,
                &frames[start..start + m],
                &placed[start..start + m],
                &mut blended[..m * n],
                &blend_pool,
            );
            timings.meshes += t.elapsed().as_secs_f64();
            let out: &[[f64; 3]] = match &deformer {
                Some(d) => {
                    let t = Instant::now();
                    let sum = deform_chunk(
                        ch,
                        d,
                        &blended[..m * n],
                        &query[start..start + m],
                        &mut deformed[..m * n],
                        &deform_pool,
                    );
                    turned_over.before += sum.before;
                    turned_over.after += sum.after;
                    timings.deform += t.elapsed().as_secs_f64();
                    &deformed[..m * n]
                }
                None => &blended[..m * n],
            };
            for f in out.chunks(n) {
                sink.push(f)?;
            }
        }
        let steps = report_steps(ch, &retrieval, &frames);
        Ok(Report {
            frames: frames.len(),
            fps,
            reference,
            retrieval,
            jumps,
            steps,
            timings,
            deform: opts.deform,
            turned_over,
        })
    }
}

impl Prepared {
    /// [`Prepared::synthesise`]'s retrieval (the trellis), timeline and
    /// placements on the root trajectory, their times in `timings`.
    fn retrieve_and_place(
        &self,
        ch: &Character,
        clip: &Analysed,
        opts: &DriveOptions,
        timings: &mut Timings,
    ) -> (Retrieval, Vec<OutFrame>, Vec<Jump>, Vec<Floor>) {
        let t1 = Instant::now();
        let links = DatabaseLinks::of(ch);
        let input = links.input();
        let retrieval = retrieve(&clip.on_floor, &input, &opts.trellis);
        timings.retrieval = t1.elapsed().as_secs_f64();
        let t2 = Instant::now();
        let (frames, jumps) = timeline(&retrieval.path, ch, &opts.timeline);
        timings.timeline = t2.elapsed().as_secs_f64();
        let t4 = Instant::now();
        let placed = placements(ch, &retrieval.path, &frames, &clip.query, opts.smooth);
        timings.meshes = t4.elapsed().as_secs_f64();
        (retrieval, frames, jumps, placed)
    }

    /// Blends a chunk's output `frames`, placed by `placed`, into `dst`
    /// (one frame of the character's vertices each) in parallel, with
    /// per-worker scratch from `pool`.
    fn blend_chunk(
        &self,
        ch: &Character,
        frames: &[OutFrame],
        placed: &[Floor],
        dst: &mut [[f64; 3]],
        pool: &std::sync::Mutex<Vec<BlendWorker>>,
    ) {
        let blender = self.blender();
        let n = ch.n().max(1);
        dst.par_chunks_mut(n).enumerate().for_each(|(k, dst)| {
            let mut w = take(pool).unwrap_or_else(|| BlendWorker {
                ws: blender.workspace(),
                buf: vec![[0.0; 3]; n],
                grads: vec![FrameGradients::default(); 4],
            });
            let primary = frames[k].primary();
            let mut scratch = BlendScratch {
                ws: &mut w.ws,
                buf: &mut w.buf,
                grads: &mut w.grads,
            };
            blend_placed(
                ch,
                blender,
                frames[k].used(),
                primary,
                placed[k],
                |id| id == primary,
                &mut scratch,
                dst,
            );
            give(pool, w);
        });
    }
}

/// Deforms a chunk's blended frames `src` towards their `query` poses into
/// `dst` in parallel, with per-worker scratch from `pool`; the turned-over
/// counts summed over the chunk.
fn deform_chunk(
    ch: &Character,
    d: &Deformer,
    src: &[[f64; 3]],
    query: &[Pose],
    dst: &mut [[f64; 3]],
    pool: &std::sync::Mutex<Vec<crate::deform::DeformWorkspace>>,
) -> TurnedOver {
    let n = ch.n().max(1);
    dst.par_chunks_mut(n)
        .zip(src.par_chunks(n))
        .zip(query.par_iter())
        .map(|((dst, src), target)| {
            let mut ws = take(pool).unwrap_or_else(|| d.workspace());
            let sp = ch.rig().frame_joints(src);
            let c = d.deform(ch, src, &sp, target, dst, &mut ws);
            give(pool, ws);
            c
        })
        .reduce(TurnedOver::default, |a, b| TurnedOver {
            before: a.before + b.before,
            after: a.after + b.after,
        })
}

/// The report's row of each output frame: the retrieved frame, its
/// skeleton cost and what it blends, by sequence name.
fn report_steps(ch: &Character, retrieval: &Retrieval, frames: &[OutFrame]) -> Vec<Step> {
    let name = |id: crate::graph::FlatFrame| {
        let (s, t) = ch.graph().frame_of(id);
        (ch.graph().sequences()[s].name.clone(), t)
    };
    retrieval
        .path
        .iter()
        .zip(&retrieval.skeleton_cost)
        .zip(frames)
        .map(|((&id, &c), o)| {
            let (sequence, frame) = name(id);
            Step {
                sequence,
                frame,
                skeleton_cost: c,
                blend: o
                    .used()
                    .iter()
                    .map(|&(f, w)| {
                        let (s, t) = name(f);
                        (s, t, w)
                    })
                    .collect(),
            }
        })
        .collect()
}

/// One worker's blending scratch in [`Prepared::synthesise`].
struct BlendWorker {
    ws: crate::mesh::blend::BlendWorkspace,
    buf: Vec<[f64; 3]>,
    grads: Vec<FrameGradients>,
}

/// A worker's scratch from `pool`, if one is free.
fn take<T>(pool: &std::sync::Mutex<Vec<T>>) -> Option<T> {
    pool.lock().unwrap_or_else(|e| e.into_inner()).pop()
}

/// Gives a worker's scratch back to `pool`.
fn give<T>(pool: &std::sync::Mutex<Vec<T>>, w: T) {
    pool.lock().unwrap_or_else(|e| e.into_inner()).push(w);
}
