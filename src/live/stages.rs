//! Where a live frame's time goes: the session's stages timed one after
//! the other (each stage ends where the next begins, so the stages of a
//! frame add up to its mesh work), on the wall clock and on the process's
//! CPU clock (all threads: the work rayon hands to other threads counts;
//! on a machine busy with other work the CPU time is the stage's own cost,
//! the wall time adds the waits for a core).

use super::report::Latencies;
use serde::Serialize;
use std::time::Instant;

/// The stages of one output frame, in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Stage {
    /// The pose kernel over the analysis window (and the window's upkeep).
    Analysis,
    /// The online trellis: candidates of the new frame, the fixed-lag solve.
    Retrieval,
    /// The offline timeline (interpolation, blend weights) and placement
    /// over the decided history.
    Placement,
    /// Blending the retrieved frames at their placements.
    Blending,
    /// The part-based deformation towards the query pose, with the fold
    /// repair when triangles turned over.
    Deformation,
}

impl Stage {
    /// Every stage, in order.
    pub const ALL: [Stage; 5] = [
        Stage::Analysis,
        Stage::Retrieval,
        Stage::Placement,
        Stage::Blending,
        Stage::Deformation,
    ];

    /// The stage's name in the report.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Analysis => "analysis",
            Stage::Retrieval => "retrieval",
            Stage::Placement => "timeline+placement",
            Stage::Blending => "blending",
            Stage::Deformation => "deformation",
        }
    }
}

pub(crate) use crate::util::cpu::{process_cpu_seconds, thread_cpu_seconds};

/// The stage times of one output frame (milliseconds). The analysis and
/// retrieval of an arriving frame count with the first frame it lets the
/// session output (at the end of a stream one arrival outputs several).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStages {
    /// Wall time of each stage ([`Stage::ALL`] order).
    pub wall_ms: [f64; 5],
    /// Process CPU time of each stage (0 where not known).
    pub cpu_ms: [f64; 5],
    /// The deformation repaired turned-over triangles on this frame.
    pub repaired: bool,
    /// The fold repair's work on this frame (patch systems factored and
    /// their unknowns, projections).
    pub repair_work: crate::deform::unflip::Work,
}

impl FrameStages {
    /// Wall milliseconds of all stages.
    pub fn total_wall_ms(&self) -> f64 {
        self.wall_ms.iter().sum()
    }
}

/// A running stage clock: [`StageClock::lap`] ends the current stage and
/// starts the next.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StageClock {
    wall: Instant,
    cpu: Option<f64>,
}

impl StageClock {
    /// Starts the clock.
    pub fn start() -> StageClock {
        StageClock {
            wall: Instant::now(),
            cpu: process_cpu_seconds(),
        }
    }

    /// Adds the time since the last lap to `stage` of `into` and starts
    /// the next stage.
    pub fn lap(&mut self, stage: Stage, into: &mut FrameStages) {
        let now = StageClock::start();
        let i = stage as usize;
        into.wall_ms[i] += now.wall.saturating_duration_since(self.wall).as_secs_f64() * 1e3;
        if let (Some(a), Some(b)) = (self.cpu, now.cpu) {
            into.cpu_ms[i] += ((b - a) * 1e3).max(0.0);
        }
        *self = now;
    }

    /// Ends `stage` of two frames made at once (the two-frame overlap):
    /// the wall time since the last lap goes to both (each frame's mesh is
    /// ready when the pair's is), the process CPU time is split, `share`
    /// of it to `a` (the threads' own CPU times' ratio: an estimate, as
    /// the work rayon hands between the two threads counts with the
    /// thread that runs it).
    pub fn lap_pair(&mut self, stage: Stage, a: &mut FrameStages, b: &mut FrameStages, share: f64) {
        let now = StageClock::start();
        let i = stage as usize;
        let wall = now.wall.saturating_duration_since(self.wall).as_secs_f64() * 1e3;
        a.wall_ms[i] += wall;
        b.wall_ms[i] += wall;
        if let (Some(x), Some(y)) = (self.cpu, now.cpu) {
            let cpu = ((y - x) * 1e3).max(0.0);
            let share = share.clamp(0.0, 1.0);
            a.cpu_ms[i] += cpu * share;
            b.cpu_ms[i] += cpu * (1.0 - share);
        }
        *self = now;
    }
}

/// The stage times of a session, binned (flat memory).
#[derive(Debug, Clone, Default)]
pub(crate) struct StageTally {
    wall: [Latencies; 5],
    cpu: [Latencies; 5],
    /// Frames whose deformation ran the fold repair, and their
    /// deformation's wall time.
    repaired: Latencies,
    /// The other frames' deformation wall time.
    plain: Latencies,
    /// The fold repair's work summed over the frames.
    work: crate::deform::unflip::Work,
    /// Frames whose repair stopped at its budget
    /// ([`crate::deform::unflip::Work::stopped`] above 0).
    budget_reached: u64,
    /// Frames counted.
    frames: u64,
}

impl StageTally {
    /// Counts one output frame.
    pub fn add(&mut self, f: &FrameStages) {
        for (w, &ms) in self.wall.iter_mut().zip(&f.wall_ms) {
            w.add_ms(ms);
        }
        for (c, &ms) in self.cpu.iter_mut().zip(&f.cpu_ms) {
            c.add_ms(ms);
        }
        let w = &f.repair_work;
        self.work.patches += w.patches;
        self.work.patch_vertices += w.patch_vertices;
        self.work.projections += w.projections;
        self.work.surface_patches += w.surface_patches;
        self.work.retry_patches += w.retry_patches;
        self.work.later_pass_patches += w.later_pass_patches;
        self.work.replayed_rounds += w.replayed_rounds;
        self.work.stopped += w.stopped;
        self.budget_reached += u64::from(w.stopped > 0);
        self.frames += 1;
        let d = f.wall_ms[Stage::Deformation as usize];
        if f.repaired {
            self.repaired.add_ms(d);
        } else {
            self.plain.add_ms(d);
        }
    }

    /// The summary.
    pub fn summary(&self) -> StageReport {
        let stages = Stage::ALL
            .iter()
            .map(|&s| {
                let (w, c) = (&self.wall[s as usize], &self.cpu[s as usize]);
                let ws = w.summary();
                let cs = c.summary();
                StageSummary {
                    stage: s.name(),
                    median_ms: ws.median_ms,
                    p99_ms: ws.p99_ms,
                    max_ms: ws.max_ms,
                    mean_ms: ws.mean_ms,
                    cpu_mean_ms: cs.mean_ms,
                    cpu_p99_ms: cs.p99_ms,
                    cpu_max_ms: cs.max_ms,
                }
            })
            .collect();
        let (r, p) = (self.repaired.summary(), self.plain.summary());
        let per_frame = |x: usize| x as f64 / self.frames.max(1) as f64;
        StageReport {
            patch_solves_per_frame: per_frame(self.work.patches),
            patch_unknowns_per_frame: per_frame(self.work.patch_vertices),
            projections_per_frame: per_frame(self.work.projections),
            surface_patch_solves_per_frame: per_frame(self.work.surface_patches),
            retry_patch_solves_per_frame: per_frame(self.work.retry_patches),
            later_pass_patch_solves_per_frame: per_frame(self.work.later_pass_patches),
            replayed_rounds_per_frame: per_frame(self.work.replayed_rounds),
            budget_reached_frames: self.budget_reached,
            stages,
            repaired_frames: r.frames,
            deformation_repaired_mean_ms: r.mean_ms,
            deformation_repaired_p99_ms: r.p99_ms,
            deformation_plain_mean_ms: p.mean_ms,
            deformation_plain_p99_ms: p.p99_ms,
        }
    }
}

/// One stage's figures over a session (milliseconds per output frame).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StageSummary {
    /// The stage ([`Stage::name`]).
    pub stage: &'static str,
    /// Wall time: median, 99th percentile, largest, mean.
    pub median_ms: f64,
    /// Wall time, 99th percentile.
    pub p99_ms: f64,
    /// Wall time, largest.
    pub max_ms: f64,
    /// Wall time, mean.
    pub mean_ms: f64,
    /// Process CPU time (all threads), mean.
    pub cpu_mean_ms: f64,
    /// Process CPU time, 99th percentile.
    pub cpu_p99_ms: f64,
    /// Process CPU time, largest.
    pub cpu_max_ms: f64,
}

/// The stage breakdown of a session.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct StageReport {
    /// Each stage, in order; their means add up to the mesh work's mean.
    pub stages: Vec<StageSummary>,
    /// Frames whose deformation ran the fold repair.
    pub repaired_frames: u64,
    /// Their deformation's wall time, mean and 99th percentile.
    pub deformation_repaired_mean_ms: f64,
    /// Their deformation's wall time, 99th percentile.
    pub deformation_repaired_p99_ms: f64,
    /// The other frames' deformation wall time, mean.
    pub deformation_plain_mean_ms: f64,
    /// The other frames' deformation wall time, 99th percentile.
    pub deformation_plain_p99_ms: f64,
    /// The fold repair's patch systems factored per output frame, mean
    /// ([`crate::deform::unflip::Work::patches`]).
    pub patch_solves_per_frame: f64,
    /// Their unknowns per output frame, mean.
    pub patch_unknowns_per_frame: f64,
    /// The untangling's projections per output frame, mean.
    pub projections_per_frame: f64,
    /// Of the patch solves, the surface repair's rounds', per output
    /// frame ([`crate::deform::unflip::Work::surface_patches`]).
    pub surface_patch_solves_per_frame: f64,
    /// Of the patch solves, the adaptive retry's, per output frame.
    pub retry_patch_solves_per_frame: f64,
    /// Of the patch solves, the second and later passes', per output frame.
    pub later_pass_patch_solves_per_frame: f64,
    /// Rounds taken from the pass before instead of solved again, per
    /// output frame ([`crate::deform::unflip::Replay`]).
    pub replayed_rounds_per_frame: f64,
    /// Frames whose repair stopped at its budget (a step not started:
    /// [`crate::deform::unflip::Work::stopped`]); 0 with no budget.
    pub budget_reached_frames: u64,
}
