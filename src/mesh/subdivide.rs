//! Midpoint (1-to-4) subdivision, for building larger test and benchmark
//! meshes from real ones, and a unit icosahedron.

use super::Mesh;
use std::collections::HashMap;

/// Splits every triangle into four at its edge midpoints. Vertices grow to
/// about 4× (V + E), triangles exactly 4×. Colours and groups are dropped.
pub fn midpoint(mesh: &Mesh) -> Mesh {
    let mut pos = mesh.positions().to_vec();
    let mut mid: HashMap<(u32, u32), u32> = HashMap::with_capacity(mesh.triangle_count() * 3 / 2);
    let mut tris = Vec::with_capacity(mesh.triangle_count() * 4);
    let mut edge = |a: u32, b: u32, pos: &mut Vec<[f64; 3]>| -> u32 {
        let key = (a.min(b), a.max(b));
        *mid.entry(key).or_insert_with(|| {
            let (p, q) = (pos[a as usize], pos[b as usize]);
            pos.push([
                (p[0] + q[0]) * 0.5,
                (p[1] + q[1]) * 0.5,
                (p[2] + q[2]) * 0.5,
            ]);
            (pos.len() - 1) as u32
        })
    };
    for &[a, b, c] in mesh.triangles() {
        let ab = edge(a, b, &mut pos);
        let bc = edge(b, c, &mut pos);
        let ca = edge(c, a, &mut pos);
        tris.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    Mesh::new(pos, tris).expect("subdivision of a valid mesh is valid")
}

/// A regular icosahedron with unit circumradius.
pub fn icosahedron() -> Mesh {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let s = 1.0 / (1.0 + t * t).sqrt();
    let p: Vec<[f64; 3]> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|v| v.map(|x| x * s))
    .collect();
    let f = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    Mesh::new(p, f).expect("icosahedron is valid")
}
