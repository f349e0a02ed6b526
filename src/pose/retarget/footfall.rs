//! The character's feet on the clip's footfalls (issue 44,
//! [`Footfalls::Targets`](super::Footfalls::Targets)), so that its stride
//! and its travel agree by construction.
//!
//! The kernel puts each limb bone along the clip's direction on the
//! character's own bones and carries the body by the clip's travel scaled
//! (Huang et al. 2015, Sec. 5.2 copy the translation; the scale is this
//! project's). The feet then land where the directions put them, not
//! where the scaled travel does: the CC-rig BVH conversion of CMU
//! 02_01-02_03 has legs 1.164 times the AMC's but travels only 1.146
//! times as far, so its strides on the character are 1.3-3.0 % short,
//! and a planted foot slides (session 37, `pose::stride`).
//!
//! Here each footfall of the clip (a run of three frames or more in
//! which a foot touches its ground, [`Support::touch`], and its ankle or
//! toe joint moves less than 1 % of the clip's leg horizontally from the
//! frame before) becomes a target: the body is first carried by its
//! hips' midpoint (the clip's scaled by the one travel scale `k`, so that
//! no rig's root placement sways it about the held feet:
//! [`carry_by_hips`]); in each footfall frame the target is the clip's
//! ankle scaled, `k a(t)`, plus the footfall's mean horizontal offset of
//! the character's hip on that side from the clip's, scaled
//! (`mean(h_char − k h_clip)`, so the character keeps its own hip
//! width). A foot still in the clip is still on the character. Between
//! footfalls the ankle's offset from where the limbs put it eases
//! (smoothstep) from the last footfall's to the next's, so nothing pops;
//! before the first and after the last it is held. The height is the
//! limbs' own: only the horizontal place changes, so the feet's ground
//! ([`place_feet_into`](super::feet::place_feet_into)), applied after, stands them
//! as before. Where a planted foot's target lies beyond 0.997 of its
//! leg's reach (or the posed leg's, if longer), the body is shifted
//! horizontally (the least shift, by alternating projection over the
//! planted feet, then smoothed over ±4 frames): the pelvis follows the
//! feet. The legs reach the targets by two-bone IK
//! ([`leg_ik`](super::leg_ik)). A clip with no footfall is unchanged.
//!
//! Retrieval compares the poses before the feet were put on their
//! footfalls (`OnCharacter::free_feet`): on the samba capture (a dance,
//! no walking frame) CMU 03_02's query is 2.6 m (summed over 19 joints)
//! from its nearest frames, and holding one frame (129) or another (0,
//! the A-pose) cost within 0.1 % of each other; the planted legs (their
//! ankles 1-2 cm off) tipped the choice to the A-pose, whose head carriage
//! raised the head's p95 3.4° → 6.3° (session 38).
//!
//! An option, off by default: measured (session 39,
//! `scripts/yardstick.sh` on samba) it still slides the Bandai Namco
//! walk's and run's feet more than the default (0.324 → 0.348, 0.519 →
//! 0.541 cm/frame) and raises CMU 03_02's velocity error 0.123 → 0.140.

use super::ground::Support;
use super::leg_ik::{LEGS, reach};
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

/// A footfall: its first and last frame.
type Plant = (usize, usize);

/// The fewest frames a footfall lasts: a foot still for two frames is a
/// pause in its swing (a run's stance lasts 6-8 frames at 30 fps).
const MIN_FRAMES: usize = 3;

/// Frames either side over which the body's shift is averaged.
const SMOOTH: usize = 4;

/// The share of a leg's length a planted foot's target may lie from the
/// hip before the body is shifted (a knee bent about 9°).
const REACH: f64 = 0.997;

fn flat(v: DVec3) -> DVec3 {
    DVec3::new(v.x, 0.0, v.z)
}

/// Puts the character's feet of `out` (its poses after placement, before
/// the feet's ground) on the footfalls of `mocap` (the clip's poses,
/// levelled; `support` its supports; `leg` its leg's length) mapped by
/// the travel scale `k`: see the module docs.
pub(super) fn plant_feet(
    mocap: &[Pose],
    support: &Support,
    (k, leg): (f64, f64),
    out: &mut [(Pose, [DQuat; Canonical::COUNT])],
) {
    let n = mocap.len().min(out.len());
    if n < 2 || !(k.is_finite() && k > 0.0 && leg.is_finite() && leg > 0.0) {
        return;
    }
    let still = 0.01 * leg;
    let plants = [0, 1].map(|f| footfalls(&mocap[..n], support, f, still));
    if plants.iter().all(Vec::is_empty) {
        return;
    }
    carry_by_hips(&mocap[..n], k, &mut out[..n]);
    let offsets = [0, 1].map(|f| ankle_offsets(&mocap[..n], &out[..n], f, &plants[f], k));
    let goals: [Vec<DVec3>; 2] = [0, 1].map(|f| {
        let a = LEGS[f][2].index();
        (0..n).map(|i| out[i].0[a] + offsets[f][i]).collect()
    });
    let planted: [Vec<bool>; 2] = plants.each_ref().map(|p| {
        let mut v = vec![false; n];
        for &(a, b) in p {
            v[a..=b].fill(true);
        }
        v
    });
    let shift = smoothed(&body_shifts(&out[..n], &goals, &planted));
    for (i, (t, g)) in out.iter_mut().take(n).enumerate() {
        for p in t.iter_mut() {
            *p += shift[i];
        }
        for (f, goal) in goals.iter().enumerate() {
            if offsets[f][i] != DVec3::ZERO {
                reach(t, g, f, goal[i]);
            }
        }
    }
}

/// The footfalls of foot `f` (0 left, 1 right): the runs of
/// [`MIN_FRAMES`] frames or more in which it touches its ground and its ankle or toe moves
/// less than `still` horizontally from the frame before (the first frame:
/// to the next).
fn footfalls(mocap: &[Pose], support: &Support, f: usize, still: f64) -> Vec<Plant> {
    let [_, _, a, t] = LEGS[f].map(|c| c.index());
    let n = mocap.len();
    let planted = |i: usize| {
        let j = if i > 0 { i - 1 } else { 1 };
        let moved = |c: usize| flat(mocap[i][c] - mocap[j][c]).length();
        let touch = support.touch[f].get(i).is_some_and(|g| g.is_some());
        touch && moved(a).min(moved(t)) < still
    };
    let mut out = Vec::new();
    let mut start: Option<usize> = None;
    for i in 0..=n {
        match (i < n && planted(i), start) {
            (true, None) => start = Some(i),
            (false, Some(s)) => {
                if i - s >= MIN_FRAMES {
                    out.push((s, i - 1));
                }
                start = None;
            }
            _ => {}
        }
    }
    out
}

/// Moves each pose of `out` horizontally so that the character's hips'
/// midpoint follows the clip's (`mocap`'s) scaled by `k`, from where it
/// is at the first frame. The footfalls' targets are the clip's feet
/// scaled, held still in the world, so the body they are reached from
/// must be carried by a point every rig puts alike (the thighs' heads),
/// not by the root, which a rig puts anywhere in the pelvis: carried by
/// a root moved 11 % of the leg up and 5 % back, the body swayed about
/// the held feet with the pelvis's turns and the result's posture
/// differed by 0.065 % of the height (session 38). With the hips placed
/// so already ([`Anchor::Hips`](super::Anchor::Hips)) nothing moves.
fn carry_by_hips(mocap: &[Pose], k: f64, out: &mut [(Pose, [DQuat; Canonical::COUNT])]) {
    let hips = |p: &Pose| flat(0.5 * (p[LEGS[0][0].index()] + p[LEGS[1][0].index()]));
    let Some(first) = out.first().map(|(t, _)| hips(t) - k * hips(&mocap[0])) else {
        return;
    };
    for (m, (t, _)) in mocap.iter().zip(out.iter_mut()) {
        let d = first - (hips(t) - k * hips(m));
        if !d.is_finite() {
            continue;
        }
        for p in t.iter_mut() {
            *p += d;
        }
    }
}

/// Per frame, the horizontal offset of foot `f`'s ankle from where the
/// limbs put it (`out`) to its target: in a footfall (`plants`), the
/// clip's ankle scaled by `k` plus the footfall's mean offset of the
/// character's hip from the clip's, scaled; between footfalls eased from
/// one's to the next's; held before the first and after the last; zero
/// everywhere for a foot with none. Held on the ankle, not on the toe
/// from heel-off (measured, session 39: the toe held while the heel
/// rises slid the surface's feet more, Bandai Namco's walk 0.348 → 0.617
/// cm/frame on samba, its knees straightened up to 4.5° past straight).
fn ankle_offsets(
    mocap: &[Pose],
    out: &[(Pose, [DQuat; Canonical::COUNT])],
    f: usize,
    plants: &[Plant],
    k: f64,
) -> Vec<DVec3> {
    let n = mocap.len();
    let [h, _, a, _] = LEGS[f].map(|c| c.index());
    let mut o = vec![DVec3::ZERO; n];
    for &(s, e) in plants {
        let hip = (s..=e)
            .map(|i| flat(out[i].0[h] - k * mocap[i][h]))
            .sum::<DVec3>()
            / (e + 1 - s) as f64;
        for (i, oi) in o.iter_mut().enumerate().take(e + 1).skip(s) {
            let d = flat(k * mocap[i][a] + hip - out[i].0[a]);
            *oi = if d.is_finite() { d } else { DVec3::ZERO };
        }
    }
    let (Some(&(first, _)), Some(&(_, last))) = (plants.first(), plants.last()) else {
        return o;
    };
    let (o0, o1) = (o[first], o[last]);
    o[..first].fill(o0);
    o[last + 1..].fill(o1);
    for w in plants.windows(2) {
        let ((_, b), (c, _)) = (w[0], w[1]);
        let (from, to) = (o[b], o[c]);
        for (i, oi) in o.iter_mut().enumerate().take(c).skip(b + 1) {
            let x = (i - b) as f64 / (c - b) as f64;
            *oi = from + (to - from) * (x * x * (3.0 - 2.0 * x));
        }
    }
    o
}

/// Per frame, the least horizontal shift of the body that puts each
/// planted foot's goal within [`REACH`] of its leg's length (or the
/// posed leg's hip → ankle, if longer) from its hip: four rounds of
/// projection onto each planted foot's reachable disc.
fn body_shifts(
    out: &[(Pose, [DQuat; Canonical::COUNT])],
    goals: &[Vec<DVec3>; 2],
    planted: &[Vec<bool>; 2],
) -> Vec<DVec3> {
    out.iter()
        .enumerate()
        .map(|(i, (t, _))| {
            let mut d = DVec3::ZERO;
            for _ in 0..4 {
                for f in 0..2 {
                    if !planted[f][i] {
                        continue;
                    }
                    let [h, k, a, _] = LEGS[f].map(|c| c.index());
                    let length = t[h].distance(t[k]) + t[k].distance(t[a]);
                    let r = (REACH * length).max(t[h].distance(t[a]));
                    let to = goals[f][i] - (t[h] + d);
                    let across = r * r - to.y * to.y;
                    let level = flat(to);
                    let far = level.length();
                    if across <= 0.0 || !far.is_finite() {
                        continue;
                    }
                    let most = across.sqrt();
                    if far > most {
                        d += level * ((far - most) / far);
                    }
                }
            }
            d
        })
        .collect()
}

/// `d` averaged over ±[`SMOOTH`] frames with triangular weights (fewer
/// at the ends).
fn smoothed(d: &[DVec3]) -> Vec<DVec3> {
    let n = d.len();
    (0..n)
        .map(|i| {
            let (lo, hi) = (i.saturating_sub(SMOOTH), (i + SMOOTH).min(n - 1));
            let (mut sum, mut w) = (DVec3::ZERO, 0.0);
            for (j, v) in d.iter().enumerate().take(hi + 1).skip(lo) {
                let x = (SMOOTH + 1 - i.abs_diff(j)) as f64;
                sum += x * *v;
                w += x;
            }
            sum / w
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::Canonical as C;

    /// A clip whose left foot stands at x = 0 (frames 0-4), swings, and
    /// stands at x = 1 (frames 10-14), its hips over x = 0.5 t / 14; and
    /// the character's poses: the same at `k` = 1.2 but with strides 5 %
    /// short (the limbs' directions), its hips where `k` carries them.
    fn clip_and_character() -> (Vec<Pose>, Vec<(Pose, [DQuat; Canonical::COUNT])>) {
        let k = 1.2;
        let foot = |i: usize| match i {
            0..=4 => 0.0,
            10..=14 => 1.0,
            _ => (i as f64 - 4.0) / 6.0,
        };
        let clip: Vec<Pose> = (0..15)
            .map(|i| {
                let mut p = [DVec3::ZERO; Canonical::COUNT];
                p[C::LHip.index()] = DVec3::new(0.5 * i as f64 / 14.0, 0.9, 0.1);
                p[C::LAnkle.index()] = DVec3::new(foot(i), 0.08, 0.1);
                p
            })
            .collect();
        let out = clip
            .iter()
            .map(|p| {
                let mut t = p.map(|x| k * x);
                let h = t[C::LHip.index()];
                t[C::LAnkle.index()] = h + 0.95 * (t[C::LAnkle.index()] - h);
                (t, [DQuat::IDENTITY; Canonical::COUNT])
            })
            .collect();
        (clip, out)
    }

    #[test]
    fn a_planted_foot_is_held_where_the_scaled_clip_holds_it_and_eases_between() {
        let (clip, out) = clip_and_character();
        let o = ankle_offsets(&clip, &out, 0, &[(0, 4), (10, 14)], 1.2);
        let a = C::LAnkle.index();
        let at = |i: usize| out[i].0[a] + o[i];
        for (plant, x) in [(0..=4, 0.0), (10..=14, 1.2)] {
            for i in plant {
                // The scaled clip's ankle, on the character's hip side.
                assert!((at(i).x - x).abs() < 1e-9, "frame {i}: {}", at(i));
                assert!((at(i).z - 0.12).abs() < 1e-9 && o[i].y == 0.0);
            }
        }
        // Between, the offset eases from one footfall's to the next's.
        let along: Vec<f64> = (4..=10).map(|i| o[i].x).collect();
        assert!(
            along
                .windows(2)
                .all(|w| (w[1] - w[0]) * (along[6] - along[0]) >= 0.0)
        );
        // A foot with no footfall keeps its place.
        assert!(
            ankle_offsets(&clip, &out, 0, &[], 1.2)
                .iter()
                .all(|v| *v == DVec3::ZERO)
        );
    }

    #[test]
    fn smoothing_keeps_a_constant_and_stays_level() {
        let o = vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::X,
            DVec3::ZERO,
            DVec3::ZERO,
            DVec3::ZERO,
            DVec3::Z,
            DVec3::Z,
            DVec3::ZERO,
        ];
        let s = smoothed(&o);
        assert_eq!(s.len(), o.len());
        assert!(s.iter().all(|v| v.is_finite() && v.y == 0.0));
        let flat_line = smoothed(&[DVec3::X; 12]);
        assert!(flat_line.iter().all(|v| v.distance(DVec3::X) < 1e-12));
    }
}
