//! Turned-over triangles of a result against the character's rest frame,
//! and vertices that leave their one-ring ([`OffRing`]).
//!
//! The test is the deformation's own ([`crate::deform::unflip::turned_over`],
//! the repair after the part-based PCA Laplacian deformation of Huang et al.
//! 2015, Sec. 5.2.3): a triangle is *turned over* when its normal makes more
//! than 90° with the reference triangle's normal turned by the triangle's
//! rotation (the mean of its corners'), so a triangle that merely turns
//! with its surroundings, however far, is not counted. The reference here is
//! the rest frame, and a vertex's rotation is the best rigid alignment
//! (Kabsch: the rotation of the polar decomposition of `Σ xᵢ oᵢᵀ`, `oᵢ` the
//! rest offsets from their centroid) of a neighbourhood, the vertices
//! within [`RINGS`] edges of a seed vertex, from the rest frame onto the
//! frame; every vertex is a seed or next to one (a greedy dominating set,
//! about a quarter of the vertices), and takes its seed's rotation. The
//! deformation turns its source by the skeleton's skin-blended rotations
//! instead; against the rest frame those miss the twist of a limb about its
//! bone, which positions do not show: on the real samba capture a forearm
//! turned about itself read as up to 945 of 19,938 triangles turned over
//! in one frame (738 of them on the left forearm, frame 135), where the
//! neighbourhoods read none there.
//!
//! It needs only the rest mesh, so it runs on every result (`retarget`,
//! `synth`, `transfer`, `eval`) and on a database's own captured frames
//! (the captured range); the rest frame itself counts none, under any
//! rigid motion too. `retarget` also reports what its repair left against
//! the retrieved frames ([`crate::deform::TurnedOver`]).
//!
//! A vertex *leaves its one-ring* when it is far from the centroid of its
//! neighbours, measured in its rest frame's mean edge length around it
//! (so the measure is the same on a coarse and a fine part of the mesh,
//! and under any rigid motion): the single-vertex spikes a faulty repair
//! made (CMU 131_01 retargeted onto a synthetic samba database: vertex 9760
//! 1.33 m off its ring in frame 121, 98 edge lengths) read far above the
//! real samba capture's most, 1.6 (a captured fold or crease), where the
//! smoothest captured surface reads 0. A turned-over count misses them (a
//! vertex pulled straight out along its normal turns nothing over), and an
//! edge's stretch against the rest frame does not tell them apart (the
//! capture's shortest edges stretch 5.4×, the healthy folds of a
//! retargeted result 20×).

use super::EvalError;
use crate::deform::TurnedOver;
use crate::deform::near_turns::{Neighbourhoods, best_turn};
use crate::deform::unflip::{Adjacency, turned_over};
use glam::{DQuat, DVec3};
use rayon::prelude::*;
use serde::Serialize;

/// Edges from a vertex to the farthest vertex of its neighbourhood
/// ([`crate::deform::near_turns::RINGS`], the fold repair's own).
pub const RINGS: usize = crate::deform::near_turns::RINGS;

/// Scratch of [`RestTriangles::turned_over`].
#[derive(Debug, Default)]
pub struct TurnScratch {
    seeds: Vec<DQuat>,
    turn: Vec<DQuat>,
}

/// The rest frame a result's triangles are compared with.
#[derive(Debug, Clone)]
pub struct RestTriangles {
    triangles: Vec<[u32; 3]>,
    rest: Vec<[f64; 3]>,
    /// The seed whose rotation each vertex takes (index into `start`).
    seed_of: Vec<u32>,
    /// Neighbourhood of seed `s`: `start[s]..start[s + 1]` of `near`.
    start: Vec<usize>,
    near: Vec<u32>,
    /// Rest offsets of `near` from their neighbourhood's centroid.
    offsets: Vec<DVec3>,
    /// One-ring of vertex `v`: `ring_start[v]..ring_start[v + 1]` of `ring`.
    ring_start: Vec<usize>,
    ring: Vec<u32>,
    /// Each vertex's mean rest edge length (at least 1e-3 of the mesh's
    /// median), the unit of [`OffRing`].
    edge: Vec<f64>,
}

impl RestTriangles {
    /// The rest frame `rest` with `triangles` (any units and axes: each
    /// neighbourhood is aligned rigidly, so the frames compared may be moved,
    /// turned and in other axes, not scaled).
    pub fn new(rest: &[[f64; 3]], triangles: &[[u32; 3]]) -> Result<RestTriangles, EvalError> {
        let n = rest.len();
        if let Some((i, t)) = triangles
            .iter()
            .enumerate()
            .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
        {
            return Err(EvalError::Triangle {
                index: i,
                corners: *t,
                vertices: n,
            });
        }
        let adj = Adjacency::new(n, triangles);
        let Neighbourhoods {
            seed_of,
            start,
            near,
        } = Neighbourhoods::new(&adj, RINGS);
        let mut offsets = Vec::with_capacity(near.len());
        for w in start.windows(2) {
            let near = &near[w[0]..w[1]];
            let c = near
                .iter()
                .map(|&u| DVec3::from_array(rest[u as usize]))
                .sum::<DVec3>()
                / near.len() as f64;
            offsets.extend(
                near.iter()
                    .map(|&u| DVec3::from_array(rest[u as usize]) - c),
            );
        }
        let mut ring_start = vec![0];
        let mut ring = Vec::new();
        let mut edge: Vec<f64> = Vec::with_capacity(n);
        for (v, nb) in adj.vertices.iter().enumerate() {
            ring.extend_from_slice(nb);
            ring_start.push(ring.len());
            let p = DVec3::from_array(rest[v]);
            let sum: f64 = nb
                .iter()
                .map(|&u| DVec3::from_array(rest[u as usize]).distance(p))
                .sum();
            edge.push(sum / nb.len().max(1) as f64);
        }
        let mut sorted: Vec<f64> = edge.iter().copied().filter(|e| *e > 0.0).collect();
        sorted.sort_by(f64::total_cmp);
        let floor = 1e-3 * sorted.get(sorted.len() / 2).copied().unwrap_or(1.0);
        for e in &mut edge {
            *e = e.max(floor).max(f64::MIN_POSITIVE);
        }
        Ok(RestTriangles {
            triangles: triangles.to_vec(),
            rest: rest.to_vec(),
            seed_of,
            start,
            near,
            offsets,
            ring_start,
            ring,
            edge,
        })
    }

    /// Triangles of the mesh.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Vertices of the mesh.
    pub fn vertex_count(&self) -> usize {
        self.rest.len()
    }

    /// Each vertex's rotation from the rest frame onto `frame`: the best
    /// rigid alignment of its seed's neighbourhood, into `turn` (`seeds`:
    /// scratch of one rotation a seed).
    pub fn turns(&self, frame: &[[f64; 3]], seeds: &mut Vec<DQuat>, turn: &mut Vec<DQuat>) {
        seeds.clear();
        seeds.extend(self.start.windows(2).map(|w| {
            let r = w[0]..w[1];
            best_turn(
                self.near[r.clone()]
                    .iter()
                    .zip(&self.offsets[r])
                    .map(|(&u, &o)| (DVec3::from_array(frame[u as usize]), o)),
            )
        }));
        turn.clear();
        turn.extend(self.seed_of.iter().map(|&s| seeds[s as usize]));
    }

    /// The triangles of `frame` (the rest frame's vertex count) turned over
    /// against the rest frame; `scratch` holds rotations (kept between
    /// calls).
    pub fn turned_over(&self, frame: &[[f64; 3]], scratch: &mut TurnScratch) -> Vec<u32> {
        self.turns(frame, &mut scratch.seeds, &mut scratch.turn);
        turned_over(&self.triangles, &self.rest, frame, &scratch.turn)
    }

    /// The vertex of `frame` farthest from the centroid of its one-ring,
    /// in its mean rest edge lengths: `(edge lengths, vertex, distance in
    /// the frame's units)`; zeros for a mesh without edges.
    pub fn off_ring(&self, frame: &[[f64; 3]]) -> (f64, u32, f64) {
        let mut worst = (0.0, 0, 0.0);
        for (v, w) in self.ring_start.windows(2).enumerate() {
            let ring = &self.ring[w[0]..w[1]];
            if ring.is_empty() {
                continue;
            }
            let c = ring
                .iter()
                .map(|&u| DVec3::from_array(frame[u as usize]))
                .sum::<DVec3>()
                / ring.len() as f64;
            let d = DVec3::from_array(frame[v]).distance(c);
            let r = d / self.edge[v];
            // A non-finite frame reads as infinitely far off.
            if r > worst.0 || (!r.is_finite() && worst.0.is_finite()) {
                worst = (if r.is_finite() { r } else { f64::INFINITY }, v as u32, d);
            }
        }
        worst
    }

    /// [`RestTriangles::off_ring`] of each frame of `frames` (frame-major,
    /// the rest frame's vertex count each), in parallel.
    pub fn off_ring_per_frame(&self, frames: &[[f64; 3]]) -> Vec<(f64, u32, f64)> {
        frames
            .par_chunks_exact(self.rest.len().max(1))
            .map(|f| self.off_ring(f))
            .collect()
    }

    /// The count of turned-over triangles of each frame of `frames`
    /// (frame-major, the rest frame's vertex count each), in parallel.
    pub fn per_frame(&self, frames: &[[f64; 3]]) -> Vec<usize> {
        frames
            .par_chunks_exact(self.rest.len().max(1))
            .map_init(TurnScratch::default, |s, f| self.turned_over(f, s).len())
            .collect()
    }
}

/// Turned-over triangles of a sequence against the rest frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct TurnedOverCount {
    /// Triangles of the mesh.
    pub triangles: usize,
    /// Frames measured.
    pub frames: usize,
    /// Triangle-frames turned over, summed over the frames.
    pub triangle_frames: usize,
    /// `triangle_frames / (triangles · frames)`.
    pub fraction: f64,
    /// Frames with at least one triangle turned over.
    pub frames_with_any: usize,
    /// The most in one frame.
    pub max_in_a_frame: usize,
    /// The (first) frame with the most (0 when none).
    pub worst_frame: usize,
    /// What the deformation's repair left turned over against the
    /// retrieved frames (`retarget` only; [`crate::deform::TurnedOver`]).
    /// Not read back (a cached reference has none).
    #[serde(skip_deserializing)]
    pub deformation: Option<TurnedOver>,
}

impl TurnedOverCount {
    /// The count of a sequence of `triangles` triangles a frame from its
    /// per-frame counts.
    pub fn of(per_frame: &[usize], triangles: usize) -> TurnedOverCount {
        let triangle_frames: usize = per_frame.iter().sum();
        let (worst_frame, max_in_a_frame) = per_frame
            .iter()
            .copied()
            .enumerate()
            .fold((0, 0), |b, (f, c)| if c > b.1 { (f, c) } else { b });
        let cells = triangles * per_frame.len();
        TurnedOverCount {
            triangles,
            frames: per_frame.len(),
            triangle_frames,
            fraction: if cells > 0 {
                triangle_frames as f64 / cells as f64
            } else {
                0.0
            },
            frames_with_any: per_frame.iter().filter(|&&c| c > 0).count(),
            max_in_a_frame,
            worst_frame,
            deformation: None,
        }
    }
}

/// The vertex farthest off its one-ring in a sequence (see the module
/// docs): a single-vertex spike reads tens of edge lengths, a real capture
/// under two.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct OffRing {
    /// Frames measured.
    pub frames: usize,
    /// The largest distance of a vertex from the centroid of its one-ring,
    /// in its mean rest edge lengths.
    pub max_edge_lengths: f64,
    /// That distance (cm).
    pub max_cm: f64,
    /// Its frame.
    pub frame: usize,
    /// Its vertex.
    pub vertex: u32,
    /// Median over the frames of each frame's largest (edge lengths).
    pub median_edge_lengths: f64,
    /// The rest frame's own largest (edge lengths): a scan's line when there
    /// are no captured frames to compare with.
    pub rest_edge_lengths: f64,
}

impl OffRing {
    /// The summary of per-frame [`RestTriangles::off_ring`] values, with
    /// distances in units of `metres_per_unit` metres, and `rest`'s own.
    pub fn of(
        per_frame: &[(f64, u32, f64)],
        metres_per_unit: f64,
        rest: &RestTriangles,
    ) -> OffRing {
        let rest_edge_lengths = rest.off_ring(&rest.rest).0;
        let Some((frame, &(r, vertex, d))) = per_frame
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.0.total_cmp(&b.1.0))
        else {
            return OffRing {
                rest_edge_lengths,
                ..OffRing::default()
            };
        };
        let mut all: Vec<f64> = per_frame.iter().map(|x| x.0).collect();
        all.sort_by(f64::total_cmp);
        OffRing {
            frames: per_frame.len(),
            max_edge_lengths: r,
            max_cm: 100.0 * d * metres_per_unit,
            frame,
            vertex,
            median_edge_lengths: all[all.len() / 2],
            rest_edge_lengths,
        }
    }

    /// One line for the command line.
    pub fn describe(&self) -> String {
        format!(
            "up to {:.1} edge lengths ({:.1} cm, vertex {} in frame {}), median {:.1} a frame",
            self.max_edge_lengths, self.max_cm, self.vertex, self.frame, self.median_edge_lengths
        )
    }
}

impl TurnedOverCount {
    /// One line for the command line: triangle-frames, their share, the
    /// frames with any and the worst frame.
    pub fn describe(&self) -> String {
        let share = 100.0 * self.fraction;
        format!(
            "{} triangle-frames ({share:.3} % of {} a frame), in {} of {} frames, up to {} (frame {})",
            self.triangle_frames,
            self.triangles,
            self.frames_with_any,
            self.frames,
            self.max_in_a_frame,
            self.worst_frame
        )
    }
}
