//! The canonical skeleton every rig convention is mapped onto.

use serde::{Deserialize, Serialize};

/// A joint of the canonical skeleton (19 joints). Past the `mocap` layer the
/// pipeline speaks only of these.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum Canonical {
    Pelvis,
    Spine,
    Chest,
    Neck,
    Head,
    LShoulder,
    LElbow,
    LWrist,
    RShoulder,
    RElbow,
    RWrist,
    LHip,
    LKnee,
    LAnkle,
    LToe,
    RHip,
    RKnee,
    RAnkle,
    RToe,
}

impl Canonical {
    /// All canonical joints, parents before children.
    pub const ALL: [Canonical; 19] = [
        Canonical::Pelvis,
        Canonical::Spine,
        Canonical::Chest,
        Canonical::Neck,
        Canonical::Head,
        Canonical::LShoulder,
        Canonical::LElbow,
        Canonical::LWrist,
        Canonical::RShoulder,
        Canonical::RElbow,
        Canonical::RWrist,
        Canonical::LHip,
        Canonical::LKnee,
        Canonical::LAnkle,
        Canonical::LToe,
        Canonical::RHip,
        Canonical::RKnee,
        Canonical::RAnkle,
        Canonical::RToe,
    ];

    /// Number of canonical joints.
    pub const COUNT: usize = 19;

    /// The arm joints, left and right at each level from the shoulders
    /// down (shoulders, elbows, wrists).
    pub const ARMS: [Canonical; 6] = [
        Canonical::LShoulder,
        Canonical::RShoulder,
        Canonical::LElbow,
        Canonical::RElbow,
        Canonical::LWrist,
        Canonical::RWrist,
    ];

    /// The leg joints, left then right, each from hip to toe (the last
    /// eight of [`Canonical::ALL`]).
    pub(crate) const LEGS: [Canonical; 8] = {
        let mut out = [Canonical::LHip; 8];
        let mut i = 0;
        while i < out.len() {
            out[i] = Canonical::ALL[Canonical::LHip as usize + i];
            i += 1;
        }
        out
    };

    /// The torso's joints below the neck (pelvis, spine, chest) and
    /// [`Canonical::LEGS`]: the joints that a CMU AMC clip and its
    /// third-party BVH conversions place alike. The conversions hang the
    /// neck and shoulders elsewhere on the thorax (11.7 cm lower on CMU
    /// 01_01's cgspeed BVH than on its ASF), so the neck, head and arms
    /// land apart (issue 17).
    pub const TORSO_AND_LEGS: [Canonical; 11] = {
        let mut out = [Canonical::Pelvis; 11];
        out[1] = Canonical::Spine;
        out[2] = Canonical::Chest;
        let mut i = 0;
        while i < Canonical::LEGS.len() {
            out[3 + i] = Canonical::LEGS[i];
            i += 1;
        }
        out
    };

    /// Index into [`Canonical::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// snake_case name, as in map files.
    pub fn name(self) -> &'static str {
        match self {
            Canonical::Pelvis => "pelvis",
            Canonical::Spine => "spine",
            Canonical::Chest => "chest",
            Canonical::Neck => "neck",
            Canonical::Head => "head",
            Canonical::LShoulder => "l_shoulder",
            Canonical::LElbow => "l_elbow",
            Canonical::LWrist => "l_wrist",
            Canonical::RShoulder => "r_shoulder",
            Canonical::RElbow => "r_elbow",
            Canonical::RWrist => "r_wrist",
            Canonical::LHip => "l_hip",
            Canonical::LKnee => "l_knee",
            Canonical::LAnkle => "l_ankle",
            Canonical::LToe => "l_toe",
            Canonical::RHip => "r_hip",
            Canonical::RKnee => "r_knee",
            Canonical::RAnkle => "r_ankle",
            Canonical::RToe => "r_toe",
        }
    }

    /// Parses a snake_case name.
    pub fn from_name(s: &str) -> Option<Canonical> {
        Canonical::ALL.into_iter().find(|c| c.name() == s)
    }

    /// Parent in the canonical tree (`None` for the pelvis).
    pub fn parent(self) -> Option<Canonical> {
        use Canonical::*;
        Some(match self {
            Pelvis => return None,
            Spine => Pelvis,
            Chest => Spine,
            Neck => Chest,
            Head => Neck,
            LShoulder | RShoulder => Chest,
            LElbow => LShoulder,
            LWrist => LElbow,
            RElbow => RShoulder,
            RWrist => RElbow,
            LHip | RHip => Pelvis,
            LKnee => LHip,
            LAnkle => LKnee,
            LToe => LAnkle,
            RKnee => RHip,
            RAnkle => RKnee,
            RToe => RAnkle,
        })
    }
}
