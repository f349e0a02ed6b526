//! The root's height taken from the legs, for a clip whose root carries
//! no vertical motion.
//!
//! Some conversions drop the root's vertical channel: CMU 02_03's BVH on
//! the Reallusion CC rig keeps its hips at one height (0.000 m of bounce,
//! the AMC it came from rises and falls 0.151 m a stride), so the legs
//! bend under a body that stays put and the feet rise off the floor with
//! every bent knee. Such a clip is stood on its feet again: in every frame
//! a foot is planted, the body is put where the planted foot's leg
//! reaches the ground; between such frames (a run's flight) the height is
//! interpolated.

use super::reference::leg_length;
use crate::pose::Pose;
use crate::rig::Canonical;

use Canonical as C;

/// The feet's joints (ankle, toe) per foot, left then right.
const FEET: [(C, C); 2] = [(C::LAnkle, C::LToe), (C::RAnkle, C::RToe)];

/// `mocap` (metres, Y up) with its root's height taken from its legs when
/// the root carries no vertical motion (the pelvis's height over the clip
/// varies by less than 0.1 mm per metre of leg) while the legs move the
/// feet up and down under it (the lowest foot joint's height below the
/// pelvis varies by more than 5 % of the leg's length); `None` when the
/// rule does not apply (the clip is then used as it is).
///
/// A foot is planted in a frame when its ankle or its toe joint moves
/// less than 2 % of the leg's length horizontally from the frame before
/// (the first frame: to the next); its vertical motion is the root's
/// missing one and says nothing. In a frame with a planted foot the pose
/// is moved up or down so that the lowest joint of its planted feet
/// stands on the floor (the lowest foot joint of the clip as given, over
/// all frames); across frames with none the move is interpolated
/// linearly, and held before the first and after the last.
pub(super) fn root_from_legs(mocap: &[Pose]) -> Option<Vec<Pose>> {
    if mocap.len() < 3 || !mocap.iter().all(|p| p.iter().all(|x| x.is_finite())) {
        return None;
    }
    let root = C::Pelvis.index();
    let leg = leg_length(&mocap[mocap.len() / 2]);
    if leg.is_nan() || leg <= 0.0 {
        return None;
    }
    let span = |v: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), y| {
            (l.min(y), h.max(y))
        });
        hi - lo
    };
    if span(&mut mocap.iter().map(|p| p[root].y)) > 1e-4 * leg {
        return None;
    }
    let low = |p: &Pose, feet: &[(C, C)]| {
        feet.iter()
            .flat_map(|(a, t)| [p[a.index()].y, p[t.index()].y])
            .fold(f64::INFINITY, f64::min)
    };
    if span(&mut mocap.iter().map(|p| low(p, &FEET) - p[root].y)) <= 0.05 * leg {
        return None;
    }
    let floor = mocap
        .iter()
        .map(|p| low(p, &FEET))
        .fold(f64::INFINITY, f64::min);
    let still = 0.02 * leg;
    let flat = |v: glam::DVec3| glam::DVec2::new(v.x, v.z);
    let lift: Vec<Option<f64>> = (0..mocap.len())
        .map(|i| {
            let j = if i > 0 { i - 1 } else { 1 };
            let planted: Vec<(C, C)> = FEET
                .into_iter()
                .filter(|(a, t)| {
                    let moved =
                        |c: &C| flat(mocap[i][c.index()]).distance(flat(mocap[j][c.index()]));
                    moved(a).min(moved(t)) < still
                })
                .collect();
            (!planted.is_empty()).then(|| floor - low(&mocap[i], &planted))
        })
        .collect();
    let known: Vec<usize> = (0..lift.len()).filter(|&i| lift[i].is_some()).collect();
    let (&a, &b) = (known.first()?, known.last()?);
    let mut out = mocap.to_vec();
    let mut k = 0;
    for (i, p) in out.iter_mut().enumerate() {
        let d = match lift[i] {
            Some(d) => d,
            None if i < a => lift[a]?,
            None if i > b => lift[b]?,
            None => {
                while known[k + 1] < i {
                    k += 1;
                }
                let (i0, i1) = (known[k], known[k + 1]);
                let (d0, d1) = (lift[i0]?, lift[i1]?);
                d0 + (d1 - d0) * (i - i0) as f64 / (i1 - i0) as f64
            }
        };
        for x in p.iter_mut() {
            x.y += d;
        }
    }
    Some(out)
}
