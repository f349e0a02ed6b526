//! The cloth's crumple (issue 42): how sharply a skirt's surface bends,
//! read off the mesh alone, per body region, against the capture's own
//! frames.
//!
//! A captured skirt is smooth with a clean hem; a crumpled one is a band
//! of small facets, each edge bent sharply one way or the other. The
//! number is the mean absolute bend (degrees; signed dihedral angle of
//! [`Edges::bends`], 0 on a flat surface) over the cloth's edges — both
//! ends with [`crate::deform::soft::softness`] above 0, the vertices the
//! deformation treats as cloth — and the share of those edges bent more
//! than [`SHARP_DEG`]. Per region: an edge counts for the part its first
//! vertex is labelled with (the rig's [`Part`]s: the skirt is the torso's
//! and both thighs'). The yardstick is the same number on the database's
//! captured frames ([`ClothBends::captured`]). Unchanged under any rigid
//! motion and uniform scale of a frame. Cost: one pass over the edges.

use crate::embed::Embedding;
use crate::embed::parts::Part;
use crate::mesh::Mesh;
use crate::mesh::quality::Edges;
use serde::Serialize;

/// An edge bent more than this (degrees) is sharp.
pub(crate) const SHARP_DEG: f64 = 30.0;

/// The cloth's edges of a character, read once.
pub struct ClothBends {
    edges: Edges,
    /// Per edge: the part it counts for, or `None` off the cloth.
    part: Vec<Option<Part>>,
    count: usize,
}

/// One frame's crumple.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrameCrumple {
    /// Mean absolute bend over the cloth's edges (degrees).
    pub mean_deg: f64,
    /// Share of the cloth's edges bent more than [`SHARP_DEG`] (0-1).
    pub sharp: f64,
    /// Mean absolute bend per region (index [`Part::index`]; 0 without
    /// cloth edges there).
    pub regions: [f64; Part::COUNT],
}

impl ClothBends {
    /// The cloth of a character's `rest` mesh and rig.
    pub fn new(rest: &Mesh, rig: &Embedding) -> ClothBends {
        let soft = crate::deform::soft::softness(rest, rig);
        let cloth: Vec<bool> = soft.iter().map(|&s| s > 0.0).collect();
        ClothBends::of(rest.triangles(), &cloth, &rig.labels)
    }

    /// The cloth `cloth` marks (one per vertex) of a mesh with `triangles`
    /// and part `labels` (one per vertex).
    pub fn of(triangles: &[[u32; 3]], cloth: &[bool], labels: &[u8]) -> ClothBends {
        let edges = Edges::new(triangles);
        let on = |v: u32| cloth.get(v as usize).copied().unwrap_or(false);
        let part: Vec<Option<Part>> = edges
            .ends
            .iter()
            .map(|&[a, b]| {
                (on(a) && on(b))
                    .then(|| {
                        labels
                            .get(a as usize)
                            .and_then(|&l| Part::ALL.get(l as usize))
                    })
                    .flatten()
                    .copied()
            })
            .collect();
        let count = part.iter().filter(|p| p.is_some()).count();
        ClothBends { edges, part, count }
    }

    /// The cloth's edges.
    pub fn len(&self) -> usize {
        self.count
    }

    /// Whether the character has no cloth edge.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The crumple of one frame (positions in any unit); `bends` is
    /// scratch.
    pub fn frame(&self, pos: &[[f64; 3]], bends: &mut Vec<f64>) -> FrameCrumple {
        self.edges.bends(pos, bends);
        let (mut sum, mut sharp) = (0.0, 0usize);
        let mut by = [(0.0, 0usize); Part::COUNT];
        for (b, p) in bends.iter().zip(&self.part) {
            let Some(p) = p else { continue };
            let d = b.abs().to_degrees();
            sum += d;
            sharp += usize::from(d > SHARP_DEG);
            let r = &mut by[p.index()];
            r.0 += d;
            r.1 += 1;
        }
        let n = self.count.max(1) as f64;
        FrameCrumple {
            mean_deg: sum / n,
            sharp: sharp as f64 / n,
            regions: by.map(|(s, c)| if c > 0 { s / c as f64 } else { 0.0 }),
        }
    }

    /// The crumple of every frame of `frames` (frame-major, `n` vertices
    /// a frame).
    pub fn frames(&self, frames: &[[f64; 3]], n: usize) -> Vec<FrameCrumple> {
        let mut bends = Vec::new();
        frames
            .chunks_exact(n.max(1))
            .map(|f| self.frame(f, &mut bends))
            .collect()
    }
}
