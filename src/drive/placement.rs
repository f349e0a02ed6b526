//! Placing retrieved frames on the query's root trajectory and blending
//! them (Huang et al. 2015, Sec. 4.4 and 5.2).

use super::timeline::{self, Frames, OutFrame};
use crate::db::Character;
use crate::graph::FlatFrame;
use crate::mesh::blend::{Blender, FrameGradients};
use crate::pose::Pose;
use crate::pose::measure::{floor_fit, rotate_yaw};
use glam::DVec3;

/// Scratch of [`blend_placed`]: a blending workspace, a frame buffer and
/// up to four frames' gradients.
pub struct BlendScratch<'a> {
    /// The blender's workspace.
    pub ws: &'a mut crate::mesh::blend::BlendWorkspace,
    /// One frame's positions.
    pub buf: &'a mut Vec<[f64; 3]>,
    /// Gradients of each frame blended (at least four).
    pub grads: &'a mut Vec<FrameGradients>,
}

/// One output frame (Huang et al. 2015, Sec. 4.4): the database frames
/// `used` (id, weight), each placed on the floor by `place` (the placement
/// of frame `anchor`; a frame of another capture, `!same(id)`, is first
/// fitted onto the anchor's skeleton), then blended non-linearly into
/// `dst` (a single frame is copied). Shared by `retarget` and `keyframe`.
#[allow(clippy::too_many_arguments)]
pub fn blend_placed(
    ch: &Character,
    blender: &Blender,
    used: &[(FlatFrame, f64)],
    anchor: FlatFrame,
    place: Floor,
    same: impl Fn(FlatFrame) -> bool,
    s: &mut BlendScratch<'_>,
    dst: &mut [[f64; 3]],
) {
    for (i, &(id, _)) in used.iter().enumerate() {
        let pl = if same(id) {
            place
        } else {
            place.after(&Floor::fit(ch.pose(id), ch.pose(anchor)))
        };
        ch.frame_metres(id, s.buf);
        for p in s.buf.iter_mut() {
            *p = pl.apply(DVec3::from_array(*p)).to_array();
        }
        if used.len() == 1 {
            dst.copy_from_slice(s.buf);
        } else {
            blender.decompose_into(s.buf, s.ws, &mut s.grads[i]);
        }
    }
    if used.len() > 1 {
        let inputs: [(&FrameGradients, f64); 4] =
            std::array::from_fn(|i| (&s.grads[i], used.get(i).map_or(0.0, |u| u.1)));
        blender.blend_many(&inputs[..used.len()], dst, s.ws);
    }
}

/// A rigid motion on the floor: rotation `theta` about Y, then `t` (y = 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Floor {
    /// Rotation about Y (radians, [`rotate_yaw`]'s sense).
    pub theta: f64,
    /// Translation (y = 0).
    pub t: DVec3,
}

impl Floor {
    /// The floor motion that best maps `from` onto `to` (least squares).
    pub fn fit(from: &Pose, to: &Pose) -> Floor {
        let (cos, sin, ct, cf) = floor_fit(to, from);
        let theta = sin.atan2(cos);
        Floor {
            theta,
            t: ct - rotate_yaw(cf, cos, sin),
        }
    }
    /// The motion applied to a point.
    pub fn apply(&self, p: DVec3) -> DVec3 {
        rotate_yaw(p, self.theta.cos(), self.theta.sin()) + self.t
    }
    /// `self ∘ other`.
    pub fn after(&self, other: &Floor) -> Floor {
        Floor {
            theta: self.theta + other.theta,
            t: rotate_yaw(other.t, self.theta.cos(), self.theta.sin()) + self.t,
        }
    }
}

impl Frames for Character {
    fn frame_of(&self, id: FlatFrame) -> (usize, usize) {
        self.graph().frame_of(id)
    }
    fn flat_id(&self, s: usize, t: usize) -> FlatFrame {
        self.graph().flat_id(s, t)
    }
    fn len(&self, s: usize) -> usize {
        self.graph().sequences()[s].len
    }
    fn transition_window(&self, from: FlatFrame, to_prev: FlatFrame) -> Option<usize> {
        let (sa, m) = self.graph().frame_of(from);
        let (sb, n) = self.graph().frame_of(to_prev);
        self.graph()
            .transitions()
            .iter()
            .find(|t| t.from == sa && t.to == sb && t.m == m && t.n == n)
            .map(|t| t.window)
    }
}

/// The placement of every output frame on the query's root trajectory:
/// its primary source fitted onto the query pose, smoothed over `smooth`
/// frames either side within a segment (between jumps).
pub(crate) fn placements(
    ch: &Character,
    path: &[FlatFrame],
    frames: &[OutFrame],
    query: &[Pose],
    smooth: usize,
) -> Vec<Floor> {
    let mut out = Vec::with_capacity(frames.len().min(query.len()));
    let scratch = &mut PlacementScratch::default();
    placements_into(ch, (path, frames, query), smooth, scratch, &mut out);
    out
}

/// The buffers [`placements_into`] reuses from one window to the next (a
/// live session's; cleared before use).
#[derive(Debug, Clone, Default)]
pub(crate) struct PlacementScratch {
    /// Each frame's placement before smoothing.
    raw: Vec<Floor>,
    /// Their turns, unwrapped.
    unwrapped: Vec<f64>,
    /// Each frame's segment (between jumps).
    segment: Vec<usize>,
}

/// [`placements`] into `out` (cleared), with `scratch` its buffers: no
/// allocation once they and `out` hold the window's frames.
pub(crate) fn placements_into(
    ch: &Character,
    (path, frames, query): (&[FlatFrame], &[OutFrame], &[Pose]),
    smooth: usize,
    scratch: &mut PlacementScratch,
    out: &mut Vec<Floor>,
) {
    let PlacementScratch {
        raw,
        unwrapped,
        segment,
    } = scratch;
    // Placement of each output frame's primary source, smoothed.
    raw.clear();
    raw.extend(
        frames
            .iter()
            .zip(query)
            .map(|(o, q)| Floor::fit(ch.pose(o.primary()), q)),
    );
    unwrapped.clear();
    unwrapped.extend(raw.iter().map(|f| f.theta));
    for k in 1..unwrapped.len() {
        let d = unwrapped[k] - unwrapped[k - 1];
        unwrapped[k] -= (d / std::f64::consts::TAU).round() * std::f64::consts::TAU;
    }
    // Frames of one segment (between jumps) share their capture's world
    // frame, so their placements can be averaged; across a jump they
    // cannot (the two captures stand in different places).
    segment.clear();
    segment.resize(frames.len(), 0);
    for k in 1..frames.len() {
        segment[k] = segment[k - 1] + usize::from(!timeline::plays_on(ch, path[k - 1], path[k]));
    }
    out.clear();
    out.extend((0..raw.len()).map(|k| {
        let mut a = k.saturating_sub(smooth);
        let mut b = (k + smooth + 1).min(raw.len());
        while segment[a] != segment[k] {
            a += 1;
        }
        while segment[b - 1] != segment[k] {
            b -= 1;
        }
        let w = (b - a) as f64;
        Floor {
            theta: unwrapped[a..b].iter().sum::<f64>() / w,
            t: raw[a..b].iter().map(|f| f.t).sum::<DVec3>() / w,
        }
    }));
}
