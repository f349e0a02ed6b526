//! The boundary loops of a triangle mesh: the edges of one triangle only
//! (an open cut's rim, a hole), joined into connected runs by union-find.
//! O(T log T) for the edge count.

use std::collections::HashMap;

/// The boundary of `triangles` (over `vertex_count` vertices) as loops:
/// the vertices of each connected run of boundary edges (an edge of
/// exactly one triangle; an edge of three or more triangles is not
/// boundary), each loop's vertices ascending, the loops by their least
/// vertex. A closed mesh has none. A triangle naming a vertex at or past
/// `vertex_count`, or a degenerate one (a vertex twice), is skipped.
pub fn boundary_loops(vertex_count: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in triangles {
        if t.iter().any(|&v| v as usize >= vertex_count)
            || t[0] == t[1]
            || t[1] == t[2]
            || t[0] == t[2]
        {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut edges: Vec<(u32, u32)> = uses
        .into_iter()
        .filter(|&(_, n)| n == 1)
        .map(|(e, _)| e)
        .collect();
    edges.sort_unstable();
    let mut parent: Vec<u32> = (0..vertex_count as u32).collect();
    let mut on = vec![false; vertex_count];
    for &(a, b) in &edges {
        on[a as usize] = true;
        on[b as usize] = true;
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            parent[ra.max(rb) as usize] = ra.min(rb);
        }
    }
    let mut slot: Vec<u32> = vec![u32::MAX; vertex_count];
    let mut loops: Vec<Vec<u32>> = Vec::new();
    for v in 0..vertex_count as u32 {
        if !on[v as usize] {
            continue;
        }
        let r = find(&mut parent, v) as usize;
        if slot[r] == u32::MAX {
            slot[r] = loops.len() as u32;
            loops.push(Vec::new());
        }
        loops[slot[r] as usize].push(v);
    }
    loops
}

fn find(p: &mut [u32], mut x: u32) -> u32 {
    while p[x as usize] != x {
        let g = p[p[x as usize] as usize];
        p[x as usize] = g;
        x = g;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `n` quads round a tube (two rings of `n` vertices,
    /// `first` the first ring's first vertex): two loops.
    fn tube(first: u32, n: u32) -> Vec<[u32; 3]> {
        let mut t = Vec::new();
        for k in 0..n {
            let (a, b) = (first + k, first + (k + 1) % n);
            let (c, d) = (a + n, b + n);
            t.push([a, b, d]);
            t.push([a, d, c]);
        }
        t
    }

    #[test]
    fn a_tube_has_two_loops_and_a_capped_one_fewer() {
        let t = tube(0, 6);
        let loops = boundary_loops(12, &t);
        assert_eq!(loops, vec![(0..6).collect::<Vec<_>>(), (6..12).collect()]);
        // The first ring capped by a fan to vertex 12: one loop left.
        let mut capped = t.clone();
        capped.extend((0..6).map(|k| [12, (k + 1) % 6, k]));
        assert_eq!(
            boundary_loops(13, &capped),
            vec![(6..12).collect::<Vec<_>>()]
        );
        // Two tubes: four loops; a bad triangle is skipped.
        let mut two = t;
        two.extend(tube(12, 5));
        two.push([0, 0, 1]);
        two.push([0, 1, 99]);
        let loops = boundary_loops(22, &two);
        assert_eq!(loops.len(), 4);
        assert_eq!(loops[2], (12..17).collect::<Vec<_>>());
    }
}
