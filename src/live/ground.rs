//! The ground decisions a live session's analysis makes over its window,
//! and the offline ones swapped in for them (issue 45, fidelity: where
//! live loses to offline, stage by stage).
//!
//! Offline, the pose kernel levels the clip's ground ([`ground_tilt`]),
//! finds its floor ([`clip_floor`]) and the supports its feet stand on
//! ([`clip_support`]) over the whole clip; live, over the window it has
//! (the last frames and the undecided ones). [`OfflineGround`] holds the
//! offline decisions of a whole clip and hands each window its share
//! ([`OfflineGround::window`]), so that a session replaying that clip can
//! be run with one decision at a time made as offline ([`Swap`]).

use crate::pose::Pose;
use crate::pose::retarget::{
    ClipNeutral, ClipNeutralSource, Support, clip_support, ground_tilt, leg_length,
};
use glam::DQuat;

/// Which of the kernel's ground decisions are taken from the offline
/// analysis of the whole clip.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Swap {
    /// The levelling of the ground.
    pub tilt: bool,
    /// The floor height.
    pub floor: bool,
    /// The supports (per foot and frame: touch, held, at rest, the ground
    /// under it) and the floor they stand on.
    pub support: bool,
}

/// The offline ground decisions of one clip (its own joints, metres,
/// Y-up; a clip whose root carries vertical motion, as every CMU and
/// Bandai clip does: the kernel's stand-on-the-legs rule for a root
/// without it is not applied here).
#[derive(Debug, Clone)]
pub struct OfflineGround {
    tilt: DQuat,
    support: Support,
    swap: Swap,
}

/// A window's share of [`OfflineGround`]: what to give the kernel.
#[derive(Debug, Clone, Default)]
pub struct WindowGround {
    /// The levelling (when swapped).
    pub tilt: Option<DQuat>,
    /// The floor (when swapped).
    pub floor: Option<f64>,
    /// The window's frames of the offline support (when swapped).
    pub support: Option<Support>,
}

impl OfflineGround {
    /// The decisions the kernel makes over all of `mocap` with `reference`
    /// (as [`crate::pose::retarget::retarget`] does), `swap` saying which a
    /// window is given.
    pub fn of(reference: &ClipNeutral, mocap: &[Pose], swap: Swap) -> OfflineGround {
        let tilt = ground_tilt(mocap);
        let levelled: Vec<Pose> = mocap.iter().map(|m| m.map(|p| tilt * p)).collect();
        let r = match reference.source {
            ClipNeutralSource::Frame(i) if i < levelled.len() => levelled[i],
            _ => reference.pose,
        };
        OfflineGround {
            tilt,
            support: clip_support(&levelled, leg_length(&r)),
            swap,
        }
    }

    /// The share of the window of `n` frames from stream frame `first`.
    pub fn window(&self, first: usize, n: usize) -> WindowGround {
        let s = &self.support;
        let floor = self.swap.floor || self.swap.support;
        let support = (self.swap.support && first + n <= s.ground.len()).then(|| {
            let cut = |v: &Vec<Option<f64>>| v[first..first + n].to_vec();
            let cut_b = |v: &Vec<bool>| v[first..first + n].to_vec();
            Support {
                floor: s.floor,
                ground: cut(&s.ground),
                touch: [cut(&s.touch[0]), cut(&s.touch[1])],
                under: [cut(&s.under[0]), cut(&s.under[1])],
                held: [cut_b(&s.held[0]), cut_b(&s.held[1])],
                rests: [cut_b(&s.rests[0]), cut_b(&s.rests[1])],
                band: s.band,
            }
        });
        WindowGround {
            tilt: self.swap.tilt.then_some(self.tilt),
            floor: floor.then_some(s.floor),
            support,
        }
    }
}
