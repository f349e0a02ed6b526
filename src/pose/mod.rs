//! Canonical poses (the 19 joint positions of one frame) and what is
//! measured on them: the joint rotations that explain a pose relative to a
//! rest pose ([`rotations`]), skeleton measures and BVH clips of poses
//! ([`measure`]: the skeletal dissimilarity `c_skel`, Huang et al. 2015
//! Eq. 28), and the rest-pose-aware retargeting kernel that puts a clip's
//! poses onto a character's own skeleton ([`retarget`]).

pub mod measure;
pub mod retarget;
pub mod rotations;

pub use rotations::{Pose, children, pose_rotations};
