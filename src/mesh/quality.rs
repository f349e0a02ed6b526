//! Surface-quality kernels read off one frame of a mesh: the bend
//! (signed dihedral) angle at each interior edge, each triangle's shape
//! quality, edge lengths, and triangles of different groups (body parts)
//! that pass through each other. The measure built on them, against a
//! capture's own distribution, is [`crate::tools::eval::surface`].
//!
//! All of them depend on the shape only: the same under any rigid motion
//! and (bends and quality) any uniform scale.

use glam::DVec3;

/// The interior edges of a triangle mesh (two triangles each, oriented
/// consistently), built once from the connectivity.
#[derive(Debug, Clone, Default)]
pub struct Edges {
    /// End vertices `[a, b]` of each edge, as the first triangle runs it.
    pub ends: Vec<[u32; 2]>,
    /// The vertex opposite the edge in the first triangle (which runs
    /// `a → b`) and in the second (which runs `b → a`).
    pub opposite: Vec<[u32; 2]>,
    /// The two triangles.
    pub triangles: Vec<[u32; 2]>,
}

impl Edges {
    /// The interior edges of `triangles`. Edges on a boundary, shared by
    /// more than two triangles, or between two triangles that run them the
    /// same way (inconsistent orientation) have no bend and are left out.
    pub fn new(triangles: &[[u32; 3]]) -> Edges {
        // (low, high, triangle, corner k: the edge runs t[k] → t[k + 1]).
        let mut half: Vec<(u32, u32, u32, u8)> = Vec::with_capacity(triangles.len() * 3);
        for (i, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if a != b {
                    half.push((a.min(b), a.max(b), i as u32, k as u8));
                }
            }
        }
        half.sort_unstable();
        let mut e = Edges::default();
        let mut i = 0;
        while i < half.len() {
            let mut j = i + 1;
            while j < half.len() && half[j].0 == half[i].0 && half[j].1 == half[i].1 {
                j += 1;
            }
            if j - i == 2 {
                let (t1, k1) = (half[i].2, half[i].3 as usize);
                let (t2, k2) = (half[i + 1].2, half[i + 1].3 as usize);
                let (p, q) = (triangles[t1 as usize], triangles[t2 as usize]);
                let (a, b) = (p[k1], p[(k1 + 1) % 3]);
                // The second triangle must run the edge the other way.
                if q[k2] == b && q[(k2 + 1) % 3] == a {
                    e.ends.push([a, b]);
                    e.opposite.push([p[(k1 + 2) % 3], q[(k2 + 2) % 3]]);
                    e.triangles.push([t1, t2]);
                }
            }
            i = j;
        }
        e
    }

    /// Number of interior edges.
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    /// True when the mesh has no interior edge.
    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }

    /// The bend angle (radians) of every edge in `pos`, into `out`: the
    /// angle between the two triangles' normals, positive where the
    /// surface is convex at the edge (a ridge), negative where concave (a
    /// valley); 0 on a flat surface, ±π folded flat onto itself. An edge
    /// next to a triangle of no area reads π (a collapsed triangle is the
    /// sharpest fold there is).
    pub fn bends(&self, pos: &[[f64; 3]], out: &mut Vec<f64>) {
        out.clear();
        out.extend(
            self.ends
                .iter()
                .zip(&self.opposite)
                .map(|(&[a, b], &[c, d])| {
                    let p = |v: u32| DVec3::from_array(pos[v as usize]);
                    let (a, b, c, d) = (p(a), p(b), p(c), p(d));
                    let e = b - a;
                    let n1 = e.cross(c - a);
                    let n2 = (a - b).cross(d - b);
                    let el = e.length();
                    let s = n1.cross(n2).dot(e) / el.max(f64::MIN_POSITIVE);
                    let c = n1.dot(n2);
                    if n1.length_squared() == 0.0 || n2.length_squared() == 0.0 || el == 0.0 {
                        return std::f64::consts::PI;
                    }
                    let r = s.atan2(c);
                    if r.is_finite() {
                        r
                    } else {
                        std::f64::consts::PI
                    }
                }),
        );
    }

    /// The length of every edge in `pos`, into `out`.
    pub fn lengths(&self, pos: &[[f64; 3]], out: &mut Vec<f64>) {
        out.clear();
        out.extend(self.ends.iter().map(|&[a, b]| {
            DVec3::from_array(pos[a as usize]).distance(DVec3::from_array(pos[b as usize]))
        }));
    }
}

/// The shape quality of a triangle: `4√3 · area / (sum of squared edge
/// lengths)`, 1 for an equilateral triangle, 0 for a degenerate one (a
/// sliver or a needle); the same under any similarity transform. A
/// non-finite triangle reads 0.
pub(crate) fn triangle_quality(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let s = (b - a).length_squared() + (c - b).length_squared() + (a - c).length_squared();
    let area2 = (b - a).cross(c - a).length();
    let q = 2.0 * 3f64.sqrt() * area2 / s;
    if q.is_finite() {
        q.clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// [`triangle_quality`] of every triangle of `triangles` in `pos`, into
/// `out`.
pub(crate) fn qualities(triangles: &[[u32; 3]], pos: &[[f64; 3]], out: &mut Vec<f64>) {
    out.clear();
    out.extend(triangles.iter().map(|t| {
        let [a, b, c] = t.map(|v| DVec3::from_array(pos[v as usize]));
        triangle_quality(a, b, c)
    }));
}

/// Whether the segment `q0 → q1` passes through the inside of triangle
/// `a b c` (touching an edge or a corner, or lying in its plane, is not
/// counted).
fn segment_crosses(q0: DVec3, q1: DVec3, a: DVec3, b: DVec3, c: DVec3) -> bool {
    let n = (b - a).cross(c - a);
    let (d0, d1) = (n.dot(q0 - a), n.dot(q1 - a));
    if !(d0 > 0.0 && d1 < 0.0 || d0 < 0.0 && d1 > 0.0) {
        return false;
    }
    let x = q0 + (q1 - q0) * (d0 / (d0 - d1));
    let s0 = (b - a).cross(x - a).dot(n);
    let s1 = (c - b).cross(x - b).dot(n);
    let s2 = (a - c).cross(x - c).dot(n);
    s0 > 0.0 && s1 > 0.0 && s2 > 0.0 || s0 < 0.0 && s1 < 0.0 && s2 < 0.0
}

/// Whether two triangles (corner positions) pass through each other: an
/// edge of one crosses the inside of the other (transversal crossings;
/// coplanar overlaps are not counted).
pub(crate) fn triangles_cross(p: [DVec3; 3], q: [DVec3; 3]) -> bool {
    (0..3).any(|k| segment_crosses(q[k], q[(k + 1) % 3], p[0], p[1], p[2]))
        || (0..3).any(|k| segment_crosses(p[k], p[(k + 1) % 3], q[0], q[1], q[2]))
}

/// Pairs of triangles of different groups that pass through each other
/// in `pos` (`group`: one label per triangle; pairs sharing a vertex are
/// left out, as they meet by construction). Sweep and prune on the
/// triangles' bounding boxes along X, then [`triangles_cross`]. Each pair
/// once, `[lower, higher]` triangle index, sorted. A triangle with a
/// non-finite corner is left out.
pub(crate) fn crossing_pairs(
    triangles: &[[u32; 3]],
    pos: &[[f64; 3]],
    group: &[u8],
) -> Vec<[u32; 2]> {
    let boxes: Vec<(DVec3, DVec3)> = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| DVec3::from_array(pos[v as usize]));
            (a.min(b).min(c), a.max(b).max(c))
        })
        .collect();
    let mut order: Vec<u32> = (0..triangles.len() as u32)
        .filter(|&i| boxes[i as usize].0.is_finite() && boxes[i as usize].1.is_finite())
        .collect();
    order.sort_unstable_by(|&i, &j| boxes[i as usize].0.x.total_cmp(&boxes[j as usize].0.x));
    let mut active: Vec<u32> = Vec::new();
    let mut out = Vec::new();
    for &i in &order {
        let (lo, hi) = boxes[i as usize];
        active.retain(|&j| boxes[j as usize].1.x >= lo.x);
        let ti = triangles[i as usize];
        for &j in &active {
            if group[j as usize] == group[i as usize] {
                continue;
            }
            let (lj, hj) = boxes[j as usize];
            if lj.y > hi.y || hj.y < lo.y || lj.z > hi.z || hj.z < lo.z {
                continue;
            }
            let tj = triangles[j as usize];
            if ti.iter().any(|v| tj.contains(v)) {
                continue;
            }
            let p = ti.map(|v| DVec3::from_array(pos[v as usize]));
            let q = tj.map(|v| DVec3::from_array(pos[v as usize]));
            if triangles_cross(p, q) {
                out.push([i.min(j), i.max(j)]);
            }
        }
        active.push(i);
    }
    out.sort_unstable();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A unit square folded along its diagonal by `h` (corner 3 lifted).
    fn folded(h: f64) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        (
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, h],
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    #[test]
    fn a_flat_square_bends_zero_and_a_fold_reads_its_angle_and_sign() {
        let (p, t) = folded(0.0);
        let e = Edges::new(&t);
        assert_eq!(e.len(), 1);
        let mut b = Vec::new();
        e.bends(&p, &mut b);
        assert!(b[0].abs() < 1e-12);
        // Corner 3 lifted towards the normal (+Z): a valley.
        let (p, _) = folded(1.0);
        e.bends(&p, &mut b);
        let want = 2f64.sqrt().atan();
        assert!(b[0] < 0.0 && (b[0].abs() - want).abs() < 1e-9, "{b:?}");
        let (p, _) = folded(-1.0);
        e.bends(&p, &mut b);
        assert!(b[0] > 0.0 && (b[0] - want).abs() < 1e-9, "{b:?}");
    }

    #[test]
    fn quality_is_one_for_equilateral_and_small_for_a_sliver() {
        let q = triangle_quality(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(0.5, 3f64.sqrt() / 2.0, 0.0),
        );
        assert!((q - 1.0).abs() < 1e-12);
        let s = triangle_quality(DVec3::ZERO, DVec3::X, DVec3::new(0.5, 0.01, 0.0));
        assert!(s < 0.05);
        assert_eq!(triangle_quality(DVec3::ZERO, DVec3::X, DVec3::X * 2.0), 0.0);
    }

    #[test]
    fn crossing_triangles_of_two_groups_are_found_and_touching_ones_are_not() {
        let pos = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            // Through the first triangle's inside.
            [0.2, 0.2, -1.0],
            [0.2, 0.2, 1.0],
            [0.3, 0.9, 1.0],
            // Well away.
            [5.0, 5.0, 5.0],
            [6.0, 5.0, 5.0],
            [5.0, 6.0, 5.0],
        ];
        let tris = vec![[0, 1, 2], [3, 4, 5], [6, 7, 8], [0, 1, 4]];
        assert_eq!(
            crossing_pairs(&tris, &pos, &[0, 1, 1, 1]),
            vec![[0, 1]],
            "the third triangle is far and the fourth shares an edge"
        );
        assert!(crossing_pairs(&tris, &pos, &[0, 0, 0, 0]).is_empty());
    }
}
