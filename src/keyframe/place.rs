//! From a key-frame path to meshes (Huang et al. 2015, Secs. 4.4 and 5.1):
//! the frames are blended across transitions as [`crate::drive`] does
//! ([`timeline`]: the transition's window, non-linear blending), and the
//! character is placed on the floor by accumulating the root motion of
//! every frame across transitions.
//!
//! Placement: the output's heading starts at the first key-frame's and
//! turns only at a transition `a → b`, by the rotation about the vertical
//! that best maps the skeleton of `b − 1` (the frame of the new sequence
//! paired with `a`) onto that of `a`: each new segment continues where the
//! previous left off, facing the same way. The floor centroid of output
//! frame `k` is `X_k = X_{k−1} + R(θ_k) (c(b) − c(b − 1))` with `c` the
//! frame's centroid in its own capture; every output frame is moved on the
//! floor so that its mean vertex lies exactly at `X_k`. The output thus
//! travels `Σ |c(b) − c(b−1)|`, the distance the search counted
//! ([`super::graph::KeyGraph::step`]).
//!
//! Across a transition the blended frames move on the floor as the blend
//! of the two sequences' root motions (Sec. 4.4 blends the geometry over
//! the window; [`ease_steps`] does the same for the floor speed, with the
//! window's path length kept, so the output still
//! travels exactly the counted distance. Without it the whole body
//! changed speed within one frame at a walk-to-run transition (1.0 to
//! 2.4 m/s, 35 m/s² on every vertex).
//!
//! The frames are blended with the character's prepared blender
//! ([`crate::drive::Prepared`], factored once per job) and handed to a
//! [`FrameSink`], as surface synthesis and transfer do: held
//! ([`place`]) and streamed output ([`place_into`]) are one path.

use super::graph::{KeyGraph, centre_of};
use crate::db::Character;
use crate::drive::timeline::{Jump, OutFrame, TimelineOptions, timeline};
use crate::drive::{BlendScratch, CHUNK_FRAMES, Floor, FrameSink, blend_placed};
use crate::graph::FlatFrame;
use crate::mesh::blend::{Blender, FrameGradients};
use crate::mesh::solver::SolveError;
use crate::pose::measure::rotate_yaw;
use glam::DVec3;
use rayon::prelude::*;

/// The placed, blended sequence.
pub struct Placed {
    /// Positions, frame-major (metres, Y-up).
    pub positions: Vec<[f64; 3]>,
    /// What each output frame blends.
    pub frames: Vec<OutFrame>,
    /// The jumps with their blend windows.
    pub jumps: Vec<Jump>,
    /// Heading (radians about Y) of every output frame relative to the
    /// first key-frame's capture.
    pub heading: Vec<f64>,
    /// Floor centroid `(x, z)` of every output frame.
    pub centre: Vec<[f64; 2]>,
}

/// The heading and floor motion of every path frame (see the module docs):
/// `placement[k]` maps frame `path[k]` from its capture to the output.
pub fn placements(ch: &Character, g: &KeyGraph, path: &[FlatFrame]) -> (Vec<Floor>, Vec<[f64; 2]>) {
    let mut theta = 0.0f64;
    let mut x = path.first().map_or([0.0; 2], |&f| g.centre[f.index()]);
    let mut out = Vec::with_capacity(path.len());
    let mut centres = Vec::with_capacity(path.len());
    for (k, &b) in path.iter().enumerate() {
        if k > 0 {
            let a = path[k - 1];
            let plain = b == a.next() && g.sequence[a.index()] == g.sequence[b.index()];
            if !plain && let Some(before_b) = b.prev() {
                let fit = Floor::fit(ch.pose(before_b), ch.pose(a));
                theta += fit.theta;
            }
            let (cb, cp) = (g.centre[b.index()], g.centre[b.index() - 1]);
            let v = rotate_yaw(
                DVec3::new(cb[0] - cp[0], 0.0, cb[1] - cp[1]),
                theta.cos(),
                theta.sin(),
            );
            x = [x[0] + v.x, x[1] + v.z];
        }
        let c = g.centre[b.index()];
        let r = rotate_yaw(DVec3::new(c[0], 0.0, c[1]), theta.cos(), theta.sin());
        out.push(Floor {
            theta,
            t: DVec3::new(x[0] - r.x, 0.0, x[1] - r.z),
        });
        centres.push(x);
    }
    (out, centres)
}

/// Eases the floor speed across every jump `a → b` at output frame `at`
/// with half-window `L`, as Sec. 4.4 blends the geometry: the steps
/// `X_k − X_{k−1}` of the window `k = at + o`, `o ∈ [−L, L − 1]`, keep
/// their directions and take the length `(1 − α) s_i(a + o + 1) + α
/// s_j(b + o)`, `α = (o + L + ½) / 2L`, with `s_i`, `s_j` the floor steps
/// of the two sequences ([`KeyGraph::step`]) around the frames the blend
/// pairs (the one available where the other lies outside its sequence),
/// all scaled so that the window's path length is unchanged; the frames
/// after the window move with its end. A window with a standing step
/// (shorter than 0.1 mm) is left as is.
pub(crate) fn ease_steps(centre: &mut [[f64; 2]], jumps: &[Jump], g: &KeyGraph) {
    let step = |f: i64, seq: u32| -> Option<f64> {
        let i = usize::try_from(f).ok()?;
        (i > 0 && g.sequence.get(i) == Some(&seq) && g.sequence.get(i - 1) == Some(&seq))
            .then(|| g.step[i])
    };
    for j in jumps {
        let l = j.window.max(1);
        let lo = j.at.saturating_sub(l).max(1);
        let hi = (j.at + l - 1).min(centre.len().saturating_sub(1));
        if lo >= j.at || j.at > hi || j.from.index() >= g.sequence.len() {
            continue;
        }
        let (si, sj) = (
            g.sequence[j.from.index()],
            g.sequence.get(j.to.index()).copied(),
        );
        let Some(sj) = sj else { continue };
        let steps: Vec<[f64; 2]> = (lo..=hi)
            .map(|k| {
                [
                    centre[k][0] - centre[k - 1][0],
                    centre[k][1] - centre[k - 1][1],
                ]
            })
            .collect();
        let len: Vec<f64> = steps.iter().map(|v| v[0].hypot(v[1])).collect();
        if len.iter().any(|&x| x < 1e-4) {
            continue;
        }
        let want: Vec<f64> = (lo..=hi)
            .zip(&len)
            .map(|(k, &now)| {
                let o = k as i64 - j.at as i64;
                let alpha = (o + l as i64) as f64 / (2 * l) as f64 + 0.5 / (2 * l) as f64;
                let left = step(i64::from(j.from.get()) + o + 1, si);
                let entered = step(i64::from(j.to.get()) + o, sj);
                match (left, entered) {
                    (Some(x), Some(y)) => (1.0 - alpha) * x + alpha * y,
                    (Some(x), None) | (None, Some(x)) => x,
                    (None, None) => now,
                }
            })
            .collect();
        let sum: f64 = want.iter().sum();
        if sum < 1e-4 {
            continue;
        }
        let scale = len.iter().sum::<f64>() / sum;
        let old_end = centre[hi];
        let mut x = centre[lo - 1];
        for (i, k) in (lo..=hi).enumerate() {
            let f = want[i] * scale / len[i];
            x = [x[0] + steps[i][0] * f, x[1] + steps[i][1] * f];
            centre[k] = x;
        }
        let d = [x[0] - old_end[0], x[1] - old_end[1]];
        for c in centre.iter_mut().skip(hi + 1) {
            c[0] += d[0];
            c[1] += d[1];
        }
    }
}

/// Blends and places the frames of `path`, every frame held
/// ([`place_into`] the sink `Vec`; for short paths and tests). A one-off:
/// the blender is factored here for this call.
pub fn place(
    ch: &Character,
    g: &KeyGraph,
    path: &[FlatFrame],
    opts: &TimelineOptions,
) -> Result<Placed, SolveError> {
    let blender = Blender::new(&ch.topology_metres())?;
    let mut positions = Vec::with_capacity(path.len() * ch.n());
    let track = match place_into(ch, &blender, g, path, opts, &mut positions) {
        Ok(track) => track,
        Err(never) => match never {},
    };
    Ok(Placed {
        positions,
        frames: track.frames,
        jumps: track.jumps,
        heading: track.heading,
        centre: track.centre,
    })
}

/// What [`place_into`] returns: [`Placed`] without the positions, which
/// went to the sink frame by frame.
pub struct Track {
    /// What each output frame blends.
    pub frames: Vec<OutFrame>,
    /// The jumps with their blend windows.
    pub jumps: Vec<Jump>,
    /// Heading (radians about Y) of every output frame.
    pub heading: Vec<f64>,
    /// Floor centroid `(x, z)` of every output frame.
    pub centre: Vec<[f64; 2]>,
}

/// Blends (with `blender`, factored on the character's topology in
/// metres: [`crate::drive::Prepared::blender`]) and places the frames of
/// `path`, handing each (the character's vertices) to `sink` in order.
/// Every output frame is blended on its own (its window's frames and
/// weights come from the timeline, its floor placement from the track
/// computed first for the whole path), so frames are made
/// [`CHUNK_FRAMES`] at a time in parallel: a path of any length needs the
/// memory of one chunk, not of every frame (attack s14, item 3: 8.6 MB per
/// output second). The frames are those of [`place`], bit for bit. The
/// first error of the sink stops the placement and is returned.
pub(crate) fn place_into<S: FrameSink>(
    ch: &Character,
    blender: &Blender,
    g: &KeyGraph,
    path: &[FlatFrame],
    opts: &TimelineOptions,
    mut sink: S,
) -> Result<Track, S::Error> {
    let (frames, jumps) = timeline(path, &super::graph::KeyFrames { ch, graph: g }, opts);
    let (place, mut centre) = placements(ch, g, path);
    if opts.blend {
        // No blending (`--no-blend`): each frame keeps its own sequence's
        // steps, as it keeps its own geometry.
        ease_steps(&mut centre, &jumps, g);
    }
    let n = ch.n().max(1);
    let chunk = CHUNK_FRAMES.min(frames.len()).max(1);
    let mut buffer = vec![[0.0; 3]; chunk * n];
    // Per-worker scratch, taken and given back frame by frame (allocated
    // once per worker, not per frame or chunk).
    type Worker = (
        crate::mesh::blend::BlendWorkspace,
        Vec<[f64; 3]>,
        Vec<FrameGradients>,
    );
    let pool = std::sync::Mutex::new(Vec::<Worker>::new());
    for start in (0..frames.len()).step_by(chunk) {
        let m = chunk.min(frames.len() - start);
        buffer[..m * n]
            .par_chunks_mut(n)
            .enumerate()
            .for_each(|(i, dst)| {
                let k = start + i;
                let taken = pool.lock().ok().and_then(|mut p| p.pop());
                let (mut ws, mut buf, mut grads) = taken.unwrap_or_else(|| {
                    (
                        blender.workspace(),
                        vec![[0.0; 3]; n],
                        vec![FrameGradients::default(); 4],
                    )
                });
                let o = &frames[k];
                let r = path[k];
                let same = |id: FlatFrame| g.sequence[id.index()] == g.sequence[r.index()];
                let mut scratch = BlendScratch {
                    ws: &mut ws,
                    buf: &mut buf,
                    grads: &mut grads,
                };
                blend_placed(ch, blender, o.used(), r, place[k], same, &mut scratch, dst);
                // Exactly on the accumulated floor track.
                let c = centre_of(dst);
                let (dx, dz) = (centre[k][0] - c[0], centre[k][1] - c[1]);
                for p in dst.iter_mut() {
                    p[0] += dx;
                    p[2] += dz;
                }
                if let Ok(mut p) = pool.lock() {
                    p.push((ws, buf, grads));
                }
            });
        for f in buffer[..m * n].chunks(n) {
            sink.push(f)?;
        }
    }
    Ok(Track {
        frames,
        jumps,
        heading: place.iter().map(|p| p.theta).collect(),
        centre,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn length(c: &[[f64; 2]]) -> f64 {
        c.windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum()
    }

    #[test]
    fn easing_a_walk_to_run_jump_blends_the_speeds_and_keeps_the_path_length() {
        // Sequence 0 (frames 0-29) steps 1 cm per frame along x, sequence
        // 1 (30-59) 2.5 cm along z; the path takes 0..=19, jumps 19 → 40
        // (at output frame 20, L = 4) and goes on to 59.
        let centre: Vec<[f64; 2]> = (0..60)
            .map(|f| {
                if f < 30 {
                    [0.01 * f as f64, 0.0]
                } else {
                    [0.0, 0.025 * f as f64]
                }
            })
            .collect();
        let succ: Vec<Vec<(FlatFrame, f64)>> = (0..60u32)
            .map(|f| {
                if f % 30 != 29 {
                    vec![(FlatFrame::new(f + 1), 0.0)]
                } else {
                    vec![]
                }
            })
            .collect();
        let g = KeyGraph::new(&succ, centre, (0..60).map(|f| f / 30).collect());
        let path: Vec<FlatFrame> = (0..20).chain(40..60).map(FlatFrame::new).collect();
        let mut c = vec![[0.0, 0.0]];
        for k in 1..path.len() {
            let p = c[k - 1];
            c.push(if k < 20 {
                [p[0] + 0.01, p[1]]
            } else {
                [p[0], p[1] + 0.025]
            });
        }
        let before = c.clone();
        let jump = Jump {
            at: 20,
            from: FlatFrame::new(19),
            to: FlatFrame::new(40),
            window: 4,
            transition: true,
        };
        ease_steps(&mut c, &[jump], &g);
        assert!((length(&c) - length(&before)).abs() < 1e-12);
        let speed = |c: &[[f64; 2]], k: usize| (c[k][0] - c[k - 1][0]).hypot(c[k][1] - c[k - 1][1]);
        // Largest change of speed between consecutive steps: 1.5 cm at
        // the jump before; eight steps of 1.5/8 cm after.
        let jerk = |c: &[[f64; 2]]| {
            (2..40)
                .map(|k| (speed(c, k) - speed(c, k - 1)).abs())
                .fold(0.0, f64::max)
        };
        assert!((jerk(&before) - 0.015).abs() < 1e-12);
        assert!(jerk(&c) < 0.015 / 7.0, "{}", jerk(&c));
        // Outside the window nothing changes speed.
        for k in (1..=15).chain(24..40) {
            assert!((speed(&c, k) - speed(&before, k)).abs() < 1e-12, "{k}");
        }
        // Directions are kept: the steps before the jump stay along x.
        assert!(c[19][1].abs() < 1e-12 && c[39][0] > 0.19);
    }
}
