//! The papers' metrics and the plausibility checks of a result.
//!
//! Metrics: the joint-velocity error of Huang et al. 2015 (Sec. 6.2,
//! [`velocity`]) and the vertex error against ground truth of Confluent
//! Motion's self-transfer ([`vertex`]). Plausibility ([`plausibility`]):
//! the head-to-torso angle measured on the mesh ([`head`]), foot sliding
//! during contact ([`feet`]), ground penetration and floating ([`ground`]),
//! knee hyper-extension ([`knee`]) and the triangles turned over against the
//! rest frame ([`triangles`], the deformation's own test), each against the
//! character's captured range.

pub mod feet;
pub mod ground;
pub mod head;
pub mod knee;
pub mod plausibility;
pub mod summary;
pub mod triangles;
pub mod velocity;
pub mod vertex;

pub use feet::{ClipSliding, Feet, FootOptions, Sliding, clip_sliding, track_sliding};
pub use ground::{Ground, floor_height, ground, lowest_heights};
pub use head::{HeadOptions, HeadTorso};
pub use knee::knee_hyperextension;
pub use plausibility::{Checker, Limits, Plausibility, PlausibilityOptions, Reference};
pub use summary::Summary;
pub use triangles::{RestTriangles, TurnedOverCount};
pub use velocity::{VelocityError, velocity_error};
pub use vertex::{VertexError, vertex_error};

/// What can go wrong setting up a plausibility check.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// The part labels do not match the mesh.
    #[error("{have} part labels for a mesh of {want} vertices")]
    Labels {
        /// Labels given.
        have: usize,
        /// Vertices of the mesh.
        want: usize,
    },
    /// A body part the check needs has no vertices.
    #[error("the rig labels no vertex as part '{part}'")]
    MissingPart {
        /// The part's name.
        part: &'static str,
    },
    /// A triangle naming a vertex the mesh does not have.
    #[error("triangle {index} {corners:?} names a vertex past the mesh's {vertices}")]
    Triangle {
        /// Its index.
        index: usize,
        /// Its corners.
        corners: [u32; 3],
        /// Vertices of the mesh.
        vertices: usize,
    },
    /// A sequence whose vertex count is not the character's.
    #[error("a sequence of {have} vertices for a character of {want}")]
    VertexCount {
        /// Its vertex count.
        have: usize,
        /// The character's.
        want: usize,
    },
}
