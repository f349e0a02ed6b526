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
use crate::embed::parts::Part;
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

/// Foot sliding of a skeletal clip (centimetres per frame), measured on its
/// toe and ankle joints.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct ClipSliding {
    /// Joint-frames in contact (toe and ankle of both feet counted).
    pub contact_frames: usize,
    /// Median horizontal travel per contact frame (cm/frame).
    pub median_cm_per_frame: f64,
    /// 95th percentile of the horizontal travel per contact frame (cm/frame).
    pub p95_cm_per_frame: f64,
    /// Mean horizontal travel per contact frame (cm/frame).
    pub mean_cm_per_frame: f64,
}

/// Sliding of a clip's feet: each of the `tracks` (a foot joint's world
/// positions per frame, in metres) is in contact at frame `t` when it is
/// within `opts.contact_height` of its own lowest height (5th percentile
/// along `up`) at both `t−1` and `t`, at any speed; its sliding is then its
/// horizontal travel from `t−1` to `t`, against the ground (world space),
/// not the body. `fps` rescales the travel to 30 frames per second, so
/// clips at 120 fps read per 1/30 s. A planted foot reads ~0 (CMU and
/// Bandai walks: ~0.1-0.3 cm/frame median); a foot skating along the floor
/// reads its speed.
pub fn track_sliding(
    tracks: &[Vec<DVec3>],
    up: DVec3,
    fps: f64,
    opts: &FootOptions,
) -> ClipSliding {
    let up = up.normalize_or(DVec3::Y);
    let scale = if fps.is_finite() && fps > 0.0 {
        fps / 30.0
    } else {
        1.0
    };
    let mut steps = Vec::new();
    for track in tracks {
        let mut h: Vec<f64> = track
            .iter()
            .map(|p| p.dot(up))
            .filter(|h| h.is_finite())
            .collect();
        if h.len() < 2 {
            continue;
        }
        h.sort_by(f64::total_cmp);
        let low = h[(h.len() - 1) * 5 / 100];
        let touch = |p: DVec3| p.dot(up) - low <= opts.contact_height;
        for w in track.windows(2) {
            if touch(w[0]) && touch(w[1]) {
                let d = w[1] - w[0];
                let d = (d - up * d.dot(up)).length();
                if d.is_finite() {
                    steps.push(100.0 * d * scale);
                }
            }
        }
    }
    if steps.is_empty() {
        return ClipSliding::default();
    }
    let mean = steps.iter().sum::<f64>() / steps.len() as f64;
    steps.sort_by(f64::total_cmp);
    let at = |q: f64| steps[((steps.len() - 1) as f64 * q).round() as usize];
    ClipSliding {
        contact_frames: steps.len(),
        median_cm_per_frame: at(0.5),
        p95_cm_per_frame: at(0.95),
        mean_cm_per_frame: mean,
    }
}

/// [`track_sliding`] on a clip's toe and ankle joints (found with
/// [`crate::rig::detect_clip`]), in metres and the clip's up.
pub fn clip_sliding(
    clip: &crate::mocap::Clip,
    opts: &FootOptions,
) -> Result<ClipSliding, crate::rig::RigError> {
    use crate::rig::Canonical as C;
    let det = crate::rig::detect_clip(clip)?;
    let ids: Vec<usize> = [C::LAnkle, C::LToe, C::RAnkle, C::RToe]
        .iter()
        .filter_map(|k| det.map.joints.get(k))
        .filter_map(|name| clip.joint(name))
        .map(|j| j.idx())
        .collect();
    let m = clip.units.metres_per_unit;
    let up = match clip.up {
        crate::mocap::UpAxis::Y => DVec3::Y,
        crate::mocap::UpAxis::Z => DVec3::Z,
    };
    let mut tracks = vec![Vec::with_capacity(clip.frame_count()); ids.len()];
    for f in 0..clip.frame_count() {
        let p = clip.world_positions(f);
        for (tr, &j) in tracks.iter_mut().zip(&ids) {
            tr.push(p.get(j).copied().unwrap_or(DVec3::NAN) * m);
        }
    }
    Ok(track_sliding(&tracks, up, clip.fps(), opts))
}
