//! Resampling a clip to another frame rate: slerp of local rotations (shortest
//! arc), lerp of translations, at times `k / fps` within the clip's duration.

use super::clip::Clip;

impl Clip {
    /// The clip resampled to `fps` frames per second. The first frame is kept;
    /// the last output frame is the last sample time not past the clip's end.
    /// Returns a copy unchanged if `fps` is not a positive finite number.
    pub fn resampled(&self, fps: f64) -> Clip {
        if !(fps.is_finite() && fps > 0.0) {
            return self.clone();
        }
        let n = self.joint_count();
        let src = self.frame_count();
        let dt = 1.0 / fps;
        let dur = self.duration();
        let out_frames = ((dur / dt) + 1e-9).floor() as usize + 1;
        let mut rotations = Vec::with_capacity(out_frames * n);
        let mut translations = Vec::with_capacity(out_frames * n);
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
}
