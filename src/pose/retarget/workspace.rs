//! The pose kernel's reusable buffers (issue 45): a live session runs
//! the kernel over its analysis window (the last 128 frames and the
//! undecided ones) for every frame it receives, and each run made and
//! dropped window-length `Vec`s in the kernel's clip-level steps — the
//! levelling ([`ground_tilt`](super::ground_tilt)), the floor and the
//! supports ([`clip_support_on`](super::clip_support_on), twice: the
//! kernel's and the stance offsets'), the feet's flat elevation, the
//! upright frames, the gaps interpolated (heaptrack on main's binary:
//! ~250 of the 297 allocation calls a frame). A [`KernelWorkspace`]
//! owned by the session holds those buffers; each step clears and
//! refills its own, so once they have held a window no step allocates.
//! Offline callers keep the functions without a workspace (each makes a
//! fresh one): the results are the same bit for bit.
//!
//! The kernel's outputs are refilled too when the caller keeps them
//! ([`super::on_character_into`], a live session's `Analysed`): the
//! levelled clip and the rotations live here, the frames are written in
//! parallel into the kept buffer (`par_iter_mut`), the feet's grounds
//! into kept ones. What still allocates per run: a clip whose root
//! carries no vertical motion stood on its legs (a copy), and rayon's
//! own bookkeeping when its pool threads take the work.

use super::feet::{FeetScratch, FlatScratch};
use super::ground::{Support, SupportScratch, TiltScratch};
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::DQuat;

/// The buffers the pose kernel's clip-level steps reuse from one run to
/// the next (a live session's, one per session). Empty when made (no
/// allocation); each buffer grows to the longest clip it has been given
/// and keeps that capacity. What it holds between runs means nothing.
#[derive(Debug, Clone, Default)]
pub struct KernelWorkspace {
    /// The levelling's buffers.
    pub(super) tilt: TiltScratch,
    /// The support's buffers.
    pub(super) support: SupportScratch,
    /// The clip's support (the kernel's, then the stance offsets').
    pub(super) found: Support,
    /// The flat feet's buffers.
    pub(super) flat: FlatScratch,
    /// The feet's placement's buffers.
    pub(super) feet: FeetScratch,
    /// The levelled clip (the kernel's, then the stance offsets').
    pub(super) levelled: Vec<Pose>,
    /// The clip's rotations since its reference (the kernel's).
    pub(super) rotations: Vec<[DQuat; Canonical::COUNT]>,
    /// The frames before the feet go on the clip's footfalls
    /// ([`Footfalls::Targets`](super::Footfalls::Targets)).
    pub(super) was: Vec<(Pose, [DQuat; Canonical::COUNT])>,
    /// The frames' trunk angles and the upright frames' rotations.
    pub(super) trunk: Vec<f64>,
    pub(super) upright: Vec<[DQuat; Canonical::COUNT]>,
    /// The known values of a sequence with gaps, and the stance heights
    /// before their gaps are filled.
    pub(super) known: Vec<(usize, f64)>,
    pub(super) raised: Vec<Option<f64>>,
    /// The feet's grounds as the kernel leaves them, before their gaps
    /// are filled ([`super::on_character_into`]).
    pub(super) grounds: [Vec<Option<f64>>; 2],
    /// The stance offsets ([`super::stance_offsets_in`]).
    pub(super) offsets: Vec<f64>,
}

impl KernelWorkspace {
    /// An empty workspace (no allocation until it is used).
    pub fn new() -> Self {
        Self::default()
    }
}

#[cfg(test)]
mod tests {
    use super::super::feet::{FeetScratch, FlatScratch, Toes, flat_feet_with, place_feet};
    use super::super::ground::{
        Given, clip_support_given, clip_support_given_into, ground_tilt, ground_tilt_with,
        interpolate_gaps, interpolate_gaps_into,
    };
    use super::super::kernel::retarget;
    use super::super::measures::{stance_offsets_given, stance_offsets_in};
    use super::super::reference::{choose_reference, leg_length};
    use super::super::torso::{clip_rotations, upright, upright_into};
    use super::*;
    use crate::deform::allocation_calls;
    use glam::{DQuat, DVec3};

    /// The kernel's clip-level steps over `clip` in the buffers of `ws`,
    /// as a live session's analysis runs them (the kernel's levelling,
    /// support, flat feet, upright frames and its feet's grounds' gaps
    /// filled, the feet placed, then the stance offsets'), each checked
    /// against the same step without a workspace, bit for bit; returns
    /// this thread's allocation calls made inside the steps (the checks'
    /// own not counted; the feet's placement returns two grounds, each
    /// run's two allocations).
    fn steps(character: &Pose, clip: &[Pose], ws: &mut KernelWorkspace) -> usize {
        let reference = choose_reference(None, clip).unwrap();
        let given = Given::default();
        let leg = leg_length(&reference.pose);
        let (mut calls, mut extra) = (0, 0);
        let mut counted = |f: &mut dyn FnMut()| {
            let before = allocation_calls();
            f();
            calls += allocation_calls() - before;
        };
        let mut tilt = DQuat::IDENTITY;
        counted(&mut || tilt = ground_tilt_with(clip, &mut ws.tilt));
        assert_eq!(tilt, ground_tilt(clip));
        let levelled: Vec<Pose> = clip.iter().map(|m| m.map(|p| tilt * p)).collect();
        counted(&mut || {
            clip_support_given_into(&levelled, leg, &given, &mut ws.support, &mut ws.found)
        });
        assert_eq!(ws.found, clip_support_given(&levelled, leg, &given));
        let mut flat = reference.pose;
        let r = reference.pose;
        counted(&mut || flat = flat_feet_with(&r, &levelled, &ws.found, &mut ws.flat));
        let fresh = flat_feet_with(&r, &levelled, &ws.found, &mut FlatScratch::default());
        assert_eq!(flat, fresh);
        let rotations = clip_rotations(&r, &levelled, &reference, tilt);
        counted(&mut || upright_into(&levelled, &rotations, &mut ws.trunk, &mut ws.upright));
        assert_eq!(ws.upright, upright(&levelled, &rotations));
        let gaps = ws.found.under[0].clone();
        let mut filled = Vec::with_capacity(gaps.len());
        counted(&mut || interpolate_gaps_into(&gaps, &mut ws.known, &mut filled));
        assert_eq!(filled, interpolate_gaps(&gaps));
        // The feet placed (and the toes bent) on the character as the
        // kernel has it, as with fresh buffers.
        let frames = retarget(character, &reference, clip);
        let s = leg_length(character) / leg;
        for how in [(Toes::Rigid, false), (Toes::Bending, true)] {
            let (mut placed, mut again) = (frames.clone(), frames.clone());
            let mut grounds = Default::default();
            let support = &ws.found;
            // Less the two grounds it returns.
            counted(&mut || {
                let before = allocation_calls();
                grounds = place_feet(character, support, s, how, &mut placed, &mut ws.feet);
                extra += (allocation_calls() - before).min(2);
            });
            let fresh = place_feet(
                character,
                support,
                s,
                how,
                &mut again,
                &mut FeetScratch::default(),
            );
            assert_eq!((&grounds, &placed), (&fresh, &again));
        }
        let fresh = stance_offsets_given(character, &reference, clip, &given);
        let before = allocation_calls();
        let offsets = stance_offsets_in(character, &reference, clip, &given, ws);
        calls += allocation_calls() - before;
        assert_eq!(offsets, &fresh[..]);
        assert!(fresh.contains(&0.0), "no frame on the floor");
        calls - extra
    }

    /// A generated walk (metres, Y-up) as the rig detection maps it.
    fn walk(seconds: f64) -> Vec<Pose> {
        let clip = crate::synth::gait_clip(crate::synth::Gait::Walk, seconds, 30.0);
        crate::rig::detect_clip(&clip)
            .unwrap()
            .map
            .poses(&clip)
            .unwrap()
    }

    /// Issue 45: a live session's analysis runs the kernel's clip-level
    /// steps over its sliding window every frame; in the session's
    /// workspace, once a window has been analysed, the next allocates
    /// nothing (the window slid by one frame, and a shorter one) and
    /// gives the results of the steps without it, bit for bit. On a walk
    /// as generated, mirrored, turned and tilted 2° (the levelling has a
    /// slope to take off), and in centimetres. A fresh workspace's first
    /// window does allocate (the test would pass on code that never ran).
    #[test]
    fn a_warm_workspace_analyses_the_next_window_without_allocating() {
        let turn = DQuat::from_rotation_y(1.1) * DQuat::from_rotation_x(2f64.to_radians());
        type Map = fn(DVec3, DQuat) -> DVec3;
        let variants: [(&str, Map); 4] = [
            ("as generated", |p, _| p),
            ("mirrored", |p, _| DVec3::new(-p.x, p.y, p.z)),
            ("turned and tilted", |p, q| q * p),
            ("centimetres", |p, _| p * 100.0),
        ];
        let base = walk(4.0);
        let n = base.len();
        assert!(n >= 100, "{n} frames");
        for (name, map) in variants {
            let clip: Vec<Pose> = base.iter().map(|m| m.map(|p| map(p, turn))).collect();
            let character = clip[0];
            let mut ws = KernelWorkspace::new();
            let first = steps(&character, &clip[..n - 1], &mut ws);
            assert!(first > 0, "{name}: the first window allocated nothing");
            let slid = steps(&character, &clip[1..], &mut ws);
            assert_eq!(slid, 0, "{name}: the slid window allocated {slid} times");
            let short = steps(&character, &clip[10..n - 20], &mut ws);
            assert_eq!(short, 0, "{name}: a shorter window allocated {short} times");
        }
    }
}
