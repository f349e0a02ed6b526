//! Rig naming conventions mapped onto the [`Canonical`] skeleton, with
//! auto-detection and JSON map files.

use super::canonical::Canonical;
use crate::mocap::{Clip, JointId};
use crate::skeleton::Pose;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// A known naming convention: for each canonical joint, candidate names in
/// order of preference (compared case-insensitively, after stripping any
/// `namespace:` or `path|` prefix).
pub struct Convention {
    /// Human-readable name.
    pub name: &'static str,
    /// Names whose presence identifies this convention among similar ones.
    pub signature: &'static [&'static str],
    /// Candidates per canonical joint, in [`Canonical::ALL`] order.
    pub candidates: [&'static [&'static str]; 19],
}

macro_rules! lr {
    ($l:expr, $r:expr) => {
        ($l, $r)
    };
}

const fn conv(
    name: &'static str,
    signature: &'static [&'static str],
    torso: [&'static [&'static str]; 5],
    arms: [(&'static [&'static str], &'static [&'static str]); 3],
    legs: [(&'static [&'static str], &'static [&'static str]); 4],
) -> Convention {
    Convention {
        name,
        signature,
        candidates: [
            torso[0], torso[1], torso[2], torso[3], torso[4], arms[0].0, arms[1].0, arms[2].0,
            arms[0].1, arms[1].1, arms[2].1, legs[0].0, legs[1].0, legs[2].0, legs[3].0, legs[0].1,
            legs[1].1, legs[2].1, legs[3].1,
        ],
    }
}

/// The built-in conventions, most specific first.
pub static CONVENTIONS: [Convention; 7] = [
    conv(
        "CMU cgspeed BVH (MotionBuilder-friendly)",
        &["LHipJoint", "LowerBack"],
        [
            &["Hips"],
            &["Spine"],
            &["Spine1"],
            &["Neck1", "Neck"],
            &["Head"],
        ],
        [
            lr!(&["LeftArm"], &["RightArm"]),
            lr!(&["LeftForeArm"], &["RightForeArm"]),
            lr!(&["LeftHand"], &["RightHand"]),
        ],
        [
            lr!(&["LeftUpLeg"], &["RightUpLeg"]),
            lr!(&["LeftLeg"], &["RightLeg"]),
            lr!(&["LeftFoot"], &["RightFoot"]),
            lr!(&["LeftToeBase"], &["RightToeBase"]),
        ],
    ),
    conv(
        "CMU BVH (3dsMax-friendly)",
        &["LHipJoint", "LeftCollar", "Chest2"],
        [
            &["Hips"],
            &["Chest"],
            &["Chest2"],
            &["Neck", "lowerneck"],
            &["Head"],
        ],
        [
            lr!(&["LeftShoulder"], &["RightShoulder"]),
            lr!(&["LeftElbow"], &["RightElbow"]),
            lr!(&["LeftWrist"], &["RightWrist"]),
        ],
        [
            lr!(&["LeftHip"], &["RightHip"]),
            lr!(&["LeftKnee"], &["RightKnee"]),
            lr!(&["LeftAnkle"], &["RightAnkle"]),
            lr!(&["LeftToe"], &["RightToe"]),
        ],
    ),
    conv(
        "CMU ASF/AMC",
        &["lhumerus", "lfemur", "thorax"],
        [
            &["root"],
            &["upperback"],
            &["thorax"],
            &["lowerneck"],
            &["head"],
        ],
        [
            lr!(&["lhumerus"], &["rhumerus"]),
            lr!(&["lradius"], &["rradius"]),
            lr!(&["lwrist"], &["rwrist"]),
        ],
        [
            lr!(&["lfemur"], &["rfemur"]),
            lr!(&["ltibia"], &["rtibia"]),
            lr!(&["lfoot"], &["rfoot"]),
            lr!(&["ltoes"], &["rtoes"]),
        ],
    ),
    conv(
        "Reallusion CC_Base",
        &["CC_Base_Hip", "CC_Base_Pelvis"],
        [
            &["CC_Base_Pelvis", "CC_Base_Hip"],
            &["CC_Base_Spine01", "CC_Base_Waist"],
            &["CC_Base_Spine02"],
            &["CC_Base_NeckTwist01"],
            &["CC_Base_Head"],
        ],
        [
            lr!(&["CC_Base_L_Upperarm"], &["CC_Base_R_Upperarm"]),
            lr!(&["CC_Base_L_Forearm"], &["CC_Base_R_Forearm"]),
            lr!(&["CC_Base_L_Hand"], &["CC_Base_R_Hand"]),
        ],
        [
            lr!(&["CC_Base_L_Thigh"], &["CC_Base_R_Thigh"]),
            lr!(&["CC_Base_L_Calf"], &["CC_Base_R_Calf"]),
            lr!(&["CC_Base_L_Foot"], &["CC_Base_R_Foot"]),
            lr!(&["CC_Base_L_ToeBase"], &["CC_Base_R_ToeBase"]),
        ],
    ),
    conv(
        "Bandai Namco Research Motion",
        &["UpperLeg_L", "LowerArm_L"],
        [&["Hips"], &["Spine"], &["Chest"], &["Neck"], &["Head"]],
        [
            lr!(&["UpperArm_L"], &["UpperArm_R"]),
            lr!(&["LowerArm_L"], &["LowerArm_R"]),
            lr!(&["Hand_L"], &["Hand_R"]),
        ],
        [
            lr!(&["UpperLeg_L"], &["UpperLeg_R"]),
            lr!(&["LowerLeg_L"], &["LowerLeg_R"]),
            lr!(&["Foot_L"], &["Foot_R"]),
            lr!(&["Toes_L", "Toe_L"], &["Toes_R", "Toe_R"]),
        ],
    ),
    conv(
        "Mixamo",
        &["mixamorig"],
        [
            &["Hips"],
            &["Spine"],
            &["Spine2", "Spine1"],
            &["Neck"],
            &["Head"],
        ],
        [
            lr!(&["LeftArm"], &["RightArm"]),
            lr!(&["LeftForeArm"], &["RightForeArm"]),
            lr!(&["LeftHand"], &["RightHand"]),
        ],
        [
            lr!(&["LeftUpLeg"], &["RightUpLeg"]),
            lr!(&["LeftLeg"], &["RightLeg"]),
            lr!(&["LeftFoot"], &["RightFoot"]),
            lr!(
                &["LeftToeBase", "LeftToe_End"],
                &["RightToeBase", "RightToe_End"]
            ),
        ],
    ),
    conv(
        "MotionBuilder HumanIK",
        &["LeftUpLeg", "LeftForeArm"],
        [
            &["Hips"],
            &["Spine"],
            &["Spine2", "Spine1"],
            &["Neck", "Neck1"],
            &["Head"],
        ],
        [
            lr!(&["LeftArm"], &["RightArm"]),
            lr!(&["LeftForeArm"], &["RightForeArm"]),
            lr!(&["LeftHand"], &["RightHand"]),
        ],
        [
            lr!(&["LeftUpLeg"], &["RightUpLeg"]),
            lr!(&["LeftLeg"], &["RightLeg"]),
            lr!(&["LeftFoot"], &["RightFoot"]),
            lr!(&["LeftToeBase"], &["RightToeBase"]),
        ],
    ),
];

/// Strips a `namespace:` / `path|` prefix and lowercases.
pub fn normalise_name(s: &str) -> String {
    let s = s.rsplit([':', '|']).next().unwrap_or(s);
    s.trim().to_ascii_lowercase()
}

/// A map from canonical joints to a clip's joint names. Saved and loaded as
/// JSON: `{"convention": "...", "joints": {"pelvis": "Hips", ...}}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigMap {
    /// Name of the convention (informative).
    pub convention: String,
    /// Canonical joint name → joint name in the file.
    pub joints: BTreeMap<Canonical, String>,
}

/// Error of rig mapping.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// Some canonical joints have no joint in the clip.
    #[error("rig map '{convention}' leaves canonical joints unmapped: {missing}")]
    Missing {
        /// Convention name.
        convention: String,
        /// Comma-separated canonical names.
        missing: String,
    },
    /// A mapped name is not a joint of the clip.
    #[error("rig map names '{name}' for {canonical}, which is not a joint of the clip")]
    UnknownJoint {
        /// The name.
        name: String,
        /// Canonical joint.
        canonical: &'static str,
    },
    /// The map file could not be read or parsed.
    #[error("{path}: {msg}")]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// What went wrong.
        msg: String,
    },
    /// The clip's skeleton cannot be retargeted (no extent, no frames).
    #[error("degenerate skeleton: {reason}")]
    Degenerate {
        /// What is wrong.
        reason: String,
    },
}

/// Result of auto-detection.
#[derive(Debug, Clone, Serialize)]
pub struct Detection {
    /// The best map found (may be incomplete; see `missing`).
    pub map: RigMap,
    /// Canonical joints with no match.
    pub missing: Vec<Canonical>,
    /// Whether a signature name of the convention was present.
    pub signature: bool,
}

/// Detects the naming convention from joint names.
pub fn detect(names: &[String]) -> Detection {
    let norm: Vec<String> = names.iter().map(|n| normalise_name(n)).collect();
    let raw_lower: Vec<String> = names.iter().map(|n| n.to_ascii_lowercase()).collect();
    let mut best: Option<(f64, Detection)> = None;
    for c in &CONVENTIONS {
        let mut joints = BTreeMap::new();
        let mut missing = Vec::new();
        for (k, cands) in Canonical::ALL.iter().zip(c.candidates.iter()) {
            let hit = cands.iter().find_map(|cand| {
                let cl = cand.to_ascii_lowercase();
                norm.iter().position(|n| *n == cl).map(|i| names[i].clone())
            });
            match hit {
                Some(h) => {
                    joints.insert(*k, h);
                }
                None => missing.push(*k),
            }
        }
        let signature = c.signature.iter().any(|s| {
            let sl = s.to_ascii_lowercase();
            norm.contains(&sl) || raw_lower.iter().any(|r| r.contains(&sl) && sl.len() > 8)
        });
        let score = joints.len() as f64 + if signature { 0.5 } else { 0.0 };
        if best.as_ref().is_none_or(|(s, _)| score > *s) {
            best = Some((
                score,
                Detection {
                    map: RigMap {
                        convention: c.name.to_string(),
                        joints,
                    },
                    missing,
                    signature,
                },
            ));
        }
    }
    best.map(|b| b.1).unwrap_or(Detection {
        map: RigMap {
            convention: "none".into(),
            joints: BTreeMap::new(),
        },
        missing: Canonical::ALL.to_vec(),
        signature: false,
    })
}

impl RigMap {
    /// Reads a JSON map file.
    pub fn load(path: &Path) -> Result<RigMap, RigError> {
        let text = crate::fsutil::read_text(path).map_err(|e| RigError::File {
            path: path.into(),
            msg: e.source.to_string(),
        })?;
        serde_json::from_str(&text).map_err(|e| RigError::File {
            path: path.into(),
            msg: e.to_string(),
        })
    }

    /// Writes the map as pretty JSON, atomically.
    pub fn save(&self, path: &Path) -> Result<(), crate::fsutil::FsError> {
        let s = serde_json::to_string_pretty(self).unwrap_or_default();
        crate::fsutil::write_bytes_atomic(path, s.as_bytes())
    }

    /// Canonical joint positions of every frame of `clip`, in the clip's
    /// units. Rig maps name a canonical joint by the bone that starts there,
    /// so each is the joint origin (also for ASF/AMC clips, whose native
    /// points are bone ends).
    pub fn poses(&self, clip: &Clip) -> Result<Vec<Pose>, RigError> {
        use rayon::prelude::*;
        let ids = self.resolve(clip)?;
        Ok((0..clip.frame_count())
            .into_par_iter()
            .map(|f| {
                let p = clip.world_positions(f);
                std::array::from_fn(|c| p[ids[c].idx()])
            })
            .collect())
    }

    /// Canonical joint positions of the clip's rest skeleton (every local
    /// rotation the identity, offsets as in the file), in the clip's units.
    pub fn rest_pose(&self, clip: &Clip) -> Result<Pose, RigError> {
        let ids = self.resolve(clip)?;
        let (p, _) = clip.rest_positions();
        Ok(std::array::from_fn(|c| p[ids[c].idx()]))
    }

    /// Resolves every canonical joint to a joint of `clip`.
    pub fn resolve(&self, clip: &Clip) -> Result<[JointId; 19], RigError> {
        let mut out = [JointId(0); 19];
        let mut missing = Vec::new();
        for c in Canonical::ALL {
            match self.joints.get(&c) {
                Some(name) => {
                    let id = clip.joint(name).ok_or_else(|| RigError::UnknownJoint {
                        name: name.clone(),
                        canonical: c.name(),
                    })?;
                    out[c.index()] = id;
                }
                None => missing.push(c.name()),
            }
        }
        if !missing.is_empty() {
            return Err(RigError::Missing {
                convention: self.convention.clone(),
                missing: missing.join(", "),
            });
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(v: &[&str]) -> Vec<String> {
        v.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn mixamo_prefix_is_stripped_and_detected() {
        let n = names(&[
            "mixamorig:Hips",
            "mixamorig:Spine",
            "mixamorig:Spine1",
            "mixamorig:Spine2",
            "mixamorig:Neck",
            "mixamorig:Head",
            "mixamorig:LeftArm",
            "mixamorig:LeftForeArm",
            "mixamorig:LeftHand",
            "mixamorig:RightArm",
            "mixamorig:RightForeArm",
            "mixamorig:RightHand",
            "mixamorig:LeftUpLeg",
            "mixamorig:LeftLeg",
            "mixamorig:LeftFoot",
            "mixamorig:LeftToeBase",
            "mixamorig:RightUpLeg",
            "mixamorig:RightLeg",
            "mixamorig:RightFoot",
            "mixamorig:RightToeBase",
        ]);
        let d = detect(&n);
        assert_eq!(d.map.convention, "Mixamo");
        assert!(d.missing.is_empty());
        assert_eq!(d.map.joints[&Canonical::Chest], "mixamorig:Spine2");
    }

    #[test]
    fn json_round_trip() {
        let d = detect(&names(&["Hips", "Spine"]));
        let s = serde_json::to_string(&d.map).unwrap();
        let back: RigMap = serde_json::from_str(&s).unwrap();
        assert_eq!(back, d.map);
        assert!(s.contains("\"pelvis\""));
    }
}
