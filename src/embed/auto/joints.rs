//! The joint between two rigid parts: the rest-frame point that both
//! parts' motions carry to the same place in every frame (Le & Deng 2014,
//! Sec. 5, joint location from bone transformations; the same fixed-point
//! fit as O'Brien et al. 2000, "Automatic Joint Parameter Estimation from
//! Magnetic Motion Capture Data"):
//! `min_p Σ_f ‖R_a(f) p + t_a(f) − R_b(f) p − t_b(f)‖² + λ ‖p − c‖²`,
//! regularised towards the parts' boundary centre `c` (a hinge fixes its
//! axis, not the point along it).

use super::decompose::PartMotion;
use glam::{DMat3, DVec3};

/// A joint found between two parts.
#[derive(Debug, Clone, Copy)]
pub struct PartJoint {
    /// Rest-frame position.
    pub position: DVec3,
    /// RMS over frames of the relative rotation's angle (degrees): how much
    /// the joint bends in the capture.
    pub articulation_deg: f64,
    /// RMS distance over frames between the point as carried by either
    /// part (length units): how well one point explains both motions.
    pub mismatch: f64,
}

/// The joint between motions `a` and `b`, regularised towards `centre`
/// with weight `lambda` (relative to the data term's scale).
pub(crate) fn joint_between(
    a: &PartMotion,
    b: &PartMotion,
    centre: DVec3,
    lambda: f64,
) -> PartJoint {
    let frames = a.r.len().min(b.r.len());
    let mut ata = DMat3::ZERO;
    let mut atd = DVec3::ZERO;
    let mut ang2 = 0.0;
    for f in 0..frames {
        let m = a.r[f] - b.r[f];
        let d = b.t[f] - a.t[f];
        ata += m.transpose() * m;
        atd += m.transpose() * d;
        let rel = a.r[f] * b.r[f].transpose();
        let c = ((rel.x_axis.x + rel.y_axis.y + rel.z_axis.z - 1.0) * 0.5).clamp(-1.0, 1.0);
        ang2 += c.acos().powi(2);
    }
    let scale = (ata.x_axis.x + ata.y_axis.y + ata.z_axis.z) / 3.0;
    let l = lambda * scale.max(1e-12);
    let sys = ata + DMat3::from_diagonal(DVec3::splat(l));
    let rhs = atd + centre * l;
    let position = if sys.determinant().abs() > 1e-300 {
        sys.inverse() * rhs
    } else {
        centre
    };
    let position = if position.is_finite() {
        position
    } else {
        centre
    };
    let mut mis = 0.0;
    for f in 0..frames {
        mis += (a.apply(f, position) - b.apply(f, position)).length_squared();
    }
    PartJoint {
        position,
        articulation_deg: (ang2 / frames.max(1) as f64).sqrt().to_degrees(),
        mismatch: (mis / frames.max(1) as f64).sqrt(),
    }
}
