//! Live retargeting from a mocap stream (issue 45): the actor moves in the
//! suit, the 4D character moves now.
//!
//! [`online`] is the fixed-lag skeletal trellis (the offline
//! [`crate::drive::trellis`] decided frame by frame), [`session`] the
//! per-frame synthesis on a character prepared once, [`source`] the
//! stream input ([`replay`] a clip file as a stream, [`bvh_tcp`] BVH over
//! TCP, [`vmc`] and [`rokoko`] over UDP through [`stream`] and the
//! [`humanoid`] bone tables, each through a [`mailbox`]), [`floor`] the
//! running floor the pose kernel stands the stream on, [`kept`] the levelling and floor
//! decided once and kept, [`ground`] the
//! offline ground decisions swapped in stage by stage, [`report`] the
//! latency and throughput figures, [`stages`] where a frame's time goes, [`overlap`] when two frames are deformed at once, [`page`] the browser page and its
//! WebSocket.

pub mod bvh_tcp;
pub mod floor;
pub mod ground;
pub mod humanoid;
pub mod kept;
pub mod mailbox;
pub mod online;
pub mod overlap;
pub mod page;
pub mod replay;
pub mod report;
pub mod rokoko;
pub mod send;
pub mod session;
pub mod source;
pub mod stages;
pub mod stream;
pub mod vmc;

#[cfg(test)]
mod tests;

pub use online::{Advance, Committed, OnlineOptions, OnlineStats, OnlineTrellis};
pub use overlap::Overlap;
pub use session::{LiveFrame, Session, SessionOptions};
