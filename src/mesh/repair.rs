//! Mesh repair for raw scans: weld duplicate vertices, drop degenerate and
//! duplicate triangles and unreferenced vertices, report and split connected
//! components.

use super::components::components;
use super::{Group, Mesh};
use serde::Serialize;
use std::collections::{HashMap, HashSet};

/// Options for [`repair`].
#[derive(Debug, Clone, Copy)]
pub struct RepairOptions {
    /// Weld vertices closer than this fraction of the bounding-box diagonal.
    /// Default: 0 (weld only exact duplicates).
    pub weld_tolerance: f64,
    /// Keep only the largest connected component (by triangle count). Default: false.
    pub keep_largest: bool,
}

impl Default for RepairOptions {
    fn default() -> Self {
        RepairOptions {
            weld_tolerance: 0.0,
            keep_largest: false,
        }
    }
}

/// One connected component.
#[derive(Debug, Clone, Serialize)]
pub struct ComponentInfo {
    /// Vertices in it.
    pub vertices: usize,
    /// Triangles in it.
    pub triangles: usize,
}

/// What [`repair`] changed.
#[derive(Debug, Clone, Serialize, Default)]
pub struct RepairReport {
    /// Vertices merged into another.
    pub welded_vertices: usize,
    /// Triangles dropped for a repeated vertex (after welding).
    pub degenerate_triangles: usize,
    /// Triangles dropped as duplicates of another (same three vertices).
    pub duplicate_triangles: usize,
    /// Vertices dropped because no triangle uses them.
    pub unreferenced_vertices: usize,
    /// Triangles dropped with smaller components (`keep_largest`).
    pub dropped_component_triangles: usize,
    /// Kept triangles of (numerically) zero area: three distinct but
    /// collinear vertices (cross product under 1e-12 of the squared
    /// bounding-box diagonal). Not dropped, as that would open holes;
    /// reported so a flat or collapsed mesh does not pass as clean.
    #[serde(default)]
    pub zero_area_triangles: usize,
    /// Connected components of the result, largest first.
    pub components: Vec<ComponentInfo>,
}

impl RepairReport {
    /// True when nothing was changed.
    pub fn unchanged(&self) -> bool {
        self.welded_vertices
            + self.degenerate_triangles
            + self.duplicate_triangles
            + self.unreferenced_vertices
            + self.dropped_component_triangles
            == 0
    }
}

fn weld_map(p: &[[f64; 3]], tol: f64) -> Vec<u32> {
    let n = p.len();
    let mut map: Vec<u32> = (0..n as u32).collect();
    if tol <= 0.0 {
        let mut seen: HashMap<[u64; 3], u32> = HashMap::with_capacity(n);
        for (i, q) in p.iter().enumerate() {
            let key = q.map(|v| if v == 0.0 { 0 } else { v.to_bits() });
            map[i] = *seen.entry(key).or_insert(i as u32);
        }
        return map;
    }
    // Grid hashing with cells of size tol; compare against the 27 neighbours.
    let cell = |q: &[f64; 3]| q.map(|v| (v / tol).floor() as i64);
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::with_capacity(n);
    for (i, q) in p.iter().enumerate() {
        let c = cell(q);
        let mut found = None;
        'outer: for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(list) = grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) {
                        for &j in list {
                            let r = p[j as usize];
                            let d2: f64 = (0..3).map(|k| (r[k] - q[k]).powi(2)).sum();
                            if d2 <= tol * tol {
                                found = Some(j);
                                break 'outer;
                            }
                        }
                    }
                }
            }
        }
        match found {
            Some(j) => map[i] = j,
            None => grid.entry(c).or_default().push(i as u32),
        }
    }
    map
}

/// Repairs a mesh. Returns the repaired mesh, what changed, and for each
/// input vertex its index in the output (`u32::MAX` if dropped).
pub fn repair(mesh: &Mesh, opts: &RepairOptions) -> (Mesh, RepairReport, Vec<u32>) {
    let mut rep = RepairReport::default();
    let p = mesh.positions();
    let tol = opts.weld_tolerance.max(0.0) * mesh.bounds().diagonal();
    let weld = weld_map(p, tol);
    rep.welded_vertices = weld
        .iter()
        .enumerate()
        .filter(|(i, w)| **w as usize != *i)
        .count();
    // Triangles: weld, drop degenerate and duplicate; remember each kept triangle's origin.
    let mut seen = HashSet::with_capacity(mesh.triangle_count());
    let mut tris = Vec::with_capacity(mesh.triangle_count());
    let mut origin = Vec::with_capacity(mesh.triangle_count());
    for (ti, t) in mesh.triangles().iter().enumerate() {
        let w = t.map(|v| weld[v as usize]);
        if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
            rep.degenerate_triangles += 1;
            continue;
        }
        let mut key = w;
        key.sort_unstable();
        if !seen.insert(key) {
            rep.duplicate_triangles += 1;
            continue;
        }
        tris.push(w);
        origin.push(ti as u32);
    }
    if opts.keep_largest && !tris.is_empty() {
        let tmp = Mesh::new(p.to_vec(), tris.clone()).expect("indices are in range");
        let c = components(&tmp);
        let mut count = vec![0usize; c.count];
        for t in &tris {
            count[c.label[t[0] as usize] as usize] += 1;
        }
        let best = (0..c.count).max_by_key(|&k| count[k]).unwrap_or(0) as u32;
        let before = tris.len();
        let keep: Vec<bool> = tris
            .iter()
            .map(|t| c.label[t[0] as usize] == best)
            .collect();
        let mut k = 0;
        tris.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        let mut k = 0;
        origin.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        rep.dropped_component_triangles = before - tris.len();
    }
    let diag = mesh.bounds().diagonal();
    let eps = 1e-12 * diag * diag;
    rep.zero_area_triangles = tris
        .iter()
        .filter(|t| {
            let [a, b, c] = t.map(|v| glam::DVec3::from_array(p[v as usize]));
            let area2 = (b - a).cross(c - a).length();
            area2.is_nan() || area2 <= eps
        })
        .count();
    // Compact vertices.
    let mut used = vec![false; p.len()];
    for t in &tris {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut new_index = vec![u32::MAX; p.len()];
    let mut pos = Vec::new();
    let mut col = mesh.colors().map(|_| Vec::new());
    for (i, &u) in used.iter().enumerate() {
        if u {
            new_index[i] = pos.len() as u32;
            pos.push(p[i]);
            if let (Some(c), Some(src)) = (col.as_mut(), mesh.colors()) {
                c.push(src[i]);
            }
        }
    }
    rep.unreferenced_vertices = (0..p.len())
        .filter(|&i| weld[i] as usize == i && !used[i])
        .count();
    let vertex_map: Vec<u32> = weld.iter().map(|&w| new_index[w as usize]).collect();
    let tris: Vec<[u32; 3]> = tris
        .iter()
        .map(|t| t.map(|v| new_index[v as usize]))
        .collect();
    // Groups follow their triangles.
    let mut groups = Vec::new();
    for g in mesh.groups() {
        let start = origin.partition_point(|&o| o < g.start) as u32;
        let end = origin.partition_point(|&o| o < g.end) as u32;
        groups.push(Group {
            name: g.name.clone(),
            start,
            end,
        });
    }
    let mut out = Mesh::new(pos, tris)
        .expect("indices are in range")
        .with_groups(groups);
    if let Some(c) = col {
        out = out.with_colors(c).expect("one colour per vertex");
    }
    let c = components(&out);
    let mut info = vec![
        ComponentInfo {
            vertices: 0,
            triangles: 0
        };
        c.count
    ];
    for &l in &c.label {
        if l != u32::MAX {
            info[l as usize].vertices += 1;
        }
    }
    for t in out.triangles() {
        info[c.label[t[0] as usize] as usize].triangles += 1;
    }
    info.sort_by_key(|c| std::cmp::Reverse(c.triangles));
    rep.components = info;
    (out, rep, vertex_map)
}

/// Splits a mesh into its connected components (unreferenced vertices are
/// dropped). Each part comes with the original index of each of its vertices.
pub fn split_components(mesh: &Mesh) -> Vec<(Mesh, Vec<u32>)> {
    let c = components(mesh);
    let mut local = vec![u32::MAX; mesh.vertex_count()];
    let mut verts: Vec<Vec<u32>> = vec![Vec::new(); c.count];
    for (v, &l) in c.label.iter().enumerate() {
        if l != u32::MAX {
            local[v] = verts[l as usize].len() as u32;
            verts[l as usize].push(v as u32);
        }
    }
    let mut tris: Vec<Vec<[u32; 3]>> = vec![Vec::new(); c.count];
    for t in mesh.triangles() {
        tris[c.label[t[0] as usize] as usize].push(t.map(|v| local[v as usize]));
    }
    verts
        .into_iter()
        .zip(tris)
        .map(|(vs, ts)| {
            let p = vs.iter().map(|&v| mesh.positions()[v as usize]).collect();
            (Mesh::new(p, ts).expect("indices are in range"), vs)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression (issue 18, item 16): a mesh of collinear triangles is
    /// not reported as clean.
    #[test]
    fn zero_area_triangles_are_reported() {
        let m = Mesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [2.0, 0.0, 0.0],
                [3.0, 0.0, 0.0],
            ],
            vec![[0, 1, 2], [0, 1, 3], [1, 2, 3]],
        )
        .unwrap();
        let (_, rep, _) = repair(&m, &RepairOptions::default());
        assert_eq!(rep.zero_area_triangles, 3);
        let ok = Mesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        )
        .unwrap();
        assert_eq!(
            repair(&ok, &RepairOptions::default()).1.zero_area_triangles,
            0
        );
    }

    #[test]
    fn welds_drops_and_splits() {
        // Two triangles sharing an edge through duplicated vertices, a
        // degenerate triangle, a duplicate, a loose vertex and a second island.
        let p = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [7.0, 7.0, 7.0],
            [5.0, 0.0, 0.0],
            [6.0, 0.0, 0.0],
            [5.0, 1.0, 0.0],
        ];
        let t = vec![[0, 1, 2], [3, 5, 4], [0, 1, 3], [2, 1, 0], [7, 8, 9]];
        let m = Mesh::new(p, t).unwrap();
        let (r, rep, map) = repair(&m, &RepairOptions::default());
        assert_eq!(rep.welded_vertices, 2);
        assert_eq!(rep.degenerate_triangles, 1);
        assert_eq!(rep.duplicate_triangles, 1);
        assert_eq!(rep.unreferenced_vertices, 1);
        assert_eq!((r.vertex_count(), r.triangle_count()), (7, 3));
        assert_eq!(rep.components.len(), 2);
        assert_eq!(map[3], map[1]);
        assert_eq!(map[6], u32::MAX);
        let parts = split_components(&r);
        assert_eq!(parts.len(), 2);
        let (big, _, _) = repair(
            &m,
            &RepairOptions {
                keep_largest: true,
                ..Default::default()
            },
        );
        assert_eq!(big.triangle_count(), 2);
        // Tolerance welding.
        let q = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1e-4, 0.0],
            [1.0, 1.0, 0.0],
        ];
        let m = Mesh::new(q, vec![[0, 1, 2], [3, 4, 2]]).unwrap();
        let (_, rep, _) = repair(
            &m,
            &RepairOptions {
                weld_tolerance: 1e-3,
                ..Default::default()
            },
        );
        assert_eq!(rep.welded_vertices, 1);
    }
}
