//! The demo character: a procedural humanoid, one closed surface, with its
//! landmarks. Nothing is downloaded or copied: the body is the zero set of
//! a smooth union of capsules along an A-pose skeleton (1.75 m, facing +Z,
//! its left on +X), meshed by surface nets (Gibson 1998): one vertex per
//! grid cell the surface crosses, at the mean of the cell's edge
//! crossings, and one quad per crossed grid edge joining the four cells
//! around it, split into two triangles.

use crate::embed::landmarks::Landmarks;
use crate::mesh::Mesh;
use glam::DVec3;

/// A capsule `(a, b, radius)`.
type Capsule = (DVec3, DVec3, f64);

/// Shape parameters of the procedural humanoid (body-local frame: facing
/// +Z, its left on +X, feet on y = 0, mid-plane x = 0, before `height`,
/// `yaw` and `offset` place it). [`HumanoidShape::default`] is the demo
/// character exactly (same capsules, same grid box, same mesh, same
/// landmarks; checked by a test).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HumanoidShape {
    /// Scale of the hip joints' distance from the mid-plane (0.09 m).
    /// Default value: 1.
    pub hip_width: f64,
    /// Scale of the shoulder joints' distance from the mid-plane (0.18 m).
    /// Default value: 1.
    pub shoulder_width: f64,
    /// Angle of the arms below the horizontal, degrees: 0 is a T-pose, 45
    /// an A-pose. Default value: 45.
    pub arm_angle: f64,
    /// Angle of each leg outward from the vertical about its hip joint,
    /// degrees; negative brings the knees together. Default value: 0.
    pub leg_spread: f64,
    /// How far the lower end of the torso is raised (metres, before
    /// scaling). The crotch between the thighs rises with it while the hip
    /// joints and the groin landmark (4 cm below them) stay: from about
    /// 0.15 the horizontal section 3.5 % of the height above the groin cuts
    /// two separate thighs. Default value: 0.
    pub crotch_lift: f64,
    /// Body height in metres (a uniform scale of the 1.75 m body about the
    /// floor point of its mid-plane). Default value: 1.75.
    pub height: f64,
    /// Turn about the vertical (+Y), degrees, right-handed. Default value: 0.
    pub yaw: f64,
    /// Translation after scaling and turning. Default value: `[0, 0, 0]`.
    pub offset: [f64; 3],
}

impl Default for HumanoidShape {
    fn default() -> Self {
        HumanoidShape {
            hip_width: 1.0,
            shoulder_width: 1.0,
            arm_angle: 45.0,
            leg_spread: 0.0,
            crotch_lift: 0.0,
            height: 1.75,
            yaw: 0.0,
            offset: [0.0; 3],
        }
    }
}

impl HumanoidShape {
    fn scale(&self) -> f64 {
        self.height / 1.75
    }

    /// Body-local point to world. Each step is skipped when it is the
    /// identity, so the default shape reproduces the demo bit for bit.
    pub fn to_world(&self, p: DVec3) -> DVec3 {
        let mut q = p;
        if self.height != 1.75 {
            q *= self.scale();
        }
        if self.yaw != 0.0 {
            q = glam::DQuat::from_rotation_y(self.yaw.to_radians()) * q;
        }
        if self.offset != [0.0; 3] {
            q += DVec3::from_array(self.offset);
        }
        q
    }

    /// World point to body-local (the inverse of [`HumanoidShape::to_world`]).
    pub fn to_local(&self, p: DVec3) -> DVec3 {
        let mut q = p;
        if self.offset != [0.0; 3] {
            q -= DVec3::from_array(self.offset);
        }
        if self.yaw != 0.0 {
            q = glam::DQuat::from_rotation_y(-self.yaw.to_radians()) * q;
        }
        if self.height != 1.75 {
            q /= self.scale();
        }
        q
    }

    /// The body's true mid-plane (sagittal plane) in world space: a point
    /// on it and its unit normal (towards the character's left).
    pub fn mid_plane(&self) -> (DVec3, DVec3) {
        let n = if self.yaw != 0.0 {
            glam::DQuat::from_rotation_y(self.yaw.to_radians()) * DVec3::X
        } else {
            DVec3::X
        };
        (self.to_world(DVec3::ZERO), n)
    }
}

/// The rotation of leg point `p` about `hip` by `deg` outward (about +Z,
/// sign `x` for the side); the identity at 0 degrees.
fn spread(p: DVec3, hip: DVec3, deg: f64, x: f64) -> DVec3 {
    if deg == 0.0 {
        return p;
    }
    hip + glam::DQuat::from_rotation_z(x * deg.to_radians()) * (p - hip)
}

/// The joints of the body-local shape: `(name, position)` of the landmarks
/// it marks, and the capsules of the body.
fn body(s: &HumanoidShape) -> (Vec<(&'static str, DVec3)>, Vec<Capsule>) {
    let v = DVec3::new;
    // The demo's A-pose uses the exact constants (cos 45° computed in
    // floating point differs from 1/√2 in the last bit).
    let (sa, ca) = if s.arm_angle == 45.0 {
        (
            std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        )
    } else {
        s.arm_angle.to_radians().sin_cos()
    };
    let mut marks = vec![
        ("chin", v(0.0, 1.53, 0.07)),
        ("groin", v(0.0, 0.86, 0.0)),
        ("head_top", v(0.0, 1.75, 0.01)),
    ];
    let mut caps = vec![
        (v(0.0, 0.93 + s.crotch_lift, 0.0), v(0.0, 1.12, 0.0), 0.135),
        (v(0.0, 1.12, 0.0), v(0.0, 1.33, 0.0), 0.13),
        (v(0.0, 1.33, 0.0), v(0.0, 1.50, 0.0), 0.05),
        (v(0.0, 1.60, 0.02), v(0.0, 1.65, 0.02), 0.095),
    ];
    for (side, x) in [("l", 1.0), ("r", -1.0)] {
        let shoulder = v(0.18 * x * s.shoulder_width, 1.40, 0.0);
        let dir = v(ca * x, -sa, 0.0);
        let elbow = shoulder + dir * 0.29;
        let wrist = elbow + dir * 0.26;
        let tip = wrist + dir * 0.16;
        let hip = v(0.09 * x * s.hip_width, 0.90, 0.0);
        let leg = |p: DVec3| spread(p, hip, s.leg_spread, x);
        let knee = leg(v(0.09 * x * s.hip_width, 0.49, 0.01));
        let ankle = leg(v(0.09 * x * s.hip_width, 0.08, 0.0));
        let toe = leg(v(0.09 * x * s.hip_width, 0.03, 0.17));
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
    humanoid_mesh_with(h, &HumanoidShape::default())
}

/// The humanoid of shape `s` at grid spacing `h` (world units). The default
/// shape is meshed over the demo's fixed box; any other over the box of its
/// placed capsules plus a margin.
pub fn humanoid_mesh_with(h: f64, s: &HumanoidShape) -> Mesh {
    let (_, caps) = body(s);
    if *s == HumanoidShape::default() {
        return surface_nets(
            &|p| sdf(p, &caps),
            DVec3::new(-0.8, -0.05, -0.3),
            DVec3::new(0.8, 1.85, 0.4),
            h,
        );
    }
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for (a, b, r) in &caps {
        for e in [*a, *b] {
            let m = DVec3::splat(r + 0.06);
            lo = lo.min(s.to_world(e - m).min(s.to_world(e + m)));
            hi = hi.max(s.to_world(e - m).max(s.to_world(e + m)));
            // A turned box: its other corners too.
            for c in 0..8 {
                let corner = e + DVec3::new(
                    if c & 1 == 0 { -m.x } else { m.x },
                    if c & 2 == 0 { -m.y } else { m.y },
                    if c & 4 == 0 { -m.z } else { m.z },
                );
                lo = lo.min(s.to_world(corner));
                hi = hi.max(s.to_world(corner));
            }
        }
    }
    let k = s.scale();
    surface_nets(&|p| sdf(s.to_local(p), &caps) * k, lo, hi, h)
}

/// The demo character's landmarks as a landmark file's JSON (named points
/// on its skeleton).
pub fn humanoid_landmarks_json() -> String {
    humanoid_landmarks_json_with(&HumanoidShape::default())
}

/// The landmarks of shape `s` as a landmark file's JSON: the same
/// anatomical places as the demo's (points on its skeleton), placed with
/// the body.
pub fn humanoid_landmarks_json_with(s: &HumanoidShape) -> String {
    let (marks, _) = body(s);
    let map: std::collections::BTreeMap<String, Vec<f64>> = marks
        .iter()
        .map(|(n, p)| (n.to_string(), s.to_world(*p).to_array().to_vec()))
        .collect();
    serde_json::to_string_pretty(&map).unwrap_or_default()
}

/// The demo character's landmarks.
pub fn humanoid_landmarks(mesh: &Mesh) -> Landmarks {
    humanoid_landmarks_with(mesh, &HumanoidShape::default())
}

/// The landmarks of shape `s` on its mesh.
pub fn humanoid_landmarks_with(mesh: &Mesh, s: &HumanoidShape) -> Landmarks {
    Landmarks::parse(
        &humanoid_landmarks_json_with(s),
        std::path::Path::new("<demo>"),
        mesh.vertex_count(),
    )
    .expect("the demo's landmarks are complete")
}

/// Surface nets of the zero set of `f` over the box `[lo, hi]`, spacing `h`.
/// Closed where the zero set stays inside the box; a few edges may be
/// shared by four triangles where two sheets pass one cell edge.
pub(crate) fn surface_nets(f: &dyn Fn(DVec3) -> f64, lo: DVec3, hi: DVec3, h: f64) -> Mesh {
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

    /// The demo's capsules as they were before the body took shape
    /// parameters (frozen here), for the regression test below.
    fn frozen_demo_capsules() -> Vec<Capsule> {
        let v = DVec3::new;
        let (s45, c45) = (
            std::f64::consts::FRAC_1_SQRT_2,
            std::f64::consts::FRAC_1_SQRT_2,
        );
        let mut caps = vec![
            (v(0.0, 0.93, 0.0), v(0.0, 1.12, 0.0), 0.135),
            (v(0.0, 1.12, 0.0), v(0.0, 1.33, 0.0), 0.13),
            (v(0.0, 1.33, 0.0), v(0.0, 1.50, 0.0), 0.05),
            (v(0.0, 1.60, 0.02), v(0.0, 1.65, 0.02), 0.095),
        ];
        for x in [1.0, -1.0] {
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
        }
        caps
    }

    /// A checksum of a mesh: positions' bits and indices, folded (FNV-1a).
    fn checksum(m: &Mesh) -> u64 {
        let mut h: u64 = 0xcbf29ce484222325;
        let mut eat = |x: u64| {
            h ^= x;
            h = h.wrapping_mul(0x100000001b3);
        };
        for p in m.positions() {
            p.iter().for_each(|c| eat(c.to_bits()));
        }
        for t in m.triangles() {
            t.iter().for_each(|&v| eat(v as u64));
        }
        h
    }

    #[test]
    fn the_default_shape_is_the_demo_mesh_bit_for_bit() {
        let caps = frozen_demo_capsules();
        let before = surface_nets(
            &|p| sdf(p, &caps),
            DVec3::new(-0.8, -0.05, -0.3),
            DVec3::new(0.8, 1.85, 0.4),
            DEMO_GRID,
        );
        let after = humanoid_mesh(DEMO_GRID);
        assert_eq!(before.vertex_count(), after.vertex_count());
        assert_eq!(checksum(&before), checksum(&after));
        assert_eq!(body(&HumanoidShape::default()).1, caps);
        eprintln!(
            "demo mesh: {} vertices, checksum {:016x}",
            after.vertex_count(),
            checksum(&after)
        );
        // Landmarks: the demo's points, unmoved by the identity placement.
        let s = HumanoidShape::default();
        for (_, p) in body(&s).0 {
            assert_eq!(s.to_world(p), p);
        }
    }

    #[test]
    fn a_placed_shape_is_the_local_body_moved() {
        let s = HumanoidShape {
            height: 1.6,
            yaw: 30.0,
            offset: [0.3, 0.1, -0.2],
            ..Default::default()
        };
        let p = DVec3::new(0.1, 0.9, 0.05);
        assert!(s.to_local(s.to_world(p)).distance(p) < 1e-12);
        let m = humanoid_mesh_with(DEMO_GRID, &s);
        let b = m.bounds();
        assert!((b.max[1] - b.min[1] - 1.6).abs() < 0.05, "{b:?}");
        let (o, n) = s.mid_plane();
        // The mesh is mirror-symmetric about its mid-plane: the mean signed
        // distance of its vertices from the plane is near zero.
        let mean: f64 = m
            .positions()
            .iter()
            .map(|q| (DVec3::from_array(*q) - o).dot(n))
            .sum::<f64>()
            / m.vertex_count() as f64;
        assert!(mean.abs() < 0.01, "{mean}");
    }

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
        let rig = crate::embed::Embedding::new(&m, &humanoid_landmarks(&m), None).unwrap();
        let nb = crate::embed::parts::neighbours(m.vertex_count(), m.triangles());
        let counts = crate::embed::parts::piece_counts(&rig.labels, &nb);
        assert!(counts.iter().all(|&c| c <= 1), "{counts:?} {:?}", rig.notes);
    }
}
