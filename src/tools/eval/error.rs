//! The error of setting up a plausibility check.

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
