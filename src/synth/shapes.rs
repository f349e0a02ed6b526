//! Procedural closed meshes for tests, fixtures and the demo.

use crate::mesh::Mesh;

/// A closed, outward-oriented capsule along Y centred at the origin: a
/// cylinder of radius `r` and length `len` capped by hemispheres.
/// `segments` around (≥ 3), `rings` per hemisphere (≥ 1). Volume
/// `π r² (len + 4r/3)` in the limit of fine tessellation.
pub fn capsule_mesh(r: f64, len: f64, segments: usize, rings: usize) -> Mesh {
    let segments = segments.max(3);
    let rings = rings.max(1);
    let mut p = vec![[0.0, len / 2.0 + r, 0.0]];
    // Latitude rows from the top pole down: rings rows on the upper cap
    // (excluding the pole), then the same on the lower cap.
    let mut rows = Vec::new();
    for i in 1..=rings {
        let a = std::f64::consts::FRAC_PI_2 * i as f64 / rings as f64;
        rows.push((r * a.sin(), len / 2.0 + r * a.cos()));
    }
    for i in 0..rings {
        let a = std::f64::consts::FRAC_PI_2 * i as f64 / rings as f64;
        rows.push((r * a.cos(), -len / 2.0 - r * a.sin()));
    }
    for &(rad, y) in &rows {
        for s in 0..segments {
            let t = std::f64::consts::TAU * s as f64 / segments as f64;
            p.push([rad * t.cos(), y, -rad * t.sin()]);
        }
    }
    let bottom = p.len() as u32;
    p.push([0.0, -len / 2.0 - r, 0.0]);
    let ring = |row: usize, s: usize| (1 + row * segments + s % segments) as u32;
    let mut t = Vec::new();
    for s in 0..segments {
        t.push([0, ring(0, s), ring(0, s + 1)]);
    }
    for row in 0..rows.len() - 1 {
        for s in 0..segments {
            let (a, b) = (ring(row, s), ring(row, s + 1));
            let (c, d) = (ring(row + 1, s), ring(row + 1, s + 1));
            t.push([a, c, d]);
            t.push([a, d, b]);
        }
    }
    let last = rows.len() - 1;
    for s in 0..segments {
        t.push([bottom, ring(last, s + 1), ring(last, s)]);
    }
    Mesh::new(p, t).expect("capsule indices are in range and coordinates finite")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn capsule_is_closed_and_outward() {
        let m = capsule_mesh(0.2, 1.0, 16, 6);
        assert!(m.problems().is_empty(), "{:?}", m.problems());
        // Closed: every edge is shared by exactly two triangles.
        let mut edges = std::collections::HashMap::new();
        for t in m.triangles() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        assert!(edges.values().all(|&c| c == 2));
        // Outward: positive signed volume near the exact one.
        let p = m.positions();
        let vol: f64 = m
            .triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| glam::DVec3::from_array(p[v as usize]));
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        let exact = std::f64::consts::PI * 0.04 * (1.0 + 0.8 / 3.0);
        assert!(
            vol > 0.0 && (vol / exact - 1.0).abs() < 0.05,
            "{vol} {exact}"
        );
    }
}
