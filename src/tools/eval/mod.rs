//! The papers' metrics and the plausibility checks of a result.
//!
//! Metrics: the joint-velocity error of Huang et al. 2015 (Sec. 6.2,
//! [`velocity`]) and the vertex error against ground truth of Confluent
//! Motion's self-transfer ([`vertex`]). Plausibility ([`plausibility`]):
//! the head-to-torso angle measured on the mesh ([`head`]), foot sliding
//! during contact ([`feet`]), ground penetration and floating ([`ground`]),
//! knee hyper-extension ([`knee`]) and the triangles turned over against the
//! rest frame ([`triangles`], the deformation's own test), each against the
//! character's captured range. The automatic landmarks of a scan against a
//! hand-made file: [`landmarks`].

pub mod error;
pub mod feet;
pub mod ground;
pub mod head;
pub mod knee;
pub mod landmarks;
pub mod plausibility;
pub mod summary;
pub mod surface;
pub mod surface_crumple;
pub mod surface_follow;
pub mod triangles;
pub mod velocity;
pub mod vertex;

pub use error::EvalError;
pub use feet::{ClipSliding, Feet, FootOptions, Sliding, clip_sliding, sole_ends, track_sliding};
pub use ground::{Ground, floor_height, ground, lowest_heights};
pub use head::{HeadOptions, HeadTorso};
pub use knee::knee_hyperextension;
#[allow(deprecated)]
pub use plausibility::Reference; // old name
pub use plausibility::{Baseline, Checker, Limits, Plausibility, PlausibilityOptions};
pub use summary::EvalSummary;
#[allow(deprecated)]
pub use summary::Summary;
pub use triangles::{RestTriangles, TurnedOverCount};
pub use velocity::{VelocityError, velocity_error};
pub use vertex::{VertexError, vertex_error};
