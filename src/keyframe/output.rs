//! A planned path made into frames: synthesis along the timeline with the
//! character's prepared blender ([`Prepared`]), into any [`FrameSink`]
//! (held or streamed: one path).

use super::heading::wrap;
use super::planner::*;
use super::problem::*;
use super::report::*;
use super::{place, pose, smoothness};
use crate::db::Character;
use crate::deform::DeformMode;
use crate::drive::{DriveOptions, FrameSink, Prepared};
use crate::graph::FlatFrame;
use std::time::Instant;

/// The synthesised key-frame animation.
pub struct Output {
    /// Positions, frame-major (metres, Y-up).
    pub positions: Vec<[f64; 3]>,
    /// The plan.
    pub plan: Plan,
    /// The report.
    pub report: Report,
}

/// Plans and synthesises: key-frames `keys` (at least two), targets,
/// options. Errors: the search's (no path between two key-frames) or a
/// failed factorisation of the blender. A one-off: the character is
/// prepared ([`prepare`]) for this call and every frame is held
/// ([`plan_path`] then [`Planned::synthesise_into`] the sink `Vec`); the
/// CLI streams its output instead.
pub fn synthesise(
    ch: &Character,
    keys: &[FlatFrame],
    targets: &Targets,
    opts: &KeyframeOptions,
) -> Result<Output, KeyframeError> {
    let planned = plan_path(ch, keys, targets, opts, &mut |_| {})?;
    // The positions held below.
    let what = if keys.len() > 2 {
        format!(
            "the key-frame path through {} key-frames (use fewer via key-frames, or lower `Targets::distance` or `Targets::time`)",
            keys.len()
        )
    } else {
        "the key-frame path (lower `Targets::distance` or `Targets::time`)".to_string()
    };
    crate::util::budget::check_frames(&what, planned.frames(), ch.n(), 1)?;
    let prepared = prepare(ch)?;
    let mut positions = Vec::with_capacity(planned.frames() * ch.n());
    let s = planned.synthesise_into::<_, KeyframeError>(
        ch,
        &prepared,
        targets,
        opts,
        &mut positions,
    )?;
    Ok(Output {
        positions,
        plan: s.plan,
        report: s.report,
    })
}

/// A key-frame path found ([`plan_path`]), its meshes not yet made.
pub struct Planned {
    planner: Planner,
    plan: Plan,
}

impl Planned {
    /// Bounds the search hit (e.g. a time target beyond the longest path
    /// it considers), for messages about the path it found.
    pub fn bounds_hit(&self) -> &[String] {
        &self.plan.stats.bounds_hit
    }
}

/// The character prepared for key-frame synthesis ([`Prepared::new`]
/// without a deformation: the topology in metres and the factored
/// blender, built once per job and read by every query). Errors: a failed
/// factorisation of the blender.
pub fn prepare(ch: &Character) -> Result<Prepared, KeyframeError> {
    let opts = DriveOptions {
        deform: DeformMode::None,
        ..DriveOptions::default()
    };
    Prepared::new(ch, &opts).map_err(|e| KeyframeError::Search(format!("blending: {e}")))
}

/// [`Output`] without the positions, which went to a sink frame by frame
/// ([`Planned::synthesise_into`]).
pub struct Streamed {
    /// The plan.
    pub plan: Plan,
    /// The report.
    pub report: Report,
}

/// Finds the path through key-frames `keys` (at least two) for the
/// targets (Eq. 7). Errors: too few keys, or the search's (no path
/// between two key-frames).
/// `progress` is told each stage (the graph, preparing, searching).
pub fn plan_path(
    ch: &Character,
    keys: &[FlatFrame],
    targets: &Targets,
    opts: &KeyframeOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<Planned, KeyframeError> {
    if keys.len() < 2 {
        return Err(KeyframeError::TooFew);
    }
    let fps = ch.manifest().fps;
    progress("the frame graph");
    let g = key_graph_with(ch, opts, progress);
    progress("preparing the search (segments, loops)");
    let mut planner = Planner::new(g, keys, fps, &opts.search)
        .map_err(|e| KeyframeError::Search(describe(ch, &e)))?;
    planner.facing = facing_change(ch, keys);
    progress("searching");
    let plan = planner
        .plan(targets, &opts.search)
        .map_err(|e| KeyframeError::Search(describe(ch, &e)))?;
    Ok(Planned { planner, plan })
}

/// A sink that counts the seconds spent in the sink it wraps.
struct Timed<S> {
    sink: S,
    seconds: f64,
}

impl<S: FrameSink> FrameSink for Timed<S> {
    type Error = S::Error;
    fn push(&mut self, frame: &[[f64; 3]]) -> Result<(), S::Error> {
        let t = Instant::now();
        let r = self.sink.push(frame);
        self.seconds += t.elapsed().as_secs_f64();
        r
    }
}

impl Planned {
    /// Output frames of the path.
    pub fn frames(&self) -> usize {
        self.plan.path.len()
    }

    /// Blends and places the path's meshes ([`place::place_into`]) with
    /// the character's prepared blender ([`prepare`], or any
    /// [`Prepared`] of this character), handing each output frame (the
    /// character's vertices, metres, Y-up) to `sink` in order, and
    /// reports. A path of any length needs the memory of one chunk of
    /// frames, not of every frame, when the sink streams. The report's
    /// `mesh_seconds` leaves out the time spent in the sink. Errors: a
    /// preparation of another character, or the sink's first error.
    pub fn synthesise_into<S: FrameSink, E: From<KeyframeError> + From<S::Error>>(
        self,
        ch: &Character,
        prepared: &Prepared,
        targets: &Targets,
        opts: &KeyframeOptions,
        sink: S,
    ) -> Result<Streamed, E> {
        let vertices = prepared.topology_metres().vertex_count();
        if vertices != ch.n() {
            return Err(E::from(KeyframeError::Unprepared(format!(
                "prepared for {vertices} vertices; the database has {}",
                ch.n()
            ))));
        }
        let Planned { planner, plan } = self;
        let fps = ch.manifest().fps;
        let t0 = Instant::now();
        let mut timed = Timed { sink, seconds: 0.0 };
        let track = place::place_into(
            ch,
            prepared.blender(),
            &planner.graph,
            &plan.path,
            &opts.timeline,
            &mut timed,
        )?;
        let mesh_seconds = (t0.elapsed().as_secs_f64() - timed.seconds).max(0.0);
        let mut cache = smoothness::Measurer::new(ch);
        let trans = transitions(ch, &planner.graph, &plan.path, &opts.timeline, &mut cache);
        let (de, te) = match targets {
            Targets::Global { distance, time } => (
                Some(plan.measure.distance - distance),
                Some(plan.measure.frames as f64 / fps - time),
            ),
            Targets::PerSegment(_) => (None, None),
        };
        let report = Report {
            keys: planner.keys.iter().map(|&k| key_name(ch, k)).collect(),
            targets: targets.clone(),
            weights: opts.search.weights,
            solver: opts.search.solver,
            fps,
            frames: plan.path.len(),
            distance: plan.measure.distance,
            time: plan.measure.frames as f64 / fps,
            distance_error: de,
            time_error: te,
            cost: plan.cost,
            segments: segment_reports(ch, &planner, &plan, targets),
            smoothness: mean_smoothness(&trans),
            smoothness_vertex: mean_smoothness_vertex(&trans),
            transitions: trans,
            final_heading_deg: track.heading.last().copied().unwrap_or(0.0).to_degrees(),
            final_facing_deg: plan.facing_deg,
            heading_target_deg: opts.search.heading.map(|h| h.degrees),
            heading_error_deg: opts
                .search
                .heading
                .map(|h| wrap((plan.facing_deg - h.degrees).to_radians()).to_degrees()),
            poses: Vec::new(),
            stats: plan.stats.clone(),
            prepare_seconds: planner.prepare_seconds,
            search_seconds: plan.search_seconds,
            search_cpu_seconds: plan.search_cpu_seconds,
            mesh_seconds,
            reach: match targets {
                Targets::Global { distance, time } => {
                    planner.reach_of(*distance, *time, &opts.search)
                }
                Targets::PerSegment(_) => None,
            },
        };
        Ok(Streamed { plan, report })
    }
}

/// The end key-frame's facing minus the start's (radians, from their
/// skeletons; [`Planner::facing`]).
pub fn facing_change(ch: &Character, keys: &[FlatFrame]) -> f64 {
    match (keys.first(), keys.last()) {
        (Some(&a), Some(&b)) if a.max(b).index() < ch.poses().len() => {
            pose::facing(ch.pose(b)) - pose::facing(ch.pose(a))
        }
        _ => 0.0,
    }
}
