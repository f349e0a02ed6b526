//! The prepared character (faer's "factor once, solve many"): everything
//! surface synthesis needs that depends only on the character and the
//! deformation options — the topology in metres, the blender's
//! factorisation, the deformer's per-region factorisations (Huang et al.
//! 2015, Eq. 32), the character's neutral pose and the database's floor
//! lift — built once per job ([`Prepared::new`]) and read, by reference,
//! by every clip of a batch and every run of the `retarget` verb
//! ([`Prepared::synthesise`]). [`Prepared::analyse`] makes the per-clip
//! value ([`Analysed`]): the clip on the character's skeleton and the
//! ground under each foot, from one run of the pose kernel, read by
//! retrieval, placement, deformation, the joint-velocity error and the
//! plausibility checks (which ran the kernel three more times per clip
//! before issue 40).
//!
//! What it depends on, by reading the code: [`Blender::new`] reads the
//! topology only; [`Deformer::new`] reads the character (topology, rig,
//! frames, manifest overrides) and the [`DeformMode`] and
//! [`DeformOptions`]: a prepared character is keyed on those two
//! ([`Prepared::fits`]). The trellis, timeline and smoothing options are
//! per clip.

use super::options::{DriveError, DriveOptions};
use super::query::database_floor_lift_on;
use crate::db::Character;
use crate::deform::{DeformMode, DeformOptions, Deformer};
use crate::mesh::Mesh;
use crate::mesh::blend::Blender;
use crate::pose::Pose;
use crate::pose::retarget::{
    CharacterNeutral, ClipNeutral, Given, KernelWorkspace, OnCharacter, character_neutral,
    on_character_into, stance_offsets_in,
};
use crate::util::stages::Stages;
use glam::DVec3;
use serde::Serialize;
use std::time::Instant;

/// Seconds spent preparing a character (once per job).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct PrepareTimings {
    /// The topology in metres, the neutral pose and the floor lift.
    pub character: f64,
    /// Factoring the blender.
    pub factor: f64,
    /// Prefactoring the deformation (zero for `lbs` and `none`).
    pub deform_factor: f64,
}

impl PrepareTimings {
    /// All of it.
    pub fn total(&self) -> f64 {
        self.character + self.factor + self.deform_factor
    }
}

/// A character prepared for synthesis: built once, shared (it is `Sync`)
/// by every clip driven through it.
pub struct Prepared {
    topology: Mesh,
    blender: Blender,
    deformer: Option<Deformer>,
    deform: DeformMode,
    deform_options: DeformOptions,
    neutral: CharacterNeutral,
    floor_lift: f64,
    timings: PrepareTimings,
    vertices: usize,
    frames: usize,
}

/// One clip analysed against a character: made once per clip by
/// [`Prepared::analyse`] (or [`Analysed::new`] without a preparation).
#[derive(Debug, Clone, Default)]
pub struct Analysed {
    /// The clip on the character's skeleton, measured from its neutral
    /// pose and standing on the database's floor (metres, Y-up): what
    /// placement and deformation follow and the joint-velocity error is
    /// measured against ([`super::query::to_database`], bit for bit).
    pub query: Vec<Pose>,
    /// The query with the clip's stance height taken off (with the feet
    /// on the clip's footfalls, before they were put there:
    /// [`OnCharacter::free_feet`]): retrieval
    /// compares poses as they stand on the database's floor (a block CMU
    /// subject 03 climbs is no part of the pose).
    pub on_floor: Vec<Pose>,
    /// The pose kernel's run the query is made of: the clip's joints and
    /// global rotations on the character's skeleton (before the floor
    /// lift) and the ground under each foot, read by the plausibility
    /// checks (the ground their floating, penetration and contact are
    /// measured from; the clip's own foot glide).
    pub on_character: OnCharacter,
    /// Seconds analysing.
    pub seconds: f64,
}

impl Analysed {
    /// The clip `mocap` (the clip's own joints, metres, Y-up, the
    /// character's rate) with its neutral `reference` on `ch`, measured
    /// from the character's neutral pose `neutral` and raised by
    /// `floor_lift` metres (the pose kernel runs once here): the query is
    /// [`super::query::on_character`]'s, bit for bit.
    pub fn new(
        ch: &Character,
        neutral: &Pose,
        floor_lift: f64,
        reference: &ClipNeutral,
        mocap: &[Pose],
    ) -> Analysed {
        let ws = &mut KernelWorkspace::new();
        Analysed::on_given(
            ch,
            neutral,
            floor_lift,
            reference,
            mocap,
            &Given::default(),
            ws,
        )
    }

    /// [`Analysed::new`] with what the caller decides instead of the pose
    /// kernel over `mocap` ([`Given`]: the levelling, the floor, the
    /// supports; a live session's decisions over its stream), the pose
    /// kernel's clip-level steps in the buffers of `ws` (a live session's,
    /// reused from frame to frame: the result is the same whatever it
    /// held).
    pub(crate) fn on_given(
        ch: &Character,
        neutral: &Pose,
        floor_lift: f64,
        reference: &ClipNeutral,
        mocap: &[Pose],
        given: &Given<'_>,
        ws: &mut KernelWorkspace,
    ) -> Analysed {
        let mut out = Analysed::default();
        let on = (neutral, floor_lift);
        out.refill(ch, on, reference, mocap, (given, ws));
        out
    }

    /// [`Analysed::on_given`] into this value (every part cleared and
    /// refilled, `(neutral, floor_lift)` the character's neutral pose and
    /// the database's floor lift): no allocation once it and `ws` hold
    /// the clip's frames (issue 45: a live session keeps both).
    pub(crate) fn refill(
        &mut self,
        ch: &Character,
        (neutral, floor_lift): (&Pose, f64),
        reference: &ClipNeutral,
        mocap: &[Pose],
        (given, ws): (&Given<'_>, &mut KernelWorkspace),
    ) {
        let t = Instant::now();
        let rest = ch.rest_pose();
        let Analysed {
            query,
            on_floor,
            on_character,
            ..
        } = self;
        on_character_into(rest, neutral, reference, mocap, given, ws, on_character);
        let lift = DVec3::new(0.0, floor_lift, 0.0);
        query.clear();
        query.extend(on_character.frames.iter().map(|(p, _)| p.map(|q| q + lift)));
        let raised = stance_offsets_in(rest, reference, mocap, given, ws);
        // With the feet on the clip's footfalls, retrieval compares the
        // poses before (issue 44: CMU 03_02 on samba chose other frames).
        let raised = raised.iter().chain(std::iter::repeat(&0.0));
        let down = |(p, &r): (Pose, &f64)| p.map(|q| q - DVec3::Y * r);
        on_floor.clear();
        match &on_character.free_feet {
            Some(f) => {
                let free = f.iter().map(|p| p.map(|q| q + lift));
                on_floor.extend(free.zip(raised).map(down));
            }
            None => on_floor.extend(query.iter().copied().zip(raised).map(down)),
        }
        self.seconds = t.elapsed().as_secs_f64();
    }
}

impl Prepared {
    /// Prepares `ch` for synthesis with the deformation of `opts`
    /// (factorisations made here, once).
    pub fn new(ch: &Character, opts: &DriveOptions) -> Result<Prepared, DriveError> {
        Prepared::new_staged(ch, opts, &mut Stages::start())
    }

    /// [`Prepared::new`], its stages timed into `stages` (issue 43):
    /// `topology in metres`, `neutral pose`, `floor lift`, `blender`
    /// (factored) and `deformer` (prefactored; when deforming).
    pub fn new_staged(
        ch: &Character,
        opts: &DriveOptions,
        stages: &mut Stages,
    ) -> Result<Prepared, DriveError> {
        let t = Instant::now();
        let topology = ch.topology_metres();
        stages.lap("topology in metres");
        let neutral = character_neutral(ch.rest_pose(), ch.poses());
        stages.lap("neutral pose");
        let floor_lift = database_floor_lift_on(ch, &topology);
        stages.lap("floor lift");
        let mut timings = PrepareTimings {
            character: t.elapsed().as_secs_f64(),
            ..PrepareTimings::default()
        };
        let t = Instant::now();
        let blender = Blender::new(&topology)?;
        timings.factor = t.elapsed().as_secs_f64();
        stages.lap("blender");
        let deformer = if opts.deform != DeformMode::None {
            let t = Instant::now();
            let d = Deformer::new(ch, opts.deform, &opts.deform_options)?;
            // The examples it chose, kept for the next load (issue 43).
            ch.examples().save();
            timings.deform_factor = t.elapsed().as_secs_f64();
            stages.lap("deformer");
            Some(d)
        } else {
            None
        };
        Ok(Prepared {
            topology,
            blender,
            deformer,
            deform: opts.deform,
            deform_options: opts.deform_options,
            neutral,
            floor_lift,
            timings,
            vertices: ch.n(),
            frames: ch.frame_count(),
        })
    }

    /// True when this preparation serves `ch` driven with `opts` (same
    /// deformation mode and options; the character's vertex and frame
    /// counts as prepared).
    pub fn fits(&self, ch: &Character, opts: &DriveOptions) -> bool {
        self.deform == opts.deform
            && self.deform_options == opts.deform_options
            && self.vertices == ch.n()
            && self.frames == ch.frame_count()
    }

    /// The topology in metres, Y-up (what outputs are written with).
    pub fn topology_metres(&self) -> &Mesh {
        &self.topology
    }

    /// The factored blender.
    pub fn blender(&self) -> &Blender {
        &self.blender
    }

    /// The prefactored deformation (`None` for [`DeformMode::None`]).
    pub fn deformer(&self) -> Option<&Deformer> {
        self.deformer.as_ref()
    }

    /// The deformation mode prepared.
    pub fn deform(&self) -> DeformMode {
        self.deform
    }

    /// The character's neutral pose ([`character_neutral`]).
    pub fn neutral(&self) -> &CharacterNeutral {
        &self.neutral
    }

    /// Seconds spent preparing.
    pub fn timings(&self) -> PrepareTimings {
        self.timings
    }

    /// The clip `mocap` (the clip's own joints, metres, Y-up, the
    /// database's rate) with its neutral `reference`, analysed for `ch`
    /// (the pose kernel runs once here).
    pub fn analyse(&self, ch: &Character, reference: &ClipNeutral, mocap: &[Pose]) -> Analysed {
        Analysed::new(ch, &self.neutral.pose, self.floor_lift, reference, mocap)
    }

    /// [`Prepared::analyse`] with what the caller decides, in the
    /// buffers of `ws` and into `out` ([`Analysed::refill`]: a live
    /// session's, kept from frame to frame).
    pub(crate) fn analyse_into(
        &self,
        ch: &Character,
        reference: &ClipNeutral,
        mocap: &[Pose],
        given: (&Given<'_>, &mut KernelWorkspace),
        out: &mut Analysed,
    ) {
        let on = (&self.neutral.pose, self.floor_lift);
        out.refill(ch, on, reference, mocap, given);
    }
}
