//! The clip's ground: levelling its floor and the supports its feet stand
//! on (floor and steps).

use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

use Canonical as C;

/// Lowest ankle or toe joint height of a pose.
pub fn foot_height(p: &Pose) -> f64 {
    [C::LAnkle, C::LToe, C::RAnkle, C::RToe]
        .iter()
        .map(|c| p[c.index()].y)
        .fold(f64::INFINITY, f64::min)
}

/// Where a clip stands: its floor and, per frame, the height of the
/// ground its planted foot stands on.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Support {
    /// The clip's floor: the 5th percentile of its lowest ankle or toe
    /// joint over the frames.
    pub floor: f64,
    /// Per frame, the support under the clip's lowest planted foot when it
    /// touches it (its lowest joint within the contact band, [`Support::band`]);
    /// `None` in the air. The
    /// lowest of the two feet's [`Support::touch`].
    pub ground: Vec<Option<f64>>,
    /// Per foot (left, right) and frame, the support the foot touches: its
    /// footfall's when its lowest joint is within the contact band of it,
    /// the floor when within the band of the floor; `None` otherwise.
    pub touch: [Vec<Option<f64>>; 2],
    /// Per foot and frame, the ground under the foot: the support it
    /// touches; in the air, the higher of the last support it touched and
    /// the next when its lowest joint is above that one's top (a heel
    /// striking a block, a heel rising on it), else the lower (a foot
    /// stepping down from a block, or leaving the floor beside one, is
    /// over the floor); the only one before its first touch or after its
    /// last; `None` for a foot that never touches.
    pub under: [Vec<Option<f64>>; 2],
    /// Per foot and frame, whether the foot stands on a footfall's
    /// support: its lowest joint within the contact band of the height
    /// the footfall holds, on the floor, a step, or a block too low to
    /// be told from the floor (3-6 cm, which it does not touch).
    pub held: [Vec<bool>; 2],
    /// Per foot and frame, whether the foot is at rest: its ankle and toe
    /// joints both moving less than 0.5 % of the leg's length from the
    /// frame before (the first frame: to the next).
    pub rests: [Vec<bool>; 2],
    /// The contact band (the clip's metres, 3.6 % of its leg's length):
    /// a foot whose lowest joint is within it of a support touches that
    /// support.
    pub band: f64,
}

/// The ground under a foot per frame (see [`Support::under`]) from the
/// supports it touches, `touch`, and its lowest joint's height, `low`:
/// where it touches, that support; in the air, the higher of the last
/// support it touched and the next that the foot is not below (a foot
/// above a block's top may be over it: at a heel strike on it, or its
/// heel rising on it), else the lower.
///
/// Into `out` (cleared), with `sides` a buffer for
/// [`grounds_either_side_into`]: no allocation once both hold a clip's
/// frames.
pub(super) fn ground_under_into(
    touch: &[Option<f64>],
    low: &[f64],
    sides: &mut Vec<(Option<f64>, Option<f64>)>,
    out: &mut Vec<Option<f64>>,
) {
    grounds_either_side_into(touch, sides);
    out.clear();
    out.extend(
        sides
            .iter()
            .enumerate()
            .map(|(i, &(last, next))| match (touch[i], last, next) {
                (Some(t), _, _) => Some(t),
                (None, Some(a), Some(b)) => {
                    let (lo, hi) = (a.min(b), a.max(b));
                    Some(if low[i] >= hi { hi } else { lo })
                }
                (None, a, b) => a.or(b),
            }),
    );
}

/// Per frame, the last support a foot touched (this frame's when it
/// touches one) and the next, from the supports it touches, `touch`.
/// Into `out` (cleared and refilled).
pub(super) fn grounds_either_side_into(
    touch: &[Option<f64>],
    out: &mut Vec<(Option<f64>, Option<f64>)>,
) {
    out.clear();
    out.resize(touch.len(), (None, None));
    let mut l: Option<f64> = None;
    for (o, t) in out.iter_mut().zip(touch) {
        l = t.or(l);
        o.0 = l;
    }
    let mut n: Option<f64> = None;
    for (o, t) in out.iter_mut().zip(touch).rev() {
        n = t.or(n);
        o.1 = n;
    }
}

/// The contact band as a fraction of the clip's leg length (hip, knee,
/// ankle): a foot whose lowest joint is within it of a support touches
/// that support. 3.0 cm on CMU subject 02's legs (0.838 m), 2.9 cm on
/// the CMU BVH skeleton's and Bandai Namco's (0.80 m), as the fixed 3 cm
/// band it replaces; 3.5 cm on the Reallusion CC rig's (0.975 m). A
/// fixed band did not scale with the clip: CMU 02_03's CC-rig BVH
/// conversion scaled by 1.37 stood the character's pelvis 1.28 % of its
/// height from the AMC's instead of 1.17 % (issue 44).
pub(super) const CONTACT_PER_LEG: f64 = 0.036;

/// The contact band (the clip's metres) of a clip whose legs are `leg`
/// long: [`CONTACT_PER_LEG`] of it; 3 cm for a leg of no finite length.
pub fn contact_band(leg: f64) -> f64 {
    if leg.is_finite() && leg > 0.0 {
        CONTACT_PER_LEG * leg
    } else {
        0.03
    }
}

/// The height a footfall holds its lowest joint at, from its heights
/// `h` in the frames the foot is at rest (metres, sorted ascending): the
/// lowest of the largest set of them within the contact band of one
/// another (the first such set). `INFINITY` for no heights.
pub(super) fn held_height(h: &[f64], band: f64) -> f64 {
    let (mut best, mut lo, mut j) = (0, f64::INFINITY, 0);
    for i in 0..h.len() {
        while h[i] - h[j] > band {
            j += 1;
        }
        if i + 1 - j > best {
            (best, lo) = (i + 1 - j, h[j]);
        }
    }
    lo
}

/// The clip's support per footfall (poses levelled, Y-up, metres; `leg`
/// the clip's leg length). A foot is planted while its ankle or its toe
/// joint moves less than 2 % of the leg length per frame (a heel rising
/// about a planted toe, or a toe lowering about a planted heel); a
/// footfall is a run of planted frames, and its support is the height
/// its lowest joint holds in it while the foot is at rest, its ankle and
/// toe both moving less than 0.5 % of the leg length per frame
/// ([`held_height`]: the lowest of the largest set of those heights
/// within the contact band, [`Support::band`], 3.6 % of the leg; of all
/// its heights when it never rests). A support
/// within twice the contact band of the clip's floor is the floor (a flat
/// capture keeps one plane); a higher one is a step the clip stands on
/// (CMU subject 03 walks over blocks 11-25 cm high) when the footfall
/// lasts at least 5 frames, the foot rests in some and bears weight (it
/// is the lower foot in some frame of it). A frame touches the ground when any foot
/// joint is within the band of the floor (as on a flat capture), or a
/// planted foot's lowest joint is within the band of its footfall's
/// support; the
/// lowest such support is the frame's ground.
///
/// The support was the lowest height the footfall's lowest joint
/// reached, and steps began 6 cm above the floor. A run of planted frames
/// also holds the frames where the foot comes down onto a block toe
/// first, or leaves it over the edge onto its toes, its ankle moving
/// slowly (more such frames the higher the frame rate, the bound being
/// per frame): on a 30 cm block the toe was 5 cm below the top when the
/// run began, stepping down off 20 cm it dropped 4 cm past the edge, and
/// the frames flat on the block, more than 3 cm above that lowest
/// height, touched nothing (the foot's flat elevation was then read off
/// its toe-off, [`flat_feet_with`](super::feet::flat_feet_with), and it stood toes up on the block). On the
/// README's walks at 30 frames per second the resting frames' lowest
/// height is the footfall's lowest. A block 3-6 cm high is still the
/// floor (CMU 131_02 holds a foot 3.8 cm above its floor for 6 frames;
/// as a step it raised samba's penetration maximum 0.50 → 1.18 cm),
/// which the foot on it does not touch; [`Support::held`] has it. The
/// frames of the clip's trailing hold ([`frozen_frames`]: exact repeats
/// of the whole pose up to the end) count neither toward a step's 5
/// frames nor as its rest.
pub fn clip_support(mocap: &[Pose], leg: f64) -> Support {
    clip_support_on(mocap, leg, None)
}

/// The floor [`clip_support`] finds for `mocap` (levelled, metres): the
/// 5th percentile of its frames' lowest ankle or toe joint (the first
/// frame's pelvis height when no foot joint is finite).
pub fn clip_floor(mocap: &[Pose]) -> f64 {
    clip_floor_with(mocap, &mut Vec::new())
}

/// [`clip_floor`] with `lows` a buffer for the frames' lowest foot
/// joints (cleared; no allocation once it holds the clip's frames).
pub fn clip_floor_with(mocap: &[Pose], lows: &mut Vec<f64>) -> f64 {
    lows.clear();
    lows.reserve(mocap.len());
    lows.extend(mocap.iter().map(foot_height).filter(|h| h.is_finite()));
    lows.sort_by(f64::total_cmp);
    lows.get(lows.len() / 20)
        .copied()
        .unwrap_or_else(|| mocap.first().map_or(0.0, |p| p[C::Pelvis.index()].y))
}

/// What a caller decides for the pose kernel instead of its finding it
/// over the clip it is given: a live session's window is a few seconds of
/// a stream, and decisions made over it alone move from one window to the
/// next (`live::ground`). `Given::default()` decides nothing: the kernel's
/// result is the offline one, bit for bit.
#[derive(Clone, Copy, Default)]
pub struct Given<'a> {
    /// The rotation levelling the ground (else [`ground_tilt`]'s over the
    /// clip).
    pub tilt: Option<DQuat>,
    /// The floor (the levelled clip's height, metres; else
    /// [`clip_floor`]'s).
    pub floor: Option<f64>,
    /// The last word on the supports: called with the levelled clip and
    /// the support found over it.
    pub support: Option<SupportHook<'a>>,
    /// The clip ends at a stream's newest frame: a foot in the air after
    /// its last touch in it has not landed yet, and the floor, the lowest
    /// support it can land on, stands for the one it lands on (offline,
    /// the lower of the support it left and the next one decides how low
    /// it may go before it lifts the body: [`Support::under`]). A foot
    /// that left a step above the floor and has not landed carries the
    /// body down from the step no faster than the clip's pelvis falls
    /// fastest in the clip (`place_feet`'s causal step-down). False: the
    /// clip is whole.
    pub open_end: bool,
}

/// [`Given::support`]: called with the levelled clip and the support found
/// over it, may change the support.
pub(crate) type SupportHook<'a> = &'a dyn Fn(&[Pose], &mut Support);

impl Given<'_> {
    /// Only the floor given (or nothing).
    pub fn floor(floor: Option<f64>) -> Given<'static> {
        Given {
            floor,
            ..Given::default()
        }
    }

    /// The levelling: the given one, else [`ground_tilt`]'s over `mocap`.
    pub(crate) fn tilt_of(&self, mocap: &[Pose]) -> DQuat {
        self.tilt_with(mocap, &mut TiltScratch::default())
    }

    /// [`Given::tilt_of`] with `scratch` [`ground_tilt_with`]'s buffers.
    pub(crate) fn tilt_with(&self, mocap: &[Pose], scratch: &mut TiltScratch) -> DQuat {
        self.tilt
            .unwrap_or_else(|| ground_tilt_with(mocap, scratch))
    }
}

/// [`clip_support_on`] with what `given` decides (the floor, the last
/// word).
pub fn clip_support_given(mocap: &[Pose], leg: f64, given: &Given<'_>) -> Support {
    let mut s = Support::default();
    clip_support_given_into(mocap, leg, given, &mut SupportScratch::default(), &mut s);
    s
}

/// [`clip_support_given`] into `out` (every field refilled), with
/// `scratch` its buffers: no allocation once they and `out` hold the
/// clip's frames (but what a [`Given::support`] hook makes).
pub fn clip_support_given_into(
    mocap: &[Pose],
    leg: f64,
    given: &Given<'_>,
    scratch: &mut SupportScratch,
    out: &mut Support,
) {
    clip_support_into(mocap, leg, given.floor, scratch, out);
    if let Some(f) = given.support {
        f(mocap, out);
    }
}

/// The buffers [`clip_support_into`] reuses from one clip to the next
/// (each cleared before use; what they hold between calls means
/// nothing).
#[derive(Debug, Clone, Default)]
pub struct SupportScratch {
    /// The frames' lowest foot joints ([`clip_floor_with`]), then one
    /// foot's lowest joint per frame.
    lows: Vec<f64>,
    /// Per frame, how far the ankle and the toe joint moved.
    moved: Vec<(f64, f64)>,
    /// Per frame, whether the foot is planted.
    planted: Vec<bool>,
    /// A footfall's heights (at rest, or all of them).
    heights: Vec<f64>,
    /// The clip's trailing hold ([`frozen_frames`]).
    frozen: Vec<bool>,
    /// [`grounds_either_side_into`]'s buffer.
    sides: Vec<(Option<f64>, Option<f64>)>,
}

/// [`clip_support`] on the floor `floor` when the caller gives one (the
/// levelled clip's height, metres), else on [`clip_floor`]'s: a live
/// session's window is a few seconds of the stream, and its own 5th
/// percentile moved by millimetres from one window to the next, which
/// changed the frames a foot touches within the 3 cm band and the body's
/// lift with them (see `live::floor`).
pub fn clip_support_on(mocap: &[Pose], leg: f64, floor: Option<f64>) -> Support {
    let mut s = Support::default();
    clip_support_into(mocap, leg, floor, &mut SupportScratch::default(), &mut s);
    s
}

/// Clears `v` and fills it with `n` copies of `x` (its capacity kept).
fn refill<T: Clone>(v: &mut Vec<T>, n: usize, x: T) {
    v.clear();
    v.resize(n, x);
}

/// [`clip_support_on`] into `out` (every field refilled), with `scratch`
/// its buffers: no allocation once they and `out` hold the clip's frames
/// (a live session's analysis window, issue 45).
pub fn clip_support_into(
    mocap: &[Pose],
    leg: f64,
    floor: Option<f64>,
    scratch: &mut SupportScratch,
    out: &mut Support,
) {
    let floor = match floor {
        Some(f) if f.is_finite() => f,
        _ => clip_floor_with(mocap, &mut scratch.lows),
    };
    let n = mocap.len();
    for foot in 0..2 {
        refill(&mut out.touch[foot], n, None);
        refill(&mut out.held[foot], n, false);
        refill(&mut out.rests[foot], n, false);
    }
    let still = 0.02 * leg.max(1e-9);
    let band = contact_band(leg);
    frozen_frames(mocap, &mut scratch.frozen);
    for (foot, (ankle, toe)) in [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)]
        .into_iter()
        .enumerate()
    {
        support_of_foot(
            mocap,
            (ankle, toe),
            (floor, still, band),
            scratch,
            out,
            foot,
        );
    }
    out.ground.clear();
    out.ground
        .extend((0..n).map(|i| match (out.touch[0][i], out.touch[1][i]) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }));
    for (foot, (a, k)) in [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)]
        .into_iter()
        .enumerate()
    {
        scratch.lows.clear();
        scratch
            .lows
            .extend(mocap.iter().map(|p| p[a.index()].y.min(p[k.index()].y)));
        ground_under_into(
            &out.touch[foot],
            &scratch.lows,
            &mut scratch.sides,
            &mut out.under[foot],
        );
    }
    out.floor = floor;
    out.band = band;
}

/// One foot's part of [`clip_support_into`] (`foot`, its ankle and toe
/// joints; `floor`, the still bound and the contact band): its rests, the
/// frames it is held on a footfall's support, and those it touches one.
fn support_of_foot(
    mocap: &[Pose],
    (ankle, toe): (C, C),
    (floor, still, band): (f64, f64, f64),
    scratch: &mut SupportScratch,
    out: &mut Support,
    foot: usize,
) {
    let SupportScratch {
        moved,
        planted,
        heights,
        frozen,
        ..
    } = scratch;
    let (a, k) = (ankle.index(), toe.index());
    let low = |p: &Pose| if p[a].y <= p[k].y { p[a] } else { p[k] };
    // Per frame, how far the ankle and the toe joint moved from the
    // frame before (the first frame: to the next).
    moved.clear();
    moved.extend((0..mocap.len()).map(|t| {
        let (i, j) = if t > 0 {
            (t - 1, t)
        } else {
            (0, 1.min(mocap.len() - 1))
        };
        (
            (mocap[j][a] - mocap[i][a]).length(),
            (mocap[j][k] - mocap[i][k]).length(),
        )
    }));
    planted.clear();
    planted.extend(
        (0..mocap.len()).map(|t| moved[t].0.min(moved[t].1) <= still && low(&mocap[t]).is_finite()),
    );
    // At rest: the whole foot, ankle and toe, still (a quarter of the
    // planted bound).
    let moved = &*moved;
    let resting = |t: usize| moved[t].0.max(moved[t].1) <= 0.25 * still;
    for (t, r) in out.rests[foot].iter_mut().enumerate() {
        *r = resting(t);
    }
    let mut t = 0;
    while t < mocap.len() {
        if !planted[t] {
            t += 1;
            continue;
        }
        let start = t;
        while t < mocap.len() && planted[t] {
            t += 1;
        }
        let run = start..t;
        let height = |i: usize| low(&mocap[i]).y;
        heights.clear();
        heights.reserve(mocap.len());
        heights.extend(run.clone().filter(|&i| resting(i)).map(height));
        if heights.is_empty() {
            heights.extend(run.clone().map(height));
        }
        heights.sort_by(f64::total_cmp);
        let sup = held_height(heights, band);
        // A step is twice the contact band above the floor (~6 cm; a
        // kerb or a block), held at least 5 frames with the foot at
        // rest in some, and bears weight: the foot is the lower of
        // the two in some frame of the footfall (a leg held still in
        // the air, the other foot on the floor, is no step; nor a
        // gliding foot hovering over it).
        // The clip's trailing hold (a take run past its last key) is
        // no evidence of standing: held in the air, it made a step of
        // nothing.
        let live = run.clone().filter(|&i| !frozen[i]).count();
        let rests_live = run.clone().any(|i| resting(i) && !frozen[i]);
        let bears = run
            .clone()
            .any(|i| low(&mocap[i]).y <= foot_height(&mocap[i]) + 1e-9);
        if sup > floor + 2.0 * band && !(bears && rests_live && live >= 5) {
            continue;
        }
        for i in run.clone() {
            if (low(&mocap[i]).y - sup).abs() <= band {
                out.held[foot][i] = true;
            }
        }
        let sup = if sup <= floor + 2.0 * band {
            floor
        } else {
            sup
        };
        // The frames within the contact band of it: not those where
        // the foot, still counted planted, has dropped past the
        // block's edge (stepping down) or not yet come down onto it.
        for i in run {
            if (low(&mocap[i]).y - sup).abs() <= band {
                out.touch[foot][i] = Some(sup);
            }
        }
    }
    // On the floor, as on a flat capture: the foot within the band of it.
    for (i, p) in mocap.iter().enumerate() {
        if low(p).y <= floor + band {
            out.touch[foot][i] = Some(floor);
        }
    }
}

/// Per frame, whether it belongs to the clip's trailing hold: the frames
/// from the first of a run that repeats the whole pose before it exactly
/// (every joint within 1e-9 of the body's size) to the clip's end. A take
/// that runs past its last key holds that key (Kenney's Maya walk holds
/// its first pose, the loop's last key, over its last five frames, both
/// feet in the air, and that hold read as a 7.5 cm step under the right
/// foot: the result floated 8 cm over its last six frames). Only the end:
/// a pose held still elsewhere (a figure standing on a block) is motion.
///
/// Into `out` (cleared and refilled).
fn frozen_frames(mocap: &[Pose], out: &mut Vec<bool>) {
    let start = hold_start(mocap);
    out.clear();
    out.extend((0..mocap.len()).map(|t| t >= start));
}

/// The first frame of the clip's trailing hold ([`frozen_frames`]; the
/// clip's length when it has none).
fn hold_start(mocap: &[Pose]) -> usize {
    let same = |t: usize| {
        let (a, b) = (&mocap[t - 1], &mocap[t]);
        let size = a[C::Pelvis.index()].distance(a[C::Head.index()]).max(1e-9);
        (0..Canonical::COUNT).all(|j| a[j].distance(b[j]) <= 1e-9 * size)
    };
    let mut start = mocap.len();
    while start > 1 && same(start - 1) {
        start -= 1;
    }
    start
}

/// Fills the `None`s of `v` linearly between their known neighbours (the
/// nearest known value past either end; all zeros when none is known).
pub(super) fn interpolate_gaps(v: &[Option<f64>]) -> Vec<f64> {
    let mut out = Vec::with_capacity(v.len());
    interpolate_gaps_into(v, &mut Vec::new(), &mut out);
    out
}

/// [`interpolate_gaps`] into `out` (cleared), with `known` a buffer for
/// the known values: no allocation once both hold `v`'s length.
pub(super) fn interpolate_gaps_into(
    v: &[Option<f64>],
    known: &mut Vec<(usize, f64)>,
    out: &mut Vec<f64>,
) {
    known.clear();
    known.reserve(v.len());
    known.extend(v.iter().enumerate().filter_map(|(i, x)| x.map(|x| (i, x))));
    out.clear();
    out.reserve(v.len());
    let (Some(&first), Some(&last)) = (known.first(), known.last()) else {
        out.resize(v.len(), 0.0);
        return;
    };
    let mut k = 0;
    for i in 0..v.len() {
        while k + 1 < known.len() && known[k + 1].0 <= i {
            k += 1;
        }
        out.push(if i <= first.0 {
            first.1
        } else if i >= last.0 {
            last.1
        } else {
            let ((i0, a), (i1, b)) = (known[k], known[k + 1]);
            if i1 == i0 {
                a
            } else {
                a + (b - a) * (i - i0) as f64 / (i1 - i0) as f64
            }
        });
    }
}

/// The rotation that makes a clip's ground level: a plane
/// `y = a + b·x + c·z` fitted to the lowest ankle or toe joint of every
/// frame (least squares, then three times on the lower half of the
/// residuals, so that lifted feet and jumps do not count), its slope
/// shrunk by a ridge of (0.22 m)² so that a clip standing in place has
/// none, turned onto the horizontal. Identity for a clip of fewer than 10
/// frames or a slope past 5° (a ramp or stairs, not a tilted floor).
pub fn ground_tilt(mocap: &[Pose]) -> DQuat {
    ground_tilt_with(mocap, &mut TiltScratch::default())
}

/// The buffers [`ground_tilt_with`] reuses from one clip to the next
/// (cleared before use).
#[derive(Debug, Clone, Default)]
pub struct TiltScratch {
    /// The lowest foot joint of each frame.
    samples: Vec<DVec3>,
    /// Their residuals to the plane.
    residuals: Vec<f64>,
    /// The samples on or below the median residual.
    low: Vec<DVec3>,
}

/// [`ground_tilt`] with `scratch` its buffers: no allocation once they
/// hold the clip's frames.
pub fn ground_tilt_with(mocap: &[Pose], scratch: &mut TiltScratch) -> DQuat {
    let TiltScratch {
        samples,
        residuals: r,
        low,
    } = scratch;
    let feet = [C::LAnkle, C::LToe, C::RAnkle, C::RToe];
    samples.clear();
    samples.reserve(mocap.len());
    samples.extend(mocap.iter().filter_map(|p| {
        feet.iter()
            .map(|c| p[c.index()])
            .filter(|q| q.is_finite())
            .min_by(|a, b| a.y.total_cmp(&b.y))
    }));
    if samples.len() < 10 {
        return DQuat::IDENTITY;
    }
    const RIDGE: f64 = 0.05;
    let fit = |keep: &[DVec3]| -> Option<(f64, f64, f64, DVec3)> {
        let n = keep.len() as f64;
        let mean = keep.iter().copied().sum::<DVec3>() / n;
        let (mut sxx, mut sxz, mut szz, mut sxy, mut szy) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for q in keep {
            let d = *q - mean;
            sxx += d.x * d.x;
            sxz += d.x * d.z;
            szz += d.z * d.z;
            sxy += d.x * d.y;
            szy += d.z * d.y;
        }
        let (sxx, szz) = (sxx + n * RIDGE, szz + n * RIDGE);
        let det = sxx * szz - sxz * sxz;
        if !(det.is_finite() && det > 0.0) {
            return None;
        }
        let b = (sxy * szz - szy * sxz) / det;
        let c = (szy * sxx - sxy * sxz) / det;
        Some((mean.y, b, c, mean))
    };
    let Some(mut plane) = fit(samples) else {
        return DQuat::IDENTITY;
    };
    for _ in 0..3 {
        let (a, b, c, m) = plane;
        let res = |q: &DVec3| q.y - (a + b * (q.x - m.x) + c * (q.z - m.z));
        r.clear();
        r.reserve(samples.len());
        r.extend(samples.iter().map(res));
        r.sort_by(f64::total_cmp);
        let cut = r[r.len() / 2];
        low.clear();
        low.reserve(samples.len());
        low.extend(samples.iter().copied().filter(|q| res(q) <= cut));
        if low.len() < 5 {
            break;
        }
        match fit(low) {
            Some(p) => plane = p,
            None => break,
        }
    }
    let (_, b, c, _) = plane;
    let normal = DVec3::new(-b, 1.0, -c).normalize();
    if normal.angle_between(DVec3::Y) > 5f64.to_radians() || !normal.is_finite() {
        return DQuat::IDENTITY;
    }
    DQuat::from_rotation_arc(normal, DVec3::Y)
}
