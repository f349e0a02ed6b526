//! The automatic rig's settings and refusals.

use super::decompose::DecomposeOptions;

/// Settings of [`super::rig::auto_rig`]. The defaults are `db init`'s.
#[derive(Debug, Clone, Copy)]
pub struct AutoOptions {
    /// The frame of the capture the parts are found in (its positions are
    /// the decomposition's rest); the landmarks are written on the
    /// topology mesh whatever the frame. Default `None`: the topology mesh
    /// itself (the capture's frame 0). `db init` passes the frame
    /// `embed::rest::choose_rest_frame` chooses (the clearest of contact).
    pub rest_frame: Option<usize>,
    /// Frames of the capture used. Default 40.
    pub max_frames: usize,
    /// The frames chosen by their poses (farthest-point first from the
    /// rest frame's pose, `embed::pose_order`), the topology not in the fit:
    /// the same capture in any order is fitted on the same frames. Default
    /// false (session 25): spread evenly in the order given, after the
    /// topology's positions as the fit's first frame — on with `db init`,
    /// the merged build's `embed::auto_arms`/`auto_knees` (the automatic
    /// rig against the landmark rigs on the real captures) failed, and the
    /// yardstick with it was not measured.
    pub frames_by_pose: bool,
    /// The decomposition's settings.
    pub decompose: DecomposeOptions,
}

impl Default for AutoOptions {
    fn default() -> Self {
        AutoOptions {
            rest_frame: None,
            max_frames: 40,
            frames_by_pose: false,
            decompose: DecomposeOptions::default(),
        }
    }
}

/// Why a capture cannot be rigged automatically; each a one-line reason.
#[derive(Debug, thiserror::Error)]
pub enum AutoError {
    /// Fewer than two frames.
    #[error(
        "automatic rigging: the capture has {0} frame(s); the rig is learnt from how the body moves: give a sequence of several frames, or landmarks"
    )]
    TooFewFrames(usize),
    /// A frame with another vertex count than the mesh.
    #[error(
        "automatic rigging: frame {frame} has {have} vertices, the mesh {want}: every frame must be the mesh's vertices in its order"
    )]
    VertexCount {
        /// The frame.
        frame: usize,
        /// Its vertex count.
        have: usize,
        /// The mesh's.
        want: usize,
    },
    /// The rest frame asked for is not in the capture.
    #[error("automatic rigging: rest frame {frame} is past the capture's {frames} frames")]
    RestFrame {
        /// Asked.
        frame: usize,
        /// Frames.
        frames: usize,
    },
    /// The capture is not a standing humanoid; the reason says what was
    /// found.
    #[error("automatic rigging: not a humanoid: {0}; give landmarks")]
    NotHumanoid(String),
}
