//! Two checks of a limb's joints against the motion, after the parts are
//! found (session 33):
//!
//! - [`split_knee`]: a leg's knee matched at a part boundary that is no
//!   joint. Under [`super::decompose::MergeRule::Settle`] samba's left
//!   shin was cut at mid-shin in 9 of 20 draws (session 32, `autorig_eval
//!   … spread 10 renumbered`) and the knee landed on the cut, 4.9-5.5 % of
//!   the height low. The debug log of salt 1 shows the part below the cut
//!   to be the foot with the lower shin (the ankle inside it, the
//!   boundary bending 33°: the foot's motion against the shin's), the part
//!   above the upper shin, then the knee at the next boundary. Each part
//!   beside the matched boundary is split in two by its vertices' motion
//!   (Dem Bones' bone insertion, Le & Deng 2014, Sec. 4.1, made local: a
//!   2-means on the two halves' rigid motions, as
//!   [`super::decompose::MergeRule::SettleSplit`] splits a part, here only
//!   along the limb); when the half next to the boundary moves with the
//!   part across it (bending less than [`MIN_BEND_DEG`]) while the two
//!   halves bend at least that much, the boundary lies inside one bone.
//!   Not the default ([`super::options::AutoOptions::split_knee`]): on
//!   salt 1 the halves bend 11.5° (below) and 13.9° (above) but the half
//!   next to the cut bends 29.3° and 23.9° against the other part's
//!   whole motion (which mixes the foot, or the hem, in), so no knee
//!   moved in 20 draws. The next step compares the halves next to the
//!   cut with each other.
//! - [`guard_pivot`]: a joint's fixed point (Le & Deng 2014, Sec. 5) is
//!   loose when the joint barely bends; one of crane's (the "shoulder" of
//!   `merge=settle,salt=3`, bending 6°) lay 23 cm across the body. A fixed
//!   point farther than [`LOOSE`] of the height from its own limb's path
//!   is replaced by the centre of the two parts' boundary, which lies on
//!   the limb.

use super::body::{Body, MIN_BEND_DEG};
use super::decompose::{PartMotion, kabsch};
use super::humanoid::{Crossing, boundary_centre, geodesic};
use super::joints::{PartJoint, joint_between};
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
fn motion_of(rest: &[[f64; 3]], frames: &[&[[f64; 3]]], idx: &[u32]) -> PartMotion {
    let (r, t) = frames.iter().map(|f| kabsch(rest, f, idx)).unzip();
    PartMotion { r, t }
}

/// Squared error of rest vertex `v` under `m`, summed over `frames`.
fn err(rest: &[[f64; 3]], frames: &[&[[f64; 3]]], m: &PartMotion, v: u32) -> f64 {
    let p = v3(rest[v as usize]);
    frames
        .iter()
        .enumerate()
        .map(|(f, x)| (m.apply(f, p) - v3(x[v as usize])).length_squared())
        .sum()
}

/// A part's vertices within `reach` of a limb's tip along the surface
/// (`d`: each vertex's distance from the tip) split in two by a 2-means on
/// the halves' rigid motions over the fitted frames, started from its
/// nearer and farther halves by `d`. Returns the halves' motions (nearer
/// first) and each vertex's half (0: not in the part; 1: the nearer; 2:
/// the farther); `None` when a half would be smaller than the least part.
fn split_part(
    body: &Body,
    d: &[f64],
    part: u32,
    reach: f64,
) -> Option<(PartMotion, PartMotion, Vec<u8>)> {
    let (rest, frames, dec) = (body.rest, body.frames, &body.dec);
    let n = rest.len();
    let mut idx: Vec<u32> = (0..n as u32)
        .filter(|&v| dec.labels[v as usize] == part && d[v as usize] <= reach)
        .collect();
    let min_size = (n / 400).max(8);
    if idx.len() < 2 * min_size || frames.is_empty() {
        return None;
    }
    idx.sort_by(|&a, &b| d[a as usize].total_cmp(&d[b as usize]).then(a.cmp(&b)));
    let mut near: Vec<bool> = (0..idx.len()).map(|i| i < idx.len() / 2).collect();
    let halves = |near: &[bool]| -> (Vec<u32>, Vec<u32>) {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        for (&v, &is) in idx.iter().zip(near) {
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
        let new: Vec<bool> = idx
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
    let mut half = vec![0u8; n];
    for (&v, &is) in idx.iter().zip(&near) {
        half[v as usize] = if is { 1 } else { 2 };
    }
    Some((
        motion_of(rest, frames, &a),
        motion_of(rest, frames, &b),
        half,
    ))
}

/// What [`split_knee`] finds of a matched knee.
#[derive(Debug, Clone, Copy)]
pub(crate) enum KneeCheck {
    /// The crossing is a joint as far as the motion shows.
    Joint,
    /// The part below the crossing straddles a joint (samba's foot and
    /// lower shin in one part, the ankle inside it): its farther half
    /// moves with the part above, so the crossing lies inside one bone
    /// and the knee is a later crossing.
    InsideBelow,
    /// The part above straddles the knee: the knee is where its halves
    /// meet.
    Above(Crossing),
}

/// Whether the crossing `knee` matched on the leg from `tip` (its `path`,
/// tip first) is the knee the motion shows. The part below it
/// (`knee.distal`) and then the part above (`knee.proximal`), each within
/// `reach` of the tip along the surface, is split in two by its
/// vertices' motion ([`split_part`]). When the part below's farther half
/// moves with the part above (they bend less than [`MIN_BEND_DEG`]
/// against each other) while its halves bend at least that much, the
/// crossing is inside one bone ([`KneeCheck::InsideBelow`]). When the part
/// above's nearer half moves with the part below and its halves bend,
/// the knee is where the path first enters the farther half, at the
/// centre of the halves' boundary (the ring, as the knee is placed)
/// ([`KneeCheck::Above`]). O(rounds · parts · frames) and one geodesic
/// from the tip.
pub(crate) fn split_knee(
    body: &Body,
    tip: u32,
    path: &[(u32, f64)],
    knee: &Crossing,
    reach: f64,
) -> KneeCheck {
    let (rest, dec, nb) = (body.rest, &body.dec, body.nb);
    let (d, _) = geodesic(rest, nb, &[tip]);
    let bend = |a: &PartMotion, b: &PartMotion, c: DVec3| joint_between(a, b, c, 0.05);
    let at = knee.joint.position;
    if let Some((ma, mb, _)) = split_part(body, &d, knee.distal, reach) {
        let (inside, across) = (
            bend(&ma, &mb, at),
            bend(&mb, &dec.motions[knee.proximal as usize], at),
        );
        tracing::debug!(
            "automatic rig, knee {}>{} at {:.3} from the tip (bends {:.1}°): the part below split, its halves bend {:.1}°, its farther half {:.1}° against the part above",
            knee.distal,
            knee.proximal,
            knee.from_tip,
            knee.joint.articulation_deg,
            inside.articulation_deg,
            across.articulation_deg
        );
        if across.articulation_deg < MIN_BEND_DEG && inside.articulation_deg >= MIN_BEND_DEG {
            return KneeCheck::InsideBelow;
        }
    }
    let Some((ma, mb, half)) = split_part(body, &d, knee.proximal, reach) else {
        return KneeCheck::Joint;
    };
    let ring: Vec<u32> = (0..rest.len() as u32)
        .filter(|&v| half[v as usize] == 1 && nb[v as usize].iter().any(|&u| half[u as usize] == 2))
        .collect();
    if ring.is_empty() {
        return KneeCheck::Joint;
    }
    let centre = ring.iter().map(|&v| v3(rest[v as usize])).sum::<DVec3>() / ring.len() as f64;
    let below = bend(&dec.motions[knee.distal as usize], &ma, at);
    let inside = bend(&ma, &mb, centre);
    let Some(from_tip) = path.iter().find(|x| half[x.0 as usize] == 2).map(|x| x.1) else {
        return KneeCheck::Joint;
    };
    tracing::debug!(
        "automatic rig, knee {}>{} at {:.3} from the tip: the part above split, its nearer half bends {:.1}° against the part below, its halves {:.1}° at {from_tip:.3} from the tip",
        knee.distal,
        knee.proximal,
        knee.from_tip,
        below.articulation_deg,
        inside.articulation_deg,
    );
    if below.articulation_deg < MIN_BEND_DEG
        && inside.articulation_deg >= MIN_BEND_DEG
        && from_tip > knee.from_tip
    {
        return KneeCheck::Above(Crossing {
            distal: knee.distal,
            proximal: knee.proximal,
            from_tip,
            joint: PartJoint {
                position: centre,
                articulation_deg: inside.articulation_deg,
                mismatch: inside.mismatch,
            },
        });
    }
    KneeCheck::Joint
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
