//! Synthetic data made by the project's own code: procedural mocap clips
//! (and, later, the procedural demo character and synthetic 4D databases).

pub mod clips;
pub mod database;
pub mod humanoid;
pub mod shapes;

pub use clips::{Gait, gait_clip, skeleton};
