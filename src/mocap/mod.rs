//! Skeletal motion capture: the [`Clip`], its readers (BVH, ASF/AMC, FBX,
//! glTF skin animation), BVH
//! writer, forward kinematics, resampling and unit/up-axis normalisation.

pub mod asfamc;
pub mod bvh;
mod clip;
mod error;
pub mod euler;
pub mod fbx;
mod fk;
mod load;
mod resample;
pub mod skin;
pub mod units;

pub use clip::{
    Channel, Clip, ClipError, ClipParts, Joint, JointId, PointConvention, Units, UpAxis,
};
pub use error::MocapError;
pub use load::{MocapFormat, find_asf, read_clip};
