//! A skinned character's joint hierarchy read as a [`Clip`], beside the BVH,
//! ASF/AMC and FBX readers: the clip reader of glTF skin animation.

use super::{Channel, Clip, Joint, JointId, PointConvention, Units, UpAxis};
use glam::{DQuat, DVec3};

/// A skin's joints as a clip, so rigged characters go through the same joint
/// mapping as BVH and ASF (`rig::detect_skin`): one joint per skin joint
/// (`joint_names`, `parents` within the skin; parents first; a zero
/// `skin_root` above several roots), six channels each, in metres, Y-up.
/// The rest (the joint offsets) is `pose` (skin order: bind or rest
/// positions); the frames are `frames` (skin order, world space), so the
/// structure analysis sees motion (travel, knee bends), or `pose` alone when
/// `frames` is empty.
/// Every local rotation is the identity and every local translation the
/// offset from the parent's position. Also returns, per clip joint, its skin
/// joint (`None` for `skin_root`). The glTF reader feeds it
/// (`GltfAsset::skin_clip` in `mesh::io::gltf`).
pub fn skin_clip(
    joint_names: &[String],
    parents: &[Option<u32>],
    pose: &[DVec3],
    frames: Vec<Vec<DVec3>>,
) -> Result<(Clip, Vec<Option<usize>>), String> {
    let n = joint_names.len();
    if n == 0 || pose.len() != n {
        return Err(format!(
            "the skin has {n} joints and {} positions",
            pose.len()
        ));
    }
    let parent = |j: usize| {
        parents
            .get(j)
            .copied()
            .flatten()
            .map(|p| p as usize)
            .filter(|&p| p < n && p != j)
    };
    let mut children = vec![Vec::new(); n];
    let mut roots = Vec::new();
    for j in 0..n {
        match parent(j) {
            Some(p) => children[p].push(j),
            None => roots.push(j),
        }
    }
    let mut order: Vec<Option<usize>> = Vec::with_capacity(n + 1);
    if roots.len() != 1 {
        order.push(None);
    }
    let mut stack: Vec<usize> = roots.iter().rev().copied().collect();
    while let Some(j) = stack.pop() {
        if order.len() > n + 1 {
            break;
        }
        order.push(Some(j));
        stack.extend(children[j].iter().rev().copied());
    }
    if order.iter().flatten().count() != n {
        return Err("the skin's joint hierarchy has a cycle".into());
    }
    let mut clip_of = vec![0usize; n];
    for (k, j) in order.iter().enumerate() {
        if let Some(j) = j {
            clip_of[*j] = k;
        }
    }
    let six = vec![
        Channel::Xposition,
        Channel::Yposition,
        Channel::Zposition,
        Channel::Zrotation,
        Channel::Xrotation,
        Channel::Yrotation,
    ];
    let parent_in_clip = |k: usize| -> Option<usize> {
        match order[k] {
            None => None,
            Some(j) => match parent(j) {
                Some(p) => Some(clip_of[p]),
                None if order[0].is_none() => Some(0),
                None => None,
            },
        }
    };
    let local = |pos: &[DVec3], k: usize| -> DVec3 {
        let here = order[k].map_or(DVec3::ZERO, |j| pos[j]);
        match parent_in_clip(k).and_then(|p| order[p]) {
            Some(p) => here - pos[p],
            None => here,
        }
    };
    let joints: Vec<Joint> = (0..order.len())
        .map(|k| Joint {
            name: order[k].map_or("skin_root".to_string(), |j| joint_names[j].clone()),
            parent: parent_in_clip(k).map(|p| JointId(p as u32)),
            offset: local(pose, k),
            channels: six.clone(),
            tail: None,
        })
        .collect();
    // The rest (offsets) is `pose`; the frames are the animation when there
    // is one (world space, which may differ from bind space by the root
    // node's transform), else `pose` again.
    let mut frames = frames;
    if frames.is_empty() {
        frames.push(pose.to_vec());
    }
    let m = order.len();
    let mut rot = Vec::with_capacity(frames.len() * m);
    let mut tr = Vec::with_capacity(frames.len() * m);
    for p in &frames {
        for k in 0..m {
            rot.push(DQuat::IDENTITY);
            tr.push(local(p, k));
        }
    }
    let clip = Clip::new(
        joints,
        1.0 / 30.0,
        rot,
        tr,
        Units {
            metres_per_unit: 1.0,
            name: "m".into(),
            reason: "glTF is in metres".into(),
        },
        UpAxis::Y,
        PointConvention::JointOrigins,
    )
    .map_err(|e| e.to_string())?;
    Ok((clip, order))
}
