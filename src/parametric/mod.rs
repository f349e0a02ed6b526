//! 4D parametric motion (Casas et al. 2013, Sec. 3): related sequences of a
//! character become one *motion space* steered by high-level parameters
//! (speed, turn rate), blended in real time, with transitions between
//! spaces found at run time.
//!
//! One kernel per file, in pipeline order: [`local`] (each frame in its
//! body frame: horizontal centroid removed, turned to face +Z, and the root
//! motion kept apart), [`align`] (cycle-aware time alignment of a space's
//! sequences), [`hybrid`] (hybrid non-linear blending, Eq. 3), [`params`]
//! (parameter measurement and the inverse map `w = h⁻¹(p)`, Sec. 3.1.4),
//! [`transition`] (online transitions, Eqs. 4-5), [`space`] (a space and
//! the whole parametric model built from a database), [`store`] (the
//! model's cache file) and [`controller`] (frame-by-frame playback).

pub mod align;
pub mod controller;
pub mod error;
pub mod hybrid;
pub mod local;
pub mod motion_space;
pub mod params;
pub mod script;
pub mod space;
pub mod store;
pub mod transition;

pub use controller::{Control, Controller, Notice, TransitionRecord};
pub use error::ParamError;
pub use params::Parameter;
pub use space::{Motion, MotionOptions, MotionSpace};
