//! The top of a headless body's neck (issue 41, partial bodies): a body
//! cut at the neck ends in a stump, and its landmarks declare
//! `"absent": ["head"]` (no chin). When the cut is open (the mesh has a
//! boundary loop there, [`crate::mesh::boundary::boundary_loops`]) the
//! stump's top is the centroid of that loop, the rim ([`pick_rim`]);
//! otherwise (a closed cap, or no loop passes) the centre of the highest
//! ring of vertices near the body's axis ([`stump_top`]). The chin is put
//! 4 % of the height ahead of it ([`neck_top`]), where joint placement
//! looks for a chin (the neck is sought 4 % behind the chin,
//! [`super::joints`]), and the head joint is put on it
//! (`joints::neck_and_head`): the head ends where the body does. The neck
//! joint is sought [`neck_below_top`] below the top ring's centre (5 %,
//! as below a whole body's chin, unless `SURFMOTION_AUTORIG` says
//! `neck=P`), whether or not the head is on a rim: sought as far below the
//! rim's centroid it lay lower than session 40's on every cut measured.

use super::landmarks::{Landmark, Landmarks};
use glam::DVec3;

/// The top of a headless body's neck.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StumpTop {
    /// The rim's centroid when an open cut's boundary loop passes
    /// [`RimLoop::passes`]; else the centre of the ring: the vertices
    /// within 1.5 % of the height of the highest one near the body's axis
    /// (the vertical through the groin, up from the knees to the groin,
    /// within 12 % of the height of it).
    pub centre: DVec3,
    /// The centre of the ring (as `centre` when no rim passes): the neck
    /// joint is sought below it ([`neck_below_top`]) whether or not the
    /// head is put on a rim, as in session 40.
    pub ring: DVec3,
    /// Facing: left × up, left from the limb landmarks' pairs.
    pub facing: DVec3,
    /// The height along up.
    pub height: f64,
}

/// The body's vertical through the groin (up from the knees' midpoint to
/// the groin) and its height along it.
struct BodyAxis {
    groin: DVec3,
    up: DVec3,
    height: f64,
}

impl BodyAxis {
    /// The axis of the body at `positions` marked by `lm`; `None` without
    /// a groin or knees.
    fn of(lm: &Landmarks, positions: &[[f64; 3]]) -> Option<BodyAxis> {
        let at = |l: Landmark| lm.point(l, positions).map(DVec3::from_array);
        let g = at(Landmark::Groin)?;
        let (lk, rk) = (at(Landmark::LKnee)?, at(Landmark::RKnee)?);
        let up = super::axes::body_up(g - (lk + rk) * 0.5);
        let hs = positions.iter().map(|q| DVec3::from_array(*q).dot(up));
        let (lo, hi) = hs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
        Some(BodyAxis {
            groin: g,
            up,
            height: (hi - lo).max(1e-9),
        })
    }

    /// How far `q` lies across up from the axis.
    fn across(&self, q: DVec3) -> f64 {
        let d = q - self.groin;
        (d - self.up * d.dot(self.up)).length()
    }

    /// The highest ring near the axis: the centre of the vertices within
    /// 12 % of the height of the axis and 1.5 % of the height of the
    /// highest of them, and that highest height along up.
    fn top_ring(&self, positions: &[[f64; 3]]) -> Option<(DVec3, f64)> {
        let h = self.height;
        let axis: Vec<DVec3> = positions
            .iter()
            .map(|q| DVec3::from_array(*q))
            .filter(|&q| self.across(q) < 0.12 * h)
            .collect();
        let top = axis
            .iter()
            .map(|q| q.dot(self.up))
            .fold(f64::NEG_INFINITY, f64::max);
        let ring: Vec<DVec3> = axis
            .into_iter()
            .filter(|q| q.dot(self.up) >= top - 0.015 * h)
            .collect();
        if ring.is_empty() {
            return None;
        }
        Some((ring.iter().copied().sum::<DVec3>() / ring.len() as f64, top))
    }
}

/// One boundary loop of a body's mesh read as a possible rim of its cut
/// neck; distances are fractions of the body's height.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RimLoop {
    /// The loop's vertices' centroid.
    pub centre: DVec3,
    /// How many vertices the loop has.
    pub vertices: usize,
    /// How far the centroid lies across up from the body's axis.
    pub off_axis: f64,
    /// How far the loop's farthest vertex lies across up from the axis.
    pub reach: f64,
    /// How far the centroid lies below the highest vertex near the axis
    /// ([`BodyAxis::top_ring`]; negative above it).
    pub below_top: f64,
    /// The centroid's distance to the nearest elbow or wrist landmark
    /// (infinite without them).
    pub from_arms: f64,
}

/// How far across up from the body's axis a rim's centroid may lie (a
/// fraction of the height): as the top ring's vertices (12 %). An arm
/// stump's or a hand's hole lies farther (the shoulders alone are 10-13 %
/// of the height off the axis).
pub const RIM_AXIS: f64 = 0.12;
/// How far below the highest vertex near the axis a rim's centroid may
/// lie (a fraction of the height): a foot's or a leg's hole lies far
/// lower.
pub const RIM_BELOW_TOP: f64 = 0.10;
/// How near a rim's centroid may come to an elbow or a wrist landmark (a
/// fraction of the height): a hand's hole lies at the wrist.
pub const RIM_FROM_ARMS: f64 = 0.08;
/// How far across up from the body's axis a rim's vertices may reach (a
/// fraction of the height), unless `SURFMOTION_AUTORIG` says `rim=P`. A
/// cut at the neck joint slants into the trapezius: session 40 measured
/// the body 11.3-14.8 % across at the rim's centre's height there, and
/// session 40's 12 % refused those rims.
pub const RIM_REACH: f64 = 0.25;

impl RimLoop {
    /// Whether the loop is read as the rim of the cut neck: its centroid
    /// within [`RIM_AXIS`] of the axis, at most [`RIM_BELOW_TOP`] below the
    /// top and farther than [`RIM_FROM_ARMS`] from the elbows and wrists,
    /// its vertices within `reach` of the axis.
    pub fn passes(&self, reach: f64) -> bool {
        self.off_axis <= RIM_AXIS
            && self.below_top <= RIM_BELOW_TOP
            && self.from_arms > RIM_FROM_ARMS
            && self.reach <= reach
    }
}

/// Every boundary loop of the body at `positions` (`triangles`) marked by
/// `lm`, with its figures ([`RimLoop`]); empty without a groin or knees,
/// or for a closed mesh.
pub(crate) fn rim_loops(
    lm: &Landmarks,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Vec<RimLoop> {
    let Some(ax) = BodyAxis::of(lm, positions) else {
        return Vec::new();
    };
    let Some((_, top)) = ax.top_ring(positions) else {
        return Vec::new();
    };
    loops_on(&ax, top, lm, positions, triangles)
}

/// [`rim_loops`] on the axis `ax` whose top near the axis is `top`.
fn loops_on(
    ax: &BodyAxis,
    top: f64,
    lm: &Landmarks,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Vec<RimLoop> {
    let h = ax.height;
    let arms: Vec<DVec3> = [
        Landmark::LElbow,
        Landmark::RElbow,
        Landmark::LWrist,
        Landmark::RWrist,
    ]
    .into_iter()
    .filter_map(|l| lm.point(l, positions).map(DVec3::from_array))
    .collect();
    crate::mesh::boundary::boundary_loops(positions.len(), triangles)
        .into_iter()
        .map(|vs| {
            let q: Vec<DVec3> = vs
                .iter()
                .map(|&v| DVec3::from_array(positions[v as usize]))
                .collect();
            let centre = q.iter().copied().sum::<DVec3>() / q.len().max(1) as f64;
            let reach = q.iter().map(|&x| ax.across(x)).fold(0.0, f64::max);
            let from_arms = arms
                .iter()
                .map(|a| a.distance(centre))
                .fold(f64::INFINITY, f64::min);
            RimLoop {
                centre,
                vertices: q.len(),
                off_axis: ax.across(centre) / h,
                reach: reach / h,
                below_top: (top - centre.dot(ax.up)) / h,
                from_arms: from_arms / h,
            }
        })
        .collect()
}

/// The rim of the cut neck among `loops`: the highest that passes
/// ([`RimLoop::passes`] with `reach`); `None` when none does.
pub(crate) fn pick_rim(loops: &[RimLoop], reach: f64) -> Option<RimLoop> {
    loops
        .iter()
        .filter(|l| l.passes(reach))
        .min_by(|a, b| a.below_top.total_cmp(&b.below_top))
        .copied()
}

/// The top of the neck of the body at `positions` (`triangles`) marked by
/// `lm` (groin and knees needed; the elbows and wrists side it too): the
/// rim of an open cut ([`pick_rim`]), else the top ring near the axis.
/// `None` without a groin or knees.
pub(crate) fn stump_top(
    lm: &Landmarks,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Option<StumpTop> {
    let at = |l: Landmark| lm.point(l, positions).map(DVec3::from_array);
    let ax = BodyAxis::of(lm, positions)?;
    let (ring, top) = ax.top_ring(positions)?;
    let rim = pick_rim(&loops_on(&ax, top, lm, positions, triangles), rim_reach());
    let up = ax.up;
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
        centre: rim.map_or(ring, |r| r.centre),
        ring,
        facing: left.cross(up),
        height: ax.height,
    })
}

/// The chin of a body without a head: [`stump_top`]'s centre moved
/// forward by 4 % of the height (joint placement looks for the neck that
/// far behind the chin). `None` without a groin or knees.
pub(crate) fn neck_top(
    lm: &Landmarks,
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Option<[f64; 3]> {
    let s = stump_top(lm, positions, triangles)?;
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
/// 96.8 / 97.0 / 96.6 %): not the default. Since session 41 an open
/// cut's head joint is its rim's centroid ([`pick_rim`]), lower than the
/// ring by the rim's slant; the neck is still sought below the ring
/// ([`StumpTop::ring`]): sought 5 % below the rim's centroid (session
/// 41's first build, `autorig_eval … headless`) the neck was 1.6 % of
/// the height farther from the truth on SMPL cut at its neck joint (1.68
/// / 1.87 / 2.58 → 3.30 / 3.51 / 4.04 %), and the joints but the head
/// 0.16-0.23 worse on the 0 % cuts of samba and SMPL.
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
    key_percent(text, "neck=", 10.0)
}

/// [`RIM_REACH`], or the `rim=P` (percent of the height, 0-100; 0: no
/// rim is read, the top ring alone, session 40's rule) of
/// [`crate::embed::auto::options::AUTORIG_ENV`] for measurements. Read
/// once per process.
pub(crate) fn rim_reach() -> f64 {
    static REACH: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *REACH.get_or_init(|| {
        let text = std::env::var(crate::embed::auto::options::AUTORIG_ENV).unwrap_or_default();
        rim_percent(&text).map_or(RIM_REACH, |p| p / 100.0)
    })
}

/// The `rim=P` of an override text (`P` a percent from 0 to 100); `None`
/// when it has none or it does not parse.
pub(crate) fn rim_percent(text: &str) -> Option<f64> {
    key_percent(text, "rim=", 100.0)
}

/// The last `KEY=P` of an override text with `P` from 0 to `max`.
fn key_percent(text: &str, key: &str, max: f64) -> Option<f64> {
    text.split(',')
        .filter_map(|p| p.trim().strip_prefix(key))
        .filter_map(|v| v.parse::<f64>().ok())
        .rfind(|p| (0.0..=max).contains(p))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::embed::landmarks::Mark;

    /// A tube through `rings` (each of the same count of points, in
    /// order round it) appended to `p`/`t`: open at both ends.
    fn tube(rings: &[Vec<DVec3>], p: &mut Vec<[f64; 3]>, t: &mut Vec<[u32; 3]>) {
        let first = p.len() as u32;
        let n = rings[0].len() as u32;
        for r in rings {
            p.extend(r.iter().map(|q| q.to_array()));
        }
        for k in 0..rings.len() as u32 - 1 {
            for j in 0..n {
                let (a, b) = (first + k * n + j, first + k * n + (j + 1) % n);
                t.push([a, b, b + n]);
                t.push([a, b + n, a + n]);
            }
        }
    }

    /// A ring of `n` points round `c` across y, radii `rx` and `rz`, at
    /// heights `c.y + slant·cos θ`.
    fn ring(c: DVec3, rx: f64, rz: f64, slant: f64, n: usize) -> Vec<DVec3> {
        (0..n)
            .map(|j| {
                let a = std::f64::consts::TAU * j as f64 / n as f64;
                c + DVec3::new(rx * a.cos(), slant * a.cos(), rz * a.sin())
            })
            .collect()
    }

    /// A generated body: a trunk tube narrowing to a neck whose open top
    /// is cut slanted and reaches 15 % across (the trapezius), an arm's
    /// stump off to the side whose rim is higher than the neck's, a hand's
    /// hole in front of the chest at a wrist landmark, a foot's hole; the
    /// landmarks they need (`y` up). With the neck `capped` by a fan.
    fn body(capped: bool) -> (Vec<[f64; 3]>, Vec<[u32; 3]>, Landmarks) {
        let (mut p, mut t) = (Vec::new(), Vec::new());
        let c = |y: f64| DVec3::new(0.0, y, 0.0);
        let trunk = vec![
            ring(c(0.30), 0.15, 0.10, 0.0, 24),
            ring(c(0.60), 0.15, 0.10, 0.0, 24),
            ring(c(0.80), 0.14, 0.06, 0.0, 24),
            ring(c(0.86), 0.135, 0.06, 0.03, 24),
        ];
        tube(&trunk, &mut p, &mut t);
        if capped {
            let tip = p.len() as u32;
            p.push([0.0, 0.88, 0.0]);
            let first = 3 * 24;
            t.extend((0..24).map(|j| [first + j, first + (j + 1) % 24, tip]));
        }
        // An arm's stump off to the side, a hand's hole in front of the
        // chest, a foot's hole: short open tubes of 8 points a ring.
        for (at, r, from, to) in [
            (DVec3::new(0.24, 0.0, 0.0), 0.03, 0.70, 0.90),
            (DVec3::new(0.0, 0.0, 0.09), 0.02, 0.76, 0.84),
            (DVec3::new(0.05, 0.0, 0.0), 0.03, 0.0, 0.06),
        ] {
            let rings = [from, to].map(|y| ring(at + c(y), r, r, 0.0, 8));
            tube(&rings, &mut p, &mut t);
        }
        let mut lm = Landmarks::default();
        for (l, q) in [
            (Landmark::Groin, [0.0, 0.45, 0.0]),
            (Landmark::LKnee, [0.06, 0.25, 0.0]),
            (Landmark::RKnee, [-0.06, 0.25, 0.0]),
            (Landmark::LElbow, [0.22, 0.62, 0.0]),
            (Landmark::RElbow, [-0.25, 0.6, 0.0]),
            (Landmark::LWrist, [0.0, 0.84, 0.09]),
            (Landmark::RWrist, [-0.3, 0.45, 0.0]),
        ] {
            lm.marks.insert(l, Mark::Point(q));
        }
        (p, t, lm)
    }

    /// The boundary-loop pick on a generated body (as made; mirrored,
    /// Z-up and in centimetres): the slanted neck rim (its vertices 15 % of the height
    /// across, over session 40's 12 %) is the stump's top; the arm's stump
    /// (higher, off the axis), the hand's hole (at a wrist) and the foot's
    /// and trunk's lower holes are not; capped, the top ring is kept.
    #[test]
    fn the_slanted_neck_rim_is_picked_and_no_arm_stump_or_hand_hole() {
        let (p, t, lm) = body(false);
        let loops = rim_loops(&lm, &p, &t);
        assert_eq!(loops.len(), 8, "{loops:?}");
        let rim = pick_rim(&loops, RIM_REACH).expect("a rim");
        assert!(
            rim.centre.distance(DVec3::new(0.0, 0.86, 0.0)) < 1e-9,
            "{rim:?}"
        );
        assert!(rim.reach > 0.14 && rim.reach < 0.16, "{rim:?}");
        assert!(pick_rim(&loops, 0.12).is_none(), "{loops:?}");
        // The arm's stump is higher than the rim but off the axis; the
        // hand's hole passes every check but the wrist's.
        let arm = loops
            .iter()
            .filter(|l| l.off_axis > 0.2)
            .min_by(|a, b| a.below_top.total_cmp(&b.below_top))
            .expect("the arm");
        assert!(arm.below_top < rim.below_top && !arm.passes(1.0), "{arm:?}");
        let hand = loops.iter().find(|l| l.from_arms < 1e-9).expect("the hand");
        assert!(hand.off_axis <= RIM_AXIS && hand.below_top <= RIM_BELOW_TOP);
        assert!(!hand.passes(1.0));
        // Mirrored, turned Z-up and in centimetres: the same rim, moved.
        let f = |q: [f64; 3]| [-100.0 * q[0], -100.0 * q[2], 100.0 * q[1]];
        let moved: Vec<[f64; 3]> = p.iter().map(|q| f(*q)).collect();
        let mut lm2 = Landmarks::default();
        for (l, m) in &lm.marks {
            if let Mark::Point(q) = m {
                lm2.marks.insert(*l, Mark::Point(f(*q)));
            }
        }
        let top = stump_top(&lm2, &moved, &t).expect("a top");
        let want = DVec3::from_array(f([0.0, 0.86, 0.0]));
        assert!(top.centre.distance(want) < 1e-6, "{:?}", top.centre);
        // Capped: no rim, the top ring (the cap's tip and the rim's
        // highest vertices near the axis).
        let (p, t, lm) = body(true);
        let loops = rim_loops(&lm, &p, &t);
        assert_eq!(loops.len(), 7);
        assert!(pick_rim(&loops, RIM_REACH).is_none(), "{loops:?}");
        let top = stump_top(&lm, &p, &t).expect("a top");
        assert!(top.centre.y > 0.87, "{:?}", top.centre);
    }

    #[test]
    fn the_neck_override_reads_a_percent_and_ignores_the_rest() {
        assert_eq!(neck_percent("head=axis"), None);
        assert_eq!(neck_percent("head=axis, neck=5"), Some(5.0));
        assert_eq!(neck_percent("neck=2.5,max=60"), Some(2.5));
        assert_eq!(neck_percent("neck=11"), None);
        assert_eq!(neck_percent("neck=x"), None);
        assert_eq!(rim_percent("neck=5,rim=0"), Some(0.0));
        assert_eq!(rim_percent("rim=30"), Some(30.0));
        assert_eq!(rim_percent("rim=101"), None);
        assert_eq!(rim_percent("neck=5"), None);
    }
}
