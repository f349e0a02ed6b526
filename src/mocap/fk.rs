//! Forward kinematics: local joint transforms to world positions.
//!
//! World transform of joint j: `W_j = W_parent · T(t_j) · R(q_j)` with `t_j`
//! the local translation (the rest offset, or the position channels when the
//! joint has them) and `q_j` the local rotation. O(joints) per frame.

use super::clip::{Clip, PointConvention};
use glam::{DQuat, DVec3};

impl Clip {
    /// World position and rotation of every joint at `frame`, written into
    /// `pos` and `rot` (each `joint_count()` long). No allocation.
    ///
    /// # Panics
    /// If `frame >= frame_count()` or the slices are shorter than the joint count.
    pub fn world_into(&self, frame: usize, pos: &mut [DVec3], rot: &mut [DQuat]) {
        let q = self.frame_rotations(frame);
        let t = self.frame_translations(frame);
        for (i, j) in self.joints.iter().enumerate() {
            match j.parent {
                None => {
                    pos[i] = t[i];
                    rot[i] = q[i];
                }
                Some(p) => {
                    let (pp, pr) = (pos[p.idx()], rot[p.idx()]);
                    pos[i] = pp + pr * t[i];
                    rot[i] = pr * q[i];
                }
            }
        }
    }

    /// World positions of every joint origin at `frame`.
    pub fn world_positions(&self, frame: usize) -> Vec<DVec3> {
        let n = self.joint_count();
        let mut pos = vec![DVec3::ZERO; n];
        let mut rot = vec![DQuat::IDENTITY; n];
        self.world_into(frame, &mut pos, &mut rot);
        pos
    }

    /// The clip's native points at `frame` (see [`PointConvention`]): joint
    /// origins for BVH; root position plus bone end points for ASF/AMC.
    pub fn points_at(&self, frame: usize) -> Vec<DVec3> {
        let n = self.joint_count();
        let mut pos = vec![DVec3::ZERO; n];
        let mut rot = vec![DQuat::IDENTITY; n];
        self.world_into(frame, &mut pos, &mut rot);
        if self.points == PointConvention::BoneEnds {
            for (i, j) in self.joints.iter().enumerate() {
                if j.parent.is_some()
                    && let Some(tail) = j.tail
                {
                    pos[i] += rot[i] * tail;
                }
            }
        }
        pos
    }

    /// World positions of the rest pose (every local rotation identity,
    /// translations equal to the offsets), including End Sites as a second list.
    pub fn rest_positions(&self) -> (Vec<DVec3>, Vec<DVec3>) {
        let mut pos: Vec<DVec3> = Vec::with_capacity(self.joint_count());
        let mut ends = Vec::new();
        for j in &self.joints {
            let p = j.parent.map_or(j.offset, |p| pos[p.idx()] + j.offset);
            pos.push(p);
            if let Some(t) = j.tail {
                ends.push(p + t);
            }
        }
        (pos, ends)
    }
}
