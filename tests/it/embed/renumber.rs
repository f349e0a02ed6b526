//! Vertex and frame orders the automatic-rig tests draw: a fixed
//! pseudo-random order and a capture renumbered by an order.

use surfmotion::mesh::Mesh;

/// The fixed orders `autorig_eval` draws (the library's, so the tests
/// and the evaluation renumber alike).
pub(super) use surfmotion::tools::autorig::{EVAL_SEED, xorshift_order};

/// `mesh` and `frames` renumbered by `order`: new vertex `k` is old
/// vertex `order[k]`.
pub(super) fn renumbered<I: Copy + TryInto<usize>>(
    mesh: &Mesh,
    frames: &[Vec<[f64; 3]>],
    order: &[I],
) -> (Mesh, Vec<Vec<[f64; 3]>>) {
    let at = |o: I| o.try_into().ok().expect("a vertex index");
    let mut new_of = vec![0u32; order.len()];
    for (k, &o) in order.iter().enumerate() {
        new_of[at(o)] = k as u32;
    }
    let put = |f: &[[f64; 3]]| -> Vec<[f64; 3]> { order.iter().map(|&o| f[at(o)]).collect() };
    let tris = mesh
        .triangles()
        .iter()
        .map(|t| t.map(|i| new_of[i as usize]))
        .collect();
    let m = Mesh::new(put(mesh.positions()), tris).unwrap();
    (m, frames.iter().map(|f| put(f)).collect())
}
