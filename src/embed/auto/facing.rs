//! The body's left-right axis on the rest frame: the widest horizontal
//! axis of its chest and shoulders.
//!
//! A standing body is wider from shoulder to shoulder than from chest to
//! back (biacromial breadth about 0.23 of the stature, chest depth about
//! 0.13: Drillis & Contini 1966, the proportions [`super::limbs`] uses), and
//! the upper arms hanging beside the chest or held out (A- or T-pose) only
//! widen it the same way. So the principal axis of the horizontal second
//! moment of the vertices between [`BAND`] of the height is left-right, and
//! the facing is square to it; the toes decide its sign
//! ([`super::limbs::side`]). It was the line through the hips found on the
//! legs' paths, and a hip found at a skirt band put samba's facing 31° off
//! (0.86, 0, −0.51): the hips' line joined (0.325, 0.741, −0.133) at a
//! band to (0.443, 0.930, 0.070) at the trunk, 12 cm apart front to back.
//!
//! Built from the positions alone, the axis turns, mirrors and scales with
//! the body and does not depend on the vertices' order. Cost: one pass over
//! the rest frame.

use super::decompose::PartMotion;
use glam::DVec3;

/// The heights (fractions of the height above the lowest point along up)
/// whose vertices give the axis: waist to shoulders. On samba's and
/// crane's rest frames (A-poses) any band from 0.5-0.75 to 0.7-0.85, and
/// the bodies cut at 0.8-0.9 of their height (headless), gave an axis
/// within 1.2° of the landmark fixtures' left-right (knees, elbows and
/// wrists, as `embed::joints` reads it).
pub(crate) const BAND: (f64, f64) = (0.55, 0.8);

/// The widest axis is trusted when its second moment is at least this many
/// times the other's (samba's and crane's rest frames: 7.7 and 9.9).
pub(crate) const MIN_RATIO: f64 = 1.5;

/// The widest horizontal axis (unit, square to `up`, its sign arbitrary)
/// of the vertices of `rest` between [`BAND`] of `height` above `lo`
/// (along `up`), and the ratio of the two horizontal second moments
/// (largest over smallest). `None` with fewer than three vertices in the
/// band or a band without spread.
pub(crate) fn widest_across(
    rest: &[[f64; 3]],
    up: DVec3,
    lo: f64,
    height: f64,
) -> Option<(DVec3, f64)> {
    let (a, b) = up.any_orthonormal_pair();
    let (from, to) = (lo + BAND.0 * height, lo + BAND.1 * height);
    let band: Vec<(f64, f64)> = rest
        .iter()
        .map(|q| DVec3::from_array(*q))
        .filter(|q| (from..=to).contains(&q.dot(up)))
        .map(|q| (q.dot(a), q.dot(b)))
        .collect();
    if band.len() < 3 {
        return None;
    }
    let n = band.len() as f64;
    let (mx, my) = band
        .iter()
        .fold((0.0, 0.0), |(x, y), q| (x + q.0 / n, y + q.1 / n));
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in &band {
        let (dx, dy) = (x - mx, y - my);
        sxx += dx * dx;
        sxy += dx * dy;
        syy += dy * dy;
    }
    // The 2 × 2 symmetric eigenproblem in closed form.
    let half = 0.5 * (sxx - syy);
    let root = (half * half + sxy * sxy).sqrt();
    let mean = 0.5 * (sxx + syy);
    let (big, small) = (mean + root, mean - root);
    if !(big > 0.0 && big.is_finite()) {
        return None;
    }
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let across = a * angle.cos() + b * angle.sin();
    Some((across, big / small.max(big * 1e-12)))
}

/// Where a knee's bend carries the ankle, horizontally, summed over the
/// frames: the ankle's rest point `ankle` moved by the shin's motion and
/// brought back by the thigh's (in the thigh's own frame, whatever the hip
/// does), less its rest point, with the part along `up` taken off. A knee
/// flexes one way (the shin folds back under the thigh; it does not
/// extend past straight by more than a few degrees), so the sum points to
/// the body's back: the facing's sign on legs cut above the toes
/// ([`super::limbs::side`]), which the toes' direction from the knees gives
/// on whole legs. Zero when the frames show no bend.
pub(crate) fn knee_folds_towards(
    shin: &PartMotion,
    thigh: &PartMotion,
    ankle: DVec3,
    up: DVec3,
) -> DVec3 {
    let frames = shin.r.len().min(thigh.r.len());
    let mut sum = DVec3::ZERO;
    for f in 0..frames {
        let world = shin.apply(f, ankle);
        let in_thigh = thigh.r[f].transpose() * (world - thigh.t[f]);
        let d = in_thigh - ankle;
        sum += d - up * d.dot(up);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box body: a chest `w` wide along `across`, `d` deep, between
    /// 0.5 and 0.9 of a unit height above `base` along `up`, on two legs.
    fn body(up: DVec3, across: DVec3, base: DVec3, w: f64, d: f64) -> Vec<[f64; 3]> {
        let depth = up.cross(across).normalize();
        let mut p = Vec::new();
        for i in 0..=20 {
            for j in 0..=10 {
                for k in 0..=10 {
                    let (s, t, h) = (i as f64 / 20.0, j as f64 / 10.0, k as f64 / 10.0);
                    let q = base
                        + across * (w * (s - 0.5))
                        + depth * (d * (t - 0.5))
                        + up * (0.5 + 0.4 * h);
                    p.push(q.to_array());
                }
            }
        }
        // The legs (below the band) and the head top (above).
        for k in 0..=10 {
            for side in [-1.0, 1.0] {
                let q = base + across * (0.1 * side) + up * (0.05 * k as f64);
                p.push(q.to_array());
            }
        }
        p.push((base + up).to_array());
        p
    }

    #[test]
    fn the_axis_is_the_chest_width_however_the_body_is_turned_or_placed() {
        for (up, yaw) in [
            (DVec3::Y, 0.0_f64),
            (DVec3::Y, 30.0),
            (DVec3::Y, 90.0),
            (DVec3::Y, 200.0),
            (DVec3::Z, 270.0),
            (DVec3::NEG_X, 45.0),
        ] {
            let (a, b) = up.any_orthonormal_pair();
            let t = yaw.to_radians();
            let across = a * t.cos() + b * t.sin();
            let base = DVec3::new(3.0, -2.0, 0.5);
            for scale in [1.0, 100.0] {
                let p: Vec<[f64; 3]> = body(up, across, base, 0.4, 0.2)
                    .iter()
                    .map(|q| (DVec3::from_array(*q) * scale).to_array())
                    .collect();
                let lo = (base * scale).dot(up);
                let (got, ratio) = widest_across(&p, up, lo, scale).unwrap();
                assert!(got.dot(across).abs() > 0.9999, "{up} {yaw}: {got}");
                assert!(got.dot(up).abs() < 1e-9);
                // 0.4 by 0.2: (0.4 / 0.2)² less the grid's and the legs' share.
                assert!((3.0..4.0).contains(&ratio), "{ratio}");
                // Mirrored (one axis negated): the axis mirrors with it.
                let m: Vec<[f64; 3]> = p.iter().map(|q| [-q[0], q[1], q[2]]).collect();
                let flip = DVec3::new(-1.0, 1.0, 1.0);
                let m_up = up * flip;
                let (got, _) =
                    widest_across(&m, m_up, (base * scale * flip).dot(m_up), scale).unwrap();
                assert!(got.dot(across * flip).abs() > 0.9999, "mirrored {up} {yaw}");
            }
        }
    }

    #[test]
    fn a_round_chest_says_so_and_an_empty_band_gives_none() {
        let p = body(DVec3::Y, DVec3::X, DVec3::ZERO, 0.3, 0.3);
        let (_, ratio) = widest_across(&p, DVec3::Y, 0.0, 1.0).unwrap();
        assert!(ratio < MIN_RATIO, "{ratio}");
        let low: Vec<[f64; 3]> = p.iter().filter(|q| q[1] < 0.5).copied().collect();
        assert!(widest_across(&low, DVec3::Y, 0.0, 1.0).is_none());
        assert!(widest_across(&[], DVec3::Y, 0.0, 1.0).is_none());
    }

    /// A shin folding back under its thigh, the thigh turned and moved
    /// anyhow by the hip: the sum points back, whatever the hip does.
    #[test]
    fn a_folding_knee_points_to_the_back_whatever_the_hip_does() {
        use glam::DMat3;
        let (knee, ankle) = (DVec3::new(0.0, 0.5, 0.0), DVec3::ZERO);
        let (mut shin, mut thigh) = (
            PartMotion {
                r: vec![],
                t: vec![],
            },
            PartMotion {
                r: vec![],
                t: vec![],
            },
        );
        for f in 0..10 {
            let hip =
                DMat3::from_rotation_y(0.4 * f as f64) * DMat3::from_rotation_x(-0.1 * f as f64);
            let move_by = DVec3::new(0.1 * f as f64, 0.02, -0.3);
            // The shin turned about the knee's lateral axis by the flexion.
            let flex = DMat3::from_rotation_x(0.12 * f as f64);
            thigh.r.push(hip);
            thigh.t.push(move_by);
            shin.r.push(hip * flex);
            shin.t.push(hip * (knee - flex * knee) + move_by);
        }
        let back = knee_folds_towards(&shin, &thigh, ankle, DVec3::Y);
        assert!(back.normalize().dot(DVec3::NEG_Z) > 0.999, "{back}");
        // Still legs say nothing.
        let still = knee_folds_towards(&thigh, &thigh, ankle, DVec3::Y);
        assert!(still.length() < 1e-12, "{still}");
    }
}
