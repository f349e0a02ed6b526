//! Bone-heat skin weights (Baran & Popović 2007, "Automatic rigging and
//! animation of 3D characters", Sec. 4): the weight of joint j is the
//! equilibrium temperature when the bones of j are held at 1 and heat
//! diffuses over the surface,
//! `(−Δ + H) w_j = H p_j`, with `H_ii = 1 / d_i²` (`d_i` the distance from
//! vertex i to its nearest bone) and `p_j(i) = 1` where that bone is j's.
//! Multiplied through by the mass matrix it is the symmetric definite
//! `(−L + M H) w_j = M H p_j` (`L` the cotangent Laplacian), factored once
//! and solved for all joints together. Visibility of bones is not tested:
//! the nearest bone is taken as the one that heats a vertex.

use super::section::segment_distance;
use crate::mesh::Mesh;
use crate::mesh::laplacian::cotan_triplets;
use crate::mesh::mass::{MassKind, mass_diagonal};
use crate::mesh::solver::{FixedSolver, SolveError};
use crate::rig::Canonical;
use glam::DVec3;

/// A bone segment and the joint whose motion it follows.
#[derive(Debug, Clone, Copy)]
pub struct Bone {
    /// The driving joint.
    pub joint: Canonical,
    /// Start.
    pub a: DVec3,
    /// End.
    pub b: DVec3,
}

/// Dense weights: one row of [`Canonical::COUNT`] per vertex, summing to 1.
pub type Weights = Vec<[f64; Canonical::COUNT]>;

/// The nearest bone of each vertex and its distance.
///
/// Beyond a joint, a vertex's nearest point on both bones that meet there
/// is the joint itself: the two distances are equal, and which is smaller
/// was decided by rounding, so moving the mesh by 1e-9 m flipped the heat
/// source of whole caps of vertices (shoulder tops, the crotch) and up to
/// 1.1 % of the crane's labels. Distances within `1e-9` of the mesh's
/// bounding-box diagonal are a tie, won by the first bone in `bones`: in
/// [`super::bones`]' order (tree order, parents first) the proximal one, so
/// a shoulder top beyond the shoulder joint is heated by the chest's bone
/// and the side of the hip above the hip joint by the pelvis's (what an
/// exact tie gave before).
pub(crate) fn nearest_bones(positions: &[[f64; 3]], bones: &[Bone]) -> Vec<(usize, f64)> {
    let (lo, hi) = positions.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), q| {
            let p = DVec3::from_array(*q);
            (lo.min(p), hi.max(p))
        },
    );
    let tie = 1e-9 * (hi - lo).length();
    let tie = if tie.is_finite() { tie } else { 0.0 };
    positions
        .iter()
        .map(|q| {
            let p = DVec3::from_array(*q);
            let d: Vec<f64> = bones
                .iter()
                .map(|b| segment_distance(p, b.a, b.b))
                .collect();
            let Some(best) = d.iter().copied().min_by(f64::total_cmp) else {
                return (0, 1.0);
            };
            let i = (0..bones.len()).find(|&i| d[i] <= best + tie).unwrap_or(0);
            (i, d[i])
        })
        .collect()
}

/// Bone-heat weights for every vertex of `mesh`.
pub(crate) fn bone_heat(mesh: &Mesh, bones: &[Bone]) -> Result<Weights, SolveError> {
    let n = mesh.vertex_count();
    let diag = mesh.bounds().diagonal().max(1e-12);
    let near = nearest_bones(mesh.positions(), bones);
    let mass = mass_diagonal(mesh, MassKind::Barycentric);
    let mut k: Vec<(u32, u32, f64)> = cotan_triplets(mesh)
        .into_iter()
        .map(|(i, j, v)| (i, j, -v))
        .collect();
    let mut rhs = vec![[0.0; Canonical::COUNT]; n];
    // A vertex in no triangle (a mesh cut with a script leaves them) has no
    // mass and an empty row: given the mean mass it takes its nearest
    // bone's weight alone (before, the factorisation stopped at a zero
    // pivot, "not positive definite at vertex …", naming another vertex).
    let (sum, count) = mass
        .iter()
        .filter(|m| **m > 0.0)
        .fold((0.0, 0usize), |(s, c), m| (s + m, c + 1));
    let mean_mass = if count > 0 { sum / count as f64 } else { 1.0 };
    for (i, &(b, d)) in near.iter().enumerate() {
        let d = d.max(1e-4 * diag);
        let m = if mass[i] > 0.0 { mass[i] } else { mean_mass };
        let h = m / (d * d);
        k.push((i as u32, i as u32, h));
        rhs[i][bones[b].joint.index()] = h;
    }
    let solver = FixedSolver::definite(n, k)?;
    let mut ws = solver.workspace(Canonical::COUNT);
    let mut w = vec![[0.0; Canonical::COUNT]; n];
    solver.solve::<{ Canonical::COUNT }>(&rhs, &[], &mut w, &mut ws);
    for (row, &(b, _)) in w.iter_mut().zip(&near) {
        let mut s = 0.0;
        for x in row.iter_mut() {
            *x = if x.is_finite() { x.max(0.0) } else { 0.0 };
            s += *x;
        }
        if s > 1e-12 {
            row.iter_mut().for_each(|x| *x /= s);
        } else {
            *row = [0.0; Canonical::COUNT];
            row[bones[b].joint.index()] = 1.0;
        }
    }
    Ok(w)
}

/// Keeps the `K` largest weights of each row, dropping those below `min`,
/// renormalised: `(joint indices, weights)`; unused slots have weight 0.
pub(crate) fn sparsify<const K: usize>(w: &Weights, min: f64) -> Vec<([u8; K], [f64; K])> {
    w.iter()
        .map(|row| {
            let mut idx: Vec<usize> = (0..row.len()).collect();
            idx.sort_by(|&a, &b| row[b].total_cmp(&row[a]));
            let mut j = [0u8; K];
            let mut v = [0.0; K];
            for k in 0..K {
                j[k] = idx[k] as u8;
                v[k] = if k == 0 || row[idx[k]] >= min {
                    row[idx[k]]
                } else {
                    0.0
                };
            }
            let s: f64 = v.iter().sum();
            if s > 0.0 {
                v.iter_mut().for_each(|x| *x /= s);
            }
            (j, v)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::shapes::capsule_mesh;

    fn bones() -> [Bone; 2] {
        [
            Bone {
                joint: Canonical::Pelvis,
                a: DVec3::new(0.0, -0.6, 0.0),
                b: DVec3::ZERO,
            },
            Bone {
                joint: Canonical::Spine,
                a: DVec3::ZERO,
                b: DVec3::new(0.0, 0.6, 0.0),
            },
        ]
    }

    /// A vertex in no triangle (left by a cut made with a script) takes its
    /// nearest bone's weight alone and changes no other vertex's weights;
    /// before, the factorisation stopped at a zero pivot.
    #[test]
    fn a_vertex_in_no_triangle_takes_its_nearest_bone() {
        let cap = capsule_mesh(0.1, 1.0, 16, 8);
        let bones = bones();
        let whole = bone_heat(&cap, &bones).unwrap();
        for stray in [0usize, cap.vertex_count() / 2, cap.vertex_count()] {
            let mut p = cap.positions().to_vec();
            p.insert(stray, [0.05, 0.3, 0.02]);
            let tris: Vec<[u32; 3]> = cap
                .triangles()
                .iter()
                .map(|t| t.map(|v| v + u32::from(v as usize >= stray)))
                .collect();
            let mesh = Mesh::new(p, tris).unwrap();
            let w = bone_heat(&mesh, &bones).unwrap();
            let mut one_hot = [0.0; Canonical::COUNT];
            one_hot[Canonical::Spine.index()] = 1.0;
            assert_eq!(w[stray], one_hot, "stray vertex at {stray}");
            let others: Vec<_> = (0..w.len()).filter(|&i| i != stray).map(|i| w[i]).collect();
            for (i, (a, b)) in others.iter().zip(&whole).enumerate() {
                let d = a
                    .iter()
                    .zip(b)
                    .map(|(x, y)| (x - y).abs())
                    .fold(0.0, f64::max);
                assert!(d < 1e-9, "vertex {i}: weights moved by {d}");
            }
        }
    }
}
