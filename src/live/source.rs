//! The stream input: what every source (replay, VMC, Rokoko, BVH over TCP)
//! hands the session, one canonical pose at a time.

use super::report::Counters;
use crate::pose::Pose;
use crate::pose::retarget::{ClipNeutral, JointRotations};
use std::time::{Duration, Instant};

/// One frame of the stream.
#[derive(Debug, Clone, Copy)]
pub struct Incoming {
    /// The sender's frame number (from 0).
    pub seq: u64,
    /// The canonical joints (metres, Y-up).
    pub pose: Pose,
    /// The world rotations of the file joints mapped to each canonical
    /// joint, when the stream carries rotations.
    pub rotations: Option<JointRotations>,
    /// When it arrived (or, for a replay, was due).
    pub arrived: Instant,
}

/// What a source has next. A frame is moved once per frame, by value: boxing
/// it would allocate per frame.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy)]
pub enum Event {
    /// A frame.
    Frame(Incoming),
    /// Nothing within the wait.
    Idle,
    /// The stream ended.
    End,
}

/// Why a source stopped.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    /// A socket could not be opened or read.
    #[error("{what}: {source}")]
    Io {
        /// What was being done (the address).
        what: String,
        /// The error.
        source: std::io::Error,
    },
    /// The stream's skeleton could not be mapped to the canonical joints.
    #[error("{0}")]
    Rig(String),
}

/// A stream of canonical poses at the database's frame rate.
pub trait Source {
    /// The next frame, waiting at most `wait`.
    fn next(&mut self, wait: Duration) -> Result<Event, SourceError>;
    /// The stream's neutral reference pose (decided from its first frames
    /// or its header), once known.
    fn reference(&self) -> Option<ClipNeutral>;
    /// What happened to the incoming frames so far.
    fn counters(&self) -> Counters;
    /// True when the next frame is already there (a call to `next` would
    /// not wait): the session may then deform two frames at once
    /// ([`super::Overlap::Queued`]).
    fn waiting(&self) -> bool;
}
