//! Synthetic data made by the project's own code, and nothing else:
//! procedural mocap clips ([`clips`]), the procedural humanoid
//! ([`humanoid`]), test shapes ([`shapes`]) and the driving of a rest mesh
//! by clips ([`database::drive`]; the kernels it uses live in
//! [`crate::deform`] and [`crate::rig`]). Writing a synthetic database to a
//! folder is the job [`crate::jobs::write_synthetic_database`].

pub mod clips;
pub mod database;
pub mod humanoid;
pub mod shapes;

pub use clips::{Gait, gait_clip, skeleton};
