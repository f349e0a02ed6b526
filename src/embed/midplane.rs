//! The body's mid-plane (sagittal plane) in its rest frame: the vertical
//! plane, normal to the character's left, that the pelvis lies on and the
//! hips are symmetric about. Its normal is the landmarks' left direction;
//! its offset is the median of independent estimates of where the body's
//! middle is along that direction: the groin and chin landmarks, the
//! centres of horizontal cross-sections of the torso between them, and the
//! midpoint of the two knee landmarks. The median keeps one biased estimate
//! (a section that caught an arm or a hand, a landmark marked off-centre, a
//! skirt) from moving the plane.

use super::section::part_loop;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// A vertical plane `{x : x · normal = offset}`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MidPlane {
    /// Unit normal, towards the character's left.
    pub normal: [f64; 3],
    /// Offset along the normal.
    pub offset: f64,
}

impl MidPlane {
    /// Signed distance of `p` from the plane (positive on the left).
    pub fn distance(&self, p: DVec3) -> f64 {
        p.dot(DVec3::from_array(self.normal)) - self.offset
    }

    /// The foot of `p` on the plane.
    pub fn project(&self, p: DVec3) -> DVec3 {
        p - DVec3::from_array(self.normal) * self.distance(p)
    }

    /// The plane with normal `left` through the median of `points`' offsets
    /// along it (none: through the origin).
    pub(crate) fn median_of(left: DVec3, points: &[DVec3]) -> MidPlane {
        let mut d: Vec<f64> = points.iter().map(|p| p.dot(left)).collect();
        MidPlane {
            normal: left.to_array(),
            offset: median(&mut d),
        }
    }
}

/// The median of `v` (0 when empty); reorders `v`.
pub fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// Estimates the mid-plane with normal `left` (unit, horizontal) of a rest
/// mesh from `marks` = its groin and chin landmarks and the midpoint of its
/// knee landmarks. Torso
/// sections are horizontal cuts (normal `up`) at 30, 40, 50, 60 and 70 % of
/// the way from groin to chin, each the loop enclosing the groin-chin line;
/// a loop wider than a quarter of the height `h` across on average (arms
/// joined to it) is not used. Returns the plane and the estimates it is the
/// median of (name, offset), for reports.
pub(crate) fn estimate_mid_plane(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    marks: [DVec3; 3],
    up: DVec3,
    left: DVec3,
    h: f64,
) -> (MidPlane, Vec<(String, f64)>) {
    let [groin, chin, knees] = marks;
    let mut est: Vec<(String, f64)> = vec![
        ("groin".into(), groin.dot(left)),
        ("chin".into(), chin.dot(left)),
        ("knees".into(), knees.dot(left)),
    ];
    for f in [0.3, 0.4, 0.5, 0.6, 0.7] {
        let at = groin.lerp(chin, f);
        if let Some(l) = part_loop(positions, triangles, at, up, at)
            && l.radius < 0.25 * h
        {
            est.push((
                format!("torso section {:.0}%", 100.0 * f),
                l.centroid.dot(left),
            ));
        }
    }
    let mut d: Vec<f64> = est.iter().map(|e| e.1).collect();
    (
        MidPlane {
            normal: left.to_array(),
            offset: median(&mut d),
        },
        est,
    )
}
