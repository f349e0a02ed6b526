//! Connected components of a triangle mesh (vertices joined by triangle
//! edges), by union-find. O(T α(V)).

use super::Mesh;

/// Component labels.
#[derive(Debug, Clone, PartialEq)]
pub struct Components {
    /// Component of each vertex; `u32::MAX` for a vertex in no triangle.
    pub label: Vec<u32>,
    /// Number of components (unreferenced vertices not counted).
    pub count: usize,
}

fn find(p: &mut [u32], mut x: u32) -> u32 {
    while p[x as usize] != x {
        let g = p[p[x as usize] as usize];
        p[x as usize] = g;
        x = g;
    }
    x
}

/// Labels the connected components of `mesh`, numbered by first vertex.
pub fn components(mesh: &Mesh) -> Components {
    let n = mesh.vertex_count();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    let mut used = vec![false; n];
    for t in mesh.triangles() {
        for k in 0..3 {
            used[t[k] as usize] = true;
            let (a, b) = (find(&mut parent, t[k]), find(&mut parent, t[(k + 1) % 3]));
            if a != b {
                parent[a.max(b) as usize] = a.min(b);
            }
        }
    }
    let mut label = vec![u32::MAX; n];
    let mut root_label = vec![u32::MAX; n];
    let mut count = 0u32;
    for v in 0..n {
        if !used[v] {
            continue;
        }
        let r = find(&mut parent, v as u32) as usize;
        if root_label[r] == u32::MAX {
            root_label[r] = count;
            count += 1;
        }
        label[v] = root_label[r];
    }
    Components {
        label,
        count: count as usize,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_triangles_and_a_loose_vertex() {
        let p = vec![[0.0f64; 3]; 7];
        let m = Mesh::new(p, vec![[0, 1, 2], [3, 4, 5]]).unwrap();
        let c = components(&m);
        assert_eq!(c.count, 2);
        assert_eq!(c.label, vec![0, 0, 0, 1, 1, 1, u32::MAX]);
    }
}
