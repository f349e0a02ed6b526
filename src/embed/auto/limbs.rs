//! The body's five chains (two legs, two arms, the head) read off the
//! rigid parts: each limb's path from its tip to the trunk, the part
//! boundaries it crosses, and which of them are its joints; then facing
//! and the sides.

use super::body::{Body, MIN_BEND_DEG};
use super::humanoid::{self, Crossing, along, crossings, geodesic, match_joints};
use super::options::{AutoError, Facing};
use super::sides::{TrunkFrames, first_is_left};
use super::straddle::KneeCheck;
use glam::DVec3;

/// A limb: its tip, its path to the trunk (vertex, distance from the
/// tip), and its three joints where the motion showed them.
pub type Limb = (u32, Vec<(u32, f64)>, Vec<Option<Crossing>>);

/// Expected distances from the tip (fractions of the height) of a leg's
/// ankle, knee and hip, and of an arm's wrist, elbow and shoulder, along
/// the surface.
pub(crate) const LEG: [f64; 3] = [0.12, 0.37, 0.6];
/// See [`LEG`].
pub(crate) const ARM: [f64; 3] = [0.10, 0.25, 0.42];
/// The five chains' tips and the trunk they meet in.
pub struct Chains {
    /// The feet (the two lowest tips).
    pub feet: [u32; 2],
    /// The top of the head (the highest tip; [`Chains::head_nearest_axis`]
    /// and [`Chains::headed_by`] may choose another).
    pub head: u32,
    /// The hands (the other two).
    pub hands: [u32; 2],
    /// Each vertex's predecessor towards the trunk seed.
    prev: Vec<u32>,
    /// The trunk's parts.
    trunk: Vec<bool>,
    /// The trunk's patch: the vertices within [`super::sides::CORE`] of
    /// the height of the trunk's seed along the surface.
    core: Vec<u32>,
}

impl Chains {
    /// The five chains of `body` from its five extremities `tips`.
    pub fn find(body: &Body, tips: &[(u32, f64)]) -> Chains {
        let (rest, up, n) = (body.rest, body.up, body.rest.len());
        let hs = |q: [f64; 3]| DVec3::from_array(q).dot(up);
        // The five chains: feet the two lowest tips, head the highest other.
        let mut five: Vec<u32> = tips[..5].iter().map(|t| t.0).collect();
        five.sort_by(|&a, &b| hs(rest[a as usize]).total_cmp(&hs(rest[b as usize])));
        // Paths from each tip to a seed in the trunk: the vertex nearest the
        // body's axis at 65 % of its height (the belly or the back).
        let axis_at = body.centre + up * (body.lo + 0.65 * body.height - body.centre.dot(up));
        let trunk_seed = (0..n)
            .min_by(|&a, &b| {
                let d = |v: usize| {
                    let q = DVec3::from_array(rest[v]) - axis_at;
                    (q - up * q.dot(up)).length_squared() + 4.0 * q.dot(up).powi(2)
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap_or(0) as u32;
        let (from_seed, prev) = geodesic(rest, body.nb, &[trunk_seed]);
        let core = (0..n as u32)
            .filter(|&v| from_seed[v as usize] <= super::sides::CORE * body.height)
            .collect();
        // The trunk's parts: those on the paths of two limbs or more, and the
        // seed's (`rig::structure` reads the trunk of a joint tree the same
        // way: where the branches meet).
        let dec = &body.dec;
        let mut reached = vec![0usize; dec.count];
        for &tip in &five {
            let mut on: Vec<u32> = humanoid::path_to_source(rest, &prev, tip)
                .iter()
                .map(|x| dec.labels[x.0 as usize])
                .collect();
            on.sort_unstable();
            on.dedup();
            for l in on {
                reached[l as usize] += 1;
            }
        }
        let mut trunk: Vec<bool> = reached.iter().map(|&r| r >= 2).collect();
        trunk[dec.labels[trunk_seed as usize] as usize] = true;
        Chains {
            feet: [five[0], five[1]],
            head: five[4],
            hands: [five[2], five[3]],
            prev,
            trunk,
            core,
        }
    }

    /// The head's chain from `top` (a headless body's stump,
    /// [`super::neck::headless_top`]), not the highest tip: a hand held as
    /// high as the stump stays a hand. `top` must be one of the tips.
    pub fn headed_by(&mut self, top: u32) {
        for h in &mut self.hands {
            if *h == top {
                *h = self.head;
                self.head = top;
            }
        }
    }

    /// The head's chain from the hand tip nearest the body's axis (the
    /// vertical through the vertices' centroid) when the highest tip lies
    /// farther from it than [`super::neck::TOP_AXIS`] of the height and
    /// that hand tip within it ([`super::options::AutoOptions::head_axis`],
    /// the default since session 39). The body's axis holds its head and
    /// its neck's stump in any pose; the highest tip is a hand when the
    /// hands are held as high (the SMPL template's T-pose cut at the neck
    /// joint: the left hand 0.05 mm above the stump, 45 % of the height
    /// off the axis, was rigged as the head).
    pub fn head_nearest_axis(&mut self, body: &Body) {
        let (rest, up) = (body.rest, body.up);
        let flat = |v: u32| {
            let q = DVec3::from_array(rest[v as usize]) - body.centre;
            (q - up * q.dot(up)).length()
        };
        let limit = super::neck::TOP_AXIS * body.height;
        if flat(self.head) <= limit {
            return;
        }
        let near = (0..2)
            .filter(|&k| flat(self.hands[k]) <= limit)
            .min_by(|&a, &b| flat(self.hands[a]).total_cmp(&flat(self.hands[b])));
        if let Some(k) = near {
            std::mem::swap(&mut self.head, &mut self.hands[k]);
        }
    }

    /// The limb from `tip` to the trunk, its joints matched to the
    /// expected distances `exp` within `tol` of the height.
    /// With `ring_knee` (legs), the middle joint is placed at the centre
    /// of the boundary ring of its two parts.
    pub fn limb(&self, body: &Body, tip: u32, exp: &[f64; 3], tol: f64, ring_knee: bool) -> Limb {
        let (rest, height) = (body.rest, body.height);
        let p = humanoid::path_to_source(rest, &self.prev, tip);
        let mut c = crossings(rest, body.nb, &body.dec, &p, 0.05);
        if body.guard_pivots {
            for x in &mut c {
                super::straddle::guard_pivot(body, &p, x);
            }
        }
        debug_chain("limb", body, &c, height);
        // Up to the limb's entry into the trunk.
        let end = c
            .iter()
            .position(|x| self.trunk[x.proximal as usize])
            .map_or(c.len(), |i| i + 1);
        let c = &c[..end];
        let entry = (end > 0 && self.trunk[c[end - 1].proximal as usize]).then(|| c[end - 1]);
        // Legs: the hip matched as the knee is, the end of the thigh's
        // rigid part (the first crossing after the knee that bends, near
        // the hip's distance); the limb's entry into the trunk only when
        // none is. Crane's left leg enters the trunk at its sweater's
        // hem, 0.71 of the height from the toe (y 1.06 m, 58 % of the
        // height) past the thigh's end at 0.59 (y 0.91 m): the groin
        // placed from that hip sat 15 cm above the landmark rig's, the
        // pelvis 8 % of the height off (`autorig_eval real`, rest frame 0,
        // frames by pose). An option (`AutoOptions::thigh_hip`): with it
        // (rest frame by `PoseRule::Held`) crane's pelvis was still 5.0 %
        // off.
        let matched = if ring_knee && body.thigh_hip { 3 } else { 2 };
        let mut m = match_joints(c, &exp[..matched], height, MIN_BEND_DEG, tol);
        let hip = m.get(2).copied().flatten();
        m.truncate(2);
        // A knee at the ring where the shin's rigid part ends: the fixed
        // point of the shin's motion and the part above is the knee only
        // when that part is the thigh; under a skirt it is a band of cloth
        // and the point fell 4-8 cm off the leg. The embedding centres the
        // landmark in the leg's cross-section. Not the elbow: samba's
        // forearm ring lies as high as its fixed point or 2.5 cm higher
        // (the forearm's rigid part reaches over the olecranon).
        //
        // A knee matched at a boundary that is no joint
        // ([`super::straddle::split_knee`]): when the part above it
        // straddles the knee, the knee is where that part's two motions
        // meet (the ring there is the split's); when the boundary lies
        // inside one bone (samba under `merge=settle`: the foot and the
        // lower shin in one part, the shin cut at mid-shin), the knee is
        // the next boundary that bends near the knee's distance, or placed
        // by proportion.
        if ring_knee && let Some(k) = m[1] {
            let check = match body.split_knee {
                true => super::straddle::split_knee(body, tip, &p, &k, exp[2] * height),
                false => KneeCheck::Joint,
            };
            let near = |x: &Crossing| (x.from_tip - exp[1] * height).abs() <= tol * height;
            m[1] = match check {
                KneeCheck::Above(s) if near(&s) => Some(s),
                // The next boundary that bends near the knee's distance.
                KneeCheck::InsideBelow => c
                    .iter()
                    .find(|x| {
                        x.from_tip > k.from_tip
                            && x.joint.articulation_deg >= MIN_BEND_DEG
                            && near(x)
                    })
                    .copied(),
                _ => Some(k),
            };
            if let Some(k) = m[1].as_mut()
                && !matches!(check, KneeCheck::Above(s) if near(&s))
                && let Some(c) =
                    humanoid::boundary_centre(rest, body.nb, &body.dec.labels, k.distal, k.proximal)
            {
                k.joint.position = c;
            }
        }
        let used = m
            .iter()
            .flatten()
            .any(|x| Some(x.from_tip) == entry.map(|e| e.from_tip));
        let root = hip.or_else(|| {
            entry.filter(|e| {
                !used
                    && (e.from_tip - exp[2] * height).abs() <= 0.15 * height
                    && m.iter().flatten().all(|x| x.from_tip < e.from_tip)
            })
        });
        m.push(root);
        (tip, p, m)
    }
}

/// The limbs sided, and the body's facing and left.
pub struct Sided {
    /// Left leg, right leg.
    pub legs: Vec<Limb>,
    /// Left arm, right arm.
    pub arms: Vec<Limb>,
    /// Facing (unit).
    pub facing: DVec3,
    /// The character's left (unit).
    pub left: DVec3,
    /// The legs' and the arms' lateral offsets from the mid-plane, left
    /// limb first ([`super::sides::TrunkFrames::lateral`]; length units,
    /// positive to the left).
    pub lateral: [[f64; 2]; 2],
}

/// A leg's expected joint distances from its tip ([`LEG`]); from the cut,
/// the foot's [`LEG`]`[0]` taken off, when the tip is on one.
pub(crate) fn leg_distances(body: &Body, tip: u32) -> [f64; 3] {
    match body.cut_at(tip) {
        Some(_) => LEG.map(|d| d - LEG[0]),
        None => LEG,
    }
}

/// A leg's knee: found, or by proportion along the leg.
pub fn knee(body: &Body, l: &Limb) -> DVec3 {
    l.2[1]
        .map(|c| c.joint.position)
        .unwrap_or_else(|| along(body.rest, &l.1, leg_distances(body, l.0)[1] * body.height))
}

/// Where the feet point (horizontal, not unit; the facing's sign): the
/// toe tips' directions from the knees, summed. A leg cut above the foot
/// has no toes (its tip, the cut, lies under or behind the knee): its
/// knee's bend over the frames says where the back is
/// ([`super::facing::knee_folds_towards`]), when its knee was found by
/// the motion.
fn toes_point_to(body: &Body, legs: &[Limb]) -> DVec3 {
    let up = body.up;
    let flat = |d: DVec3| d - up * d.dot(up);
    let mut toes = DVec3::ZERO;
    for l in legs {
        let tip = DVec3::from_array(body.rest[l.0 as usize]);
        let Some(cut) = body.cut_at(l.0) else {
            toes += flat(tip - knee(body, l)).normalize_or_zero();
            continue;
        };
        if let Some(k) = l.2[1] {
            let m = &body.dec.motions;
            let (shin, thigh) = (&m[k.distal as usize], &m[k.proximal as usize]);
            toes -= super::facing::knee_folds_towards(shin, thigh, cut, up).normalize_or_zero();
        }
    }
    toes
}

/// The limbs of `chains`, sided; facing square to the chest's widest
/// horizontal axis ([`super::facing::widest_across`], with
/// [`Facing::Trunk`] when the chest is clearly wider than deep) or to the
/// line through the hips (or knees), on the side the toe tips point to
/// from the knees; the left limb of each pair is the one whose path lies
/// more to the left of the mid-plane over the frames ([`super::sides`]).
pub fn side(body: &Body, chains: &Chains) -> Result<Sided, AutoError> {
    let (rest, up, height) = (body.rest, body.up, body.height);
    // A leg cut above the foot ([`super::cut_ends`]) matched from the
    // cut: the foot's length taken off every expected distance.
    let leg = |tip: u32| chains.limb(body, tip, &leg_distances(body, tip), 0.1, true);
    let mut legs = vec![leg(chains.feet[0]), leg(chains.feet[1])];
    let flat = |d: DVec3| d - up * d.dot(up);
    let hips_found = legs.iter().all(|l| l.2[2].is_some());
    let side_point = |l: &Limb| match l.2[2] {
        Some(c) if hips_found => c.joint.position,
        _ => knee(body, l),
    };
    let hips = flat(side_point(&legs[0]) - side_point(&legs[1]));
    let chest = match body.facing {
        Facing::Trunk => super::facing::widest_across(rest, up, body.lo, height)
            .filter(|(_, ratio)| *ratio >= super::facing::MIN_RATIO),
        Facing::Hips => None,
    };
    debug_across(hips, chest);
    let across = chest.map_or(hips, |(a, _)| a);
    let toes = toes_point_to(body, &legs);
    let square = up.cross(across).normalize_or_zero();
    let facing = if square == DVec3::ZERO {
        toes.normalize_or_zero()
    } else if square.dot(toes) >= 0.0 {
        square
    } else {
        -square
    };
    if facing == DVec3::ZERO {
        return Err(AutoError::NotHumanoid(
            "the feet point nowhere: no facing".into(),
        ));
    }
    let left = up.cross(facing).normalize();
    // Sides: of each pair, the limb whose path lies more to the left of
    // the mid-plane over the frames, in the trunk's frame
    // ([`super::sides`]; the root's or knee's, elbow's position before).
    let trunk = TrunkFrames::new(rest, body.frames, &chains.core);
    let (first, mut leg_lat) =
        first_is_left(&trunk, left, [&legs[0].1, &legs[1].1], LEG[2] * height);
    if !first {
        legs.swap(0, 1);
        leg_lat.swap(0, 1);
    }
    // An arm cut at the wrist ([`super::cut_ends`]) matched from the cut:
    // the hand's length taken off every expected distance.
    let arm = |tip: u32| {
        let exp = match body.cut_at(tip) {
            Some(_) => ARM.map(|d| d - ARM[0]),
            None => ARM,
        };
        chains.limb(body, tip, &exp, 0.08, false)
    };
    let mut arms = vec![arm(chains.hands[0]), arm(chains.hands[1])];
    let (first, mut arm_lat) =
        first_is_left(&trunk, left, [&arms[0].1, &arms[1].1], ARM[2] * height);
    if !first {
        arms.swap(0, 1);
        arm_lat.swap(0, 1);
    }
    Ok(Sided {
        legs,
        arms,
        facing,
        left,
        lateral: [leg_lat, arm_lat],
    })
}

/// Logs the left-right axis read off the chest against the hips' line
/// (tracing, debug level).
fn debug_across(hips: DVec3, chest: Option<(DVec3, f64)>) {
    if !tracing::enabled!(tracing::Level::DEBUG) {
        return;
    }
    let angle = |a: DVec3| {
        let c = a.normalize_or_zero().dot(hips.normalize_or_zero()).abs();
        c.min(1.0).acos().to_degrees()
    };
    match chest {
        Some((a, ratio)) => tracing::debug!(
            "automatic rig, left-right: the chest's widest axis ({:.3}, {:.3}, {:.3}), {ratio:.1}× as wide as deep, {:.1}° from the hips' line",
            a.x,
            a.y,
            a.z,
            angle(a)
        ),
        None => tracing::debug!("automatic rig, left-right: the hips' line"),
    }
}

/// Logs a limb's crossings (tracing, debug level): the parts, where, how
/// much they bend, the fixed point's mismatch, the fixed point and the
/// boundary ring's centre.
fn debug_chain(what: &str, body: &Body, c: &[Crossing], h: f64) {
    if !tracing::enabled!(tracing::Level::DEBUG) {
        return;
    }
    let parts: Vec<String> = c
        .iter()
        .map(|c| {
            let ring =
                humanoid::boundary_centre(body.rest, body.nb, &body.dec.labels, c.distal, c.proximal)
                    .unwrap_or(DVec3::NAN);
            let q = c.joint.position;
            format!(
                "{}>{} at {:.2}h bends {:.0}° mis {:.1}% pivot ({:.3}, {:.3}, {:.3}) ring ({:.3}, {:.3}, {:.3})",
                c.distal,
                c.proximal,
                c.from_tip / h,
                c.joint.articulation_deg,
                100.0 * c.joint.mismatch / h,
                q.x,
                q.y,
                q.z,
                ring.x,
                ring.y,
                ring.z
            )
        })
        .collect();
    tracing::debug!("automatic rig, {what} from its tip: {}", parts.join("; "));
}

/// Each knee's distance to its toe tip, left against right: a body's
/// shins and feet have one length (whatever the pose, up to the ankle's
/// bend). Returns `(left, right, difference)` in the height's units.
pub(crate) fn knee_to_toe(body: &Body, sided: &Sided) -> (f64, f64, f64) {
    let h = |l: &Limb| knee(body, l).distance(DVec3::from_array(body.rest[l.0 as usize]));
    let (l, r) = (h(&sided.legs[0]), h(&sided.legs[1]));
    (l, r, (l - r).abs())
}
