//! Foot sliding during contact ("foot skating"): the horizontal travel of a
//! foot's sole while it is on the floor.
//!
//! The sole of each foot is chosen once on the rest frame: the foot-part
//! vertices in the bottom `sole_band` of the foot's extent along up; its two
//! ends (heel and toe, in either order) are the thirds of the sole at either
//! end of its long horizontal axis. A foot is in contact at frame `t` when
//! it stands on the ground, in either of two ways (issue 39 item 3):
//!
//! - **flat on it, at any speed**: the lowest vertex of each of its two
//!   ends is within `flat_height` of the ground. A foot dragged or carried
//!   along the floor is flat on it, and reads its speed;
//! - **touching it and held**: its lowest sole vertex is within
//!   `contact_height` of the ground and its sole centroid moves slower
//!   than `contact_speed` horizontally (backward difference; the first
//!   frame uses the forward one): a heel strike, a toe pivot.
//!
//! A swing foot passes the floor tilted, heel or toe first, its other end
//! up: on ten CMU and Bandai walks and runs retargeted onto the samba
//! capture, 528 of the 654 foot-frames that moved faster than 1.5 cm per
//! frame with their lowest point within 1 cm of the floor had the other
//! end more than 8 cm up, while walks dragged along the floor had both
//! ends within 3 cm in every such frame. Contact by height alone (at any
//! speed) counted those swing frames and read 2.7-4.1 cm per frame on
//! the seven walks (1.1-5.2 on the three runs) against the capture's
//! own 1.02; by this rule they read
//! 0.21-0.54 against the capture's 0.31 (0.21-0.43 against 0.29 before,
//! when contact needed the foot slower than `contact_speed`), and a walk
//! dragged along the floor reads its speed.
//!
//! Sliding at `t` is the horizontal travel of the sole centroid from `t−1`
//! to `t` when the foot is in contact at both, against the ground, not the
//! body. A planted foot reads ~0.

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
    /// 3-5 m/s). A foot flat on the floor is in contact at any speed.
    pub contact_speed: f64,
    /// Height above the floor within which both ends of a sole (heel and
    /// toe) stand for the foot to be flat on it, in contact at any speed
    /// (metres). Default: 0.02 (measuring the ten walks and runs above
    /// with 0.03, Bandai's happy run onto samba read 1.3 cm per contact
    /// frame against the capture's 0.3, its swing feet skimming the floor
    /// nearly flat).
    pub flat_height: f64,
}

impl Default for FootOptions {
    fn default() -> Self {
        FootOptions {
            sole_band: 0.2,
            contact_height: 0.03,
            contact_speed: 0.5,
            flat_height: 0.02,
        }
    }
}

/// The soles of the two feet (left, right).
#[derive(Debug, Clone, PartialEq)]
pub struct Feet {
    /// Sole vertices of the left and right foot.
    pub soles: [Vec<u32>; 2],
    /// The two ends of each sole (left, right; each its two ends, heel and
    /// toe in either order): the sole vertices in the first and the last
    /// third of its extent along its long horizontal axis on the rest
    /// frame ([`sole_ends`]).
    pub ends: [[Vec<u32>; 2]; 2],
}

/// Sliding of both feet over a sequence (centimetres).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
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
        let soles = [sole(Part::LFoot)?, sole(Part::RFoot)?];
        let ends = [
            sole_ends(rest, &soles[0], up),
            sole_ends(rest, &soles[1], up),
        ];
        Ok(Feet { soles, ends })
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
    pub(crate) fn sliding_on(
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
        for ((sole, ends), raised) in self.soles.iter().zip(&self.ends).zip(raised) {
            let ground = |t: usize| floor * m + raised.get(t).copied().unwrap_or(0.0);
            // Per frame, the higher of the two ends' lowest heights: the
            // sole is flat on the ground when it is within `flat_height`.
            let flat: Vec<bool> = (0..count)
                .map(|f| {
                    let p = &frames[f * n..(f + 1) * n];
                    let low = |e: &[u32]| {
                        e.iter()
                            .map(|&v| DVec3::from_array(p[v as usize]).dot(up))
                            .fold(f64::INFINITY, f64::min)
                    };
                    low(&ends[0]).max(low(&ends[1])) * m - ground(f) <= opts.flat_height
                })
                .collect();
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
                    flat[t]
                        || (track[t].1 - ground(t) <= opts.contact_height
                            && d * fps <= opts.contact_speed)
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

/// The two ends of the sole `sole` (vertex ids into `rest`): its vertices in
/// the first and in the last third of its extent along its long horizontal
/// axis (the principal axis of its vertices projected on the plane normal
/// to `up`), heel and toe in either order. A sole with no horizontal
/// extent is its own two ends.
pub fn sole_ends(rest: &[[f64; 3]], sole: &[u32], up: DVec3) -> [Vec<u32>; 2] {
    let up = up.normalize_or(DVec3::Y);
    let flat = |v: u32| {
        let p = DVec3::from_array(rest[v as usize]);
        p - up * p.dot(up)
    };
    let c = sole.iter().map(|&v| flat(v)).sum::<DVec3>() / sole.len().max(1) as f64;
    // The principal axis by power iteration on the horizontal covariance.
    let cov = |d: DVec3| -> DVec3 {
        sole.iter()
            .map(|&v| {
                let q = flat(v) - c;
                q * q.dot(d)
            })
            .sum()
    };
    let seed = up.any_orthonormal_vector();
    let mut axis = seed;
    for _ in 0..50 {
        let next = cov(axis);
        if !next.is_finite() || next.length() < 1e-300 {
            break;
        }
        axis = next.normalize();
    }
    let along = |v: u32| (flat(v) - c).dot(axis);
    let (lo, hi) = sole
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(along(v)), b.max(along(v)))
        });
    if !(hi - lo).is_finite() || hi - lo <= 0.0 {
        return [sole.to_vec(), sole.to_vec()];
    }
    let third = (hi - lo) / 3.0;
    [
        sole.iter()
            .copied()
            .filter(|&v| along(v) <= lo + third)
            .collect(),
        sole.iter()
            .copied()
            .filter(|&v| along(v) >= hi - third)
            .collect(),
    ]
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
