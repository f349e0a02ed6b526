//! Rig naming conventions mapped onto the [`Canonical`] skeleton, with
//! auto-detection and JSON map files.

use super::canonical::Canonical;
use super::derive::Derive;
use super::structure::{self, Provenance};
use crate::mocap::{Clip, JointId};
use glam::{DQuat, DVec3};
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
pub static CONVENTIONS: [Convention; 9] = [
    conv(
        "CMU cgspeed BVH (MotionBuilder-friendly)",
        &["LHipJoint", "LowerBack"],
        [
            &["Hips"],
            &["Spine"],
            &["Spine1"],
            // The base of the neck (ASF `lowerneck`, on `Spine1` with a
            // zero offset), as the structure analysis picks it.
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
    conv(
        "CMU BVH (3dsMax-friendly)",
        &["LHipJoint", "LeftCollar", "Chest2"],
        [
            &["Hips"],
            &["Chest"],
            &["Chest2"],
            // The base of the neck, as above.
            &["lowerneck", "Neck"],
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
    // Unreal Engine's mannequins (UE4: spine_01..03, the clavicles on
    // spine_03; UE5 Manny and Quinn: spine_01..05, neck_01/02).
    conv(
        "Unreal Engine mannequin",
        &["lowerarm_l", "calf_l"],
        [
            &["pelvis"],
            &["spine_01"],
            &["spine_05", "spine_03"],
            &["neck_01"],
            &["head"],
        ],
        [
            lr!(&["upperarm_l"], &["upperarm_r"]),
            lr!(&["lowerarm_l"], &["lowerarm_r"]),
            lr!(&["hand_l"], &["hand_r"]),
        ],
        [
            lr!(&["thigh_l"], &["thigh_r"]),
            lr!(&["calf_l"], &["calf_r"]),
            lr!(&["foot_l"], &["foot_r"]),
            lr!(&["ball_l"], &["ball_r"]),
        ],
    ),
    // Unity's humanoid avatar bones (HumanBodyBones), as Unity recorders
    // and exporters name them; UpperChest is optional.
    conv(
        "Unity Humanoid",
        &["LeftUpperLeg", "LeftLowerArm"],
        [
            &["Hips"],
            &["Spine"],
            &["UpperChest", "Chest"],
            &["Neck"],
            &["Head"],
        ],
        [
            lr!(&["LeftUpperArm"], &["RightUpperArm"]),
            lr!(&["LeftLowerArm"], &["RightLowerArm"]),
            lr!(&["LeftHand"], &["RightHand"]),
        ],
        [
            lr!(&["LeftUpperLeg"], &["RightUpperLeg"]),
            lr!(&["LeftLowerLeg"], &["RightLowerLeg"]),
            lr!(&["LeftFoot"], &["RightFoot"]),
            lr!(&["LeftToes"], &["RightToes"]),
        ],
    ),
];

/// Strips a `namespace:` / `path|` prefix and lowercases.
pub fn normalise_name(s: &str) -> String {
    let s = s.rsplit([':', '|']).next().unwrap_or(s);
    s.trim().to_ascii_lowercase()
}

/// A map from canonical joints to a clip's joint names. Saved and loaded as
/// JSON: `{"convention": "...", "joints": {"pelvis": "Hips", ...},
/// "derived": {"l_toe": {"rule": "end_site", "joint": "LeftFoot"}}}`
/// (`derived` is optional; files without it load unchanged).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigMap {
    /// Name of the convention (informative).
    pub convention: String,
    /// Canonical joint name → joint name in the file.
    pub joints: BTreeMap<Canonical, String>,
    /// Canonical joints with no joint in the file and the rule placing them.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub derived: BTreeMap<Canonical, Derive>,
    /// The file the map was read from ([`RigMap::load`]); a map with a
    /// file is the user's, checked against each clip it is applied to
    /// ([`RigMap::check`]).
    #[serde(skip)]
    pub file: Option<std::path::PathBuf>,
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
    /// The clip's skeleton is not a humanoid (structure analysis).
    #[error("not a humanoid: {reason}")]
    NotHumanoid {
        /// What the structure analysis found.
        reason: String,
    },
}

/// How one canonical joint was mapped.
#[derive(Debug, Clone, Serialize)]
pub struct JointReport {
    /// The canonical joint.
    pub canonical: Canonical,
    /// The clip's joint, or `None` when derived or missing.
    pub joint: Option<String>,
    /// Where it came from.
    pub source: Provenance,
    /// Confidence in [0, 1].
    pub confidence: f64,
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
    /// Per canonical joint (in [`Canonical::ALL`] order): joint, source, confidence.
    pub joints: Vec<JointReport>,
    /// Canonical joints placed by a [`Derive`] rule.
    pub derived: Vec<Canonical>,
    /// How left and right were decided.
    pub sides: String,
    /// How sure the geometry is of left and right (0-1), when the sides
    /// were decided from geometry alone (a mapping by structure).
    pub side_confidence: Option<f64>,
    /// Notes on the structure analysis: the pose it was read on (empty for
    /// the rest skeleton, or no structure analysis; else which frame stood
    /// in for a rest skeleton that is not a standing body, and why), and
    /// the chains off the chest it ignored (wings, a cape).
    #[serde(skip_serializing_if = "String::is_empty")]
    pub structure_pose: String,
}

impl Detection {
    /// A detection that reports `map` as given, every joint from `source`
    /// with confidence `confidence`.
    pub(crate) fn from_map(
        map: RigMap,
        source: Provenance,
        confidence: f64,
        sides: &str,
    ) -> Detection {
        let joints = Canonical::ALL
            .iter()
            .map(|c| JointReport {
                canonical: *c,
                joint: map.joints.get(c).cloned(),
                source: if map.joints.contains_key(c) {
                    source
                } else {
                    Provenance::Derived
                },
                confidence: if map.joints.contains_key(c) || map.derived.contains_key(c) {
                    confidence
                } else {
                    0.0
                },
            })
            .collect();
        let missing = Canonical::ALL
            .into_iter()
            .filter(|c| !map.joints.contains_key(c) && !map.derived.contains_key(c))
            .collect();
        Detection {
            derived: map.derived.keys().copied().collect(),
            missing,
            signature: false,
            joints,
            map,
            sides: sides.to_string(),
            side_confidence: None,
            structure_pose: String::new(),
        }
    }
}

/// The largest cosine between the legs' direction and the trunk's
/// ([`structure::STANDING`]) of a body that stands.
const STANDING: f64 = structure::STANDING;

/// Convention name of a map decided by name tokens inside the structure.
pub const BY_NAMES: &str = "unknown convention, mapped by names";
/// Convention name of a map decided (at least partly) by structure.
pub const BY_STRUCTURE: &str = "unknown convention, mapped by structure";

/// Detects the naming convention from joint names alone (no geometry): the
/// best of [`CONVENTIONS`]; its name is reported only when every canonical
/// joint matched, else `"unknown convention"`. For clips prefer
/// [`detect_clip`], which also maps unknown rigs by structure.
pub fn detect(names: &[String]) -> Detection {
    // Names are compared as given (namespaces stripped) and, when most of
    // them share a prefix (`Character1_`, as MotionBuilder names a
    // HumanIK character's joints), without it; the better match counts.
    let plain = detect_scored(names, None);
    let stripped: Vec<&str> = names
        .iter()
        .map(|n| super::names::strip_namespace(n))
        .collect();
    let prefixed = super::names::common_prefix(&stripped)
        .and_then(|p| detect_scored(names, Some(&p.to_ascii_lowercase())));
    let best = match (plain, prefixed) {
        (Some(a), Some(b)) if b.0 > a.0 => Some(b),
        (a, b) => a.or(b),
    };
    best.map(|b| b.1).unwrap_or_else(|| {
        Detection::from_map(
            RigMap {
                convention: "none".into(),
                joints: BTreeMap::new(),
                derived: BTreeMap::new(),
                file: None,
            },
            Provenance::Convention,
            0.0,
            "none",
        )
    })
}

/// [`detect`] with the names compared after stripping `prefix` (lower
/// case) where they carry it: the best convention and its score (names
/// matched, a half for a signature name).
fn detect_scored(names: &[String], prefix: Option<&str>) -> Option<(f64, Detection)> {
    let norm: Vec<String> = names
        .iter()
        .map(|n| {
            let n = normalise_name(n);
            match prefix {
                Some(p) if n.len() > p.len() && n.starts_with(p) => n[p.len()..].to_string(),
                _ => n,
            }
        })
        .collect();
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
            let map = RigMap {
                convention: if missing.is_empty() {
                    c.name.to_string()
                } else {
                    "unknown convention".to_string()
                },
                joints,
                derived: BTreeMap::new(),
                file: None,
            };
            let mut d = Detection::from_map(map, Provenance::Convention, 1.0, "from names");
            d.signature = signature;
            best = Some((score, d));
        }
    }
    best
}

fn swap_side(c: Canonical) -> Canonical {
    use Canonical::*;
    match c {
        LShoulder => RShoulder,
        LElbow => RElbow,
        LWrist => RWrist,
        RShoulder => LShoulder,
        RElbow => LElbow,
        RWrist => LWrist,
        LHip => RHip,
        LKnee => RKnee,
        LAnkle => RAnkle,
        LToe => RToe,
        RHip => LHip,
        RKnee => LKnee,
        RAnkle => LAnkle,
        RToe => LToe,
        o => o,
    }
}

/// How far a map's legs point from its trunk: per pose, the mean over both
/// legs of the cosine between pelvis→ankle and pelvis→head (neck, else
/// chest; each leg on its own, not their mean direction as the structure
/// analysis takes it: arms named as legs hang beside the trunk, their mean
/// straight down); the smaller of the rest pose's and the median of up to 24
/// sampled frames' (a standing human is near −1, a horizontal body near
/// 0). `None` when the map lacks those joints.
fn named_stance(clip: &Clip, map: &RigMap) -> Option<f64> {
    use Canonical as C;
    let id = |c: C| {
        map.joints
            .get(&c)
            .and_then(|n| clip.joint(n))
            .map(|j| j.idx())
    };
    let pelvis = id(C::Pelvis)?;
    let top = id(C::Head)
        .or_else(|| id(C::Neck))
        .or_else(|| id(C::Chest))?;
    let feet = [id(C::LAnkle)?, id(C::RAnkle)?];
    let cos = |p: &[DVec3]| {
        let up = (p[top] - p[pelvis]).normalize_or_zero();
        feet.iter()
            .map(|&f| 0.5 * (p[f] - p[pelvis]).normalize_or_zero().dot(up))
            .sum::<f64>()
    };
    let rest = cos(&clip.rest_positions().0);
    let n = clip.joint_count();
    let frames = clip.frame_count();
    let step = (frames / 24).max(1);
    let (mut p, mut r) = (vec![DVec3::ZERO; n], vec![DQuat::IDENTITY; n]);
    let mut all: Vec<f64> = (0..frames)
        .step_by(step)
        .map(|f| {
            clip.world_into(f, &mut p, &mut r);
            cos(&p)
        })
        .filter(|c| c.is_finite())
        .collect();
    all.sort_by(f64::total_cmp);
    let median = all.get(all.len() / 2).copied().unwrap_or(rest);
    Some(rest.min(median))
}

/// Maps a clip onto the canonical skeleton with no rig map: a known
/// convention when all its names match (its left/right checked against the
/// body's geometry, see [`super::structure`]), else the structure of the
/// hierarchy and rest/motion geometry with name tokens as hints inside
/// chains. Joints the clip lacks (toes, head, chest) get [`Derive`] rules.
///
/// Errors: [`RigError::NotHumanoid`] when neither names nor structure find
/// a humanoid.
pub fn detect_clip(clip: &Clip) -> Result<Detection, RigError> {
    let names = clip.point_names();
    let tokens = super::names::all_tokens(&names);
    let conv = detect(&names);
    let body = structure::analyse(clip, &tokens);
    // A known convention's names, kept when the structure agrees: the
    // structure finds no horizontal body (a dog rigged with HumanIK names is
    // no humanoid), and the convention's chest is the joint the arms and
    // neck branch from (Xsens MVN's Chest…Chest4 match the CMU 3dsMax
    // names, whose Chest2 would put the chest on the L3 vertebra).
    //
    // Every name of a known convention present and the structure finding a
    // horizontal body: the names decide when the legs they name point away
    // from the trunk they name in the rest pose or the median frame (the
    // structure may have read an extra chain as a leg, or legs spread or
    // bent in the rest pose), else the clip is refused.
    if conv.missing.is_empty()
        && let Err(e) = &body
        && e.0.contains(structure::HORIZONTAL)
        && named_stance(clip, &conv.map).is_none_or(|cos| cos > STANDING)
    {
        return Err(RigError::NotHumanoid {
            reason: format!(
                "{} (although every '{}' name is present)",
                e.0, conv.map.convention
            ),
        });
    }
    if conv.missing.is_empty()
        && body
            .as_ref()
            .map_or(true, |b| conv_chest_agrees(&conv, clip, b))
    {
        return match &body {
            Ok(b) => by_names_checked(conv, clip, b),
            Err(_) => by_names_alone(conv, clip),
        };
    }
    let b = body.map_err(|e| RigError::NotHumanoid { reason: e.0 })?;
    Ok(by_structure(&names, &b))
}

/// The notes of a detection on the structure analysis `b`: the frame read
/// for a rest skeleton that is not a standing body, the chains off the
/// chest ignored.
fn pose_note(b: &structure::Body) -> String {
    let mut notes: Vec<String> = Vec::new();
    if let Some(f) = b.reference_frame {
        notes.push(format!(
            "frame {f}: the rest skeleton is not a standing body (its legs do not point away from its spine, or it has no extent), so the structure was read on this frame's pose"
        ));
    }
    if !b.ignored.is_empty() {
        notes.push(format!(
            "{} chain(s) off the chest are neither arms nor the neck and are ignored: {}",
            b.ignored.len(),
            b.ignored.join(", ")
        ));
    }
    notes.extend(b.notes.iter().cloned());
    notes.join("; ")
}

/// True unless the convention's chest lies off the structure's chest by
/// more than a fifth of pelvis → neck (in the pose the structure was read
/// on), or either is missing.
fn conv_chest_agrees(conv: &Detection, clip: &Clip, b: &structure::Body) -> bool {
    let rest = &b.reference;
    let at = |c: Canonical| {
        conv.map
            .joints
            .get(&c)
            .and_then(|n| clip.joint(n))
            .map(|j| rest[j.idx()])
    };
    let picked = |c: Canonical| b.picks[c.index()].joint.map(|j| rest[j]);
    match (
        at(Canonical::Chest),
        picked(Canonical::Chest),
        picked(Canonical::Pelvis),
        picked(Canonical::Neck),
    ) {
        (Some(a), Some(c), Some(p), Some(n)) => a.distance(c) <= 0.2 * p.distance(n),
        _ => true,
    }
}

/// A full convention's map when the structure analysis found no humanoid:
/// the names decide, unless the named legs do not point away from the
/// named trunk (a T-rex or a lizard carrying every HumanIK name, its arms
/// too short to count: [`names_stand`]).
fn by_names_alone(conv: Detection, clip: &Clip) -> Result<Detection, RigError> {
    names_stand(&conv, clip)?;
    let mut d = conv;
    d.sides = "from names (the structure analysis did not find a humanoid)".into();
    Ok(d)
}

/// Refuses a convention's map whose named legs do not point away from its
/// named trunk ([`named_stance`] above [`STANDING`]).
fn names_stand(conv: &Detection, clip: &Clip) -> Result<(), RigError> {
    if let Some(cos) = named_stance(clip, &conv.map)
        && cos > STANDING
    {
        return Err(RigError::NotHumanoid {
            reason: format!(
                "the legs named '{}' and '{}' do not point away from the spine (cosine {cos:.2} in the rest pose and the median frame): {} (although every '{}' name is present)",
                conv.map
                    .joints
                    .get(&Canonical::LHip)
                    .map_or("", String::as_str),
                conv.map
                    .joints
                    .get(&Canonical::RHip)
                    .map_or("", String::as_str),
                structure::HORIZONTAL,
                conv.map.convention
            ),
        });
    }
    Ok(())
}

/// A full convention's map checked against the structure analysis `b`:
/// its chest moved to the arms' branch ([`chest_at_branch`]), its sides
/// confirmed by the geometry's, or its left and right swapped (limb pair
/// by limb pair) when the geometry puts them on the other side. Names the
/// geometry cannot place on its limbs are refused when their legs do not
/// point away from their trunk ([`names_stand`]: a rig whose arms carry
/// the leg names).
fn by_names_checked(
    conv: Detection,
    clip: &Clip,
    b: &structure::Body,
) -> Result<Detection, RigError> {
    let mut conv = conv;
    chest_at_branch(&mut conv, clip, b);
    let id = |c: Canonical| {
        conv.map
            .joints
            .get(&c)
            .and_then(|n| clip.joint(n))
            .map(|j| j.idx())
    };
    let within = |c: Canonical, set: &[usize]| id(c).is_some_and(|j| set.contains(&j));
    use Canonical as C;
    let legs_swapped = within(C::LHip, &b.right_leg) && within(C::RHip, &b.left_leg);
    let arms_swapped = within(C::LShoulder, &b.right_arm) && within(C::RShoulder, &b.left_arm);
    let confirmed = within(C::LHip, &b.left_leg)
        && within(C::RHip, &b.right_leg)
        && within(C::LShoulder, &b.left_arm)
        && within(C::RShoulder, &b.right_arm);
    if !(legs_swapped || arms_swapped) {
        if !confirmed {
            names_stand(&conv, clip)?;
        }
        let mut d = conv;
        d.structure_pose = pose_note(b);
        d.sides = if confirmed {
            format!(
                "from names, confirmed by geometry (forward from the {}, confidence {:.2})",
                b.forward_from, b.side_confidence
            )
        } else {
            "from names (geometry undecided)".into()
        };
        return Ok(d);
    }
    let mut joints = BTreeMap::new();
    for (c, n) in &conv.map.joints {
        let swap = if C::LEGS.contains(c) {
            legs_swapped
        } else {
            arms_swapped
        };
        joints.insert(if swap { swap_side(*c) } else { *c }, n.clone());
    }
    let map = RigMap {
        convention: BY_NAMES.into(),
        joints,
        derived: BTreeMap::new(),
        file: None,
    };
    let mut d = Detection::from_map(map, Provenance::Names, 0.9, "");
    d.structure_pose = pose_note(b);
    d.sides = format!(
        "from geometry (forward from the {}, confidence {:.2}); the names' left/right are mirrored",
        b.forward_from, b.side_confidence
    );
    Ok(d)
}

/// The map the structure analysis `b` found (`names`: the clip's joint
/// names), its joints, derivation rules and sides reported.
fn by_structure(names: &[String], b: &structure::Body) -> Detection {
    let mut joints = BTreeMap::new();
    let mut derived = BTreeMap::new();
    let mut reports = Vec::with_capacity(Canonical::COUNT);
    let mut all_named = true;
    for (c, p) in Canonical::ALL.iter().zip(&b.picks) {
        if let Some(j) = p.joint {
            joints.insert(*c, names[j].clone());
            all_named &= p.source == Provenance::Names;
        } else if let Some(d) = &p.derive {
            derived.insert(*c, d.clone());
        }
        reports.push(JointReport {
            canonical: *c,
            joint: p.joint.map(|j| names[j].clone()),
            source: p.source,
            confidence: p.confidence,
        });
    }
    let missing: Vec<Canonical> = Canonical::ALL
        .into_iter()
        .filter(|c| !joints.contains_key(c) && !derived.contains_key(c))
        .collect();
    let map = RigMap {
        convention: if all_named { BY_NAMES } else { BY_STRUCTURE }.into(),
        joints,
        derived,
        file: None,
    };
    let (side_confidence, sides) = if b.sides_from_names {
        (
            None,
            "from names (the geometry gives no forward direction: no foot points \
             forward, the knees are straight and the root does not travel)"
                .to_string(),
        )
    } else {
        (
            Some(b.side_confidence),
            format!(
                "from geometry (forward from the {}, confidence {:.2}){}",
                b.forward_from,
                b.side_confidence,
                if b.names_mirrored {
                    "; the names' left/right are mirrored"
                } else {
                    ""
                }
            ),
        )
    };
    Detection {
        derived: map.derived.keys().copied().collect(),
        map,
        missing,
        signature: false,
        joints: reports,
        side_confidence,
        sides,
        structure_pose: pose_note(b),
    }
}

/// A convention's chest moved up the spine to the joint the arms and the
/// neck branch from, when that joint (the structure's chest) lies above it
/// on the same chain: HumanIK names on a rig with more spine joints than
/// the convention's (BEAT and ZEGGS carry the arms on `Spine3`; the chest
/// was `Spine2`, a vertebra low, and its file rotation left out
/// `Spine3`'s).
fn chest_at_branch(d: &mut Detection, clip: &Clip, b: &structure::Body) {
    let Some(picked) = b.picks[Canonical::Chest.index()].joint else {
        return;
    };
    let Some(named) = d
        .map
        .joints
        .get(&Canonical::Chest)
        .and_then(|n| clip.joint(n))
        .map(|j| j.idx())
    else {
        return;
    };
    if picked == named || b.reference[picked].distance(b.reference[named]) < 1e-9 {
        return;
    }
    let mut j = picked;
    while let Some(p) = clip.joints[j].parent.map(|p| p.idx()) {
        if p == named {
            let name = clip.joints[picked].name.clone();
            d.map.joints.insert(Canonical::Chest, name.clone());
            if let Some(r) = d.joints.get_mut(Canonical::Chest.index()) {
                r.joint = Some(name);
                r.source = Provenance::Structure;
            }
            return;
        }
        j = p;
    }
}

/// One canonical joint resolved on a clip.
#[derive(Debug, Clone)]
enum Slot {
    Joint(usize),
    EndSite(usize, DVec3),
    Between(usize, usize, f64),
    Toe(usize, f64),
}

impl RigMap {
    /// Reads a JSON map file.
    pub fn load(path: &Path) -> Result<RigMap, RigError> {
        let text = crate::util::fsutil::read_small_text(path).map_err(|e| RigError::File {
            path: path.into(),
            msg: e.source.to_string(),
        })?;
        // The help says "canonical joint → joint name": a flat object
        // `{"pelvis": "Hips", ...}` is read as the `joints` of a map (it
        // gave "missing field `convention`").
        let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| RigError::File {
            path: path.into(),
            msg: e.to_string(),
        })?;
        let flat = v
            .as_object()
            .is_some_and(|o| !o.contains_key("joints") && o.values().all(|x| x.is_string()));
        let parsed = if flat {
            serde_json::from_value::<BTreeMap<Canonical, String>>(v).map(|joints| RigMap {
                convention: "rig map".into(),
                joints,
                derived: BTreeMap::new(),
                file: None,
            })
        } else {
            serde_json::from_value(v)
        };
        let mut map = parsed.map_err(|e| RigError::File {
            path: path.into(),
            msg: format!(
                "{e}; expected {{\"pelvis\": \"Hips\", ...}} or the form `mocap rigmap -o` \
                 writes, {{\"convention\": \"...\", \"joints\": {{\"pelvis\": \"Hips\", ...}}}}"
            ),
        })?;
        map.file = Some(path.into());
        Ok(map)
    }

    /// What can be checked of a map against the clip it is applied to,
    /// without a threshold: each file joint carries one canonical joint;
    /// along each canonical chain (pelvis → spine → chest → neck → head,
    /// chest → shoulder → elbow → wrist, pelvis → hip → knee → ankle →
    /// toe) no mapped joint is an ancestor of the previous mapped one in
    /// the file's hierarchy (pelvis and head swapped fails here; "below"
    /// would be too strict: a CC rig's spine and pelvis are siblings under
    /// its hip joint); and in most
    /// of up to 33 frames spread over the clip, left minus right of every
    /// mapped pair (shoulders, elbows, wrists, hips, knees, ankles),
    /// across the pelvis → head axis, points to the same side as the
    /// first pair's (the left arm on the right arm's joints, the legs not,
    /// fails here). A map mirrored as a whole is consistent and passes:
    /// which side is left needs the file's handedness. Joints the clip
    /// lacks are left to [`RigMap::resolve`]. Cost: forward kinematics of
    /// 33 frames.
    /// The error names the canonical entries and the file joints.
    pub fn check(&self, clip: &Clip) -> Result<(), String> {
        use Canonical::*;
        let mut seen: BTreeMap<&str, Canonical> = BTreeMap::new();
        for (&c, name) in &self.joints {
            if let Some(first) = seen.insert(name.as_str(), c) {
                return Err(format!(
                    "\"{}\" and \"{}\" both name '{name}': each canonical joint needs a joint of its own",
                    first.name(),
                    c.name()
                ));
            }
        }
        let id = |c: Canonical| {
            self.joints
                .get(&c)
                .and_then(|n| clip.joint(n).map(|j| (c, j)))
        };
        // Is `a` an ancestor of (or) `b` in the file's hierarchy?
        let above = |a: JointId, b: JointId| {
            let mut j = Some(b);
            while let Some(k) = j {
                if k == a {
                    return true;
                }
                j = clip.joints.get(k.idx()).and_then(|x| x.parent);
            }
            false
        };
        const CHAINS: [&[Canonical]; 5] = [
            &[Pelvis, Spine, Chest, Neck, Head],
            &[Chest, LShoulder, LElbow, LWrist],
            &[Chest, RShoulder, RElbow, RWrist],
            &[Pelvis, LHip, LKnee, LAnkle, LToe],
            &[Pelvis, RHip, RKnee, RAnkle, RToe],
        ];
        for chain in CHAINS {
            let mapped: Vec<(Canonical, JointId)> = chain.iter().filter_map(|&c| id(c)).collect();
            for w in mapped.windows(2) {
                let ((pc, pj), (cc, cj)) = (w[0], w[1]);
                if above(cj, pj) {
                    return Err(format!(
                        "\"{}\" names '{}', an ancestor of \"{}\" ('{}') in the file's hierarchy: the chain runs the wrong way",
                        cc.name(),
                        self.joints[&cc],
                        pc.name(),
                        self.joints[&pc]
                    ));
                }
            }
        }
        let Ok(slots) = self.plan(clip) else {
            return Ok(());
        };
        let pairs = [
            (LHip, RHip),
            (LKnee, RKnee),
            (LAnkle, RAnkle),
            (LShoulder, RShoulder),
            (LElbow, RElbow),
            (LWrist, RWrist),
        ];
        let pairs: Vec<(Canonical, Canonical)> = pairs
            .into_iter()
            .filter(|(l, r)| self.joints.contains_key(l) && self.joints.contains_key(r))
            .collect();
        // Up to 33 frames spread over the clip, not the rest skeleton: its
        // offsets can hold any pose (the Bandai files' rest skeleton has
        // the arms' left and right the other way round from the legs').
        // In each, left minus right of every pair across the pelvis → head
        // axis is compared with the first pair's; a pair crossed in most
        // frames is crossed.
        let n = clip.joint_count();
        let frames = clip.frame_count();
        let (mut p, mut r) = (vec![DVec3::ZERO; n], vec![DQuat::IDENTITY; n]);
        let mut votes = vec![(0usize, 0usize); pairs.len()];
        for f in (0..frames).step_by((frames / 32).max(1)) {
            clip.world_into(f, &mut p, &mut r);
            let pose = place(&slots, &p, &r);
            let axis = (pose[Head.index()] - pose[Pelvis.index()]).normalize_or_zero();
            let across = |(l, r): (Canonical, Canonical)| {
                let d = pose[l.index()] - pose[r.index()];
                d - axis * d.dot(axis)
            };
            let Some(reference) = pairs.first().map(|&q| across(q)) else {
                break;
            };
            for (v, &q) in votes.iter_mut().zip(&pairs) {
                let d = across(q).dot(reference);
                if d > 0.0 {
                    v.0 += 1;
                } else if d < 0.0 {
                    v.1 += 1;
                }
            }
        }
        type Voted<'a> = (&'a (Canonical, Canonical), &'a (usize, usize));
        let (same, crossed): (Vec<Voted>, Vec<Voted>) = pairs
            .iter()
            .zip(&votes)
            .filter(|(_, v)| v.0 + v.1 > 0)
            .partition(|(_, v)| v.0 >= v.1);
        if crossed.is_empty() {
            return Ok(());
        }
        let list = |v: &[Voted]| {
            v.iter()
                .map(|((l, r), _)| {
                    format!(
                        "{}/{} ('{}'/'{}')",
                        l.name(),
                        r.name(),
                        self.joints[l],
                        self.joints[r]
                    )
                })
                .collect::<Vec<_>>()
                .join(", ")
        };
        Err(format!(
            "left and right are crossed: in most frames left minus right of {} points one way, of {} the other",
            list(&same),
            list(&crossed)
        ))
    }

    /// Writes the map as pretty JSON, atomically.
    pub fn save(&self, path: &Path) -> Result<(), crate::util::fsutil::FsError> {
        let s = serde_json::to_string_pretty(self).unwrap_or_default();
        crate::util::fsutil::write_bytes_atomic(path, s.as_bytes())
    }

    /// Canonical joint positions of every frame of `clip`, in the clip's
    /// units. Rig maps name a canonical joint by the bone that starts there,
    /// so each is the joint origin (also for ASF/AMC clips, whose native
    /// points are bone ends); derived joints follow their [`Derive`] rule.
    /// Each frame is a [`crate::pose::Pose`] (spelled out here: the pose
    /// stage builds on this one, not the other way round).
    pub fn poses(&self, clip: &Clip) -> Result<Vec<[DVec3; Canonical::COUNT]>, RigError> {
        Ok(self.poses_and_rotations(clip)?.0)
    }

    /// [`RigMap::poses`] with, per frame, the world rotation of the file
    /// joint each canonical joint is mapped to (the rotation that carries
    /// that joint's own bones; `None` for a derived joint), in the clip's
    /// axes. A rest skeleton's are the identity (every local rotation is).
    pub fn poses_and_rotations(&self, clip: &Clip) -> Result<PosesAndRotations, RigError> {
        use rayon::prelude::*;
        let slots = self.plan(clip)?;
        let n = clip.joint_count();
        Ok((0..clip.frame_count())
            .into_par_iter()
            .map_init(
                || (vec![DVec3::ZERO; n], vec![DQuat::IDENTITY; n]),
                |(p, r), f| {
                    clip.world_into(f, p, r);
                    let mut q = [None; Canonical::COUNT];
                    for (c, s) in slots.iter().enumerate() {
                        if let Slot::Joint(j) = *s {
                            q[c] = Some(r[j]);
                        }
                    }
                    (place(&slots, p, r), q)
                },
            )
            .unzip())
    }

    /// Canonical joint positions of the clip's rest skeleton (every local
    /// rotation the identity, offsets as in the file), in the clip's units.
    pub fn rest_pose(&self, clip: &Clip) -> Result<[DVec3; Canonical::COUNT], RigError> {
        let slots = self.plan(clip)?;
        let (p, _) = clip.rest_positions();
        let r = vec![DQuat::IDENTITY; p.len()];
        Ok(place(&slots, &p, &r))
    }

    /// Resolves every canonical joint to a joint of `clip`. Derived joints
    /// have no joint: they are reported as missing here (use
    /// [`RigMap::poses`], which places them).
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

    /// Every canonical joint as a joint of the clip or a derivation rule
    /// whose inputs are placed before it.
    fn plan(&self, clip: &Clip) -> Result<Vec<Slot>, RigError> {
        let mut slots: Vec<Option<Slot>> = vec![None; Canonical::COUNT];
        let mut missing = Vec::new();
        let joint = |name: &str, c: Canonical| {
            clip.joint(name)
                .map(|j| j.idx())
                .ok_or_else(|| RigError::UnknownJoint {
                    name: name.to_string(),
                    canonical: c.name(),
                })
        };
        // Joints first, then rules in canonical order (a rule may use any
        // joint and the rules before it).
        for c in Canonical::ALL {
            if let Some(name) = self.joints.get(&c) {
                slots[c.index()] = Some(Slot::Joint(joint(name, c)?));
            }
        }
        for c in Canonical::ALL {
            if slots[c.index()].is_some() {
                continue;
            }
            let placed = |k: Canonical, slots: &[Option<Slot>]| slots[k.index()].is_some();
            let s = match (self.joints.get(&c), self.derived.get(&c)) {
                (Some(_), _) => None,
                (None, Some(Derive::EndSite { joint: name })) => {
                    let j = joint(name, c)?;
                    clip.joints[j].tail.map(|t| Slot::EndSite(j, t))
                }
                (None, Some(Derive::Between { from, to, t }))
                    if placed(*from, &slots) && placed(*to, &slots) && t.is_finite() =>
                {
                    Some(Slot::Between(from.index(), to.index(), *t))
                }
                (None, Some(Derive::ToeFromAnkle { ankle, fraction })) => {
                    use Canonical as C;
                    let needs = [C::Pelvis, C::Neck, C::LHip, C::RHip, *ankle];
                    let knee = ankle.parent();
                    let ok = needs.iter().all(|k| placed(*k, &slots))
                        && knee.is_some_and(|k| placed(k, &slots))
                        && fraction.is_finite();
                    ok.then(|| Slot::Toe(ankle.index(), *fraction))
                }
                _ => None,
            };
            match s {
                Some(s) => slots[c.index()] = Some(s),
                None => missing.push(c.name()),
            }
        }
        if !missing.is_empty() {
            return Err(RigError::Missing {
                convention: self.convention.clone(),
                missing: missing.join(", "),
            });
        }
        Ok(slots.into_iter().flatten().collect())
    }
}

/// Per-frame canonical poses and the world rotations of the mapped file
/// joints ([`RigMap::poses_and_rotations`]).
pub(crate) type PosesAndRotations = (
    Vec<[DVec3; Canonical::COUNT]>,
    Vec<[Option<DQuat>; Canonical::COUNT]>,
);

/// Canonical positions of one frame from world joint positions and rotations.
/// Joints and End Sites are placed first, then the rules in canonical
/// order, so a rule may use any joint: a derived chest between the spine
/// and the neck was placed before the neck, halfway between the spine and
/// the world origin (a skeleton whose arms branch off its first joint
/// above the pelvis: the Biovision sample, H-Anim LOA1, KIT's MMM).
fn place(slots: &[Slot], p: &[DVec3], r: &[DQuat]) -> [DVec3; Canonical::COUNT] {
    let mut out: [DVec3; Canonical::COUNT] = [DVec3::ZERO; 19];
    for (c, s) in slots.iter().enumerate() {
        match *s {
            Slot::Joint(j) => out[c] = p[j],
            Slot::EndSite(j, t) => out[c] = p[j] + r[j] * t,
            _ => {}
        }
    }
    for (c, s) in slots.iter().enumerate() {
        out[c] = match *s {
            Slot::Joint(_) | Slot::EndSite(..) => continue,
            Slot::Between(a, b, t) => out[a] + t * (out[b] - out[a]),
            Slot::Toe(a, f) => {
                use Canonical as C;
                let knee = Canonical::ALL[a].parent().map_or(a, |k| k.index());
                let up = (out[C::Neck.index()] - out[C::Pelvis.index()]).normalize_or_zero();
                let left = out[C::LHip.index()] - out[C::RHip.index()];
                let fwd = left.cross(up).normalize_or_zero();
                let shin = out[knee].distance(out[a]);
                let (s, co) = 20f64.to_radians().sin_cos();
                out[a] + f * shin * (co * fwd - s * up)
            }
        };
    }
    out
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
