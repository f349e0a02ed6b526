//! The top of a headless body's neck (issue 41, partial bodies): a body
//! cut at the neck ends in a stump, and its landmarks declare
//! `"absent": ["head"]` (no chin). The stump's top is the centre of the
//! highest ring of vertices near the body's axis ([`stump_top`]); the
//! chin is put 4 % of the height ahead of it ([`neck_top`]), where joint
//! placement looks for a chin (the neck is sought 4 % behind the chin,
//! [`super::joints`]), and the head joint is put on it
//! (`joints::neck_and_head`): the head ends where the body does. The neck
//! joint is sought [`neck_below_top`] below the stump's top (5 %, as
//! below a whole body's chin, unless `SURFMOTION_AUTORIG` says `neck=P`).

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

/// How far below a headless body's stump top its neck joint is sought (a
/// fraction of the height): 5 %, as a whole body's below its chin. A body
/// read as cut at the neck ([`super::auto::neck`]) ends between its neck
/// joint and its chin, and its stump's top (the highest 1.5 % ring) lies
/// above the cut rim's centre by the rim's slant (1.2-2.0 % of the height
/// on the SMPL template): its neck lay 2.2 % of the height below the rim
/// of a cut at its neck joint (where the neck is) and 4.4 % below a cut
/// 40 % up the neck→head bone (3.2 % below the rim's plane): too low.
/// `neck=3` in [`crate::embed::auto::options::AUTORIG_ENV`] (session 39,
/// `autorig_eval … headless`, 27 headless rows: three bodies × three
/// motions × three cuts) lowered the joint error on 22 rows (the neck cut
/// at 0 %: samba 2.07 / 2.64 / 1.64 → 1.76 / 2.33 / 1.36 % of the
/// height) but raised it on 2 (the 40 % cut, gait: SMPL 1.46 → 1.51,
/// MakeHuman 1.02 → 1.05) and lowered the parts on 7 (SMPL neck at 0 %,
/// CMU 02_05: 95.6 → 95.5 %; the 40 % cut: samba 94.2 /
/// 90.5 / 92.1 → 94.0 / 90.2 / 91.7 %, MakeHuman 97.3 / 97.6 / 97.1 →
/// 96.8 / 97.0 / 96.6 %): not the default.
pub(crate) const NECK_BELOW_TOP: f64 = 0.05;

/// [`NECK_BELOW_TOP`], or the `neck=P` (percent of the height, 0-10) of
/// [`crate::embed::auto::options::AUTORIG_ENV`] for measurements. Read
/// once per process.
pub(crate) fn neck_below_top() -> f64 {
    static BELOW: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *BELOW.get_or_init(|| {
        let text = std::env::var(crate::embed::auto::options::AUTORIG_ENV).unwrap_or_default();
        neck_percent(&text).map_or(NECK_BELOW_TOP, |p| p / 100.0)
    })
}

/// The `neck=P` of an override text (`P` a percent from 0 to 10); `None`
/// when it has none or it does not parse.
pub(crate) fn neck_percent(text: &str) -> Option<f64> {
    text.split(',')
        .filter_map(|p| p.trim().strip_prefix("neck="))
        .filter_map(|v| v.parse::<f64>().ok())
        .rfind(|p| (0.0..=10.0).contains(p))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_neck_override_reads_a_percent_and_ignores_the_rest() {
        assert_eq!(neck_percent("head=axis"), None);
        assert_eq!(neck_percent("head=axis, neck=5"), Some(5.0));
        assert_eq!(neck_percent("neck=2.5,max=60"), Some(2.5));
        assert_eq!(neck_percent("neck=11"), None);
        assert_eq!(neck_percent("neck=x"), None);
    }
}
