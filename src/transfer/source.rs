//! Marker motion per frame (de Aguiar et al. 2007, Secs. 5-6): the rotation
//! of every marker from the reference pose and where its centroid goes,
//! from a mocap skeleton or from a moving template mesh.
//!
//! * **Mocap** (Sec. 5): the clip is retargeted to the scan's embedded
//!   skeleton (bone directions from the clip, lengths from the scan, root
//!   scaled by the leg-length ratio; [`crate::synth::database::retarget`]).
//!   A marker on a bone turns with the bone's global rotation and rides on
//!   it: `target = J_j(t) + R_j(t) (c − J_j(rest))`.
//! * **Template** (Sec. 6): a marker turns like its template triangle, whose
//!   rotation is the polar part of the summed deformation gradients of the
//!   triangle and its neighbours (robust to capture noise); its centroid
//!   moves by the template triangle's displacement, scaled by the ratio of
//!   body heights.

use crate::mesh::frames::{polar, triangle_frame};
use crate::rig::Canonical;
use crate::skeleton::Pose;
use glam::{DMat3, DQuat, DVec3};

/// Marker rotations and targets for every frame, row-major frames × markers.
#[derive(Debug, Clone, Default)]
pub struct MarkerMotion {
    /// Markers per frame.
    pub markers: usize,
    /// Rotation from the reference pose.
    pub rotations: Vec<DQuat>,
    /// Target centroid position.
    pub targets: Vec<DVec3>,
}

impl MarkerMotion {
    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.rotations.len() / self.markers.max(1)
    }

    /// Frame `f`'s rotations and targets.
    pub fn frame(&self, f: usize) -> (&[DQuat], &[DVec3]) {
        let r = f * self.markers..(f + 1) * self.markers;
        (&self.rotations[r.clone()], &self.targets[r])
    }
}

/// Motion of bone markers from skeleton frames. `rest` is the scan's
/// skeleton; `frames` are (pose, global joint rotations from `rest`) as
/// [`crate::synth::database::retarget`] gives them; `bones[m]` and
/// `centroids[m]` are marker m's driving joint and rest centroid.
pub fn from_skeleton(
    rest: &Pose,
    frames: &[(Pose, [DQuat; Canonical::COUNT])],
    bones: &[Canonical],
    centroids: &[DVec3],
) -> MarkerMotion {
    let mut m = MarkerMotion {
        markers: bones.len(),
        rotations: Vec::with_capacity(frames.len() * bones.len()),
        targets: Vec::with_capacity(frames.len() * bones.len()),
    };
    for (pose, g) in frames {
        for (&b, &c) in bones.iter().zip(centroids) {
            let j = b.index();
            m.rotations.push(g[j]);
            m.targets.push(pose[j] + g[j] * (c - rest[j]));
        }
    }
    m
}

/// A template mesh's marker triangles with their neighbours.
pub struct TemplateMarkers {
    /// Per marker: the triangles whose gradients are summed.
    pub patches: Vec<Vec<u32>>,
    /// Per marker: its own triangle.
    pub triangles: Vec<u32>,
}

impl TemplateMarkers {
    /// Marker triangles on a template with its triangles `t` and `n`
    /// vertices; each patch is the triangle and those sharing a vertex.
    pub fn new(t: &[[u32; 3]], n: usize, markers: &[u32]) -> TemplateMarkers {
        let mut by_vertex: Vec<Vec<u32>> = vec![Vec::new(); n];
        for (i, tv) in t.iter().enumerate() {
            for &v in tv {
                by_vertex[v as usize].push(i as u32);
            }
        }
        let patches = markers
            .iter()
            .map(|&m| {
                let mut p: Vec<u32> = t[m as usize]
                    .iter()
                    .flat_map(|&v| by_vertex[v as usize].iter().copied())
                    .collect();
                p.sort_unstable();
                p.dedup();
                p
            })
            .collect();
        TemplateMarkers {
            patches,
            triangles: markers.to_vec(),
        }
    }
}

/// Motion of template markers over a sequence. `frames` are the template's
/// vertex positions per frame, `t` its triangles, `reference` its reference
/// frame; `centroids[m]` is the scan marker's rest centroid, `scale`
/// multiplies the template's displacements and `align` turns the template's
/// frame into the scan's (rotations are conjugated, displacements turned).
pub fn from_template(
    frames: &[&[[f64; 3]]],
    reference: &[[f64; 3]],
    t: &[[u32; 3]],
    markers: &TemplateMarkers,
    centroids: &[DVec3],
    scale: f64,
    align: DQuat,
) -> MarkerMotion {
    let frame_of = |p: &[[f64; 3]], i: u32| {
        let [a, b, c] = t[i as usize].map(|v| DVec3::from_array(p[v as usize]));
        triangle_frame(a, b, c)
    };
    let centre = |p: &[[f64; 3]], i: u32| {
        t[i as usize]
            .iter()
            .map(|&v| DVec3::from_array(p[v as usize]))
            .sum::<DVec3>()
            / 3.0
    };
    let rest_inv: Vec<Vec<DMat3>> = markers
        .patches
        .iter()
        .map(|patch| {
            patch
                .iter()
                .map(|&i| {
                    let f = frame_of(reference, i);
                    if f.determinant().abs() > 1e-300 {
                        f.inverse()
                    } else {
                        DMat3::ZERO
                    }
                })
                .collect()
        })
        .collect();
    let rest_centre: Vec<DVec3> = markers
        .triangles
        .iter()
        .map(|&i| centre(reference, i))
        .collect();
    let k = markers.triangles.len();
    let mut m = MarkerMotion {
        markers: k,
        rotations: Vec::with_capacity(frames.len() * k),
        targets: Vec::with_capacity(frames.len() * k),
    };
    for p in frames {
        for (mi, patch) in markers.patches.iter().enumerate() {
            let mut g = DMat3::ZERO;
            for (&i, inv) in patch.iter().zip(&rest_inv[mi]) {
                g += frame_of(p, i) * *inv;
            }
            m.rotations
                .push((align * polar(g).0 * align.conjugate()).normalize());
            let d = centre(p, markers.triangles[mi]) - rest_centre[mi];
            m.targets.push(centroids[mi] + align * d * scale);
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn template_rotation_is_recovered() {
        let m = crate::mesh::subdivide::icosahedron();
        let r = DQuat::from_axis_angle(DVec3::new(1.0, -2.0, 0.5).normalize(), 1.2);
        let moved: Vec<[f64; 3]> = m
            .positions()
            .iter()
            .map(|p| (r * DVec3::from_array(*p) + DVec3::X).to_array())
            .collect();
        let tm = TemplateMarkers::new(m.triangles(), m.vertex_count(), &[0, 7]);
        let c = [DVec3::ZERO, DVec3::ONE];
        let mo = from_template(
            &[&moved],
            m.positions(),
            m.triangles(),
            &tm,
            &c,
            1.0,
            DQuat::IDENTITY,
        );
        assert_eq!(mo.frames(), 1);
        for q in &mo.rotations {
            assert!(q.dot(r).abs() > 1.0 - 1e-9);
        }
        let (_, tg) = mo.frame(0);
        // Each centroid moves by its template triangle's displacement.
        let tri = m.triangles()[0].map(|v| DVec3::from_array(m.positions()[v as usize]));
        let cen = (tri[0] + tri[1] + tri[2]) / 3.0;
        assert!((tg[0] - (r * cen + DVec3::X - cen)).length() < 1e-9);
    }
}
