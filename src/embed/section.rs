//! Cross-sections of a closed mesh by a plane: the closed curves where the
//! plane cuts the surface, and the centre of the one that belongs to a limb
//! or the torso at a given point. A joint of a cylindrical body part lies
//! near the centroid of the part's cross-section (the idea behind placing
//! Confluent Motion's markers and Mixamo-style joints from a few clicks).

use glam::DVec3;
use std::collections::HashMap;

/// One closed (or, on an open mesh, open) curve of a cross-section.
#[derive(Debug, Clone)]
pub struct Loop {
    /// Segment endpoints in order.
    pub points: Vec<DVec3>,
    /// Length-weighted centroid.
    pub centroid: DVec3,
    /// Mean distance of the curve from its centroid.
    pub radius: f64,
    /// Total length.
    pub length: f64,
}

/// Cuts the mesh by the plane through `origin` with normal `normal` and
/// returns its loops. Vertices exactly on the plane are nudged to one side,
/// so every crossing lies strictly inside a mesh edge.
pub(crate) fn cross_section(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    origin: DVec3,
    normal: DVec3,
) -> Vec<Loop> {
    let n = normal.normalize_or(DVec3::Y);
    let side = |v: u32| {
        let d = (DVec3::from_array(positions[v as usize]) - origin).dot(n);
        if d == 0.0 { 1e-300 } else { d }
    };
    let crossing = |a: u32, b: u32| {
        let (da, db) = (side(a), side(b));
        let t = da / (da - db);
        DVec3::from_array(positions[a as usize]).lerp(DVec3::from_array(positions[b as usize]), t)
    };
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    // Each cut triangle gives one segment between two of its edges.
    let mut segs: Vec<[(u32, u32); 2]> = Vec::new();
    for t in triangles {
        let s = t.map(|v| side(v) > 0.0);
        if s[0] == s[1] && s[1] == s[2] {
            continue;
        }
        let mut e = Vec::with_capacity(2);
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if s[k] != s[(k + 1) % 3] {
                e.push(key(a, b));
            }
        }
        if e.len() == 2 {
            segs.push([e[0], e[1]]);
        }
    }
    // Chain segments through shared edges.
    let mut by_edge: HashMap<(u32, u32), Vec<usize>> = HashMap::new();
    for (i, s) in segs.iter().enumerate() {
        for e in s {
            by_edge.entry(*e).or_default().push(i);
        }
    }
    let mut used = vec![false; segs.len()];
    let mut loops = Vec::new();
    for start in 0..segs.len() {
        if used[start] {
            continue;
        }
        used[start] = true;
        let mut edges = vec![segs[start][0], segs[start][1]];
        let mut cur = segs[start][1];
        loop {
            let next = by_edge
                .get(&cur)
                .and_then(|v| v.iter().copied().find(|&i| !used[i]));
            let Some(i) = next else { break };
            used[i] = true;
            cur = if segs[i][0] == cur {
                segs[i][1]
            } else {
                segs[i][0]
            };
            if cur == edges[0] {
                break;
            }
            edges.push(cur);
        }
        let points: Vec<DVec3> = edges.iter().map(|&(a, b)| crossing(a, b)).collect();
        loops.push(summarise(points));
    }
    loops
}

fn summarise(points: Vec<DVec3>) -> Loop {
    let m = points.len();
    let (mut c, mut len) = (DVec3::ZERO, 0.0);
    for i in 0..m {
        let (a, b) = (points[i], points[(i + 1) % m]);
        let l = a.distance(b);
        c += (a + b) * 0.5 * l;
        len += l;
    }
    let centroid = if len > 0.0 {
        c / len
    } else {
        points.iter().copied().sum::<DVec3>() / m.max(1) as f64
    };
    let radius = points.iter().map(|p| p.distance(centroid)).sum::<f64>() / m.max(1) as f64;
    Loop {
        points,
        centroid,
        radius,
        length: len,
    }
}

/// Distance from `p` to the curve.
pub(crate) fn distance_to(l: &Loop, p: DVec3) -> f64 {
    let m = l.points.len();
    (0..m)
        .map(|i| segment_distance(p, l.points[i], l.points[(i + 1) % m]))
        .fold(f64::INFINITY, f64::min)
}

/// Distance from `p` to the segment `a b`.
pub(crate) fn segment_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    p.distance(a + ab * t)
}

/// Whether `p` (projected onto the loop's plane with normal `n`) is inside
/// the loop, by the winding number.
pub(crate) fn encloses(l: &Loop, p: DVec3, n: DVec3) -> bool {
    let u = n.any_orthonormal_vector();
    let v = n.cross(u);
    let q = |x: DVec3| ((x - p).dot(u), (x - p).dot(v));
    let m = l.points.len();
    let mut angle = 0.0;
    for i in 0..m {
        let (a, b) = (q(l.points[i]), q(l.points[(i + 1) % m]));
        angle += (a.0 * b.1 - a.1 * b.0).atan2(a.0 * b.0 + a.1 * b.1);
    }
    angle.abs() > std::f64::consts::PI
}

/// The loop of the section through `origin` (normal `normal`) that belongs
/// to the body part at `near`: the smallest loop enclosing `near`, else the
/// loop passing closest to it.
pub(crate) fn part_loop(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    origin: DVec3,
    normal: DVec3,
    near: DVec3,
) -> Option<Loop> {
    let n = normal.normalize_or(DVec3::Y);
    let loops = cross_section(positions, triangles, origin, n);
    let enclosing = loops
        .iter()
        .filter(|l| l.points.len() >= 3 && encloses(l, near, n))
        .min_by(|a, b| a.length.total_cmp(&b.length));
    if let Some(l) = enclosing {
        return Some(l.clone());
    }
    loops
        .into_iter()
        .filter(|l| l.points.len() >= 3)
        .min_by(|a, b| distance_to(a, near).total_cmp(&distance_to(b, near)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sphere_section_is_a_circle_about_the_axis() {
        let m = crate::mesh::subdivide::midpoint(&crate::mesh::subdivide::midpoint(
            &crate::mesh::subdivide::icosahedron(),
        ));
        // Project the subdivided icosahedron onto the unit sphere.
        let p: Vec<[f64; 3]> = m
            .positions()
            .iter()
            .map(|q| DVec3::from_array(*q).normalize().to_array())
            .collect();
        let loops = cross_section(&p, m.triangles(), DVec3::new(0.0, 0.3, 0.0), DVec3::Y);
        assert_eq!(loops.len(), 1);
        let l = &loops[0];
        assert!(l.centroid.x.abs() < 0.02 && l.centroid.z.abs() < 0.02);
        assert!((l.centroid.y - 0.3).abs() < 1e-9);
        let r = (1.0f64 - 0.09).sqrt();
        assert!((l.radius - r).abs() < 0.05 * r, "{}", l.radius);
        assert!(encloses(l, DVec3::new(0.0, 0.3, 0.0), DVec3::Y));
        assert!(!encloses(l, DVec3::new(2.0, 0.3, 0.0), DVec3::Y));
        let near = part_loop(
            &p,
            m.triangles(),
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.0, 0.1, 0.0),
        )
        .unwrap();
        assert!(near.centroid.length() < 0.05);
        assert!(cross_section(&p, m.triangles(), DVec3::new(0.0, 2.0, 0.0), DVec3::Y).is_empty());
    }
}
