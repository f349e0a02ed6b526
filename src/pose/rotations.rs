//! Canonical poses (the 19 joint positions of one frame) and the global
//! joint rotations that explain a pose relative to a rest pose: the
//! rotation of least angle (composed on the parent's) for a joint with one
//! child, the best-fitting rotation (Kabsch, via the polar decomposition of
//! `Σ d oᵀ`) for a joint with several; end joints inherit their parent's.
//! Twist about a bone is not observable from positions and is carried down
//! from the parent. Drives linear blend skinning and pose retargeting;
//! [`crate::pose::measure`] builds BVH clips from poses.

use crate::mesh::frames::polar;
use crate::rig::Canonical;
use glam::{DMat3, DQuat, DVec3};

/// Canonical joint positions of one frame, [`Canonical::ALL`] order.
pub type Pose = [DVec3; Canonical::COUNT];

/// Children of each canonical joint.
pub fn children() -> [Vec<Canonical>; Canonical::COUNT] {
    let mut c: [Vec<Canonical>; Canonical::COUNT] = Default::default();
    for j in Canonical::ALL {
        if let Some(p) = j.parent() {
            c[p.index()].push(j);
        }
    }
    c
}

/// Global rotation of each joint taking `rest`'s bones onto `pose`'s.
pub fn pose_rotations(rest: &Pose, pose: &Pose) -> [DQuat; Canonical::COUNT] {
    // Called per frame (and per part) by synthesis: the hierarchy is built once.
    static KIDS: std::sync::OnceLock<[Vec<Canonical>; Canonical::COUNT]> =
        std::sync::OnceLock::new();
    let kids = KIDS.get_or_init(children);
    let mut g = [DQuat::IDENTITY; Canonical::COUNT];
    for j in Canonical::ALL {
        let pr = j.parent().map_or(DQuat::IDENTITY, |p| g[p.index()]);
        let ks = &kids[j.index()];
        let bone = |c: &Canonical| {
            (
                rest[c.index()] - rest[j.index()],
                pose[c.index()] - pose[j.index()],
            )
        };
        g[j.index()] = match ks.len() {
            0 => pr,
            1 => {
                let (o, d) = bone(&ks[0]);
                let from = (pr * o).normalize_or_zero();
                let to = d.normalize_or_zero();
                if from == DVec3::ZERO || to == DVec3::ZERO {
                    pr
                } else {
                    (DQuat::from_rotation_arc(from, to) * pr).normalize()
                }
            }
            _ => {
                let mut h = DMat3::ZERO;
                for c in ks {
                    let (o, d) = bone(c);
                    let (o, d) = (o.normalize_or_zero(), d.normalize_or_zero());
                    h += DMat3::from_cols(d * o.x, d * o.y, d * o.z);
                }
                polar(h).0
            }
        };
    }
    g
}
