//! Where a point lies relative to a triangle mesh: inside or outside by the
//! generalised winding number (Jacobson, Kavan & Sorkine-Hornung 2013,
//! "Robust Inside-Outside Segmentation using Generalized Winding Numbers",
//! Eq. 5: the sum of the signed solid angles of the triangles seen from the
//! point, over 4π, by the formula of Van Oosterom & Strackee 1983), and its
//! distance from the surface (nearest point on each triangle, Ericson 2005,
//! *Real-Time Collision Detection*, 5.1.5). Both O(#F) per point: meant for
//! a few dozen joints and landmarks, not for every vertex.

use glam::DVec3;

/// The generalised winding number of `q` with respect to the surface: 1
/// inside a closed outward-oriented surface, 0 outside, in between near
/// holes of an open one.
pub(crate) fn winding_number(positions: &[[f64; 3]], triangles: &[[u32; 3]], q: DVec3) -> f64 {
    let mut sum = 0.0;
    for t in triangles {
        let [a, b, c] = t.map(|v| DVec3::from_array(positions[v as usize]) - q);
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let num = a.dot(b.cross(c));
        let den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
        sum += 2.0 * num.atan2(den);
    }
    sum / (4.0 * std::f64::consts::PI)
}

/// Whether `q` is inside the surface (winding number above one half in
/// magnitude, so an inward-oriented surface works too).
pub fn is_inside(positions: &[[f64; 3]], triangles: &[[u32; 3]], q: DVec3) -> bool {
    winding_number(positions, triangles, q).abs() > 0.5
}

/// The point of triangle `a b c` nearest to `p` (Ericson 2005, 5.1.5).
pub(crate) fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let den = va + vb + vc;
    if den.abs() < f64::MIN_POSITIVE {
        return a;
    }
    a + ab * (vb / den) + ac * (vc / den)
}

/// Distance from `q` to the nearest point of the surface (infinite for a
/// mesh without triangles).
pub fn distance_to_surface(positions: &[[f64; 3]], triangles: &[[u32; 3]], q: DVec3) -> f64 {
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| DVec3::from_array(positions[v as usize]));
            closest_on_triangle(q, a, b, c).distance_squared(q)
        })
        .fold(f64::INFINITY, f64::min)
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sphere() -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let m = crate::mesh::subdivide::midpoint(&crate::mesh::subdivide::midpoint(
            &crate::mesh::subdivide::icosahedron(),
        ));
        let p = m
            .positions()
            .iter()
            .map(|q| DVec3::from_array(*q).normalize().to_array())
            .collect();
        (p, m.triangles().to_vec())
    }

    #[test]
    fn the_winding_number_is_one_inside_and_zero_outside_a_sphere() {
        let (p, t) = sphere();
        for q in [
            DVec3::ZERO,
            DVec3::new(0.3, -0.5, 0.2),
            DVec3::new(0.0, 0.0, 0.9),
        ] {
            let w = winding_number(&p, &t, q);
            assert!((w.abs() - 1.0).abs() < 1e-9, "{q}: {w}");
            assert!(is_inside(&p, &t, q));
        }
        for q in [DVec3::new(1.5, 0.0, 0.0), DVec3::new(-3.0, 2.0, 1.0)] {
            let w = winding_number(&p, &t, q);
            assert!(w.abs() < 1e-9, "{q}: {w}");
        }
        // A sphere with its triangles reversed is inside out.
        let rev: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
        let (w, wr) = (
            winding_number(&p, &t, DVec3::ZERO),
            winding_number(&p, &rev, DVec3::ZERO),
        );
        assert!((w + wr).abs() < 1e-9, "{w} {wr}");
    }

    #[test]
    fn the_distance_to_a_sphere_is_the_radial_gap() {
        let (p, t) = sphere();
        // The polyhedron lies within its chord sag of the unit sphere.
        for r in [0.0, 0.5, 2.0, 4.0] {
            let q = DVec3::new(0.36, 0.48, 0.8) * r;
            let d = distance_to_surface(&p, &t, q);
            assert!(((1.0 - r).abs() - d).abs() < 0.1, "{r}: {d}");
        }
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        let inner = closest_on_triangle(DVec3::new(0.2, 0.2, 1.0), a, b, c);
        assert!(inner.distance(DVec3::new(0.2, 0.2, 0.0)) < 1e-12, "{inner}");
        assert_eq!(closest_on_triangle(DVec3::new(-1.0, -1.0, 0.0), a, b, c), a);
        // Beyond the hypotenuse: its nearest point, (1, 0) here.
        let edge = closest_on_triangle(DVec3::new(2.0, 0.5, 0.0), a, b, c);
        assert!(edge.distance(DVec3::X) < 1e-12, "{edge}");
    }
}
