//! The feet: each foot placed on or above its ground, the soles the kernel
//! stands on the ground, toes bent up about the ball, and the reference's
//! foot bones set to the elevation the clip's feet have when flat.

use super::ground::{Support, grounds_either_side_into, interpolate_gaps_into};
use super::reference::leg_length;
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

use Canonical as C;

/// [`place_feet_into`] with fresh grounds, returned (the tests' form).
#[cfg(test)]
pub(super) fn place_feet(
    character: &Pose,
    support: &Support,
    s: f64,
    (toes, open_end): (Toes, bool),
    out: &mut [(Pose, [DQuat; Canonical::COUNT])],
    scratch: &mut FeetScratch,
) -> [Vec<Option<f64>>; 2] {
    let mut grounds = [Vec::new(), Vec::new()];
    place_feet_into(
        character,
        support,
        s,
        (toes, open_end),
        out,
        (scratch, &mut grounds),
    );
    grounds
}

/// Lifts (or lowers) every pose of `out` (the character's, before its
/// vertical correction) so that each foot stands on or above its ground,
/// and with [`Toes::Bending`] turns the toes up onto it; writes into
/// `grounds` (each cleared and refilled) each foot's ground per frame (raised above the character's floor by its
/// height above the clip's floor `support.floor`, scaled by `s`; `None`
/// where the foot has none). See [`retarget_toes`](super::retarget_toes).
///
/// A foot in the air between two supports is over the higher one's top
/// only when the character's own sole is above it, the body placed by the
/// feet on their grounds and the air feet over their lower ones; else it
/// is over the lower ground ([`Support::under`] decides by the clip's
/// joints, which sit above the character's sole: a toe tip pitched down
/// reaches 5 cm below them). So a foot in the air never lifts the body
/// onto a higher top: CMU 03_02's left foot, swinging up from the floor
/// beside the block the right foot stands on, passed the next block's top
/// (24 cm) by its joints in frame 8 while the character's toe tip was 5
/// cm lower, and stood on that top the whole body lifted 7.6 cm in one
/// frame (samba) while the clip's root rose 1.6 cm. On flat ground both
/// supports are the floor and nothing changes.
///
/// So does a foot touching a step it is arriving on or leaving, not at
/// rest on it ([`Support::rests`]), the step higher than the lower of the
/// supports the foot rests on before and after, while the other foot
/// stands on a support as high (the floor, or a step it rests on, within
/// the contact band of the step or above it): with a footfall's support the
/// height the foot holds at rest ([`clip_support`](super::clip_support)), the frames it comes
/// up onto a block in, its lowest joint within the contact band below
/// the top, touch the top, and the character's sole there is lower than
/// the clip's joints (a heel pitched down is 6 cm under the ankle): the
/// generated step up onto 20 cm at 30 fps lifted the body 2.7 cm in one
/// frame more than the clip's 1.7 cm. A foot that holds the body alone
/// (the other in the air) or above a lower support stays on the step it
/// touches: stepping down off a block (CMU 03_01 on samba, frame 90),
/// the rear foot on its toes on the block holds the body up while the
/// front one strikes the floor; counted in the air, its toes went 4 cm
/// into the block for that frame.
///
/// `scratch` holds its buffers (cleared before use): no allocation once
/// they and `grounds` hold the clip's frames (issue 45).
pub(super) fn place_feet_into(
    character: &Pose,
    support: &Support,
    s: f64,
    (toes, open_end): (Toes, bool),
    out: &mut [(Pose, [DQuat; Canonical::COUNT])],
    (scratch, grounds): (&mut FeetScratch, &mut [Vec<Option<f64>>; 2]),
) {
    let FeetScratch {
        soles,
        settled,
        settled_sides,
        touch,
        sides,
        fix,
        known,
        lift,
    } = scratch;
    let clip_floor = support.floor;
    let rest_soles = foot_soles(character, character, &[DQuat::IDENTITY; Canonical::COUNT]);
    soles.clear();
    soles.extend(out.iter().map(|(t, g)| soles_of(character, t, g, toes)));
    let soles = &*soles;
    // How far frame `i` must be lifted for foot `f` to stand on ground
    // `y` (the clip's height).
    let need = |f: usize, i: usize, y: f64| rest_soles[f] + (y - clip_floor) * s - soles[i][f];
    let n = out.len();
    // The supports each foot is settled on: the floor, or a step while
    // the foot rests on it.
    for (f, settled) in settled.iter_mut().enumerate() {
        settled.clear();
        settled.extend(
            (0..n).map(|i| support.touch[f][i].filter(|&u| u <= clip_floor || support.rests[f][i])),
        );
    }
    for (t, sides) in settled.iter().zip(settled_sides.iter_mut()) {
        grounds_either_side_into(t, sides);
        landing_open(sides, clip_floor, open_end);
    }
    // A foot touching a step it is arriving on or leaving (not at rest on
    // it, and the step above the lower of the supports it settles on
    // before and after) while the other foot is settled on a support as
    // high (within the contact band) counts as in the air: the step is its
    // ground only once its sole is above the top.
    for (f, touch) in touch.iter_mut().enumerate() {
        touch.clear();
        touch.extend((0..n).map(|i| {
            let t = support.touch[f][i];
            let (Some(u), None) = (t, settled[f][i]) else {
                return t;
            };
            let lo = match settled_sides[f][i] {
                (Some(a), Some(b)) => a.min(b),
                (a, b) => a.or(b).unwrap_or(u),
            };
            if u > lo && settled[1 - f][i].is_some_and(|o| o >= u - support.band) {
                None
            } else {
                t
            }
        }));
    }
    for (t, sides) in touch.iter().zip(sides.iter_mut()) {
        grounds_either_side_into(t, sides);
        landing_open(sides, clip_floor, open_end);
    }
    let (touch, sides) = (&*touch, &*sides);
    // A foot's ground when touching; in the air, the lower of the
    // supports it left and lands on.
    let lower = |f: usize, i: usize| -> Option<f64> {
        touch[f][i].or(match sides[f][i] {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        })
    };
    fix.clear();
    fix.extend((0..out.len()).map(|i| {
        if touch.iter().all(|f| f[i].is_none()) {
            return None;
        }
        (0..2)
            .filter_map(|f| Some(need(f, i, lower(f, i)?)))
            .filter(|d| d.is_finite())
            .reduce(f64::max)
    }));
    interpolate_gaps_into(fix, known, lift);
    // A foot leaving a support for a lower one (stepping down off a
    // block) held the body up to the frame it left; from then until it
    // lands the lift comes down to the landing frame's at an even rate,
    // never below what the feet need: its ground switching to the floor
    // dropped the body in one frame while the clip's came down a few
    // millimetres (CMU 03_01 on samba, frame 89: 3.8 cm; synth3 03_02,
    // frame 39: 9.2 cm). Only raises the body, so no foot goes under its
    // ground.
    //
    // At a stream's open end ([`Given::open_end`](super::Given::open_end))
    // a foot that left a step above the floor and has not landed in the
    // window has no landing to ramp to: the body is carried from the last
    // frame the step held it and comes down no faster than the clip's
    // pelvis falls fastest in the window ([`carry_down`]), so a later
    // window's landing and ramp do not find the frames already shown
    // dropped onto the floor under them (CMU 03_01 on samba at lag 3,
    // frame 40: 8 cm below offline where the leading foot left the block).
    let open = open_end.then(|| (clip_floor, fall_rate(out)));
    ramp_step_downs(lift, touch, support.band, open);
    // The higher top under a foot in the air where the clip's joints are
    // above it and the character's sole, lifted, is too.
    for (f, g) in grounds.iter_mut().enumerate() {
        g.clear();
        g.extend((0..out.len()).map(|i| {
            let lo = lower(f, i)?;
            match support.under[f][i] {
                Some(u) if u > lo && need(f, i, u) <= lift[i] + 1e-9 => Some(u),
                _ => Some(lo),
            }
        }));
    }
    if toes == Toes::Bending {
        for (i, (t, g)) in out.iter_mut().enumerate() {
            let d = lift[i];
            for (f, sole) in rest_soles.iter().enumerate() {
                let Some(u) = grounds[f][i] else {
                    continue;
                };
                let ground = sole + (u - clip_floor) * s - d;
                bend_toes(character, t, g, f, ground);
            }
        }
    }
    for ((t, _), d) in out.iter_mut().zip(lift.iter()) {
        for p in t.iter_mut() {
            p.y += d;
        }
    }
    for y in grounds.iter_mut().flatten() {
        *y = y.map(|y| (y - clip_floor) * s);
    }
}

/// The buffers [`place_feet_into`] reuses from one clip to the next (cleared
/// before use).
#[derive(Debug, Clone, Default)]
pub struct FeetScratch {
    /// Each frame's lowest sole point per foot.
    soles: Vec<[f64; 2]>,
    /// Per foot and frame, the support it is settled on, and the last and
    /// next such.
    settled: [Vec<Option<f64>>; 2],
    settled_sides: [Vec<(Option<f64>, Option<f64>)>; 2],
    /// Per foot and frame, the support it touches as placed, and the last
    /// and next such.
    touch: [Vec<Option<f64>>; 2],
    sides: [Vec<(Option<f64>, Option<f64>)>; 2],
    /// Per frame, the lift the feet need (none in the air), the known
    /// ones, and the lift with the gaps filled.
    fix: Vec<Option<f64>>,
    known: Vec<(usize, f64)>,
    lift: Vec<f64>,
}

/// The step-down ramps of [`place_feet_into`] (its comment above the call
/// says why): for each foot that leaves a support for a lower one, `lift`
/// comes down to the landing frame's at an even rate, never below what it
/// was; with `open` (`(clip floor, fall rate)`, a stream's open end), a
/// foot that left a step above the floor and has not landed is carried
/// down at most `fall` a frame ([`carry_down`]).
fn ramp_step_downs(
    lift: &mut [f64],
    touch: &[Vec<Option<f64>>; 2],
    band: f64,
    open: Option<(f64, f64)>,
) {
    let n = lift.len();
    for t in touch {
        let mut i = 1;
        while i < n {
            if let (Some(u), None) = (t[i - 1], t[i]) {
                match (i..n).find(|&j| t[j].is_some()) {
                    Some(j) => {
                        if t[j].is_some_and(|v| v < u - band) {
                            let (a, b) = (lift[i - 1], lift[j]);
                            for (k, l) in lift.iter_mut().enumerate().take(j).skip(i) {
                                let w = (k + 1 - i) as f64 / (j + 1 - i) as f64;
                                *l = l.max(a + (b - a) * w);
                            }
                        }
                        i = j;
                        continue;
                    }
                    None => {
                        if let Some((floor, fall)) = open
                            && u > floor + band
                        {
                            carry_down(&mut lift[i - 1..], fall);
                            break;
                        }
                    }
                }
            }
            i += 1;
        }
    }
}

/// The fastest the body falls in `out` (the character's poses before the
/// feet's lift): the largest drop of the pelvis from one frame to the
/// next, metres a frame (0 for fewer than two frames or a pelvis that
/// never drops). A bound the clip's own motion shows the body can reach,
/// for [`carry_down`].
fn fall_rate(out: &[(Pose, [DQuat; Canonical::COUNT])]) -> f64 {
    let p = C::Pelvis.index();
    out.windows(2)
        .map(|w| w[0].0[p].y - w[1].0[p].y)
        .filter(|d| d.is_finite())
        .fold(0.0, f64::max)
}

/// Raises `lift[k]` (k ≥ 1) to at least `lift[0] - fall * k`: the body
/// held by `lift[0]` (the last frame a support held it) comes down by at
/// most `fall` a frame. Only raises, so no foot goes under its ground.
fn carry_down(lift: &mut [f64], fall: f64) {
    let Some(&a) = lift.first() else {
        return;
    };
    for (k, l) in lift.iter_mut().enumerate().skip(1) {
        *l = l.max(a - fall * k as f64);
    }
}

/// Sets in a foot's last and next support per frame (`sides`,
/// [`grounds_either_side_into`]'s), when the clip's end is `open` (a
/// stream's newest frame, [`Given::open_end`](super::Given::open_end)),
/// `floor` for the next one of a foot that has left its last support and
/// not landed in the clip: the lowest it can land on.
fn landing_open(sides: &mut [(Option<f64>, Option<f64>)], floor: f64, open: bool) {
    if open {
        for s in sides.iter_mut().rev() {
            match s {
                (Some(_), None) => s.1 = Some(floor),
                _ => break,
            }
        }
    }
}

/// The lowest sole point of the character posed as `t` with global
/// rotations `g`: its toe joints; under each ankle a heel point at the
/// height of the toe in the rest pose `character`; and a toe tip a quarter of the
/// foot's horizontal length beyond the toe joint at its height (a foot
/// pivoting on its toes dips the tips); both carried by the ankle.
pub(super) fn sole_height(character: &Pose, t: &Pose, g: &[DQuat; Canonical::COUNT]) -> f64 {
    let [l, r] = foot_soles(character, t, g);
    l.min(r)
}

/// The lowest sole point of each foot (left, right) of the character
/// posed as `t` with global rotations `g` (see [`sole_height`]).
pub(super) fn foot_soles(character: &Pose, t: &Pose, g: &[DQuat; Canonical::COUNT]) -> [f64; 2] {
    soles_of(character, t, g, Toes::Rigid)
}

/// The ankle and toe joints of each foot (left, right).
pub(super) const FEET: [(C, C); 2] = [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)];

/// The sole's toe tip of a foot of `character` in its rest pose, from its
/// toe joint: a quarter of the foot's horizontal length (ankle → toe
/// joint) beyond it, at its height.
pub(super) fn toe_tip(character: &Pose, foot: usize) -> DVec3 {
    let (a, k) = FEET[foot];
    let f = character[k.index()] - character[a.index()];
    DVec3::new(0.25 * f.x, 0.0, 0.25 * f.z)
}

/// The lowest sole point of each foot (left, right) of the character
/// posed as `t` with global rotations `g`, its toes moving as `toes`
/// says: the toe joint, a heel point under the ankle at the rest pose's
/// toe height, and for rigid toes the toe tip ([`toe_tip`]) carried by
/// the ankle (bending toes never take their tip below the toe joint's
/// ground: [`bend_toes`]).
pub(super) fn soles_of(
    character: &Pose,
    t: &Pose,
    g: &[DQuat; Canonical::COUNT],
    toes: Toes,
) -> [f64; 2] {
    [0, 1].map(|foot| {
        let (a, k) = FEET[foot];
        let (a, k) = (a.index(), k.index());
        let heel = DVec3::new(
            0.0,
            character[k].y.min(character[a].y) - character[a].y,
            0.0,
        );
        let tip = match toes {
            Toes::Rigid => (t[k] + g[a] * toe_tip(character, foot)).y,
            Toes::Bending => f64::INFINITY,
        };
        [t[k].y, (t[a] + g[a] * heel).y, tip]
            .into_iter()
            .fold(f64::INFINITY, f64::min)
    })
}

/// Turns foot `foot`'s toes (its toe joint's rotation in `g`, the
/// ankle's until now) up about the toe joint of `t` so that the toe tip
/// ([`toe_tip`], carried by the ankle) is no lower than `ground` (the
/// foot's ground, the character's metres): by the least angle in the
/// vertical plane through the tip, and no further than level (a toe joint
/// below its ground leaves the toes level). Toes whose tip is on or above
/// the ground are left with the foot.
pub(super) fn bend_toes(
    character: &Pose,
    t: &Pose,
    g: &mut [DQuat; Canonical::COUNT],
    foot: usize,
    ground: f64,
) {
    let (a, k) = FEET[foot];
    let (a, k) = (a.index(), k.index());
    let v = g[a] * toe_tip(character, foot);
    let len = v.length();
    if len.is_nan() || len <= 1e-12 || !ground.is_finite() || t[k].y + v.y >= ground {
        return;
    }
    let axis = v.cross(DVec3::Y).normalize_or_zero();
    if axis == DVec3::ZERO {
        return;
    }
    let now = (v.y / len).clamp(-1.0, 1.0).asin();
    let wanted = ((ground - t[k].y) / len).clamp(-1.0, 0.0).asin();
    if wanted > now {
        g[k] = (DQuat::from_axis_angle(axis, wanted - now) * g[a]).normalize();
    }
}

/// The buffers [`flat_feet_with`] reuses from one clip to the next
/// (cleared before use).
#[derive(Debug, Clone, Default)]
pub struct FlatScratch {
    /// A joint's heights, sorted.
    heights: Vec<f64>,
    /// The elevations while planted.
    held: Vec<f64>,
    /// The elevations near the lowest.
    near: Vec<f64>,
    /// The elevations near the lowest while touching.
    touching: Vec<f64>,
}

/// The 5th percentile of `c`'s finite heights over `mocap`, with
/// `heights` the buffer they are sorted in.
fn low_height(mocap: &[Pose], c: C, heights: &mut Vec<f64>) -> Option<f64> {
    heights.clear();
    heights.reserve(mocap.len());
    heights.extend(
        mocap
            .iter()
            .map(|p| p[c.index()].y)
            .filter(|y| y.is_finite()),
    );
    heights.sort_by(f64::total_cmp);
    heights.get(heights.len() / 20).copied()
}

/// The median of `e` (sorted in place; the upper one of an even count).
fn median_of(e: &mut [f64]) -> Option<f64> {
    e.sort_by(f64::total_cmp);
    e.get(e.len() / 2).copied()
}

/// `r` with each foot bone (ankle → toe) turned about its lateral axis to
/// the elevation the clip's foot has when flat on its ground: the median
/// over the frames where both the foot's ankle and toe are within 2.4 % of
/// the leg's length (2 cm on a CMU actor) of their lowest (5th
/// percentile) heights, unless it is more than 5° off
/// the elevation the foot holds longest while planted on a support
/// ([`held_elevation`] over the frames where it touches the floor or a
/// block it stands on, `support`'s [`Support::touch`], or stands on a
/// block too low to be told from the floor, [`Support::held`], with its ankle and
/// toe joints each moving less than 2 % of the leg's length from the
/// frame before), which is then taken. A rest skeleton's foot bone need
/// not point as the standing foot's does (CMU's ASF rest skeleton points
/// it 15° further down than the walks' stance, and copying that left the
/// character's heels 2 cm up); `r` unchanged for a foot never flat. The
/// lowest heights alone are not enough on uneven ground: CMU 03_02's left
/// foot touches the floor only while leaving it on its toes, then stands
/// on blocks, and that toe-off (−82° against the −14° it holds on the
/// blocks) was taken for flat: on the blocks the character's left foot
/// stood toes up by 50-60°, its heel 3-4 cm through the block's top. On
/// a flat capture the two agree (within 3° on the README's walks and
/// runs) and the lowest heights are kept. The band is a fraction of the
/// leg, not 2 cm (session 32), so a small body's foot rolling onto its
/// ball is not counted flat: a walk of a 1.1 m body (legs 0.54 m) stood
/// the character's foot 16° toes-down where the clip's was flat.
///
/// A clip that never stands a foot flat for five frames nor plants it
/// (an in-place walk cycle, its feet sliding back under the body: Kenney's
/// Maya character, 26 frames at 30 fps, one or two per foot with ankle and
/// toe near their lowest) takes the median over the frames near their
/// lowest where the foot touches its ground; with none, `r` keeps the
/// foot. The foot bone is first made to point forward ([`forward_foot`]).
///
/// `scratch` holds its buffers (cleared before use): no allocation once
/// they hold the clip's frames.
pub(super) fn flat_feet_with(
    r: &Pose,
    mocap: &[Pose],
    support: &Support,
    scratch: &mut FlatScratch,
) -> Pose {
    let mut out = *r;
    let elevation = |f: DVec3| (f.y / f.length()).clamp(-1.0, 1.0).asin();
    let leg = leg_length(r).max(1e-9);
    let still = 0.02 * leg;
    // "Near the lowest": 2.4 % of the leg (2 cm on CMU's 0.83 m legs).
    let band = 0.024 * leg;
    for (foot, (ankle, toe)) in [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)]
        .into_iter()
        .enumerate()
    {
        let (a, t) = (ankle.index(), toe.index());
        let moved = |i: usize, j: usize| {
            mocap[i][a]
                .distance(mocap[j][a])
                .max(mocap[i][t].distance(mocap[j][t]))
        };
        let planted = |i: usize| {
            let j = if i > 0 { i - 1 } else { 1.min(mocap.len() - 1) };
            let on = support.touch[foot].get(i).is_some_and(|g| g.is_some())
                || support.held[foot].get(i).is_some_and(|&h| h);
            on && moved(i, j) <= still
        };
        let held = &mut scratch.held;
        held.clear();
        held.reserve(mocap.len());
        held.extend(
            (0..mocap.len())
                .filter(|&i| planted(i))
                .map(|i| elevation(mocap[i][t] - mocap[i][a]))
                .filter(|e| e.is_finite()),
        );
        held.sort_by(f64::total_cmp);
        let held = (held.len() >= 5).then(|| held_elevation(held));
        // The frames with the foot's ankle and toe both near their
        // lowest, and of them those where the foot touches its ground.
        let la = low_height(mocap, ankle, &mut scratch.heights);
        let lt = low_height(mocap, toe, &mut scratch.heights);
        let (lowest, few) = match (la, lt) {
            (Some(la), Some(lt)) => {
                let near = |i: &usize| mocap[*i][a].y <= la + band && mocap[*i][t].y <= lt + band;
                let of = |i: usize| elevation(mocap[i][t] - mocap[i][a]);
                let e = &mut scratch.near;
                e.clear();
                e.reserve(mocap.len());
                e.extend(
                    (0..mocap.len())
                        .filter(near)
                        .map(of)
                        .filter(|e| e.is_finite()),
                );
                let touching = &mut scratch.touching;
                touching.clear();
                touching.reserve(mocap.len());
                touching.extend(
                    (0..mocap.len())
                        .filter(near)
                        .filter(|&i| support.touch[foot].get(i).is_some_and(|g| g.is_some()))
                        .map(of)
                        .filter(|e| e.is_finite()),
                );
                (
                    (e.len() >= 5).then(|| median_of(e)).flatten(),
                    median_of(touching),
                )
            }
            _ => (None, None),
        };
        let flat = match (lowest, held, few) {
            (Some(l), Some(h), _) if (l - h).abs() > 5f64.to_radians() => h,
            (Some(l), _, _) => l,
            (None, Some(h), _) => h,
            (None, None, Some(f)) => f,
            (None, None, None) => continue,
        };
        let f = forward_foot(r, r[t] - r[a]);
        let axis = f.cross(DVec3::Y).normalize_or_zero();
        if axis == DVec3::ZERO || !f.is_finite() {
            continue;
        }
        let turn = DQuat::from_axis_angle(axis, flat - elevation(f));
        out[t] = r[a] + turn * f;
    }
    out
}

/// The foot bone `f` of the pose `r` pointing forward: as it is when its
/// horizontal part points ahead of the body (the hips' and shoulders'
/// left-right axis turned a quarter about the vertical), else that part
/// mirrored across the left-right axis (its elevation and its toe-out
/// kept). A reference frame's foot can point backward: a clip whose most
/// neutral frame kicks one shin up behind (Kenney's Maya walk in place,
/// frame 8 of 26 at 30 fps: the right foot 53° down and backward); turned
/// from there to its flat elevation it still pointed back, and the clip's
/// rotation since then turned the character's foot toes-up by 64° at the
/// next heel strike, its heel 7.2 cm through the floor.
fn forward_foot(r: &Pose, f: DVec3) -> DVec3 {
    let lateral = (r[C::LHip.index()] - r[C::RHip.index()])
        + (r[C::LShoulder.index()] - r[C::RShoulder.index()]);
    let left = DVec3::new(lateral.x, 0.0, lateral.z).normalize_or_zero();
    let ahead = left.cross(DVec3::Y);
    let along = f.dot(ahead);
    if left == DVec3::ZERO || along.is_nan() || along >= 0.0 {
        return f;
    }
    f - 2.0 * along * ahead
}

/// The elevation a foot holds longest among `e` (radians, sorted
/// ascending): the median of the largest set of them within 3° of one of
/// them. A foot at rest on its support holds one elevation; rolling onto
/// it (a heel strike) or off it (a heel rising about the toe, slowly
/// enough to count as planted) passes through the others.
pub(super) fn held_elevation(e: &[f64]) -> f64 {
    let band = 3f64.to_radians();
    let (mut best, mut lo, mut hi) = (0, 0, 0);
    let mut j = 0;
    for i in 0..e.len() {
        while e[i] - e[j] > band {
            j += 1;
        }
        // e[j..=i] all within `band` below e[i].
        if i + 1 - j > best {
            (best, lo, hi) = (i + 1 - j, j, i + 1);
        }
    }
    let w = &e[lo..hi];
    w.get(w.len() / 2).copied().unwrap_or(0.0)
}

/// How the surface a result drives moves its toes, which decides the
/// sole the kernel stands on the ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Toes {
    /// The toes move with the foot (the part-based deformation's foot
    /// part turns with the ankle): the sole's toe tip, a quarter of the
    /// foot's horizontal length beyond the toe joint, is carried by the
    /// ankle and dips below the toe joint when the foot pitches down
    /// onto its ball, so the body stands on it.
    #[default]
    Rigid,
    /// The toes bend at the toe joint (the ball) where the ground stops
    /// them, as a foot's do: the body stands on the toe joint or the heel
    /// alone, and the toe joint's rotation turns the toes up about the
    /// ball just enough to keep their tip on the foot's ground (level
    /// at most). A foot in the air keeps its toes in line with it. For a
    /// deformation that turns the toes by the toe joint's rotation (the
    /// Confluent Motion markers of `transfer`).
    Bending,
}

#[cfg(test)]
mod open_end_tests {
    use super::carry_down;

    #[test]
    fn carry_down_only_raises_and_falls_at_the_rate() {
        let mut lift = vec![0.10, 0.02, 0.09, 0.0, 0.0];
        carry_down(&mut lift, 0.03);
        let want = [0.10, 0.07, 0.09, 0.01, 0.0];
        for (l, w) in lift.iter().zip(want) {
            assert!((l - w).abs() < 1e-12, "{lift:?}");
        }
        let mut none: Vec<f64> = Vec::new();
        carry_down(&mut none, 0.03);
        assert!(none.is_empty());
    }
}
