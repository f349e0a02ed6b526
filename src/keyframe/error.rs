//! The errors of the key-frame search ([`SearchError`]) and of a grid of
//! targets too large to run ([`GridError`]), below every search file so
//! that each returns them.

use super::repeats::RepeatsError;
use crate::graph::FlatFrame;
use crate::util::budget::OverBudget;

/// What went wrong in a search.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SearchError {
    /// A key-frame outside the graph.
    #[error("key-frame {0} is not a frame of the graph ({1} frames)")]
    Frame(FlatFrame, usize),
    /// No path joins two key-frames.
    #[error("no path from {from} to {to} in the graph")]
    NoPath {
        /// Start frame.
        from: FlatFrame,
        /// End frame.
        to: FlatFrame,
    },
    /// The repetition solver failed.
    #[error(transparent)]
    Repeats(#[from] RepeatsError),
    /// The exact-length search's table for the query's horizon exceeds
    /// the memory budget (its text says what to change: the key-frames or
    /// the target, [`super::lattice::chain_extremes`]).
    #[error("{0}")]
    OverBudget(#[from] OverBudget),
    /// A grid of targets too large to run ([`super::grid::check_grid`]).
    #[error(transparent)]
    Grid(#[from] GridError),
}

/// A grid too large to run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    /// More targets than [`super::grid::MAX_GRID_TARGETS`].
    #[error(
        "a grid of {} targets ({} distances × {} times): at most {}; lower the number of distances or times (a larger step or a shorter range)",
        crate::util::budget::thousands(*.count),
        crate::util::budget::thousands(*.distances as u128),
        crate::util::budget::thousands(*.times as u128),
        crate::util::budget::thousands(*.max as u128)
    )]
    TooMany {
        /// Targets asked for.
        count: u128,
        /// Distances.
        distances: usize,
        /// Times.
        times: usize,
        /// The cap.
        max: usize,
    },
    /// Its queries' records exceed the memory budget.
    #[error("{0}")]
    OverBudget(#[from] OverBudget),
}
