//! Hips the motion found where a body's hips cannot be: a clothing edge.
//!
//! A skirt's waistband moves with the thighs when the skirt is decimated
//! to a coarser mesh (samba at half its vertices, session 46): the
//! decomposition then gives the thighs' parts the skirt, and the fixed
//! point of thigh and trunk, taken for the hip, is the waistband. The
//! groin followed it 23 cm up and the pelvis, the hips and the spine
//! were 8.6-12.7 % of the height off.
//!
//! The bound is anthropometric: the hip joint stands above the knee by
//! about 0.86 of the knee's height above the floor (Winter 2009,
//! *Biomechanics and Motor Control of Human Movement*, §4.1: thigh 0.245,
//! knee height 0.285 of the stature); the fixtures' landmark rigs read
//! 0.65-0.82. The motion's estimate scatters more: over the 87 rigs of
//! `autorig_eval` (`all`, `bodies`, `headless`, `contact`, `orders`,
//! `facing`) whose hips both showed in the motion it read 0.42-1.10 (the
//! highest MakeHuman's body driven by CMU 02_05, whole and headless), and
//! on samba decimated to 0.3-0.9 of its vertices 0.71-1.03; the waistband
//! read 1.22. A bound on the legitimate side is cheap: forced down to 0.95,
//! MakeHuman's 02_05 rows moved from 1.34 / 0.83 / 1.10 % of the height
//! (whole, head part cut, neck at 0 %) to 0.80 / 1.62 / 1.89 %.

use super::body::Body;
use super::humanoid::{Placed, along, get_joint};
use super::limbs::Sided;

/// Above this many times the knees' height over the floor, hips found by
/// the motion are taken for a clothing edge.
pub const HIP_OVER_KNEE: f64 = 1.1;

/// Replaces the hips in `found` (`l_hip`, `r_hip`) by their placement by
/// proportion along the legs when the motion found both higher above the
/// knees than [`HIP_OVER_KNEE`] allows, and says so in `notes`.
pub fn bound_hips(
    body: &Body,
    sided: &Sided,
    found: &mut [(String, Placed)],
    notes: &mut Vec<String>,
) {
    let [lh, rh, lk, rk] = ["l_hip", "r_hip", "l_knee", "r_knee"].map(|n| get_joint(found, n));
    if !(lh.by_motion && rh.by_motion) {
        return;
    }
    let over_floor = |p: Placed| p.position.dot(body.up) - body.lo;
    let knees = 0.5 * (over_floor(lk) + over_floor(rk));
    let hips = 0.5 * (over_floor(lh) + over_floor(rh));
    if knees <= 0.0 {
        return;
    }
    let ratio = (hips - knees) / knees;
    if !ratio.is_finite() || ratio <= HIP_OVER_KNEE {
        return;
    }
    for (side, (tip, path, _)) in ["l", "r"].iter().zip(&sided.legs) {
        let name = format!("{side}_hip");
        let d = super::limbs::leg_distances(body, *tip)[2];
        if let Some((_, p)) = found.iter_mut().find(|(n, _)| *n == name) {
            *p = Placed {
                position: along(body.rest, path, d * body.height),
                by_motion: false,
                articulation_deg: 0.0,
            };
        }
    }
    notes.push(format!(
        "hips: the motion found them {ratio:.2} times the knees' height above the knees (a body's: about 0.86, at most {HIP_OVER_KNEE}): a clothing edge moving with the thighs (a skirt's waistband?); placed by proportion"
    ));
}
