//! The rest frame, its rigid parts and its axes as the limbs are read
//! ([`super::limbs`]) and a straddled joint is checked
//! ([`super::straddle`]); its own file so that both read it without
//! importing each other.

use super::decompose::Decomposition;
use super::options::Facing;
use glam::DVec3;

/// A joint must bend this much (RMS, degrees) in the capture.
pub(crate) const MIN_BEND_DEG: f64 = 6.0;

/// The rest frame, its parts and its axes, as the chains are read.
pub struct Body<'a> {
    /// Rest-frame positions.
    pub rest: &'a [[f64; 3]],
    /// The frames the decomposition fitted (each the rest frame's
    /// vertices in order): the limbs' sides are read on them too
    /// ([`super::sides`]).
    pub frames: &'a [&'a [[f64; 3]]],
    /// Mesh neighbours.
    pub nb: &'a [Vec<u32>],
    /// The rigid parts.
    pub dec: Decomposition,
    /// Up (unit).
    pub up: DVec3,
    /// Lowest height along up.
    pub lo: f64,
    /// Height along up.
    pub height: f64,
    /// The vertex nearest the centroid.
    pub seed: u32,
    /// The centroid.
    pub centre: DVec3,
    /// Legs' hips at the thigh's end ([`super::options::AutoOptions::thigh_hip`]).
    pub thigh_hip: bool,
    /// Where the left-right axis is read ([`super::options::AutoOptions::facing`]).
    pub facing: Facing,
    /// Knees at a boundary that is no joint moved ([`super::options::AutoOptions::split_knee`]).
    pub split_knee: bool,
    /// Loose fixed points moved onto the limb ([`super::options::AutoOptions::guard_pivots`]).
    pub guard_pivots: bool,
    /// The open boundary loops of the rest frame ([`super::cut_ends`]).
    pub(crate) rims: Vec<super::cut_ends::Rim>,
}

impl Body<'_> {
    /// The centre of the cut the extremity `tip` ends in, if it ends in
    /// one ([`super::cut_ends::cut_at`]).
    pub(crate) fn cut_at(&self, tip: u32) -> Option<DVec3> {
        super::cut_ends::cut_at(self.rest, &self.rims, tip, self.height)
    }
}
