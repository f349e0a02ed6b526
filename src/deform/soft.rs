//! Soft-region detection: how far each vertex may lag behind or leave its
//! skinning (a skirt, a loose sleeve), from its distance to the nearest bone.
//!
//! Used by [`crate::synth::database`] (the damped-spring lag of soft
//! tissue) and by [`super::lbs::constraint_vertices`] (linear blend
//! skinning would weld a skirt to a thigh, so soft vertices are never
//! constraints of Huang et al. 2015, Eq. 32).

use crate::embed::Embedding;
use crate::embed::heat::nearest_bones;
use crate::embed::parts::Part;
use crate::mesh::Mesh;

/// Softness of every vertex in [0, 1]: 0 up to 1.5 times the body's median
/// distance from skin to bone, rising to 1 at 2.5 times (a skirt, a loose
/// sleeve); always 0 on the head and feet. One entry per vertex of `rest`;
/// O(V · bones).
pub fn softness(rest: &Mesh, rig: &Embedding) -> Vec<f64> {
    let est_bones = crate::embed::bones_of(rig);
    let near = nearest_bones(rest.positions(), &est_bones);
    let mut all: Vec<f64> = near.iter().map(|x| x.1).collect();
    all.sort_by(f64::total_cmp);
    let med = all.get(all.len() / 2).copied().unwrap_or(1.0).max(1e-9);
    near.iter()
        .enumerate()
        .map(|(v, &(_, d))| {
            let p = Part::ALL[rig.labels[v] as usize];
            if matches!(p, Part::Head | Part::LFoot | Part::RFoot) {
                return 0.0;
            }
            (d / med - 1.5).clamp(0.0, 1.0)
        })
        .collect()
}
