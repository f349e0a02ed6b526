//! The options of surface synthesis and why it cannot run: read by the
//! prepared character ([`super::Prepared`]) and by each clip's synthesis
//! ([`super::synthesise`]), so neither imports the other for them.

use super::timeline::TimelineOptions;
use super::trellis::TrellisOptions;
use crate::deform::{DeformMode, DeformOptions};
use crate::mesh::solver::SolveError;

/// Options of [`super::synthesise`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DriveOptions {
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

impl Default for DriveOptions {
    fn default() -> Self {
        DriveOptions {
            trellis: TrellisOptions::default(),
            timeline: TimelineOptions::default(),
            smooth: 3,
            deform: DeformMode::Part,
            deform_options: DeformOptions::default(),
        }
    }
}

/// Why surface synthesis (a retarget) cannot run.
#[derive(Debug, thiserror::Error)]
pub enum DriveError {
    /// A solver could not be factored (mesh problems).
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The output would not fit in memory (checked before allocating).
    #[error(transparent)]
    Budget(#[from] crate::util::budget::OverBudget),
    /// The prepared character was made for another character or another
    /// deformation ([`super::Prepared::fits`]).
    #[error("the prepared character does not fit this run: {0}")]
    Unprepared(String),
}

impl From<std::convert::Infallible> for DriveError {
    fn from(e: std::convert::Infallible) -> Self {
        match e {}
    }
}

/// The old name of [`DriveOptions`] (before session 39: "retarget" names
/// the pose kernel and the verb, "drive" the synthesis).
#[deprecated(note = "renamed DriveOptions")]
pub type RetargetOptions = DriveOptions;

/// The old name of [`DriveError`].
#[deprecated(note = "renamed DriveError")]
pub type RetargetError = DriveError;
