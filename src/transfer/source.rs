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
use crate::pose::Pose;
use crate::rig::Canonical;
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
    /// Where the feet stand, per frame (mocap sources): the solved surface
    /// is stood on it ([`FootGround::shifts`]).
    pub feet: Option<FootGround>,
}

/// The floor each foot of the scan touches per frame, from the clip's
/// support (the kernel's [`crate::pose::retarget::Support::touch`]): the
/// kernel stands a sole model of the skeleton (toe joint, heel point) on
/// the ground, but the surface the markers deform has its own sole: on
/// the samba self-transfer the solved feet stood a median 1.7 cm above
/// the floor at 20 markers, and a CMU walk's went 5 cm through it. The
/// kernel's rule, applied to the surface: in a frame where a foot of the
/// clip touches the floor, the surface moves along the scan's up axis so that each
/// touching foot's lowest vertex is on or above the floor (its height in
/// the rest scan) and the foot that needs it highest stands on it; a
/// foot in the air is held above the floor only. Frames where a foot
/// stands on a block, and frames in the air, take the shift
/// interpolated between floor frames: on blocks the kernel's ground is
/// its own (taking its block tops stood CMU 03_02's surface 11 cm up on
/// a block its swinging foot was over). The shifts are then smoothed over
/// time, never below a touching frame's own (`transfer::run`'s
/// `chunk_shifts`). A clip standing as the rest frame gives the rest scan.
#[derive(Debug, Clone, Default)]
pub struct FootGround {
    /// The scan's up axis (unit; heights and the shift are along it).
    pub up: [f64; 3],
    /// Vertices of each foot (left, right): its part of the rig's labels.
    pub vertices: [Vec<u32>; 2],
    /// Each foot's lowest vertex height in the rest scan: the floor.
    pub rest_low: [f64; 2],
    /// Per foot and frame, whether it touches the floor; `None` for a
    /// frame where a foot stands on a block or none touches.
    pub touch: Vec<Option<[bool; 2]>>,
    /// Frames per second of the motion (the floor shift's smoothing is
    /// set in seconds).
    pub fps: f64,
}

fn dot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl FootGround {
    /// The vertical shift of frame `f` solved as `positions`: `None`
    /// when no foot touches the floor or one stands on a block (the
    /// caller interpolates).
    pub fn shift(&self, f: usize, positions: &[[f64; 3]]) -> Option<f64> {
        let touch = self.touch.get(f).copied().flatten()?;
        let d = (0..2)
            .filter_map(|foot| {
                let low = self.vertices[foot]
                    .iter()
                    .filter_map(|&v| positions.get(v as usize).map(|p| dot(p, &self.up)))
                    .fold(f64::INFINITY, f64::min);
                let d = self.rest_low[foot] - low;
                d.is_finite().then_some((touch[foot], d))
            })
            .collect::<Vec<_>>();
        // The touching feet stand on the floor; a foot in the air only
        // stays above it.
        let on = d.iter().filter(|x| x.0).map(|x| x.1).reduce(f64::max)?;
        Some(d.iter().map(|x| x.1).fold(on, f64::max))
    }
}

impl MarkerMotion {
    /// The frame rate of the motion, for what is set in seconds (the
    /// floor shift's smoothing; 30 fps unless set).
    pub(crate) fn set_fps(&mut self, fps: f64) {
        if let Some(f) = self.feet.as_mut() {
            f.fps = fps;
        }
    }

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
pub(crate) fn from_skeleton(
    rest: &Pose,
    frames: &[(Pose, [DQuat; Canonical::COUNT])],
    bones: &[Canonical],
    centroids: &[DVec3],
) -> MarkerMotion {
    let mut m = MarkerMotion {
        markers: bones.len(),
        rotations: Vec::with_capacity(frames.len() * bones.len()),
        targets: Vec::with_capacity(frames.len() * bones.len()),
        feet: None,
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
pub(crate) struct TemplateMarkers {
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
pub(crate) fn from_template(
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
        feet: None,
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
