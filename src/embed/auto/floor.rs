//! The floor under legs cut above the feet (issue 41: "a body without a
//! head, hands or feet gets the joints it has").
//!
//! The body's height is read from its lowest point to its top, and every
//! placement by proportion stands on that lowest point: the groin at 47 %
//! of the height, the hips' bound over the knees ([`super::hips`]). A
//! capture whose feet were cut off ends at the cuts, 6-10 % of the
//! stature above the floor: samba cut 10 cm up had its groin placed 12 cm
//! too high (8.5 % of the height from the whole capture's). With both
//! legs on cuts ([`super::cut_ends`]) and the head there, the floor is
//! found from the knees instead: a knee stands 0.285 of the stature above
//! the floor (Winter 2009, *Biomechanics and Motor Control of Human
//! Movement*, §4.1), so with the head's top at `top` and the knees at `k`
//! the floor is `(k − 0.285 · top) / (1 − 0.285)`.

use super::body::Body;
use super::limbs::{Sided, knee};

/// A knee's height over the floor, a fraction of the stature (Winter 2009,
/// §4.1).
const KNEE_HEIGHT: f64 = 0.285;

/// How far below the lowest point the floor found from the knees may lie
/// (a fraction of the height): a foot and ankle are about 4-6 % of the
/// stature high; knees that say more are no knees.
const MAX_DROP: f64 = 0.15;

/// Lowers `body`'s floor (`lo`) and lengthens its height to the stature
/// when both legs end in cuts and `head` is there, the floor read from
/// the knees; returns what `db init` says of it (`None`: the lowest point
/// stays the floor).
pub(crate) fn floor_under_cuts(body: &mut Body, sided: &Sided, head: bool) -> Option<String> {
    if !sided.legs.iter().all(|l| body.cut_at(l.0).is_some()) {
        return None;
    }
    if !head {
        return Some(
            "no feet and no head: the floor is taken at the cuts (the height is read from them)"
                .into(),
        );
    }
    let (up, lo, height) = (body.up, body.lo, body.height);
    let knees = sided
        .legs
        .iter()
        .map(|l| knee(body, l).dot(up))
        .sum::<f64>()
        / sided.legs.len() as f64;
    let top = lo + height;
    let floor = (knees - KNEE_HEIGHT * top) / (1.0 - KNEE_HEIGHT);
    if !floor.is_finite() || floor >= lo || floor < lo - MAX_DROP * height {
        return Some(format!(
            "no feet: the knees do not say where the floor is ({:.1}% of the height below the cuts); the floor is taken at the cuts",
            100.0 * (lo - floor) / height
        ));
    }
    body.lo = floor;
    body.height = top - floor;
    Some(format!(
        "no feet: the floor placed {:.1}% of the stature below the cuts, from the knees' height (a knee stands {KNEE_HEIGHT} of the stature over the floor)",
        100.0 * (lo - floor) / body.height
    ))
}
