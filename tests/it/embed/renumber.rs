//! Vertex and frame orders the automatic-rig tests draw: a fixed
//! pseudo-random order and a capture renumbered by an order.

use surfmotion::mesh::Mesh;

/// A fixed shuffle of `0..n` (xorshift from `seed`; the same every run):
/// with seed [`EVAL_SEED`] the order `examples/autorig_eval.rs` draws.
pub(super) fn xorshift_order(n: usize, seed: u64) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    let mut x = seed;
    for i in (1..n).rev() {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        order.swap(i, (x % (i as u64 + 1)) as usize);
    }
    order
}

/// The seed of `autorig_eval`'s renumbering.
pub(super) const EVAL_SEED: u64 = 0x2545_F491_4F6C_DD1D;

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
