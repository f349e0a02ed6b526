//! The demo character: a procedural humanoid, one closed surface, with its
//! landmarks. Nothing is downloaded or copied: the body is the zero set of
//! a smooth union of capsules along an A-pose skeleton (1.75 m, facing +Z,
//! its left on +X), meshed by surface nets (Gibson 1998): one vertex per
//! grid cell the surface crosses, at the mean of the cell's edge
//! crossings, and one quad per crossed grid edge joining the four cells
//! around it, split into two triangles.

use crate::mesh::Mesh;
use crate::rig::embed::landmarks::Landmarks;
use glam::DVec3;

/// A capsule `(a, b, radius)`.
type Capsule = (DVec3, DVec3, f64);

/// The A-pose joints: `(name, position)` of the landmarks the demo marks,
/// and the capsules of the body.
fn body() -> (Vec<(&'static str, DVec3)>, Vec<Capsule>) {
    let v = DVec3::new;
    let (s45, c45) = (
        std::f64::consts::FRAC_1_SQRT_2,
        std::f64::consts::FRAC_1_SQRT_2,
    );
    let mut marks = vec![
        ("chin", v(0.0, 1.53, 0.07)),
        ("groin", v(0.0, 0.86, 0.0)),
        ("head_top", v(0.0, 1.75, 0.01)),
    ];
    let mut caps = vec![
        (v(0.0, 0.93, 0.0), v(0.0, 1.12, 0.0), 0.135),
        (v(0.0, 1.12, 0.0), v(0.0, 1.33, 0.0), 0.13),
        (v(0.0, 1.33, 0.0), v(0.0, 1.50, 0.0), 0.05),
        (v(0.0, 1.60, 0.02), v(0.0, 1.65, 0.02), 0.095),
    ];
    for (side, x) in [("l", 1.0), ("r", -1.0)] {
        let shoulder = v(0.18 * x, 1.40, 0.0);
        let dir = v(s45 * x, -c45, 0.0);
        let elbow = shoulder + dir * 0.29;
        let wrist = elbow + dir * 0.26;
        let tip = wrist + dir * 0.16;
        let hip = v(0.09 * x, 0.90, 0.0);
        let knee = v(0.09 * x, 0.49, 0.01);
        let ankle = v(0.09 * x, 0.08, 0.0);
        let toe = v(0.09 * x, 0.03, 0.17);
        caps.extend([
            (v(0.05 * x, 1.36, 0.0), shoulder, 0.065),
            (shoulder, elbow, 0.048),
            (elbow, wrist, 0.038),
            (wrist, tip, 0.03),
            (hip, knee, 0.075),
            (knee, ankle, 0.05),
            (ankle, toe, 0.042),
        ]);
        let name = |j: &str| -> &'static str {
            match (side, j) {
                ("l", "wrist") => "l_wrist",
                ("l", "elbow") => "l_elbow",
                ("l", "knee") => "l_knee",
                ("l", "shoulder") => "l_shoulder",
                ("l", "ankle") => "l_ankle",
                ("r", "wrist") => "r_wrist",
                ("r", "elbow") => "r_elbow",
                ("r", "knee") => "r_knee",
                ("r", "shoulder") => "r_shoulder",
                _ => "r_ankle",
            }
        };
        marks.extend([
            (name("wrist"), wrist),
            (name("elbow"), elbow),
            (name("knee"), knee),
            (name("shoulder"), shoulder),
            (name("ankle"), ankle),
        ]);
    }
    (marks, caps)
}

/// Signed distance (approximately; negative inside) of the smooth union.
fn sdf(p: DVec3, caps: &[Capsule]) -> f64 {
    // Polynomial smooth minimum (k = blend radius).
    let k = 0.025;
    let mut d = f64::INFINITY;
    for (a, b, r) in caps {
        let ab = *b - *a;
        let t = ((p - *a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
        let di = p.distance(*a + ab * t) - r;
        d = if d.is_infinite() {
            di
        } else {
            let h = (0.5 + 0.5 * (di - d) / k).clamp(0.0, 1.0);
            di * (1.0 - h) + d * h - k * h * (1.0 - h)
        };
    }
    d
}

/// Grid spacing of the demo character (metres). Surface nets can pinch two
/// sheets at one edge where the surface passes a cell corner ambiguously;
/// at this spacing the body has none (checked by a test).
pub const DEMO_GRID: f64 = 0.02;

/// The demo character's mesh at grid spacing `h` (metres; [`DEMO_GRID`]
/// gives a closed two-manifold of about 6,000 vertices).
pub fn humanoid_mesh(h: f64) -> Mesh {
    let (_, caps) = body();
    surface_nets(
        &|p| sdf(p, &caps),
        DVec3::new(-0.8, -0.05, -0.3),
        DVec3::new(0.8, 1.85, 0.4),
        h,
    )
}

/// The demo character's landmarks as a landmark file's JSON (named points
/// on its skeleton).
pub fn humanoid_landmarks_json() -> String {
    let (marks, _) = body();
    let map: std::collections::BTreeMap<String, Vec<f64>> = marks
        .iter()
        .map(|(n, p)| (n.to_string(), p.to_array().to_vec()))
        .collect();
    serde_json::to_string_pretty(&map).unwrap_or_default()
}

/// The demo character's landmarks.
pub fn humanoid_landmarks(mesh: &Mesh) -> Landmarks {
    Landmarks::parse(
        &humanoid_landmarks_json(),
        std::path::Path::new("<demo>"),
        mesh.vertex_count(),
    )
    .expect("the demo's landmarks are complete")
}

/// Surface nets of the zero set of `f` over the box `[lo, hi]`, spacing `h`.
/// Closed where the zero set stays inside the box; a few edges may be
/// shared by four triangles where two sheets pass one cell edge.
pub fn surface_nets(f: &dyn Fn(DVec3) -> f64, lo: DVec3, hi: DVec3, h: f64) -> Mesh {
    let dims = ((hi - lo) / h).ceil().as_uvec3();
    let (nx, ny, nz) = (
        dims.x as usize + 1,
        dims.y as usize + 1,
        dims.z as usize + 1,
    );
    let at = |i: usize, j: usize, k: usize| lo + DVec3::new(i as f64, j as f64, k as f64) * h;
    let idx = |i: usize, j: usize, k: usize| (i * ny + j) * nz + k;
    let mut val = vec![0.0; nx * ny * nz];
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                val[idx(i, j, k)] = f(at(i, j, k));
            }
        }
    }
    // One vertex per crossed cell.
    let cell = |i: usize, j: usize, k: usize| (i * (ny - 1) + j) * (nz - 1) + k;
    let mut vid = vec![u32::MAX; (nx - 1) * (ny - 1) * (nz - 1)];
    let mut pos = Vec::new();
    const EDGES: [(usize, usize); 12] = [
        (0, 1),
        (2, 3),
        (4, 5),
        (6, 7),
        (0, 2),
        (1, 3),
        (4, 6),
        (5, 7),
        (0, 4),
        (1, 5),
        (2, 6),
        (3, 7),
    ];
    for i in 0..nx - 1 {
        for j in 0..ny - 1 {
            for k in 0..nz - 1 {
                let c: [(DVec3, f64); 8] = std::array::from_fn(|m| {
                    let (a, b, d) = (i + (m & 1), j + ((m >> 1) & 1), k + ((m >> 2) & 1));
                    (at(a, b, d), val[idx(a, b, d)])
                });
                let mut sum = DVec3::ZERO;
                let mut n = 0;
                for (a, b) in EDGES {
                    let (pa, fa) = c[a];
                    let (pb, fb) = c[b];
                    if (fa < 0.0) != (fb < 0.0) {
                        sum += pa + (pb - pa) * (fa / (fa - fb));
                        n += 1;
                    }
                }
                if n > 0 {
                    vid[cell(i, j, k)] = pos.len() as u32;
                    pos.push((sum / n as f64).to_array());
                }
            }
        }
    }
    // One quad per crossed grid edge, around the edge's four cells.
    let mut tris = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            for k in 0..nz {
                let f0 = val[idx(i, j, k)];
                for axis in 0..3 {
                    let (a, b, d) = match axis {
                        0 => (i + 1, j, k),
                        1 => (i, j + 1, k),
                        _ => (i, j, k + 1),
                    };
                    if a >= nx || b >= ny || d >= nz {
                        continue;
                    }
                    let f1 = val[idx(a, b, d)];
                    if (f0 < 0.0) == (f1 < 0.0) {
                        continue;
                    }
                    // The four cells sharing this edge, in the plane of the
                    // other two axes (u, v) with u × v = the edge's axis.
                    let quad: Option<[u32; 4]> = (|| {
                        let mut q = [0u32; 4];
                        for (s, (du, dv)) in [(0, 0), (1, 0), (1, 1), (0, 1)].iter().enumerate() {
                            let (ci, cj, ck) = match axis {
                                0 => (i, j.checked_sub(1 - du)?, k.checked_sub(1 - dv)?),
                                1 => (i.checked_sub(1 - dv)?, j, k.checked_sub(1 - du)?),
                                _ => (i.checked_sub(1 - du)?, j.checked_sub(1 - dv)?, k),
                            };
                            if ci >= nx - 1 || cj >= ny - 1 || ck >= nz - 1 {
                                return None;
                            }
                            let v = vid[cell(ci, cj, ck)];
                            if v == u32::MAX {
                                return None;
                            }
                            q[s] = v;
                        }
                        Some(q)
                    })();
                    let Some(mut q) = quad else { continue };
                    // Outward: the normal points from inside (f < 0) to outside.
                    if f1 < 0.0 {
                        q.reverse();
                    }
                    let p = |v: u32| DVec3::from_array(pos[v as usize]);
                    if p(q[0]).distance(p(q[2])) <= p(q[1]).distance(p(q[3])) {
                        tris.push([q[0], q[1], q[2]]);
                        tris.push([q[0], q[2], q[3]]);
                    } else {
                        tris.push([q[0], q[1], q[3]]);
                        tris.push([q[1], q[2], q[3]]);
                    }
                }
            }
        }
    }
    Mesh::new(pos, tris).expect("surface-net indices are in range")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_demo_body_is_one_closed_outward_surface() {
        let m = humanoid_mesh(DEMO_GRID);
        assert!(m.vertex_count() > 2000, "{}", m.vertex_count());
        // Closed: every edge in exactly two triangles.
        let mut edges = std::collections::HashMap::new();
        for t in m.triangles() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
            }
        }
        let mut hist = std::collections::BTreeMap::new();
        for c in edges.values() {
            *hist.entry(*c).or_insert(0) += 1;
        }
        assert!(edges.values().all(|&c| c == 2), "{hist:?}");
        let comps = crate::mesh::components::components(&m);
        assert_eq!(comps.count, 1);
        let p = m.positions();
        let vol: f64 = m
            .triangles()
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| DVec3::from_array(p[v as usize]));
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        // A 1.75 m body of about 60 litres, outward facing.
        assert!(vol > 0.03 && vol < 0.12, "{vol}");
        let b = m.bounds();
        assert!((b.max[1] - b.min[1] - 1.75).abs() < 0.05);
        // The landmarks embed a rig with one connected region per part.
        let rig = crate::rig::embed::Embedding::new(&m, &humanoid_landmarks(&m), None).unwrap();
        let nb = crate::rig::embed::parts::neighbours(m.vertex_count(), m.triangles());
        let counts = crate::rig::embed::parts::piece_counts(&rig.labels, &nb);
        assert!(counts.iter().all(|&c| c <= 1), "{counts:?} {:?}", rig.notes);
    }
}
