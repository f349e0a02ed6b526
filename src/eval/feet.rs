//! Foot sliding during contact ("foot skating"): the horizontal travel of a
//! foot's sole while it is on the floor.
//!
//! The sole of each foot is chosen once on the rest frame: the foot-part
//! vertices in the bottom `sole_band` of the foot's extent along up. A foot
//! is in contact at frame `t` when its lowest sole vertex is within
//! `contact_height` of the floor and its sole centroid moves slower than
//! `contact_speed` horizontally (backward difference; the first frame
//! uses the forward one). Sliding at `t` is the horizontal travel of the
//! sole centroid from `t−1` to `t` when the foot is in contact at both.
//! A planted foot reads ~0; a foot dragged along the floor slower than
//! `contact_speed` reads its speed per frame.

use super::EvalError;
use crate::rig::embed::parts::Part;
use glam::DVec3;
use serde::Serialize;

/// Options of [`Feet`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FootOptions {
    /// Share of each foot's extent along up that makes its sole. Default: 0.2.
    pub sole_band: f64,
    /// Height above the floor within which a sole touches it (metres).
    /// Default: 0.03.
    pub contact_height: f64,
    /// Horizontal speed below which a touching foot is in contact (m/s).
    /// Default: 0.5 (1.7 cm per frame at 30 fps; a walking swing foot moves
    /// 3-5 m/s).
    pub contact_speed: f64,
}

impl Default for FootOptions {
    fn default() -> Self {
        FootOptions {
            sole_band: 0.2,
            contact_height: 0.03,
            contact_speed: 0.5,
        }
    }
}

/// The soles of the two feet (left, right).
#[derive(Debug, Clone, PartialEq)]
pub struct Feet {
    /// Sole vertices of the left and right foot.
    pub soles: [Vec<u32>; 2],
}

/// Sliding of both feet over a sequence (centimetres).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Sliding {
    /// Foot-frames in contact (both feet counted).
    pub contact_frames: usize,
    /// Horizontal travel summed over contact frames (cm).
    pub total_cm: f64,
    /// Mean travel per contact frame (cm/frame).
    pub mean_cm_per_frame: f64,
    /// Largest travel in one contact frame (cm).
    pub max_cm_per_frame: f64,
    /// Foot-frames touching the floor (height test only, at any speed).
    pub touching_frames: usize,
    /// Mean travel per touching frame (cm/frame): sees a foot gliding
    /// faster than `contact_speed` (e.g. a held pose carried along a
    /// trajectory), which the contact test excludes.
    pub touching_mean_cm_per_frame: f64,
}

impl Feet {
    /// The soles on the rest frame `rest` (labels: [`Part::ALL`] indices).
    pub fn new(
        rest: &[[f64; 3]],
        labels: &[u8],
        up: DVec3,
        opts: &FootOptions,
    ) -> Result<Feet, EvalError> {
        if labels.len() != rest.len() {
            return Err(EvalError::Labels {
                have: labels.len(),
                want: rest.len(),
            });
        }
        let up = up.normalize_or(DVec3::Y);
        let sole = |part: Part| -> Result<Vec<u32>, EvalError> {
            let s = super::head::band(rest, labels, part, up, 0.0, opts.sole_band.clamp(1e-3, 1.0));
            if s.is_empty() {
                return Err(EvalError::MissingPart { part: part.name() });
            }
            Ok(s)
        };
        Ok(Feet {
            soles: [sole(Part::LFoot)?, sole(Part::RFoot)?],
        })
    }

    /// Sliding over `frames` (frame-major, `n` vertices each, in units of
    /// `metres_per_unit` metres) at `fps`, the floor at height `floor` along
    /// `up` (same units).
    #[allow(clippy::too_many_arguments)]
    pub fn sliding(
        &self,
        frames: &[[f64; 3]],
        n: usize,
        up: DVec3,
        floor: f64,
        fps: f64,
        metres_per_unit: f64,
        opts: &FootOptions,
    ) -> Sliding {
        self.sliding_on(frames, n, up, floor, [&[], &[]], fps, metres_per_unit, opts)
    }

    /// [`Feet::sliding`] on grounds raised by `raised[f][t]` metres above
    /// the floor under foot `f` (left, right) at frame `t` (a step the
    /// driving clip stands that foot on; frames past its end on the
    /// floor).
    #[allow(clippy::too_many_arguments)]
    pub fn sliding_on(
        &self,
        frames: &[[f64; 3]],
        n: usize,
        up: DVec3,
        floor: f64,
        raised: [&[f64]; 2],
        fps: f64,
        metres_per_unit: f64,
        opts: &FootOptions,
    ) -> Sliding {
        let m = metres_per_unit;
        let up = up.normalize_or(DVec3::Y);
        let count = frames.len() / n.max(1);
        let fps = if fps.is_finite() && fps > 0.0 {
            fps
        } else {
            30.0
        };
        let mut s = Sliding::default();
        let mut touching_cm = 0.0;
        for (sole, raised) in self.soles.iter().zip(raised) {
            let ground = |t: usize| floor * m + raised.get(t).copied().unwrap_or(0.0);
            // Horizontal centroid and lowest height per frame.
            let track: Vec<(DVec3, f64)> = (0..count)
                .map(|f| {
                    let p = &frames[f * n..(f + 1) * n];
                    let mut c = DVec3::ZERO;
                    let mut low = f64::INFINITY;
                    for &v in sole {
                        let q = DVec3::from_array(p[v as usize]);
                        c += q;
                        low = low.min(q.dot(up));
                    }
                    c /= sole.len() as f64;
                    ((c - up * c.dot(up)) * m, low * m)
                })
                .collect();
            let step = |t: usize| (track[t].0 - track[t - 1].0).length();
            let contact: Vec<bool> = (0..count)
                .map(|t| {
                    let d = if t > 0 {
                        step(t)
                    } else if count > 1 {
                        step(1)
                    } else {
                        0.0
                    };
                    track[t].1 - ground(t) <= opts.contact_height && d * fps <= opts.contact_speed
                })
                .collect();
            let touch = |t: usize| track[t].1 - ground(t) <= opts.contact_height;
            for t in 0..count {
                if touch(t) {
                    s.touching_frames += 1;
                    if t > 0 && touch(t - 1) {
                        touching_cm += 100.0 * step(t);
                    }
                }
                if contact[t] {
                    s.contact_frames += 1;
                }
                if t > 0 && contact[t] && contact[t - 1] {
                    let d = 100.0 * step(t);
                    s.total_cm += d;
                    s.max_cm_per_frame = s.max_cm_per_frame.max(d);
                }
            }
        }
        s.mean_cm_per_frame = s.total_cm / s.contact_frames.max(1) as f64;
        s.touching_mean_cm_per_frame = touching_cm / s.touching_frames.max(1) as f64;
        s
    }
}
