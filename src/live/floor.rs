//! The live session's running floor (issue 45, fidelity): the floor the
//! pose kernel stands each analysis window on, carried from one window to
//! the next instead of found anew in each.
//!
//! Offline the kernel's floor is the 5th percentile of the clip's lowest
//! (levelled) foot joint; a window of a few seconds found it a few
//! millimetres apart from one frame to the next (samba 131_02, frame 53:
//! 5.03 vs the clip's 5.68 cm), and a foot touches within 3 cm of it, so
//! contacts and the body's lift changed from frame to frame.
//! [`RunningFloor`] follows the window's own floor but moves by at most
//! [`RunningFloor::step`] a frame once frames are being output, carried
//! across the change of levelling between windows at the newest frame's
//! feet (a sloped floor, CMU 02_02's 8 cm over 4 m, is levelled by each
//! window's own tilt: a percentile over every frame seen, as heights,
//! took the lowest stretch of the slope and raised 02_02's live velocity
//! error at lag 3 from 0.265 to 0.463 cm/frame). Memory: one height and
//! one rotation.

use crate::pose::Pose;
use crate::pose::retarget::{clip_floor, ground_tilt};
use crate::rig::Canonical as C;
use glam::{DQuat, DVec3};

/// A running estimate of a stream's floor in each window's levelling.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RunningFloor {
    /// The estimate and the levelling it is a height in.
    held: Option<(f64, DQuat)>,
    /// The most the estimate moves per frame once it is held (metres).
    pub step: f64,
}

impl RunningFloor {
    /// No estimate yet; moving at most `step` metres a frame once held.
    pub fn new(step: f64) -> Self {
        RunningFloor { held: None, step }
    }

    /// The floor for the raw `window` (its newest frame last), levelled
    /// as the kernel levels it ([`ground_tilt`]): its own floor
    /// ([`clip_floor`]) while `free` (no frame output yet: nothing stood
    /// on the estimate) or before any estimate; else the estimate carried
    /// into this window's levelling and moved towards the window's floor
    /// by at most `step`. `None` for an empty window.
    pub fn update(&mut self, window: &[Pose], free: bool) -> Option<f64> {
        let newest = window.last()?;
        let tilt = ground_tilt(window);
        let levelled: Vec<Pose> = window.iter().map(|m| m.map(|p| tilt * p)).collect();
        let target = clip_floor(&levelled);
        let e = match self.held {
            Some((e, was)) if !free => {
                let c = carried(e, was, tilt, newest);
                c + (target - c).clamp(-self.step, self.step)
            }
            _ => target,
        };
        self.held = Some((e, tilt));
        Some(e)
    }
}

/// The height `e` of levelling `was` in levelling `now`, at the newest
/// frame's lowest foot joint (the floor plane's point under it).
fn carried(e: f64, was: DQuat, now: DQuat, newest: &Pose) -> f64 {
    let low = [C::LAnkle, C::LToe, C::RAnkle, C::RToe]
        .iter()
        .map(|c| newest[c.index()])
        .filter(|p| p.is_finite())
        .min_by(|a, b| a.y.total_cmp(&b.y));
    let Some(low) = low else {
        return e;
    };
    let p = was * low;
    let on_floor = was.inverse() * DVec3::new(p.x, e, p.z);
    let c = (now * on_floor).y;
    if c.is_finite() { c } else { e }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::Canonical;

    /// A pose with its foot joints at height `y` (the rest at 1 m).
    fn standing(x: f64, y: f64) -> Pose {
        let mut p = [DVec3::new(x, 1.0, 0.0); Canonical::COUNT];
        for c in [C::LAnkle, C::LToe, C::RAnkle, C::RToe] {
            p[c.index()] = DVec3::new(x, y, 0.0);
        }
        p
    }

    #[test]
    fn the_estimate_is_the_window_floor_when_free_and_moves_by_at_most_a_step() {
        let mut f = RunningFloor::new(0.0005);
        let mut w: Vec<Pose> = (0..20).map(|i| standing(0.01 * i as f64, 0.05)).collect();
        assert_eq!(f.update(&w, true), Some(0.05));
        // The window's floor drops 1 cm: the held estimate follows 0.5 mm.
        w = (0..20).map(|i| standing(0.01 * i as f64, 0.04)).collect();
        let e = f.update(&w, false).unwrap();
        assert!((e - 0.0495).abs() < 1e-12, "{e}");
        assert_eq!(f.update(&w, true), Some(0.04));
        assert_eq!(f.update(&[], false), None);
    }
}
