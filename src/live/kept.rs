//! The levelling and the floor a live session decides once and keeps
//! (issue 45, fidelity): offline the pose kernel levels the clip's ground
//! ([`ground_tilt`]) and finds its floor ([`clip_floor`]) over the whole
//! clip; a live window decided both anew for every frame, and each new
//! decision moved the frames already output (CMU 03_02 on samba, lag 3:
//! the offline levelling alone took the output's joint-velocity error
//! against offline 0.606 → 0.418 cm/frame, the floor then 0.305;
//! `live::decompose`).
//!
//! [`KeptGround`] decides them over the window once the stream has
//! [`KeptGround::after`] frames and a frame has been output, then keeps
//! them until the evidence contradicts the floor: the window's own floor
//! (the 5th percentile of its lowest foot joints, in the kept levelling)
//! more than the contact band (3.6 % of the clip's leg) from the kept one
//! — the feet have stood lower than the kept floor in at least one frame
//! in twenty (a stream that started on a block, CMU 03_01, has stepped
//! down onto the floor), or none has come within the band of it in
//! nineteen out of twenty (the ground rose: a sloping floor, CMU 02_02's
//! 8 cm over 4 m, or a platform walked onto). Then both are decided again
//! over the window. Memory: one rotation and one height.

use crate::pose::Pose;
use crate::pose::retarget::{clip_floor, ground_tilt};
use glam::DQuat;

/// The levelling and floor kept for a stream.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct KeptGround {
    /// Frames the stream must have before the levelling and floor are
    /// decided (the window's own decide until then).
    pub after: usize,
    kept: Option<(DQuat, f64)>,
    /// Times the evidence made the floor be decided again.
    pub redecided: usize,
}

impl KeptGround {
    /// Nothing decided yet; deciding once the stream has `after` frames.
    pub fn new(after: usize) -> Self {
        KeptGround {
            after,
            kept: None,
            redecided: 0,
        }
    }

    /// The levelling and floor (the levelled window's height, metres) to
    /// stand the raw `window` (its newest frame last) on, the stream
    /// having `seen` frames, the contact band being `band` (the clip's
    /// metres): `None` (the kernel decides over the window) while `free`
    /// (no frame output yet: a lag covering the stream keeps the offline
    /// result bit for bit) or before `after` frames; else the kept ones,
    /// decided over the window the first time and again when the
    /// window's own floor in the kept levelling is more than `band` from
    /// the kept floor.
    pub fn update(
        &mut self,
        window: &[Pose],
        seen: usize,
        free: bool,
        band: f64,
    ) -> Option<(DQuat, f64)> {
        if free || seen < self.after.max(1) || window.is_empty() {
            return None;
        }
        let floor_in = |tilt: DQuat| {
            let levelled: Vec<Pose> = window.iter().map(|m| m.map(|p| tilt * p)).collect();
            clip_floor(&levelled)
        };
        match self.kept {
            Some((tilt, floor)) if (floor_in(tilt) - floor).abs() <= band => {}
            was => {
                let tilt = ground_tilt(window);
                self.kept = Some((tilt, floor_in(tilt)));
                self.redecided += usize::from(was.is_some());
            }
        }
        self.kept
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::Canonical as C;
    use glam::DVec3;

    /// A pose at `x` with its foot joints at height `y` (the rest at 1 m).
    fn standing(x: f64, y: f64) -> Pose {
        let mut p = [DVec3::new(x, 1.0, 0.0); C::COUNT];
        for c in [C::LAnkle, C::LToe, C::RAnkle, C::RToe] {
            p[c.index()] = DVec3::new(x, y, 0.0);
        }
        p
    }

    /// `n` frames standing in place (no slope to level) at height `y`.
    fn walk(n: usize, y: f64) -> Vec<Pose> {
        vec![standing(0.0, y); n]
    }

    #[test]
    fn decided_once_then_kept_until_the_feet_stand_off_it() {
        let mut k = KeptGround::new(20);
        let band = 0.03;
        // Free, or too few frames: the window decides.
        assert_eq!(k.update(&walk(30, 0.25), 30, true, band), None);
        assert_eq!(k.update(&walk(10, 0.25), 10, false, band), None);
        // Decided over the window (a block 25 cm up taken for the floor).
        let (_, f) = k.update(&walk(30, 0.25), 30, false, band).unwrap();
        assert!((f - 0.25).abs() < 1e-9, "{f}");
        // A frame in twenty 1 cm lower: within the band, kept.
        let mut w = walk(40, 0.25);
        w.extend(walk(2, 0.24));
        assert!((k.update(&w, 42, false, band).unwrap().1 - 0.25).abs() < 1e-9);
        assert_eq!(k.redecided, 0);
        // Stepped down 20 cm for three frames of forty-three: decided again.
        w.extend(walk(3, 0.05));
        let (_, f) = k.update(&w[2..], 45, false, band).unwrap();
        assert!((f - 0.05).abs() < 1e-9, "{f}");
        assert_eq!(k.redecided, 1);
        // The ground rising 5 cm under every frame: decided again.
        let (_, f) = k.update(&walk(40, 0.10), 85, false, band).unwrap();
        assert!((f - 0.10).abs() < 1e-9, "{f}");
        assert_eq!(k.redecided, 2);
    }
}
