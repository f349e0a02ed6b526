//! The top of a headless body's neck (issue 41, partial bodies): a body
//! cut at the neck ends in a stump, and its landmarks declare
//! `"absent": ["head"]` (no chin). The stump's top is the centre of the
//! highest ring of vertices near the body's axis ([`stump_top`]); the
//! chin is put 4 % of the height ahead of it ([`neck_top`]), where joint
//! placement looks for a chin (the neck is sought 4 % behind the chin,
//! [`super::joints`]), and the head joint is put on it
//! (`joints::neck_and_head`): the head ends where the body does.

use super::landmarks::{Landmark, Landmarks};
use glam::DVec3;

/// The top of a headless body's neck.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StumpTop {
    /// The centre of the ring: the vertices within 1.5 % of the height of
    /// the highest one near the body's axis (the vertical through the
    /// groin, up from the knees to the groin, within 12 % of the height
    /// of it). On a body cut across the neck, the cut's centroid (the
    /// rim's, or the cap's when it is closed).
    pub centre: DVec3,
    /// Facing: left × up, left from the limb landmarks' pairs.
    pub facing: DVec3,
    /// The height along up.
    pub height: f64,
}

/// The top of the neck of the body at `positions` marked by `lm` (groin
/// and knees needed; the elbows and wrists side it too). `None` without a
/// groin or knees.
pub(crate) fn stump_top(lm: &Landmarks, positions: &[[f64; 3]]) -> Option<StumpTop> {
    let at = |l: Landmark| lm.point(l, positions).map(DVec3::from_array);
    let g = at(Landmark::Groin)?;
    let (lk, rk) = (at(Landmark::LKnee)?, at(Landmark::RKnee)?);
    let up = super::axes::body_up(g - (lk + rk) * 0.5);
    let hs = positions.iter().map(|q| DVec3::from_array(*q).dot(up));
    let (lo, hi) = hs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
        (a.min(x), b.max(x))
    });
    let h = (hi - lo).max(1e-9);
    let flat = |q: DVec3| {
        let d = q - g;
        (d - up * d.dot(up)).length()
    };
    let axis: Vec<DVec3> = positions
        .iter()
        .map(|q| DVec3::from_array(*q))
        .filter(|&q| flat(q) < 0.12 * h)
        .collect();
    let top = axis
        .iter()
        .map(|q| q.dot(up))
        .fold(f64::NEG_INFINITY, f64::max);
    let ring: Vec<DVec3> = axis
        .into_iter()
        .filter(|q| q.dot(up) >= top - 0.015 * h)
        .collect();
    if ring.is_empty() {
        return None;
    }
    let centre = ring.iter().copied().sum::<DVec3>() / ring.len() as f64;
    let side = [
        (Landmark::LKnee, Landmark::RKnee),
        (Landmark::LElbow, Landmark::RElbow),
        (Landmark::LWrist, Landmark::RWrist),
    ]
    .into_iter()
    .filter_map(|(a, b)| Some(at(a)? - at(b)?))
    .sum::<DVec3>();
    let left = (side - up * side.dot(up)).normalize_or(up.any_orthonormal_vector());
    Some(StumpTop {
        centre,
        facing: left.cross(up),
        height: h,
    })
}

/// The chin of a body without a head: [`stump_top`]'s centre moved
/// forward by 4 % of the height (joint placement looks for the neck that
/// far behind the chin). `None` without a groin or knees.
pub(crate) fn neck_top(lm: &Landmarks, positions: &[[f64; 3]]) -> Option<[f64; 3]> {
    let s = stump_top(lm, positions)?;
    Some((s.centre + s.facing * 0.04 * s.height).to_array())
}
