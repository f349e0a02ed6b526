//! From a key-frame path to meshes (Huang et al. 2015, Secs. 4.4 and 5.1):
//! the frames are blended across transitions as [`crate::retarget`] does
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

use super::graph::{KeyGraph, centre_of};
use crate::mesh::blend::{Blender, FrameGradients};
use crate::mesh::solver::SolveError;
use crate::retarget::character::Character;
use crate::retarget::timeline::{Jump, OutFrame, TimelineOptions, timeline};
use crate::retarget::{BlendScratch, Floor, blend_placed};
use crate::skeleton::rotate_yaw;
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
pub fn placements(ch: &Character, g: &KeyGraph, path: &[u32]) -> (Vec<Floor>, Vec<[f64; 2]>) {
    let mut theta = 0.0f64;
    let mut x = path.first().map_or([0.0; 2], |&f| g.centre[f as usize]);
    let mut out = Vec::with_capacity(path.len());
    let mut centres = Vec::with_capacity(path.len());
    for (k, &b) in path.iter().enumerate() {
        if k > 0 {
            let a = path[k - 1];
            let plain = b == a + 1 && g.sequence[a as usize] == g.sequence[b as usize];
            if !plain && b > 0 {
                let fit = Floor::fit(&ch.poses()[b as usize - 1], &ch.poses()[a as usize]);
                theta += fit.theta;
            }
            let (cb, cp) = (g.centre[b as usize], g.centre[b as usize - 1]);
            let v = rotate_yaw(
                DVec3::new(cb[0] - cp[0], 0.0, cb[1] - cp[1]),
                theta.cos(),
                theta.sin(),
            );
            x = [x[0] + v.x, x[1] + v.z];
        }
        let c = g.centre[b as usize];
        let r = rotate_yaw(DVec3::new(c[0], 0.0, c[1]), theta.cos(), theta.sin());
        out.push(Floor {
            theta,
            t: DVec3::new(x[0] - r.x, 0.0, x[1] - r.z),
        });
        centres.push(x);
    }
    (out, centres)
}

/// Blends and places the frames of `path`.
pub fn place(
    ch: &Character,
    g: &KeyGraph,
    path: &[u32],
    opts: &TimelineOptions,
) -> Result<Placed, SolveError> {
    let (frames, jumps) = timeline(path, &super::graph::KeyFrames { ch, graph: g }, opts);
    let (place, centre) = placements(ch, g, path);
    let topo = ch.topology_metres();
    let blender = Blender::new(&topo)?;
    let n = ch.n();
    let mut positions = vec![[0.0; 3]; frames.len() * n];
    positions
        .par_chunks_mut(n.max(1))
        .enumerate()
        .for_each_init(
            || {
                (
                    blender.workspace(),
                    vec![[0.0; 3]; n],
                    vec![FrameGradients::default(); 4],
                )
            },
            |(ws, buf, grads), (k, dst)| {
                let o = &frames[k];
                let r = path[k];
                let same = |id: u32| g.sequence[id as usize] == g.sequence[r as usize];
                let mut scratch = BlendScratch { ws, buf, grads };
                blend_placed(ch, &blender, o.used(), r, place[k], same, &mut scratch, dst);
                // Exactly on the accumulated floor track.
                let c = centre_of(dst);
                let (dx, dz) = (centre[k][0] - c[0], centre[k][1] - c[1]);
                for p in dst.iter_mut() {
                    p[0] += dx;
                    p[2] += dz;
                }
            },
        );
    Ok(Placed {
        positions,
        frames,
        jumps,
        heading: place.iter().map(|p| p.theta).collect(),
        centre,
    })
}
