//! Resampling a clip to another frame rate: slerp of local rotations (shortest
//! arc), lerp of translations, at times `k / fps` within the clip's duration.

use super::clip::Clip;

/// How far past the clip's end (in output frames) the last sample may fall
/// and still count: a `Frame Time` printed with few digits (0.0333333 for
/// 1/30) shortens the duration by a hair, which must not drop the last
/// frame (issue 18, item 17).
const END_SLACK: f64 = 0.01;

/// Bytes one frame of a clip holds per joint (a quaternion and a
/// translation, f64).
pub(crate) const CLIP_BYTES_PER_JOINT: u128 = 32 + 24;

impl Clip {
    /// Frames of the clip resampled to `fps` (no allocation): the first
    /// frame, then one per `1/fps` up to the clip's end. `None` if `fps` is
    /// not a positive finite number.
    pub(crate) fn resampled_frame_count(&self, fps: f64) -> Option<u128> {
        if !(fps.is_finite() && fps > 0.0) {
            return None;
        }
        let k = (self.duration() * fps + END_SLACK).floor();
        // Saturates instead of wrapping (a Frame Time of 1e300 once gave
        // "no frames").
        Some(if k.is_finite() && k < 1e30 {
            k as u128 + 1
        } else {
            u128::MAX
        })
    }

    /// [`Clip::resampled`] after checking that the result fits the memory
    /// budget ([`crate::util::budget`]).
    pub fn try_resampled(&self, fps: f64) -> Result<Clip, crate::util::budget::OverBudget> {
        let frames = self.resampled_frame_count(fps).unwrap_or(0);
        let joints = self.joint_count() as u128;
        crate::util::budget::check(
            || {
                format!(
                    "{:.3} s of motion at {fps} fps ({} frames of {} joints)",
                    self.duration(),
                    crate::util::budget::thousands(frames),
                    joints
                )
            },
            frames.saturating_mul(joints.max(1) * CLIP_BYTES_PER_JOINT),
        )?;
        Ok(self.resampled(fps))
    }

    /// The clip resampled to `fps` frames per second. The first frame is kept;
    /// the last output frame is the last sample time not past the clip's end
    /// (within 1 % of an output frame). Returns a copy unchanged if `fps` is
    /// not a positive finite number. Allocates frames × joints: check
    /// [`Clip::resampled_frame_count`] first, or use [`Clip::try_resampled`].
    pub fn resampled(&self, fps: f64) -> Clip {
        let Some(out_frames) = self.resampled_frame_count(fps) else {
            return self.clone();
        };
        let out_frames = usize::try_from(out_frames).unwrap_or(usize::MAX);
        let n = self.joint_count();
        let src = self.frame_count();
        let dt = 1.0 / fps;
        let mut rotations = Vec::with_capacity(out_frames.saturating_mul(n));
        let mut translations = Vec::with_capacity(out_frames.saturating_mul(n));
        for k in 0..out_frames {
            let s = (k as f64 * dt / self.frame_time).min((src - 1) as f64);
            let i0 = s.floor() as usize;
            let i1 = (i0 + 1).min(src - 1);
            let a = s - i0 as f64;
            let (q0, q1) = (self.frame_rotations(i0), self.frame_rotations(i1));
            let (t0, t1) = (self.frame_translations(i0), self.frame_translations(i1));
            for j in 0..n {
                let (qa, mut qb) = (q0[j], q1[j]);
                if qa.dot(qb) < 0.0 {
                    qb = -qb;
                }
                rotations.push(if a == 0.0 {
                    qa
                } else {
                    qa.slerp(qb, a).normalize()
                });
                translations.push(t0[j].lerp(t1[j], a));
            }
        }
        let mut out = self.clone();
        out.rotations = rotations;
        out.translations = translations;
        out.frame_time = dt;
        out
    }
}

#[cfg(test)]
mod tests {
    use crate::mocap::bvh::{BvhOptions, parse_bvh};
    use std::path::Path;

    const CLIP: &str = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\nJOINT B\n{\nOFFSET 1 0 0\nCHANNELS 3 Zrotation Yrotation Xrotation\nEnd Site\n{\nOFFSET 1 0 0\n}\n}\n}\nMOTION\nFrames: 3\nFrame Time: 0.1\n0 0 0 0 0 0 0 0 0\n1 0 0 0 0 0 90 0 0\n2 0 0 0 0 0 0 0 0\n";

    #[test]
    fn doubling_the_rate_interpolates_midpoints() {
        let c = parse_bvh(CLIP, Path::new("c.bvh"), &BvhOptions::default()).unwrap();
        let r = c.resampled(20.0);
        assert_eq!(r.frame_count(), 5);
        assert!((r.frame_translations(1)[0].x - 0.5).abs() < 1e-12);
        let p = r.world_positions(1);
        // Joint B rotated 45° at the midpoint of 0° and 90°.
        let ang = r.frame_rotations(1)[1]
            .angle_between(glam::DQuat::IDENTITY)
            .to_degrees();
        assert!((ang - 45.0).abs() < 1e-9, "{ang} {p:?}");
        // Same rate is the identity.
        let s = c.resampled(10.0);
        assert_eq!(s.frame_count(), 3);
        for (a, b) in s.rotations.iter().zip(&c.rotations) {
            assert!(a.dot(*b).abs() > 1.0 - 1e-12);
        }
    }

    #[test]
    fn a_rounded_frame_time_keeps_the_last_frame() {
        // 60 frames at "Frame Time: 0.0333333" resampled to 30 fps: 60, not 59.
        let mut text = String::from(CLIP).replace("Frames: 3", "Frames: 60");
        text = text.replace("Frame Time: 0.1", "Frame Time: 0.0333333");
        let motion = text
            .split("0 0 0 0 0 0 0 0 0\n")
            .next()
            .unwrap()
            .to_string();
        let mut t = motion;
        for k in 0..60 {
            t.push_str(&format!("{k} 0 0 0 0 0 0 0 0\n"));
        }
        let c = parse_bvh(&t, Path::new("c.bvh"), &BvhOptions::default()).unwrap();
        assert_eq!(c.frame_count(), 60);
        assert_eq!(c.resampled(30.0).frame_count(), 60);
        // 120 fps to 30: the last sample not past the end.
        assert_eq!(c.resampled_frame_count(15.0), Some(30));
    }

    #[test]
    fn absurd_rates_saturate_instead_of_wrapping() {
        let mut c = parse_bvh(CLIP, Path::new("c.bvh"), &BvhOptions::default()).unwrap();
        c.frame_time = 1e300;
        assert_eq!(c.resampled_frame_count(30.0), Some(u128::MAX));
        assert!(c.try_resampled(30.0).is_err());
    }
}
