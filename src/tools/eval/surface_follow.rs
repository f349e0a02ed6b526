//! Joint-follow (issue 42): does the deformed surface follow the clip's
//! limbs? The joints regressed from each output frame
//! ([`crate::embed::Embedding::frame_joints`], the database's own
//! regressors) against the clip's skeleton retargeted onto the character
//! (the query `retarget` deforms towards and the joint-velocity error is
//! measured against), per body part: a dancer whose arms stay in the dance
//! pose during a walk reads tens of centimetres on the arms.
//!
//! Each frame is compared with the pelvis put on the pelvis (the limbs
//! relative to the trunk; where the body stands is the placement's, not
//! the surface's), and the pelvis's own offset is reported beside it. A
//! joint counts for the part [`Part::of_joint`] gives it.

use crate::embed::parts::Part;
use crate::pose::Pose;
use crate::rig::Canonical;
use serde::Serialize;

/// The joint-follow of one part over a sequence (centimetres).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PartFollow {
    /// The body part.
    pub part: Part,
    /// Joint-frames measured (joints of the part × frames).
    pub samples: usize,
    /// Median distance (cm).
    pub median_cm: f64,
    /// 95th percentile (cm).
    pub p95_cm: f64,
    /// Largest (cm).
    pub max_cm: f64,
}

/// Joint-follow of a sequence: per part ([`Part::ALL`] order; parts
/// without a joint are left out) and the pelvis offset.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointFollow {
    /// Frames compared.
    pub frames: usize,
    /// Per part.
    pub parts: Vec<PartFollow>,
    /// The pelvis's own offset, p95 (cm): the placement, taken out of the
    /// parts' figures.
    pub pelvis_p95_cm: f64,
    /// The worst part's p95 (cm).
    pub worst_p95_cm: f64,
}

/// The value at fraction `q` of sorted `v` (nearest rank; 0 when empty).
fn quantile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let i = ((q * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1;
    v[i]
}

/// Joint-follow of `regressed` (joints read off the output surface, one
/// pose a frame) against `query` (the retargeted skeleton), over the
/// frames both have. Non-finite distances count as infinite.
pub fn joint_follow(query: &[Pose], regressed: &[Pose]) -> JointFollow {
    let frames = query.len().min(regressed.len());
    let pelvis = Canonical::Pelvis as usize;
    let mut per: Vec<Vec<f64>> = vec![Vec::new(); Part::COUNT];
    let mut root = Vec::with_capacity(frames);
    for (q, r) in query.iter().zip(regressed).take(frames) {
        let shift = q[pelvis] - r[pelvis];
        root.push(shift.length() * 100.0);
        for (j, c) in Canonical::ALL.iter().enumerate() {
            if j == pelvis {
                continue;
            }
            let d = (r[j] + shift).distance(q[j]) * 100.0;
            per[Part::of_joint(*c).index()].push(if d.is_finite() { d } else { f64::INFINITY });
        }
    }
    let sort = |v: &mut Vec<f64>| v.sort_unstable_by(|a, b| a.total_cmp(b));
    sort(&mut root);
    let parts: Vec<PartFollow> = Part::ALL
        .iter()
        .zip(per.iter_mut())
        .filter(|(_, v)| !v.is_empty())
        .map(|(&part, v)| {
            sort(v);
            PartFollow {
                part,
                samples: v.len(),
                median_cm: quantile(v, 0.5),
                p95_cm: quantile(v, 0.95),
                max_cm: v.last().copied().unwrap_or(0.0),
            }
        })
        .collect();
    JointFollow {
        frames,
        worst_p95_cm: parts.iter().map(|p| p.p95_cm).fold(0.0, f64::max),
        parts,
        pelvis_p95_cm: quantile(&root, 0.95),
    }
}

impl JointFollow {
    /// A per-part table for the command line.
    pub fn text(&self) -> String {
        let mut s = format!(
            "joint-follow over {} frames (joints regressed from the surface vs the retargeted skeleton, pelvis on pelvis; pelvis offset p95 {:.1} cm): worst part p95 {:.1} cm\n",
            self.frames, self.pelvis_p95_cm, self.worst_p95_cm
        );
        s += &format!("{:<12} {:>9} {:>9} {:>9}\n", "part", "median", "p95", "max");
        for p in &self.parts {
            s += &format!(
                "{:<12} {:>9.1} {:>9.1} {:>9.1}\n",
                p.part.name(),
                p.median_cm,
                p.p95_cm,
                p.max_cm
            );
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn a_surface_on_its_skeleton_reads_zero_and_a_lagging_arm_reads_in_its_part() {
        let q: Pose = std::array::from_fn(|j| DVec3::new(j as f64 * 0.1, 1.0, 0.0));
        // Moved as a whole: placement, not follow.
        let moved = q.map(|p| p + DVec3::new(0.5, 0.0, 0.0));
        let f = joint_follow(&[q], &[moved]);
        assert!(f.worst_p95_cm < 1e-9, "{f:?}");
        assert!((f.pelvis_p95_cm - 50.0).abs() < 1e-9);
        let mut arm = q;
        arm[Canonical::LWrist as usize] += DVec3::new(0.0, -0.2, 0.0);
        let f = joint_follow(&[q], &[arm]);
        let by = |p: Part| f.parts.iter().find(|x| x.part == p).unwrap().max_cm;
        assert!((by(Part::LForearm) - 20.0).abs() < 1e-9, "{f:?}");
        assert_eq!(by(Part::RForearm), 0.0);
        assert!((f.worst_p95_cm - 20.0).abs() < 1e-9);
    }
}
