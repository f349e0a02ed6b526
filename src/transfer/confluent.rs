//! The Confluent Motion deformation (de Aguiar et al. 2007, Sec. 4.1):
//! marker rotations → harmonic quaternion field (Eq. 2) → per-triangle
//! rotations → Poisson reconstruction of the fragmented mesh (Eqs. 3-4) →
//! placement.
//!
//! Both sparse systems are factored once per scan and marker set: the
//! harmonic system with the marker vertices fixed (only their values change
//! per frame) and the cotangent Poisson system. A frame costs one 4-column
//! and one 3-column prefactored solve plus O(triangles) work, with no
//! allocation.
//!
//! Eq. 3-4 in our terms: each triangle t of the fragmented mesh M′ is the
//! reference triangle turned by its rotation R_t; summing its cotangent
//! Laplacian rows by the connectivity of M gives `U_reduced`, and
//! `L x = U_reduced` is the Poisson system of [`Poisson`] with `T_t = R_t`.

use super::signs::{SignMode, orient};
use crate::mesh::Mesh;
use crate::mesh::components::components;
use crate::mesh::harmonic::{Harmonic, HarmonicWorkspace};
use crate::mesh::poisson::{Poisson, PoissonWorkspace};
use crate::mesh::solver::SolveError;
use glam::{DMat3, DQuat, DVec3};

/// Weight of each marker's pull towards its target in the Poisson solve
/// (dimensionless: against the cotangent Laplacian's edge weights).
///
/// The paper places the reconstructed mesh by a translation alone: the
/// rotations, interpolated over the surface, decide where each limb goes.
/// Where the surface joins two limbs the clip moves apart (the samba
/// dancer's skirt over both thighs), the interpolated rotations there
/// are a blend of both legs' and the integrated legs stayed together:
/// frame 160 of the self-transfer put the feet 10-11 cm from where the
/// skeleton carries them (the dancer's legs 37 cm apart). Each marker's
/// centroid is now also pulled towards its target (a soft constraint),
/// so the limbs go where the skeleton puts them while the rotations keep
/// the surface's shape. Self-transfer of the samba capture, mean % of
/// the height at 20 / 80 / 180 markers: 3.23 / 2.81 / 2.66 without the
/// pull, 2.89 / 2.32 / 2.10 at 0.1; 0.2 and above gave ground
/// penetration of 1.3 cm and more and turned-over triangles on CMU 03_02.
const PULL_WEIGHT: f64 = 0.1;

fn pull_weight() -> f64 {
    PULL_WEIGHT
}

/// A scan prefactored for one marker set.
pub struct Confluent {
    n: usize,
    harmonic: Harmonic,
    /// For each harmonic boundary vertex, the marker giving its value.
    boundary_marker: Vec<u32>,
    poisson: Poisson,
    marker_triangles: Vec<[u32; 3]>,
    /// Connected component of each vertex and of each marker.
    vertex_component: Vec<u32>,
    marker_component: Vec<u32>,
    components: usize,
}

/// Per-frame scratch for [`Confluent::frame`].
pub struct ConfluentWorkspace {
    values: Vec<[f64; 4]>,
    field: Vec<[f64; 4]>,
    hws: HarmonicWorkspace<4>,
    pws: PoissonWorkspace,
    shift: Vec<(DVec3, u32)>,
}

/// What happened in one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Triangles whose interpolated quaternion nearly vanished (|q| < 0.05
    /// before normalising): where a collapse would start.
    pub weak_triangles: usize,
}

/// Why a scan cannot be prefactored.
#[derive(Debug, thiserror::Error)]
pub enum ConfluentError {
    /// A marker names a triangle the mesh does not have.
    #[error("marker {index}: triangle {triangle} is out of range (the mesh has {count})")]
    Triangle {
        /// The marker.
        index: usize,
        /// Its triangle.
        triangle: u32,
        /// Triangles of the mesh.
        count: usize,
    },
    /// A connected component has no marker: nothing drives it.
    #[error(
        "a connected component of {vertices} vertices (vertex {vertex}) has no marker; repair the scan or drop it"
    )]
    Unmarked {
        /// A vertex of it.
        vertex: u32,
        /// Its size.
        vertices: usize,
    },
    /// A factorisation failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
}

impl Confluent {
    /// Factors both systems for `mesh` (the reference pose) with the given
    /// marker triangles. Every connected component needs a marker.
    pub fn new(mesh: &Mesh, markers: &[u32]) -> Result<Confluent, ConfluentError> {
        let t = mesh.triangles();
        let n = mesh.vertex_count();
        let mut owner = vec![u32::MAX; n];
        let mut boundary = Vec::new();
        let mut boundary_marker = Vec::new();
        let mut marker_triangles = Vec::with_capacity(markers.len());
        for (m, &tri) in markers.iter().enumerate() {
            let tv = *t.get(tri as usize).ok_or(ConfluentError::Triangle {
                index: m,
                triangle: tri,
                count: t.len(),
            })?;
            marker_triangles.push(tv);
            for v in tv {
                if owner[v as usize] == u32::MAX {
                    owner[v as usize] = m as u32;
                    boundary.push(v);
                    boundary_marker.push(m as u32);
                }
            }
        }
        let c = components(mesh);
        let marker_component: Vec<u32> = marker_triangles
            .iter()
            .map(|tv| c.label[tv[0] as usize])
            .collect();
        let mut marked = vec![false; c.count];
        for &k in &marker_component {
            marked[k as usize] = true;
        }
        if let Some(k) = marked.iter().position(|&m| !m) {
            let vertex = c.label.iter().position(|&l| l == k as u32).unwrap_or(0) as u32;
            let vertices = c.label.iter().filter(|&&l| l == k as u32).count();
            return Err(ConfluentError::Unmarked { vertex, vertices });
        }
        Ok(Confluent {
            n,
            harmonic: Harmonic::new(mesh, &boundary)?,
            boundary_marker,
            poisson: Poisson::with_soft_centroids(mesh, &marker_triangles, pull_weight())?,
            marker_triangles,
            vertex_component: c.label,
            marker_component,
            components: c.count,
        })
    }

    /// Number of markers.
    pub fn marker_count(&self) -> usize {
        self.marker_triangles.len()
    }

    /// Number of vertices.
    pub fn vertex_count(&self) -> usize {
        self.n
    }

    /// Scratch space for [`Confluent::frame`].
    pub fn workspace(&self) -> ConfluentWorkspace {
        ConfluentWorkspace {
            values: vec![[0.0; 4]; self.boundary_marker.len()],
            field: vec![[0.0; 4]; self.n],
            hws: self.harmonic.workspace(),
            pws: self.poisson.workspace(),
            shift: vec![(DVec3::ZERO, 0); self.components],
        }
    }

    /// Poses the scan for one frame. `rotations[m]` turns marker m from the
    /// reference pose (signs already chosen, see [`orient_frames`]);
    /// `targets[m]` is where its centroid should go: the Poisson solve
    /// pulls it there ([`PULL_WEIGHT`]), and each connected component is
    /// translated so its markers' centroids best meet their targets
    /// (least squares). Writes `out` (one row per vertex).
    pub fn frame(
        &self,
        rotations: &[DQuat],
        targets: &[DVec3],
        ws: &mut ConfluentWorkspace,
        out: &mut [[f64; 3]],
    ) -> FrameStats {
        for (v, &m) in ws.values.iter_mut().zip(&self.boundary_marker) {
            let q = rotations[m as usize];
            *v = [q.w, q.x, q.y, q.z];
        }
        self.harmonic.solve(&ws.values, &mut ws.field, &mut ws.hws);
        let mut stats = FrameStats::default();
        let field = &ws.field;
        let tris = self.poisson_triangles();
        self.poisson.assemble_with(&mut ws.pws, |t| {
            let tv = tris[t];
            let mut s = [0.0; 4];
            for v in tv {
                let f = field[v as usize];
                for k in 0..4 {
                    s[k] += f[k];
                }
            }
            let q = DQuat::from_xyzw(s[1], s[2], s[3], s[0]);
            let len = q.length() / 3.0;
            if len < 0.05 {
                stats.weak_triangles += 1;
            }
            if len > 1e-12 && q.is_finite() {
                DMat3::from_quat(q.normalize())
            } else {
                DMat3::IDENTITY
            }
        });
        Poisson::pull_centroids(&mut ws.pws, &self.marker_triangles, targets, pull_weight());
        self.poisson.solve(&mut ws.pws, out);
        // Placement: one translation per component.
        ws.shift.iter_mut().for_each(|s| *s = (DVec3::ZERO, 0));
        for ((tv, &c), target) in self
            .marker_triangles
            .iter()
            .zip(&self.marker_component)
            .zip(targets)
        {
            let centroid = tv
                .iter()
                .map(|&v| DVec3::from_array(out[v as usize]))
                .sum::<DVec3>()
                / 3.0;
            let s = &mut ws.shift[c as usize];
            s.0 += *target - centroid;
            s.1 += 1;
        }
        for (p, &c) in out.iter_mut().zip(&self.vertex_component) {
            let (d, k) = ws.shift[c as usize];
            let d = d / k.max(1) as f64;
            p[0] += d.x;
            p[1] += d.y;
            p[2] += d.z;
        }
        stats
    }

    fn poisson_triangles(&self) -> &[[u32; 3]] {
        self.poisson.triangles()
    }

    /// Centroid of every marker triangle on `positions`.
    #[cfg(test)]
    pub(crate) fn marker_centroids(&self, positions: &[[f64; 3]]) -> Vec<DVec3> {
        self.marker_triangles
            .iter()
            .map(|tv| {
                tv.iter()
                    .map(|&v| DVec3::from_array(positions[v as usize]))
                    .sum::<DVec3>()
                    / 3.0
            })
            .collect()
    }
}

/// Chooses the quaternion signs of a whole clip in order (each frame
/// against the previous, see [`orient`]); `rotations` is frames × markers,
/// row-major. Returns the number of frames with a near-singular marker.
pub fn orient_frames(rotations: &mut [DQuat], markers: usize, mode: SignMode) -> usize {
    let mut singular = 0;
    let mut prev = None;
    for f in rotations.chunks_mut(markers.max(1)) {
        let (s, mean) = orient(f, prev, mode);
        singular += usize::from(s > 0);
        prev = Some(mean);
    }
    singular
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::shapes::capsule_mesh;

    fn capsule() -> Mesh {
        capsule_mesh(0.1, 1.0, 16, 24)
    }

    /// Markers on triangles spread over the capsule.
    fn markers(m: &Mesh, k: usize) -> Vec<u32> {
        let n = m.triangle_count();
        (0..k).map(|i| (i * n / k) as u32).collect()
    }

    #[test]
    fn identity_motion_leaves_the_mesh() {
        let m = capsule();
        let mk = markers(&m, 12);
        let c = Confluent::new(&m, &mk).unwrap();
        let rot = vec![DQuat::IDENTITY; mk.len()];
        let tg = c.marker_centroids(m.positions());
        let mut ws = c.workspace();
        let mut out = vec![[0.0; 3]; m.vertex_count()];
        let s = c.frame(&rot, &tg, &mut ws, &mut out);
        assert_eq!(s.weak_triangles, 0);
        for (a, b) in out.iter().zip(m.positions()) {
            for k in 0..3 {
                assert!((a[k] - b[k]).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn rigid_rotation_of_all_markers_rotates_the_mesh() {
        let m = capsule();
        let mk = markers(&m, 12);
        let c = Confluent::new(&m, &mk).unwrap();
        let r = DQuat::from_axis_angle(DVec3::new(0.3, 1.0, -0.2).normalize(), 2.5);
        let shift = DVec3::new(0.5, -1.0, 2.0);
        let rot = vec![r; mk.len()];
        let tg: Vec<DVec3> = c
            .marker_centroids(m.positions())
            .into_iter()
            .map(|p| r * p + shift)
            .collect();
        let mut ws = c.workspace();
        let mut out = vec![[0.0; 3]; m.vertex_count()];
        c.frame(&rot, &tg, &mut ws, &mut out);
        for (a, b) in out.iter().zip(m.positions()) {
            let want = r * DVec3::from_array(*b) + shift;
            assert!((DVec3::from_array(*a) - want).length() < 1e-9);
        }
    }

    #[test]
    fn unmarked_component_is_an_error() {
        let a = capsule();
        let n = a.vertex_count() as u32;
        let mut p = a.positions().to_vec();
        p.extend(a.positions().iter().map(|q| [q[0] + 1.0, q[1], q[2]]));
        let mut t = a.triangles().to_vec();
        t.extend(a.triangles().iter().map(|tv| tv.map(|v| v + n)));
        let two = Mesh::new(p, t).unwrap();
        assert!(matches!(
            Confluent::new(&two, &[0, 5]),
            Err(ConfluentError::Unmarked { .. })
        ));
        assert!(matches!(
            Confluent::new(&two, &[u32::MAX]),
            Err(ConfluentError::Triangle { .. })
        ));
    }
}
