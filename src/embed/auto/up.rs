//! Up: the direction along which the feet rest on a floor.

use super::options::AutoError;
use super::report::axis_name;
use glam::DVec3;

/// Up: among ±X, ±Y, ±Z, the directions along which two of the five
/// extremities are at the bottom of the rest frame and the third clearly
/// higher, the one whose lowest point over the frames (the floor) varies
/// least. Returns it with a note.
pub(crate) fn find_up(
    rest: &[[f64; 3]],
    frames: &[&[[f64; 3]]],
    tips: &[(u32, f64)],
) -> Result<(DVec3, String), AutoError> {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for q in rest {
        lo = lo.min(DVec3::from_array(*q));
        hi = hi.max(DVec3::from_array(*q));
    }
    let mut best: Option<(f64, DVec3)> = None;
    for u in [
        DVec3::Y,
        DVec3::Z,
        DVec3::X,
        DVec3::NEG_Y,
        DVec3::NEG_Z,
        DVec3::NEG_X,
    ] {
        let ext = (hi - lo).dot(u.abs());
        let mut h: Vec<f64> = tips
            .iter()
            .map(|t| DVec3::from_array(rest[t.0 as usize]).dot(u))
            .collect();
        h.sort_by(f64::total_cmp);
        let bottom = rest
            .iter()
            .map(|q| DVec3::from_array(*q).dot(u))
            .fold(f64::INFINITY, f64::min);
        if !(h[1] - bottom < 0.12 * ext && h[2] - h[1] > 0.25 * ext) {
            continue;
        }
        let floors: Vec<f64> = frames
            .iter()
            .map(|f| {
                f.iter()
                    .map(|q| DVec3::from_array(*q).dot(u))
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let mean = floors.iter().sum::<f64>() / floors.len() as f64;
        let sd = (floors.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / floors.len() as f64)
            .sqrt()
            / ext;
        if best.is_none_or(|b| sd < b.0) {
            best = Some((sd, u));
        }
    }
    match best {
        Some((sd, u)) => Ok((
            u,
            format!(
                "up {}: two extremities (the feet) at the bottom, the floor steady to {:.1}% of the height over the frames",
                axis_name(u),
                100.0 * sd
            ),
        )),
        None => Err(AutoError::NotHumanoid(
            "along no axis do two extremities (feet) rest at the bottom with the others clearly above".into(),
        )),
    }
}
