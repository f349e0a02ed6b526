//! The triangle mesh every stage works on.

use super::error::TopologyError;
use serde::Serialize;
use std::collections::HashSet;

/// A named range of triangles (an OBJ `g`/`o` group).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Group {
    /// Group name.
    pub name: String,
    /// First triangle.
    pub start: u32,
    /// One past the last triangle.
    pub end: u32,
}

/// A triangle mesh: struct-of-arrays positions and `u32` triangles, with
/// optional per-vertex colours (0..1) and triangle groups.
///
/// Invariants, checked by [`Mesh::new`]: every index is below the vertex
/// count and every coordinate is finite. Degenerate and duplicate triangles
/// are allowed (real scans have them) and listed by [`Mesh::problems`].
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    positions: Vec<[f64; 3]>,
    triangles: Vec<[u32; 3]>,
    colors: Option<Vec<[f64; 3]>>,
    groups: Vec<Group>,
}

/// Axis-aligned bounds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Bounds {
    /// Minimum corner.
    pub min: [f64; 3],
    /// Maximum corner.
    pub max: [f64; 3],
}

impl Bounds {
    /// Bounds of a point set (zeros if empty).
    pub fn of(points: &[[f64; 3]]) -> Bounds {
        if points.is_empty() {
            return Bounds {
                min: [0.0; 3],
                max: [0.0; 3],
            };
        }
        let mut min = [f64::INFINITY; 3];
        let mut max = [f64::NEG_INFINITY; 3];
        for p in points {
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
            }
        }
        Bounds { min, max }
    }
    /// Length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        let d: f64 = (0..3).map(|k| (self.max[k] - self.min[k]).powi(2)).sum();
        d.sqrt()
    }
}

/// Checks that all coordinates are finite.
pub(crate) fn check_finite(points: &[[f64; 3]]) -> Result<(), TopologyError> {
    match points.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
        Some(vertex) => Err(TopologyError::NonFinite { vertex }),
        None => Ok(()),
    }
}

impl Mesh {
    /// Builds a mesh, checking indices and coordinates.
    pub fn new(positions: Vec<[f64; 3]>, triangles: Vec<[u32; 3]>) -> Result<Mesh, TopologyError> {
        if positions.len() > u32::MAX as usize || triangles.len() > u32::MAX as usize {
            return Err(TopologyError::TooLarge);
        }
        check_finite(&positions)?;
        let n = positions.len();
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&v) = tri.iter().find(|&&v| v as usize >= n) {
                return Err(TopologyError::IndexOutOfRange {
                    triangle: t,
                    vertex: v,
                    vertices: n,
                });
            }
        }
        Ok(Mesh {
            positions,
            triangles,
            colors: None,
            groups: Vec::new(),
        })
    }

    /// Adds per-vertex colours (must have one per vertex; values are clamped to 0..1).
    pub fn with_colors(mut self, colors: Vec<[f64; 3]>) -> Result<Mesh, TopologyError> {
        if colors.len() != self.positions.len() {
            return Err(TopologyError::FrameSize {
                frame: 0,
                got: colors.len(),
                expected: self.positions.len(),
            });
        }
        check_finite(&colors)?;
        self.colors = Some(
            colors
                .into_iter()
                .map(|c| c.map(|v| v.clamp(0.0, 1.0)))
                .collect(),
        );
        Ok(self)
    }

    /// Sets the triangle groups (ranges are clamped to the triangle count).
    pub(crate) fn with_groups(mut self, groups: Vec<Group>) -> Mesh {
        let nt = self.triangles.len() as u32;
        self.groups = groups
            .into_iter()
            .map(|g| Group {
                start: g.start.min(nt),
                end: g.end.min(nt),
                name: g.name,
            })
            .filter(|g| g.end > g.start)
            .collect();
        self
    }

    /// Vertex positions.
    pub fn positions(&self) -> &[[f64; 3]] {
        &self.positions
    }
    /// Triangles (counter-clockwise seen from outside, by convention).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }
    /// Per-vertex colours, if any.
    pub fn colors(&self) -> Option<&[[f64; 3]]> {
        self.colors.as_deref()
    }
    /// Triangle groups.
    pub fn groups(&self) -> &[Group] {
        &self.groups
    }
    /// The mesh made of the triangles of the named groups only (all
    /// vertices kept; a repair drops the unused ones). `None` if a name is
    /// not a group of the mesh.
    pub fn select_groups(&self, names: &[String]) -> Option<Mesh> {
        let mut tris = Vec::new();
        for name in names {
            let g = self.groups.iter().find(|g| &g.name == name)?;
            tris.extend_from_slice(self.triangles.get(g.start as usize..g.end as usize)?);
        }
        let mut m = Mesh::new(self.positions.clone(), tris).ok()?;
        m.colors = self.colors.clone();
        Some(m)
    }

    /// The mesh of the triangles whose corners all have `keep` set (one
    /// flag per vertex; a vertex without one is not kept) and only the
    /// vertices they use, in order; and those vertices' numbers in this
    /// mesh (colours kept, groups dropped).
    pub fn keep_vertices(&self, keep: &[bool]) -> Result<(Mesh, Vec<usize>), TopologyError> {
        let kept = |v: u32| keep.get(v as usize).copied().unwrap_or(false);
        let tris: Vec<[u32; 3]> = self
            .triangles
            .iter()
            .copied()
            .filter(|t| t.iter().all(|&v| kept(v)))
            .collect();
        let n = self.positions.len();
        let mut index = vec![u32::MAX; n];
        tris.iter().flatten().for_each(|&v| index[v as usize] = 0);
        let old: Vec<usize> = (0..n).filter(|&v| index[v] == 0).collect();
        for (i, &v) in old.iter().enumerate() {
            index[v] = i as u32;
        }
        let pick = |f: &[[f64; 3]]| old.iter().map(|&v| f[v]).collect::<Vec<_>>();
        let tris = tris.iter().map(|t| t.map(|v| index[v as usize])).collect();
        let mut m = Mesh::new(pick(&self.positions), tris)?;
        if let Some(c) = &self.colors {
            m.colors = Some(pick(c));
        }
        Ok((m, old))
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Replaces the positions (same count, finite), keeping the topology.
    pub fn set_positions(&mut self, p: &[[f64; 3]]) -> Result<(), TopologyError> {
        if p.len() != self.positions.len() {
            return Err(TopologyError::FrameSize {
                frame: 0,
                got: p.len(),
                expected: self.positions.len(),
            });
        }
        check_finite(p)?;
        self.positions.copy_from_slice(p);
        Ok(())
    }

    /// A copy with other positions (same count, finite).
    pub fn with_positions(&self, p: &[[f64; 3]]) -> Result<Mesh, TopologyError> {
        let mut m = self.clone();
        m.set_positions(p)?;
        Ok(m)
    }

    /// Bounding box.
    pub fn bounds(&self) -> Bounds {
        Bounds::of(&self.positions)
    }

    /// The vertices in no triangle, in order.
    pub fn unreferenced(&self) -> Vec<usize> {
        let mut used = vec![false; self.positions.len()];
        for t in &self.triangles {
            for &v in t {
                used[v as usize] = true;
            }
        }
        (0..used.len()).filter(|&v| !used[v]).collect()
    }

    /// Non-fatal problems: degenerate triangles (a repeated vertex, or zero
    /// area), duplicate triangles, unreferenced vertices. Each message gives
    /// the count and the first index.
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        let mut repeated = Vec::new();
        let mut zero_area = Vec::new();
        let mut dup = Vec::new();
        let mut seen = HashSet::with_capacity(self.triangles.len());
        for (t, &[a, b, c]) in self.triangles.iter().enumerate() {
            if a == b || b == c || a == c {
                repeated.push(t);
                continue;
            }
            let mut key = [a, b, c];
            key.sort_unstable();
            if !seen.insert(key) {
                dup.push(t);
            }
            let (pa, pb, pc) = (
                self.positions[a as usize],
                self.positions[b as usize],
                self.positions[c as usize],
            );
            let u = [pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]];
            let v = [pc[0] - pa[0], pc[1] - pa[1], pc[2] - pa[2]];
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            if n.iter().all(|x| *x == 0.0) {
                zero_area.push(t);
            }
        }
        let mut say = |what: &str, v: &[usize]| {
            if let Some(first) = v.first() {
                out.push(format!("{} {what} (first: triangle {first})", v.len()));
            }
        };
        say("triangles with a repeated vertex", &repeated);
        say("zero-area triangles", &zero_area);
        say("duplicate triangles", &dup);
        let unused = self.unreferenced();
        if let Some(first) = unused.first() {
            out.push(format!(
                "{} unreferenced vertices (first: vertex {first})",
                unused.len()
            ));
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constructor_rejects_bad_index_and_nan() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert_eq!(
            Mesh::new(p.clone(), vec![[0, 1, 3]]).unwrap_err(),
            TopologyError::IndexOutOfRange {
                triangle: 0,
                vertex: 3,
                vertices: 3
            }
        );
        let mut q = p.clone();
        q[2][1] = f64::NAN;
        assert_eq!(
            Mesh::new(q, vec![[0, 1, 2]]).unwrap_err(),
            TopologyError::NonFinite { vertex: 2 }
        );
        let m = Mesh::new(p, vec![[0, 1, 2], [2, 1, 0], [0, 0, 1]]).unwrap();
        let pr = m.problems();
        assert!(
            pr.iter()
                .any(|s| s.starts_with("1 triangles with a repeated vertex")),
            "{pr:?}"
        );
        assert!(pr.iter().any(|s| s.starts_with("1 duplicate")), "{pr:?}");
    }

    /// A strip of two triangles with the middle vertex dropped keeps no
    /// triangle; with the first dropped, the second triangle renumbered;
    /// a short flag list keeps nothing past it (no panic).
    #[test]
    fn keep_vertices_keeps_whole_triangles_renumbered() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
        let m = Mesh::new(p.clone(), vec![[0, 1, 2], [1, 3, 2]]).unwrap();
        let (k, old) = m.keep_vertices(&[false, true, true, true]).unwrap();
        assert_eq!(old, vec![1, 2, 3]);
        assert_eq!(k.triangles(), &[[0, 2, 1]]);
        assert_eq!(k.positions(), &[p[1], p[2], p[3]]);
        let (k, old) = m.keep_vertices(&[true, true, false, true]).unwrap();
        assert!(old.is_empty() && k.triangle_count() == 0);
        let (k, _) = m.keep_vertices(&[true, true, true]).unwrap();
        assert_eq!(k.triangle_count(), 1);
    }
}
