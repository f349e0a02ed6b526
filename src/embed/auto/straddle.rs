//! Two checks of a limb's joints against the motion, after the parts are
//! found (session 33):
//!
//! - [`split_knee`]: a leg's knee matched at a part boundary that is no
//!   joint. Under [`super::decompose::MergeRule::Settle`] samba's left
//!   shin was cut at mid-shin in 9 of 20 draws (session 32, `autorig_eval
//!   … spread 10 renumbered`): its upper half settled in one part with
//!   the skirt's hem, the part straddled the knee, and the knee landed on
//!   the cut, 4.9-5.5 % of the height low. The part above the matched
//!   boundary is split in two by its vertices' motion (Dem Bones' bone
//!   insertion, Le & Deng 2014, Sec. 4.1, made local: a 2-means on the
//!   two halves' rigid motions, as
//!   [`super::decompose::MergeRule::SettleSplit`] splits a part, here only
//!   along the limb); when its lower half moves with the part below (the
//!   boundary bends less than [`MIN_BEND_DEG`]) and its two halves bend
//!   at least that much against each other, the knee is where they meet.
//! - [`guard_pivot`]: a joint's fixed point (Le & Deng 2014, Sec. 5) is
//!   loose when the joint barely bends; one of crane's (the "shoulder" of
//!   `merge=settle,salt=3`, bending 6°) lay 23 cm across the body. A fixed
//!   point farther than [`LOOSE`] of the height from its own limb's path
//!   is replaced by the centre of the two parts' boundary, which lies on
//!   the limb.

use super::decompose::{Motion, kabsch};
use super::humanoid::{Crossing, boundary_centre, geodesic};
use super::joints::{PartJoint, joint_between};
use super::limbs::{Body, MIN_BEND_DEG};
use glam::DVec3;
use rayon::prelude::*;

/// A joint's fixed point lies within this fraction of the height of its
/// limb's path (the surface path from the tip to the trunk, up to the
/// crossing and this much further): 10 %, about twice a thigh's radius.
pub const LOOSE: f64 = 0.10;

/// The 2-means rounds of [`split_knee`] (it stops earlier when no vertex
/// changes half).
const SPLIT_ROUNDS: usize = 10;

fn v3(p: [f64; 3]) -> DVec3 {
    DVec3::from_array(p)
}

/// The rigid motion (Kabsch per frame) of the rest vertices `idx` over
/// `frames`.
fn motion_of(rest: &[[f64; 3]], frames: &[&[[f64; 3]]], idx: &[u32]) -> Motion {
    let (r, t) = frames.iter().map(|f| kabsch(rest, f, idx)).unzip();
    Motion { r, t }
}

/// Squared error of rest vertex `v` under `m`, summed over `frames`.
fn err(rest: &[[f64; 3]], frames: &[&[[f64; 3]]], m: &Motion, v: u32) -> f64 {
    let p = v3(rest[v as usize]);
    frames
        .iter()
        .enumerate()
        .map(|(f, x)| (m.apply(f, p) - v3(x[v as usize])).length_squared())
        .sum()
}

/// The knee of the leg from `tip` (its `path`, tip first) when the
/// crossing `knee` matched is no joint: the part above it (`knee.proximal`;
/// its vertices within `reach` of the tip along the surface) split in two
/// by a 2-means on the halves' rigid motions over the fitted frames,
/// started from its nearer and farther halves by distance from the tip.
/// `Some` only when the nearer half moves with the part below the crossing
/// (they bend less than [`MIN_BEND_DEG`] against each other) and the two
/// halves bend at least that much: the crossing then is where the path
/// first enters the farther half, the joint at the centre of the halves'
/// boundary (the ring, as the knee is placed), bending as the halves do.
/// `None` leaves the knee as matched. O(rounds · part · frames) and one
/// geodesic from the tip.
pub(crate) fn split_knee(
    body: &Body,
    tip: u32,
    path: &[(u32, f64)],
    knee: &Crossing,
    reach: f64,
) -> Option<Crossing> {
    let (rest, frames, dec, nb) = (body.rest, body.frames, &body.dec, body.nb);
    let n = rest.len();
    let (d, _) = geodesic(rest, nb, &[tip]);
    let mut part: Vec<u32> = (0..n as u32)
        .filter(|&v| dec.labels[v as usize] == knee.proximal && d[v as usize] <= reach)
        .collect();
    let min_size = (n / 400).max(8);
    if part.len() < 2 * min_size || frames.is_empty() {
        return None;
    }
    part.sort_by(|&a, &b| d[a as usize].total_cmp(&d[b as usize]).then(a.cmp(&b)));
    let mut near: Vec<bool> = (0..part.len()).map(|i| i < part.len() / 2).collect();
    let halves = |near: &[bool]| -> (Vec<u32>, Vec<u32>) {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for (&v, &is) in part.iter().zip(near) {
            if is { a.push(v) } else { b.push(v) }
        }
        (a, b)
    };
    for _ in 0..SPLIT_ROUNDS {
        let (a, b) = halves(&near);
        if a.len() < min_size || b.len() < min_size {
            return None;
        }
        let (ma, mb) = (motion_of(rest, frames, &a), motion_of(rest, frames, &b));
        let new: Vec<bool> = part
            .par_iter()
            .map(|&v| err(rest, frames, &ma, v) <= err(rest, frames, &mb, v))
            .collect();
        if new == near {
            break;
        }
        near = new;
    }
    let (a, b) = halves(&near);
    if a.len() < min_size || b.len() < min_size {
        return None;
    }
    let (ma, mb) = (motion_of(rest, frames, &a), motion_of(rest, frames, &b));
    // 0: not in the part; 1: the nearer half; 2: the farther.
    let mut half = vec![0u8; n];
    for (&v, &is) in part.iter().zip(&near) {
        half[v as usize] = if is { 1 } else { 2 };
    }
    let ring: Vec<u32> = a
        .iter()
        .copied()
        .filter(|&v| nb[v as usize].iter().any(|&u| half[u as usize] == 2))
        .collect();
    if ring.is_empty() {
        return None;
    }
    let centre = ring.iter().map(|&v| v3(rest[v as usize])).sum::<DVec3>() / ring.len() as f64;
    let below = joint_between(
        &dec.motions[knee.distal as usize],
        &ma,
        knee.joint.position,
        0.05,
    );
    let inside = joint_between(&ma, &mb, centre, 0.05);
    let from_tip = path.iter().find(|x| half[x.0 as usize] == 2).map(|x| x.1)?;
    tracing::debug!(
        "automatic rig, knee at {:.3} from the tip (bends {:.1}°): the part above split {}+{}, its nearer half bends {:.1}° against the part below, the halves {:.1}° at {:.3} from the tip",
        knee.from_tip,
        knee.joint.articulation_deg,
        a.len(),
        b.len(),
        below.articulation_deg,
        inside.articulation_deg,
        from_tip
    );
    let moved = below.articulation_deg < MIN_BEND_DEG
        && inside.articulation_deg >= MIN_BEND_DEG
        && from_tip > knee.from_tip;
    moved.then_some(Crossing {
        distal: knee.distal,
        proximal: knee.proximal,
        from_tip,
        joint: PartJoint {
            position: centre,
            articulation_deg: inside.articulation_deg,
            mismatch: inside.mismatch,
        },
    })
}

/// `c`'s fixed point replaced by the centre of its two parts' boundary
/// when it lies farther than [`LOOSE`] of the height from every vertex of
/// its limb's `path` (tip first) up to [`LOOSE`] past the crossing (and
/// the boundary's centre is nearer). Logged at debug level.
pub(crate) fn guard_pivot(body: &Body, path: &[(u32, f64)], c: &mut Crossing) {
    let limit = LOOSE * body.height;
    let off = |q: DVec3| {
        path.iter()
            .take_while(|x| x.1 <= c.from_tip + limit)
            .map(|x| v3(body.rest[x.0 as usize]).distance(q))
            .fold(f64::INFINITY, f64::min)
    };
    let far = off(c.joint.position);
    if far <= limit {
        return;
    }
    let Some(ring) = boundary_centre(body.rest, body.nb, &body.dec.labels, c.distal, c.proximal)
    else {
        return;
    };
    if off(ring) >= far {
        return;
    }
    tracing::debug!(
        "automatic rig, the joint {}>{} at {:.3} from the tip (bends {:.1}°): its fixed point {:.1}% of the height from the limb's path, the boundary's centre taken",
        c.distal,
        c.proximal,
        c.from_tip,
        c.joint.articulation_deg,
        100.0 * far / body.height
    );
    c.joint.position = ring;
}
