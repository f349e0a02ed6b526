//! Mocap-driven synthesis (Huang et al. 2015, Sec. 5.2): a mocap clip in,
//! a mesh sequence of the character out.
//!
//! [`query`] prepares the clip, [`crate::db::Character`] is the database loaded
//! with its graph, [`trellis`] retrieves the frame path (5.2.1), [`timeline`] turns
//! repeats into interpolations (5.2.2) and jumps into blends (4.4), and
//! [`synthesise`] makes the meshes: each output frame's database frames are
//! placed on the query's root trajectory (the rotation about the vertical
//! and the floor translation that best fit the frame's skeleton onto the
//! query pose, smoothed over time) and blended non-linearly.

/// The loaded character (now [`crate::db::character`]; kept here so
/// `retarget::character::Character` paths keep working).
pub mod character {
    pub use crate::db::character::*;
}
pub mod query;
pub mod timeline;
pub mod trellis;

use crate::db::Character;
use crate::deform::{DeformMode, DeformOptions, Deformer, TurnedOver};
use crate::mesh::blend::{Blender, FrameGradients};
use crate::mesh::solver::SolveError;
use crate::pose::retarget::{Reference, ReferenceSource, stance_offsets};
use crate::pose::{
    Pose,
    measure::{floor_fit, rotate_yaw},
};
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;
use timeline::{Frames, Jump, OutFrame, TimelineOptions, timeline};
use trellis::{Retrieval, TrellisInput, TrellisOptions, retrieve};

/// Options of [`synthesise`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RetargetOptions {
    /// Retrieval.
    pub trellis: TrellisOptions,
    /// Interpolation and blending.
    pub timeline: TimelineOptions,
    /// Half-width (frames) of the moving average applied to the placement
    /// on the root trajectory. Default: 3.
    pub smooth: usize,
    /// Deformation towards the query skeleton (Sec. 5.2.3). Default: part.
    pub deform: DeformMode,
    /// Its settings.
    pub deform_options: DeformOptions,
}

impl Default for RetargetOptions {
    fn default() -> Self {
        RetargetOptions {
            trellis: TrellisOptions::default(),
            timeline: TimelineOptions::default(),
            smooth: 3,
            deform: DeformMode::Part,
            deform_options: DeformOptions::default(),
        }
    }
}

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
    pub reference: ReferenceSource,
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

/// Scratch of [`blend_placed`]: a blending workspace, a frame buffer and
/// up to four frames' gradients.
pub struct BlendScratch<'a> {
    /// The blender's workspace.
    pub ws: &'a mut crate::mesh::blend::BlendWorkspace,
    /// One frame's positions.
    pub buf: &'a mut Vec<[f64; 3]>,
    /// Gradients of each frame blended (at least four).
    pub grads: &'a mut Vec<FrameGradients>,
}

/// One output frame (Huang et al. 2015, Sec. 4.4): the database frames
/// `used` (id, weight), each placed on the floor by `place` (the placement
/// of frame `anchor`; a frame of another capture, `!same(id)`, is first
/// fitted onto the anchor's skeleton), then blended non-linearly into
/// `dst` (a single frame is copied). Shared by `retarget` and `keyframe`.
#[allow(clippy::too_many_arguments)]
pub fn blend_placed(
    ch: &Character,
    blender: &Blender,
    used: &[(u32, f64)],
    anchor: u32,
    place: Floor,
    same: impl Fn(u32) -> bool,
    s: &mut BlendScratch<'_>,
    dst: &mut [[f64; 3]],
) {
    for (i, &(id, _)) in used.iter().enumerate() {
        let pl = if same(id) {
            place
        } else {
            place.after(&Floor::fit(
                &ch.poses()[id as usize],
                &ch.poses()[anchor as usize],
            ))
        };
        ch.frame_metres(id, s.buf);
        for p in s.buf.iter_mut() {
            *p = pl.apply(DVec3::from_array(*p)).to_array();
        }
        if used.len() == 1 {
            dst.copy_from_slice(s.buf);
        } else {
            blender.decompose_into(s.buf, s.ws, &mut s.grads[i]);
        }
    }
    if used.len() > 1 {
        let inputs: [(&FrameGradients, f64); 4] =
            std::array::from_fn(|i| (&s.grads[i], used.get(i).map_or(0.0, |u| u.1)));
        blender.blend_many(&inputs[..used.len()], dst, s.ws);
    }
}

/// A rigid motion on the floor: rotation `theta` about Y, then `t` (y = 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Floor {
    /// Rotation about Y (radians, [`rotate_yaw`]'s sense).
    pub theta: f64,
    /// Translation (y = 0).
    pub t: DVec3,
}

impl Floor {
    /// The floor motion that best maps `from` onto `to` (least squares).
    pub fn fit(from: &Pose, to: &Pose) -> Floor {
        let (cos, sin, ct, cf) = floor_fit(to, from);
        let theta = sin.atan2(cos);
        Floor {
            theta,
            t: ct - rotate_yaw(cf, cos, sin),
        }
    }
    /// The motion applied to a point.
    pub fn apply(&self, p: DVec3) -> DVec3 {
        rotate_yaw(p, self.theta.cos(), self.theta.sin()) + self.t
    }
    /// `self ∘ other`.
    pub fn after(&self, other: &Floor) -> Floor {
        Floor {
            theta: self.theta + other.theta,
            t: rotate_yaw(other.t, self.theta.cos(), self.theta.sin()) + self.t,
        }
    }
}

impl Frames for Character {
    fn frame_of(&self, id: u32) -> (usize, usize) {
        self.graph().frame_of(id)
    }
    fn id(&self, s: usize, t: usize) -> u32 {
        self.graph().frame_id(s, t)
    }
    fn len(&self, s: usize) -> usize {
        self.graph().sequences[s].len
    }
    fn transition_window(&self, from: u32, to_prev: u32) -> Option<usize> {
        let (sa, m) = self.graph().frame_of(from);
        let (sb, n) = self.graph().frame_of(to_prev);
        self.graph()
            .transitions
            .iter()
            .find(|t| t.from == sa && t.to == sb && t.m == m && t.n == n)
            .map(|t| t.window)
    }
}

/// Why a retarget cannot run.
#[derive(Debug, thiserror::Error)]
pub enum RetargetError {
    /// A solver could not be factored (mesh problems).
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The output would not fit in memory (checked before allocating).
    #[error(transparent)]
    Budget(#[from] crate::budget::OverBudget),
}

/// Output frames made at once by [`synthesise_each`]: blended and deformed
/// in parallel, then handed on in order. A chunk holds two copies of the
/// character's vertices per frame (64 × 6,304 vertices × 48 B ≈ 19 MB).
pub const CHUNK_FRAMES: usize = 64;

/// Drives the character by the mocap poses (metres, Y-up, the clip's own
/// skeleton at the database frame rate) and the clip's neutral `reference`
/// ([`query::load_mocap`] gives both): Sec. 5.2 up to interpolation. Every
/// output frame is held: the memory is checked against
/// [`crate::budget`] first. [`synthesise_each`] streams instead.
pub fn synthesise(
    ch: &Character,
    mocap: &[Pose],
    reference: &Reference,
    fps: f64,
    opts: &RetargetOptions,
) -> Result<Output, RetargetError> {
    // One output frame per query frame, each holding the character's
    // vertices: refuse before allocating (issue 18, item 12).
    crate::budget::check_frames(
        &format!("the retarget at {fps} fps"),
        mocap.len(),
        ch.n(),
        1,
    )?;
    let mut positions = Vec::with_capacity(mocap.len() * ch.n());
    let s = synthesise_each(ch, mocap, reference, fps, opts, |_, p| {
        positions.extend_from_slice(p);
        Ok::<(), RetargetError>(())
    })?;
    Ok(Output {
        positions,
        query: s.query,
        report: s.report,
    })
}

/// What [`synthesise_each`] returns once every frame is handed on.
pub struct Streamed {
    /// The query on the character's skeleton (metres, Y-up).
    pub query: Vec<Pose>,
    /// What was done.
    pub report: Report,
}

/// [`synthesise`] handing each output frame (its index and the character's
/// vertices, metres, Y-up) to `each` in order, so a clip of any length
/// needs the memory of [`CHUNK_FRAMES`] frames, not of every frame (issue
/// 18, item 12). The frames are those of [`synthesise`], bit for bit: the
/// placements on the root trajectory (Sec. 5.2) are computed for every
/// frame first (they are smoothed over time), then chunks of frames are
/// blended (Sec. 4.4) and deformed (Sec. 5.2.3) in parallel, each frame
/// independently, with per-worker scratch reused from chunk to chunk. The
/// report's timings count the blending and deformation, not `each`. The
/// first error of `each` stops the job and is returned.
pub fn synthesise_each<E: From<RetargetError>>(
    ch: &Character,
    mocap: &[Pose],
    reference: &Reference,
    fps: f64,
    opts: &RetargetOptions,
    mut each: impl FnMut(usize, &[[f64; 3]]) -> Result<(), E>,
) -> Result<Streamed, E> {
    let mut timings = Timings::default();
    let t0 = Instant::now();
    let query = query::to_database(ch, reference, mocap);
    timings.query = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let successor = |id: u32| ch.successor(id);
    let dissimilarity = |a: u32, b: u32| ch.matrix().get(a as usize, b as usize);
    let input = TrellisInput {
        poses: ch.poses(),
        adjacency: ch.adjacency(),
        successor: &successor,
        dissimilarity: &dissimilarity,
    };
    // Retrieval compares poses as they stand on the database's floor: the
    // clip's ground raised under a footfall on a step (a block CMU subject
    // 03 climbs) is no part of the pose, and the database's frames all
    // stand on one floor (Eq. 28 keeps height). The deformation still
    // follows the raised query.
    let raised = stance_offsets(ch.rest_pose(), reference, mocap);
    let on_floor: Vec<Pose> = query
        .iter()
        .zip(raised.iter().chain(std::iter::repeat(&0.0)))
        .map(|(p, &r)| p.map(|q| q - DVec3::Y * r))
        .collect();
    let retrieval = retrieve(&on_floor, &input, &opts.trellis);
    timings.retrieval = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    let (frames, jumps) = timeline(&retrieval.path, ch, &opts.timeline);
    timings.timeline = t2.elapsed().as_secs_f64();
    let t3 = Instant::now();
    let topo = ch.topology_metres();
    let blender = Blender::new(&topo).map_err(RetargetError::from)?;
    timings.factor = t3.elapsed().as_secs_f64();
    let t4 = Instant::now();
    let placed = placements(ch, &retrieval.path, &frames, &query, opts.smooth);
    timings.meshes = t4.elapsed().as_secs_f64();
    let deformer = if opts.deform != DeformMode::None {
        let t5 = Instant::now();
        let d =
            Deformer::new(ch, opts.deform, &opts.deform_options).map_err(RetargetError::from)?;
        timings.deform_factor = t5.elapsed().as_secs_f64();
        Some(d)
    } else {
        None
    };
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
        blended[..m * n]
            .par_chunks_mut(n)
            .enumerate()
            .for_each(|(i, dst)| {
                let k = start + i;
                let mut w = take(&blend_pool).unwrap_or_else(|| BlendWorker {
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
                    &blender,
                    frames[k].used(),
                    primary,
                    placed[k],
                    |id| id == primary,
                    &mut scratch,
                    dst,
                );
                give(&blend_pool, w);
            });
        timings.meshes += t.elapsed().as_secs_f64();
        let out: &[[f64; 3]] = match &deformer {
            Some(d) => {
                let t = Instant::now();
                let sum = deformed[..m * n]
                    .par_chunks_mut(n)
                    .zip(blended[..m * n].par_chunks(n))
                    .zip(query[start..start + m].par_iter())
                    .map(|((dst, src), target)| {
                        let mut ws = take(&deform_pool).unwrap_or_else(|| d.workspace());
                        let sp = ch.rig().frame_joints(src);
                        let c = d.deform(ch, src, &sp, target, dst, &mut ws);
                        give(&deform_pool, ws);
                        c
                    })
                    .reduce(TurnedOver::default, |a, b| TurnedOver {
                        before: a.before + b.before,
                        after: a.after + b.after,
                    });
                turned_over.before += sum.before;
                turned_over.after += sum.after;
                timings.deform += t.elapsed().as_secs_f64();
                &deformed[..m * n]
            }
            None => &blended[..m * n],
        };
        for (i, f) in out.chunks(n).enumerate() {
            each(start + i, f)?;
        }
    }
    let name = |id: u32| {
        let (s, t) = ch.graph().frame_of(id);
        (ch.graph().sequences[s].name.clone(), t)
    };
    let steps = retrieval
        .path
        .iter()
        .zip(&retrieval.skeleton_cost)
        .zip(&frames)
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
        .collect();
    Ok(Streamed {
        query,
        report: Report {
            frames: frames.len(),
            fps,
            reference: reference.source,
            retrieval,
            jumps,
            steps,
            timings,
            deform: opts.deform,
            turned_over,
        },
    })
}

/// One worker's blending scratch in [`synthesise_each`].
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

/// The placement of every output frame on the query's root trajectory:
/// its primary source fitted onto the query pose, smoothed over `smooth`
/// frames either side within a segment (between jumps).
fn placements(
    ch: &Character,
    path: &[u32],
    frames: &[OutFrame],
    query: &[Pose],
    smooth: usize,
) -> Vec<Floor> {
    // Placement of each output frame's primary source, smoothed.
    let raw: Vec<Floor> = frames
        .iter()
        .zip(query)
        .map(|(o, q)| Floor::fit(&ch.poses()[o.primary() as usize], q))
        .collect();
    let mut unwrapped: Vec<f64> = raw.iter().map(|f| f.theta).collect();
    for k in 1..unwrapped.len() {
        let d = unwrapped[k] - unwrapped[k - 1];
        unwrapped[k] -= (d / std::f64::consts::TAU).round() * std::f64::consts::TAU;
    }
    // Frames of one segment (between jumps) share their capture's world
    // frame, so their placements can be averaged; across a jump they
    // cannot (the two captures stand in different places).
    let mut segment = vec![0usize; frames.len()];
    for k in 1..frames.len() {
        segment[k] = segment[k - 1] + usize::from(!timeline::plays_on(ch, path[k - 1], path[k]));
    }
    (0..raw.len())
        .map(|k| {
            let mut a = k.saturating_sub(smooth);
            let mut b = (k + smooth + 1).min(raw.len());
            while segment[a] != segment[k] {
                a += 1;
            }
            while segment[b - 1] != segment[k] {
                b -= 1;
            }
            let w = (b - a) as f64;
            Floor {
                theta: unwrapped[a..b].iter().sum::<f64>() / w,
                t: raw[a..b].iter().map(|f| f.t).sum::<DVec3>() / w,
            }
        })
        .collect()
}
