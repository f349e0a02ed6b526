//! A rig embedded in a mesh with vertices in no triangle
//! ([`crate::mesh::stray`]: a capture cut by a script keeps them).
//!
//! Every step of the embedding reads positions — the body's height and
//! floor, the sections, the head's top, bone heat — and a point that is
//! no surface would move them (a leftover 2 cm above the head raised the
//! head's top and moved every joint). So the rig is embedded on the mesh
//! without them, and each then takes the part label, skin weights and
//! regions of its carrier, the vertex in a triangle nearest it; the
//! regressors never read them. The rig of the mesh's other vertices is
//! the rig of the mesh without the stray ones, whatever their number or
//! place in the numbering. [`Compact`] renumbers;
//! `Embedding::with_stray` (embedding_parts.rs) gives the rig back to the
//! whole mesh.

use super::landmarks::{Landmarks, Mark};
use crate::mesh::stray::StrayVertices;
use crate::mesh::{Mesh, TopologyError};

/// The renumbering of a mesh without its vertices in no triangle.
pub(crate) struct Compact {
    /// Each kept vertex's old index, in order.
    old_of: Vec<u32>,
    /// Each old vertex's new index; `u32::MAX` for a stray one.
    new_of: Vec<u32>,
    stray: StrayVertices,
}

impl Compact {
    /// `None` when every vertex of `mesh` is in a triangle (or none is).
    pub(crate) fn of(mesh: &Mesh) -> Option<Compact> {
        let stray = StrayVertices::of(mesh.positions(), mesh.triangles())?;
        let mut new_of = vec![0u32; mesh.vertex_count()];
        for &(s, _) in stray.pairs() {
            new_of[s as usize] = u32::MAX;
        }
        let mut old_of = Vec::with_capacity(mesh.vertex_count() - stray.len());
        for (v, slot) in new_of.iter_mut().enumerate() {
            if *slot != u32::MAX {
                *slot = old_of.len() as u32;
                old_of.push(v as u32);
            }
        }
        Some(Compact {
            old_of,
            new_of,
            stray,
        })
    }

    /// The mesh without its stray vertices.
    pub(crate) fn mesh(&self, mesh: &Mesh) -> Result<Mesh, TopologyError> {
        let tris = mesh
            .triangles()
            .iter()
            .map(|t| t.map(|v| self.new_of[v as usize]))
            .collect();
        Mesh::new(self.frame(mesh.positions()), tris)
    }

    /// The frames without the stray vertices (every frame of the mesh's
    /// vertex count: the callers check it first).
    pub(crate) fn frames(&self, frames: &[&[[f64; 3]]]) -> Vec<Vec<[f64; 3]>> {
        frames.iter().map(|f| self.frame(f)).collect()
    }

    /// A frame's positions without the stray vertices (a frame of another
    /// vertex count is returned empty: the caller drops it).
    pub(crate) fn frame(&self, f: &[[f64; 3]]) -> Vec<[f64; 3]> {
        if f.len() != self.new_of.len() {
            return Vec::new();
        }
        self.old_of.iter().map(|&v| f[v as usize]).collect()
    }

    /// The landmarks renumbered; a mark on a stray vertex becomes its point
    /// (`p`: the mesh's positions).
    pub(crate) fn landmarks(&self, lm: &Landmarks, p: &[[f64; 3]]) -> Landmarks {
        let marks = lm
            .marks
            .iter()
            .map(|(&l, m)| {
                let m = match *m {
                    Mark::Vertex(v) => match self.new_of.get(v as usize) {
                        Some(&u32::MAX) => Mark::Point(p[v as usize]),
                        Some(&n) => Mark::Vertex(n),
                        None => Mark::Vertex(v),
                    },
                    Mark::Surface(mut a) => {
                        a.triangle = a
                            .triangle
                            .map(|v| self.new_of.get(v as usize).copied().unwrap_or(v));
                        Mark::Surface(a)
                    }
                    Mark::Point(q) => Mark::Point(q),
                };
                (l, m)
            })
            .collect();
        Landmarks { marks }
    }

    /// Landmarks of the mesh without the stray vertices as the whole
    /// mesh's (vertex and triangle ids numbered back).
    pub(crate) fn landmarks_back(&self, lm: Landmarks) -> Landmarks {
        let back = |v: u32| self.old_of.get(v as usize).copied().unwrap_or(v);
        let marks = lm
            .marks
            .into_iter()
            .map(|(l, m)| {
                let m = match m {
                    Mark::Vertex(v) => Mark::Vertex(back(v)),
                    Mark::Surface(mut a) => {
                        a.triangle = a.triangle.map(back);
                        Mark::Surface(a)
                    }
                    Mark::Point(q) => Mark::Point(q),
                };
                (l, m)
            })
            .collect();
        Landmarks { marks }
    }

    /// Per-vertex part labels renumbered.
    pub(crate) fn labels(&self, parts: &[u8]) -> Vec<u8> {
        self.old_of
            .iter()
            .map(|&v| parts.get(v as usize).copied().unwrap_or(0))
            .collect()
    }

    /// The whole mesh's vertex count.
    pub(crate) fn vertex_count(&self) -> usize {
        self.new_of.len()
    }

    /// The whole mesh's index of the compact mesh's vertex `v`.
    pub(crate) fn old(&self, v: u32) -> u32 {
        self.old_of[v as usize]
    }

    /// The stray vertices, each with its carrier.
    pub(crate) fn stray(&self) -> &StrayVertices {
        &self.stray
    }

    /// Per-vertex values of the compact mesh as the whole mesh's: each
    /// stray vertex its carrier's.
    pub(crate) fn spread<T: Copy>(&self, per: &[T], fill: T) -> Vec<T> {
        let mut out = vec![fill; self.new_of.len()];
        for (&old, &x) in self.old_of.iter().zip(per) {
            out[old as usize] = x;
        }
        for &(s, c) in self.stray.pairs() {
            out[s as usize] = out[c as usize];
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use crate::embed::Embedding;
    use crate::mesh::Mesh;
    use crate::synth::humanoid::{humanoid_landmarks, humanoid_mesh};

    /// The synthetic body with stray points inserted before indices `at`
    /// (of the result), each 2 cm above vertex `near` of the body — one
    /// above the head's top, out of the body's bounds. Returns the mesh
    /// and each body vertex's new index.
    fn with_strays(body: &Mesh, at: &[usize], near: &[u32]) -> (Mesh, Vec<u32>) {
        let n = body.vertex_count() + at.len();
        let (mut p, mut index, mut k) = (Vec::with_capacity(n), Vec::new(), 0);
        for i in 0..n {
            match at.iter().position(|&a| a == i) {
                Some(s) => {
                    let q = body.positions()[near[s] as usize];
                    p.push([q[0], q[1] + 0.02, q[2]]);
                }
                None => {
                    index.push(i as u32);
                    p.push(body.positions()[k]);
                    k += 1;
                }
            }
        }
        let t = body
            .triangles()
            .iter()
            .map(|t| t.map(|v| index[v as usize]))
            .collect();
        (Mesh::new(p, t).unwrap(), index)
    }

    #[test]
    fn the_rig_of_the_body_is_the_rig_without_its_stray_vertices() {
        let body = humanoid_mesh(0.03);
        let lm = humanoid_landmarks(&body);
        let clean = Embedding::new(&body, &lm, None).unwrap();
        let top = (0..body.vertex_count() as u32)
            .max_by(|&a, &b| {
                body.positions()[a as usize][1].total_cmp(&body.positions()[b as usize][1])
            })
            .unwrap();
        let n = body.vertex_count();
        for at in [vec![0, n / 2, n + 2], vec![n, n + 1, n + 2]] {
            let (mesh, index) = with_strays(&body, &at, &[top, n as u32 / 2, 0]);
            // The landmarks are points: the same on both meshes.
            let e = Embedding::new(&mesh, &lm, None).unwrap();
            assert_eq!(e.joints(), clean.joints(), "{at:?}");
            assert_eq!(e.height(), clean.height(), "{at:?}");
            for (v, &w) in index.iter().enumerate() {
                let w = w as usize;
                assert_eq!(e.labels()[w], clean.labels()[v], "{at:?} {v}");
                assert_eq!(e.skin()[w], clean.skin()[v], "{at:?} {v}");
            }
            for (g, h) in e.regressors().iter().zip(clean.regressors()) {
                let back: Vec<u32> = h.vertices.iter().map(|&v| index[v as usize]).collect();
                assert_eq!(g.vertices, back, "{at:?}");
                assert_eq!(g.weights, h.weights, "{at:?}");
            }
            // The stray above the head's top: the head's part and skin.
            let head = crate::embed::parts::Part::Head.index() as u8;
            assert_eq!(e.labels()[at[0]], head, "{at:?}");
            assert!(
                e.regions()[head as usize].contains(&(at[0] as u32)),
                "{at:?}"
            );
        }
    }
}
