//! Mocap-driven synthesis (Huang et al. 2015, Sec. 5.2): a mocap clip in,
//! a mesh sequence of the character out.
//!
//! [`query`] prepares the clip, [`crate::db::Character`] is the database loaded
//! with its graph, [`trellis`] retrieves the frame path (5.2.1), [`timeline`] turns
//! repeats into interpolations (5.2.2) and jumps into blends (4.4), and
//! [`synthesis`] makes the meshes: each output frame's database frames are
//! placed on the query's root trajectory (the rotation about the vertical
//! and the floor translation that best fit the frame's skeleton onto the
//! query pose, smoothed over time) and blended non-linearly.

pub mod options;
pub mod placement;
pub mod prepared;
pub mod query;
pub mod sink;
pub mod synthesis;
pub mod timeline;
pub mod trellis;

pub use options::{DriveError, DriveOptions};
#[allow(deprecated)]
pub use options::{RetargetError, RetargetOptions};
pub use placement::{BlendScratch, Floor, blend_placed};
pub use prepared::{Analysed, PrepareTimings, Prepared};
pub use sink::{Each, FrameSink};
pub use synthesis::{CHUNK_FRAMES, Output, Report, Step, Timings, synthesise};
