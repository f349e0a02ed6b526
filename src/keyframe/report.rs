//! What a plan reports: per segment, per transition, its smoothness, and why no
//! path joins two key-frames.

use super::error::SearchError;
use super::graph::KeyGraph;
use super::planner::*;
use super::problem::*;
use super::segment::Stats;
use super::{graph, options, pose, smoothness};
use crate::db::Character;
use crate::drive::timeline::{TimelineOptions, timeline};
use crate::graph::FlatFrame;
use serde::Serialize;

/// The report of a key-frame animation.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Key-frames in order.
    pub keys: Vec<String>,
    /// The targets.
    pub targets: Targets,
    /// Weights used (per metre, per frame).
    pub weights: options::Weights,
    /// Repetition solver.
    pub solver: options::Solver,
    /// Frames per second.
    pub fps: f64,
    /// Output frames.
    pub frames: usize,
    /// Achieved distance (metres) and time (seconds).
    pub distance: f64,
    /// Seconds.
    pub time: f64,
    /// `distance − target` (global target), metres.
    pub distance_error: Option<f64>,
    /// `time − target`, seconds.
    pub time_error: Option<f64>,
    /// Eq. 7's terms.
    pub cost: CostTerms,
    /// Per segment.
    pub segments: Vec<SegmentReport>,
    /// Transitions taken, with their blend windows and smoothness (metres).
    pub transitions: Vec<TransitionReport>,
    /// Mean smoothness over the transitions (metres; `None` without any).
    pub smoothness: Option<f64>,
    /// The same with the vertex-set Hausdorff distance (the measure before
    /// the surface one; [`smoothness::Smoothness::vertex`]).
    pub smoothness_vertex: Option<f64>,
    /// Final placement rotation relative to the first key-frame's capture
    /// (degrees, the sum of the transitions' turns).
    pub final_heading_deg: f64,
    /// Final facing of the character relative to the first key-frame's
    /// (degrees, ±180: the turn plus the end key-frame's own facing minus
    /// the start's, [`pose::facing`]).
    pub final_facing_deg: f64,
    /// The heading target (`--heading`), degrees.
    pub heading_target_deg: Option<f64>,
    /// `final_facing − target`, wrapped to ±180 degrees.
    pub heading_error_deg: Option<f64>,
    /// Key-frames given as skeleton poses and the frames they resolved to
    /// (filled by the caller that resolved them).
    pub poses: Vec<pose::Resolved>,
    /// Search counts and bounds hit.
    pub stats: Stats,
    /// Seconds preparing the search (compressed graph, loops).
    pub prepare_seconds: f64,
    /// Seconds searching.
    pub search_seconds: f64,
    /// CPU seconds of the searching thread ([`clock`]; `None` where the
    /// platform does not say).
    pub search_cpu_seconds: Option<f64>,
    /// Seconds blending and placing the meshes.
    pub mesh_seconds: f64,
    /// What the database can make of a global target (`None` with
    /// per-segment targets).
    pub reach: Option<TargetReach>,
}

/// A transition of the output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TransitionReport {
    /// Output frame after the jump.
    pub at: usize,
    /// Frame left.
    pub from: String,
    /// Frame entered.
    pub to: String,
    /// Blend half-window.
    pub window: usize,
    /// Transition cost of the graph edge.
    pub cost: f64,
    /// Weighted surface Hausdorff distance of the overlapping frames
    /// (metres, [`smoothness::Smoothness::surface`]).
    pub smoothness: f64,
    /// Weighted vertex-set Hausdorff distance ([`smoothness::Smoothness::vertex`]).
    pub smoothness_vertex: f64,
}

/// The report's segments.
pub fn segment_reports(
    ch: &Character,
    planner: &Planner,
    plan: &Plan,
    targets: &Targets,
) -> Vec<SegmentReport> {
    plan.segments
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let (td, tt) = match targets {
                Targets::Global { .. } => (None, None),
                Targets::PerSegment(v) => (Some(v[i].0), Some(v[i].1)),
            };
            SegmentReport {
                from: key_name(ch, s.from),
                to: key_name(ch, s.to),
                target_distance: td,
                target_time: tt,
                distance: s.measure.distance,
                time: s.measure.frames as f64 / planner.fps,
                transition_cost: s.measure.cost,
                walk: runs(ch, &s.walk),
                loops: s
                    .loops
                    .iter()
                    .map(|l| LoopReport {
                        at: key_name(ch, l.at),
                        frames: runs(ch, &l.frames),
                        repeats: l.repeats,
                        measure: l.measure,
                    })
                    .collect(),
            }
        })
        .collect()
}

/// Transitions of a path with their blend windows (from the timeline) and
/// smoothness, measured through `cache` (each overlapping frame pair once,
/// [`smoothness::Measurer`]; the path's new pairs in parallel).
pub fn transitions(
    ch: &Character,
    g: &KeyGraph,
    path: &[FlatFrame],
    opts: &TimelineOptions,
    cache: &mut smoothness::Measurer,
) -> Vec<TransitionReport> {
    let (_, jumps) = timeline(path, &graph::KeyFrames { ch, graph: g }, opts);
    let asked: Vec<(FlatFrame, FlatFrame, usize)> =
        jumps.iter().map(|j| (j.from, j.to, j.window)).collect();
    cache.prefill(ch, &asked);
    jumps
        .iter()
        .map(|j| {
            let s = cache.transition(ch, j.from, j.to, j.window);
            TransitionReport {
                at: j.at,
                from: key_name(ch, j.from),
                to: key_name(ch, j.to),
                window: j.window,
                cost: g.edge(j.from, j.to).map_or(0.0, |e| e.cost),
                smoothness: s.surface,
                smoothness_vertex: s.vertex,
            }
        })
        .collect()
}

/// The mean of the transitions' smoothness (per transition, then over the
/// path, as Sec. 6.1 averages).
pub fn mean_smoothness(t: &[TransitionReport]) -> Option<f64> {
    (!t.is_empty()).then(|| t.iter().map(|x| x.smoothness).sum::<f64>() / t.len() as f64)
}

/// [`mean_smoothness`] of the vertex-set distance.
pub fn mean_smoothness_vertex(t: &[TransitionReport]) -> Option<f64> {
    (!t.is_empty()).then(|| t.iter().map(|x| x.smoothness_vertex).sum::<f64>() / t.len() as f64)
}

/// A search error in the database's words (`SEQUENCE:FRAME`).
pub fn describe(ch: &Character, e: &SearchError) -> String {
    match e {
        SearchError::NoPath { from, to } => format!(
            "no path from key-frame {} to {} in the graph (no sequence of transitions joins them{}; see `surfmotion graph`)",
            key_name(ch, *from),
            key_name(ch, *to),
            no_path_hint(ch, *from, *to)
        ),
        other => other.to_string(),
    }
}

/// Which key-frame to move when no path joins `from` to `to`: the earliest
/// frame of `to`'s sequence a transition of the graph enters (a frame
/// before it is reached only along its own sequence), and the last frame
/// of `from`'s sequence a transition leaves. Empty when neither explains it.
fn no_path_hint(ch: &Character, from: FlatFrame, to: FlatFrame) -> String {
    let g = ch.graph();
    let adj = ch.adjacency();
    let n = g.frame_count();
    let ((sf, ff), (st, ft)) = (g.frame_of(from), g.frame_of(to));
    let (mut entered, mut left): (Option<usize>, Option<usize>) = (None, None);
    for f in FlatFrame::all(n.min(adj.offsets.len().saturating_sub(1))) {
        for (t, _) in adj.successors(f) {
            if t == f.next() || t.index() >= n {
                continue;
            }
            let ((sa, a), (sb, b)) = (g.frame_of(f), g.frame_of(t));
            if sb == st {
                entered = Some(entered.map_or(b, |e| e.min(b)));
            }
            if sa == sf {
                left = Some(left.map_or(a, |l| l.max(a)));
            }
        }
    }
    let seq = |s: usize| &g.sequences()[s].name;
    let mut out = Vec::new();
    // `to` is reachable along its own sequence from an earlier `from`.
    let along = sf == st && ff <= ft;
    match entered {
        Some(e) if ft < e && !along => out.push(format!(
            "; the earliest frame of {0} a transition enters is {0}:{e}: move key-frame {0}:{ft} to {0}:{e} or later",
            seq(st)
        )),
        None if !along => out.push(format!("; no transition enters {}", seq(st))),
        _ => {}
    }
    match left {
        Some(l) if ff > l && !along => out.push(format!(
            "; the last frame of {0} a transition leaves is {0}:{l}: move key-frame {0}:{ff} to {0}:{l} or earlier",
            seq(sf)
        )),
        None if !along => out.push(format!("; no transition leaves {}", seq(sf))),
        _ => {}
    }
    out.concat()
}
