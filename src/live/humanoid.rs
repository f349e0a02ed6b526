//! The humanoid skeletons the network protocols name (VMC: Unity's
//! `HumanBodyBones`; Rokoko Studio Live: its body joints), and the two
//! directions between them and a clip:
//!
//! - [`BodyState::to_clip`] (receiving): the bones a stream carries, as a
//!   one-frame [`Clip`] whose hierarchy is the protocol's, each bone's
//!   parent the nearest ancestor the stream carries. The clip then goes
//!   through the same rig detection as a file.
//! - [`body_frames`] (sending): a clip file's canonical joints (metres,
//!   Y-up) as the protocol's bones, world or local transforms.
//!
//! Both protocols work in Unity's axes: Y up, metres, left-handed (X to
//! the other side). [`to_unity`] and [`from_unity`] mirror X; a rotation
//! mirrors as `(x, -y, -z, w)`.

use crate::mocap::{Channel, Clip, Joint, PointConvention, Units, UpAxis};
use crate::pose::Pose;
use crate::pose::retarget::JointRotations;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};
use std::collections::HashMap;

/// A protocol's bones: `(name, parent)` in parents-first order (`""`: the
/// root).
pub(crate) type BoneTable = &'static [(&'static str, &'static str)];

/// Unity's humanoid body bones (`HumanBodyBones`, fingers left out), as
/// VMC names them.
pub(crate) const UNITY_BONES: BoneTable = &[
    ("Hips", ""),
    ("Spine", "Hips"),
    ("Chest", "Spine"),
    ("UpperChest", "Chest"),
    ("Neck", "UpperChest"),
    ("Head", "Neck"),
    ("LeftEye", "Head"),
    ("RightEye", "Head"),
    ("Jaw", "Head"),
    ("LeftShoulder", "UpperChest"),
    ("LeftUpperArm", "LeftShoulder"),
    ("LeftLowerArm", "LeftUpperArm"),
    ("LeftHand", "LeftLowerArm"),
    ("RightShoulder", "UpperChest"),
    ("RightUpperArm", "RightShoulder"),
    ("RightLowerArm", "RightUpperArm"),
    ("RightHand", "RightLowerArm"),
    ("LeftUpperLeg", "Hips"),
    ("LeftLowerLeg", "LeftUpperLeg"),
    ("LeftFoot", "LeftLowerLeg"),
    ("LeftToes", "LeftFoot"),
    ("RightUpperLeg", "Hips"),
    ("RightLowerLeg", "RightUpperLeg"),
    ("RightFoot", "RightLowerLeg"),
    ("RightToes", "RightFoot"),
];

/// The Unity bone each canonical joint is sent as ([`Canonical::ALL`]
/// order).
pub(crate) const UNITY_CANONICAL: [&str; Canonical::COUNT] = [
    "Hips",
    "Spine",
    "Chest",
    "Neck",
    "Head",
    "LeftUpperArm",
    "LeftLowerArm",
    "LeftHand",
    "RightUpperArm",
    "RightLowerArm",
    "RightHand",
    "LeftUpperLeg",
    "LeftLowerLeg",
    "LeftFoot",
    "LeftToes",
    "RightUpperLeg",
    "RightLowerLeg",
    "RightFoot",
    "RightToes",
];

/// Rokoko Studio Live's body joints (fingers left out).
pub(crate) const ROKOKO_BONES: BoneTable = &[
    ("hip", ""),
    ("spine", "hip"),
    ("chest", "spine"),
    ("neck", "chest"),
    ("head", "neck"),
    ("leftShoulder", "chest"),
    ("leftUpperArm", "leftShoulder"),
    ("leftLowerArm", "leftUpperArm"),
    ("leftHand", "leftLowerArm"),
    ("rightShoulder", "chest"),
    ("rightUpperArm", "rightShoulder"),
    ("rightLowerArm", "rightUpperArm"),
    ("rightHand", "rightLowerArm"),
    ("leftUpLeg", "hip"),
    ("leftLeg", "leftUpLeg"),
    ("leftFoot", "leftLeg"),
    ("leftToe", "leftFoot"),
    ("leftToeEnd", "leftToe"),
    ("rightUpLeg", "hip"),
    ("rightLeg", "rightUpLeg"),
    ("rightFoot", "rightLeg"),
    ("rightToe", "rightFoot"),
    ("rightToeEnd", "rightToe"),
];

/// The Rokoko joint each canonical joint is sent as.
pub(crate) const ROKOKO_CANONICAL: [&str; Canonical::COUNT] = [
    "hip",
    "spine",
    "chest",
    "neck",
    "head",
    "leftUpperArm",
    "leftLowerArm",
    "leftHand",
    "rightUpperArm",
    "rightLowerArm",
    "rightHand",
    "leftUpLeg",
    "leftLeg",
    "leftFoot",
    "leftToe",
    "rightUpLeg",
    "rightLeg",
    "rightFoot",
    "rightToe",
];

/// A bone's transform: position and rotation (world or local as the
/// protocol says).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bone {
    /// Position (metres).
    pub pos: DVec3,
    /// Rotation.
    pub rot: DQuat,
}

/// A point from the project's axes (right-handed, Y up) to Unity's.
pub(crate) fn to_unity(p: DVec3) -> DVec3 {
    DVec3::new(-p.x, p.y, p.z)
}

/// A point from Unity's axes to the project's (the same mirror).
pub(crate) fn from_unity(p: DVec3) -> DVec3 {
    to_unity(p)
}

/// A rotation mirrored between the two (its own inverse).
pub(crate) fn mirror_rotation(q: DQuat) -> DQuat {
    DQuat::from_xyzw(q.x, -q.y, -q.z, q.w)
}

/// A bone mirrored between the project's axes and Unity's.
pub fn mirror(b: Bone) -> Bone {
    Bone {
        pos: to_unity(b.pos),
        rot: mirror_rotation(b.rot),
    }
}

/// What a stream has said about its bones so far: each bone's latest
/// transform (a VMC sender may split a frame over several bundles; a bone
/// keeps its value until it is sent again) and, when the sender gave one,
/// its neutral reference pose (a surfmotion extension other receivers
/// ignore).
#[derive(Debug, Clone, Default)]
pub struct BodyState {
    /// Latest transform of each bone named, in the project's axes.
    pub bones: HashMap<String, Bone>,
    /// The sender's neutral reference (canonical joints, metres, Y-up).
    pub reference: Option<Pose>,
    /// The avatar's root transform (VMC `/VMC/Ext/Root/Pos`), which the
    /// root bone's local transform is relative to.
    pub root: Option<Bone>,
}

impl BodyState {
    /// The bones of `table` the stream has sent, as a one-frame clip
    /// (metres, Y-up) of the protocol's hierarchy; `local` says whether
    /// the transforms are relative to the parent (VMC) or world (Rokoko).
    /// `offsets` gives the rest offset of each bone by name (this frame's
    /// translation for a bone it does not name). `None` when the root is
    /// missing.
    pub(crate) fn to_clip(
        &self,
        table: BoneTable,
        local: bool,
        offsets: Option<&HashMap<String, DVec3>>,
    ) -> Option<Clip> {
        let (joints, mut samples) = self.present(table)?;
        if let (true, Some(r)) = (local, self.root) {
            samples[0] = Bone {
                pos: r.pos + r.rot * samples[0].pos,
                rot: r.rot * samples[0].rot,
            };
        }
        let mut rot = Vec::with_capacity(joints.len());
        let mut tr = Vec::with_capacity(joints.len());
        for (j, b) in joints.iter().zip(&samples) {
            let (t, q) = match (local, j.parent) {
                (true, _) | (false, None) => (b.pos, b.rot),
                (false, Some(p)) => {
                    let pb = samples[p.idx()];
                    let inv = pb.rot.inverse();
                    (inv * (b.pos - pb.pos), inv * b.rot)
                }
            };
            tr.push(t);
            rot.push(q.normalize());
        }
        let joints = joints
            .into_iter()
            .enumerate()
            .map(|(i, mut j)| {
                j.offset = offsets
                    .and_then(|o| o.get(&j.name).copied())
                    .unwrap_or(tr[i]);
                j
            })
            .collect();
        let units = Units {
            metres_per_unit: 1.0,
            name: "m".into(),
            reason: "the protocol's unit".into(),
        };
        Clip::new(
            joints,
            1.0 / 60.0,
            rot,
            tr,
            units,
            UpAxis::Y,
            PointConvention::JointOrigins,
        )
        .ok()
    }

    /// The joints of `table` present in the state (each parented to its
    /// nearest present ancestor) and their transforms.
    fn present(&self, table: BoneTable) -> Option<(Vec<Joint>, Vec<Bone>)> {
        let mut index: HashMap<&str, usize> = HashMap::new();
        let mut joints = Vec::new();
        let mut samples = Vec::new();
        for &(name, parent) in table {
            let Some(b) = self.bones.get(name) else {
                continue;
            };
            let mut p = parent;
            let parent = loop {
                if p.is_empty() {
                    break None;
                }
                if let Some(&i) = index.get(p) {
                    break Some(i);
                }
                p = table.iter().find(|(n, _)| *n == p).map_or("", |(_, q)| q);
            };
            if parent.is_none() && !joints.is_empty() {
                continue;
            }
            index.insert(name, joints.len());
            joints.push(Joint {
                name: name.to_string(),
                parent: parent.map(|i| crate::mocap::JointId(i as u32)),
                offset: DVec3::ZERO,
                channels: vec![
                    Channel::Xposition,
                    Channel::Yposition,
                    Channel::Zposition,
                    Channel::Zrotation,
                    Channel::Xrotation,
                    Channel::Yrotation,
                ],
                tail: None,
            });
            samples.push(*b);
        }
        (!joints.is_empty() && index.contains_key(table[0].0)).then_some((joints, samples))
    }
}

/// A clip's canonical joints as world transforms (metres, Y-up, the
/// project's axes): a derived joint (no joint of its own) turns with its
/// parent.
pub fn world_bones(pose: &Pose, rotations: Option<&JointRotations>) -> [Bone; Canonical::COUNT] {
    let mut out = [Bone {
        pos: DVec3::ZERO,
        rot: DQuat::IDENTITY,
    }; Canonical::COUNT];
    for c in Canonical::ALL {
        let own = rotations.and_then(|r| r[c.index()]);
        let rot = own
            .or_else(|| c.parent().map(|p| out[p.index()].rot))
            .unwrap_or(DQuat::IDENTITY);
        out[c.index()] = Bone {
            pos: pose[c.index()],
            rot,
        };
    }
    out
}

/// World transforms made local to each canonical parent.
pub fn local_bones(world: &[Bone; Canonical::COUNT]) -> [Bone; Canonical::COUNT] {
    let mut out = *world;
    for c in Canonical::ALL {
        if let Some(p) = c.parent() {
            let pb = world[p.index()];
            let inv = pb.rot.inverse();
            out[c.index()] = Bone {
                pos: inv * (world[c.index()].pos - pb.pos),
                rot: inv * world[c.index()].rot,
            };
        }
    }
    out
}

/// The rest offsets of a neutral pose along the canonical tree (each
/// joint from its parent, the root from the origin).
pub(crate) fn rest_offsets(pose: &Pose) -> [DVec3; Canonical::COUNT] {
    let mut out = [DVec3::ZERO; Canonical::COUNT];
    for c in Canonical::ALL {
        out[c.index()] = pose[c.index()] - c.parent().map_or(DVec3::ZERO, |p| pose[p.index()]);
    }
    out
}

/// The rest offsets of the joints of a received clip by name: the
/// sender's reference's for the canonical joints sent under `names`, the
/// clip's own translations (its first frame's) for the others.
pub(crate) fn clip_offsets(
    clip: &Clip,
    names: &[&str; Canonical::COUNT],
    reference: Option<&Pose>,
) -> HashMap<String, DVec3> {
    let rest = reference.map(rest_offsets);
    clip.joints
        .iter()
        .zip(clip.frame_translations(0))
        .map(|(j, t)| {
            let r = rest
                .as_ref()
                .and_then(|r| names.iter().position(|n| *n == j.name).map(|c| r[c]));
            (j.name.clone(), r.unwrap_or(*t))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_bones_rebuilt_as_a_clip_give_back_the_world_positions() {
        let mut pose = [DVec3::ZERO; Canonical::COUNT];
        let mut rot: JointRotations = [None; Canonical::COUNT];
        for c in Canonical::ALL {
            let i = c.index() as f64;
            pose[c.index()] = DVec3::new(0.1 * i.sin(), 1.0 + 0.05 * i, 0.07 * i.cos());
            if c != Canonical::LToe {
                rot[c.index()] = Some(DQuat::from_euler(glam::EulerRot::XYZ, 0.1 * i, -0.2, 0.3));
            }
        }
        for (table, names, local) in [
            (UNITY_BONES, &UNITY_CANONICAL, true),
            (ROKOKO_BONES, &ROKOKO_CANONICAL, false),
        ] {
            let world = world_bones(&pose, Some(&rot));
            let sent = if local { local_bones(&world) } else { world };
            let mut st = BodyState::default();
            for (c, n) in names.iter().enumerate() {
                // Through Unity's axes and back.
                st.bones.insert(n.to_string(), mirror(mirror(sent[c])));
            }
            let clip = st.to_clip(table, local, None).unwrap();
            let p = clip.world_positions(0);
            for (c, n) in names.iter().enumerate() {
                let j = clip.joint(n).unwrap().idx();
                assert!(p[j].distance(pose[c]) < 1e-12, "{n}");
            }
        }
    }

    /// A standing body, left on +X, facing +Z (metres, Y-up).
    pub(crate) fn standing() -> Pose {
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        [
            v(0.0, 1.0, 0.0),
            v(0.0, 1.12, 0.0),
            v(0.0, 1.3, 0.0),
            v(0.0, 1.5, 0.0),
            v(0.0, 1.65, 0.02),
            v(0.2, 1.45, 0.0),
            v(0.45, 1.45, 0.0),
            v(0.7, 1.45, 0.0),
            v(-0.2, 1.45, 0.0),
            v(-0.45, 1.45, 0.0),
            v(-0.7, 1.45, 0.0),
            v(0.1, 0.95, 0.0),
            v(0.1, 0.52, 0.02),
            v(0.1, 0.08, 0.0),
            v(0.1, 0.02, 0.15),
            v(-0.1, 0.95, 0.0),
            v(-0.1, 0.52, 0.02),
            v(-0.1, 0.08, 0.0),
            v(-0.1, 0.02, 0.15),
        ]
    }

    #[test]
    fn the_protocols_bones_are_detected_as_humanoids() {
        let pose = standing();
        for (table, names, local) in [
            (UNITY_BONES, &UNITY_CANONICAL, true),
            (ROKOKO_BONES, &ROKOKO_CANONICAL, false),
        ] {
            let world = world_bones(&pose, None);
            let sent = if local { local_bones(&world) } else { world };
            let mut st = BodyState::default();
            for (c, n) in names.iter().enumerate() {
                st.bones.insert(n.to_string(), sent[c]);
            }
            let clip = st.to_clip(table, local, None).unwrap();
            let map = crate::rig::detect_clip(&clip).unwrap().map;
            for c in Canonical::ALL {
                assert_eq!(
                    map.joints.get(&c).map(String::as_str),
                    Some(names[c.index()]),
                    "{}: {map:?}",
                    c.name()
                );
            }
        }
    }
}
