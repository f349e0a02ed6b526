//! Steps 1-2 of the automatic landmarks: the mesh checked and reduced to
//! the vertices of its triangles (errors: the reason, in words), then the body's frame (symmetry plane,
//! up and the floor, facing) with the confidences of each.

use super::geometry::{Graph, Grid, clamp01, fit_symmetry, principal_axes};
use glam::DVec3;

/// Vertex positions and triangles.
type Surface = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// Only the vertices of triangles (a group selected from a file keeps the
/// others, unreferenced), renumbered in order; a triangle naming a vertex
/// out of range is an error.
pub(super) fn referenced(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<Surface, String> {
    let mut index = vec![u32::MAX; positions.len()];
    let mut kept: Vec<[f64; 3]> = Vec::new();
    let mut tris: Vec<[u32; 3]> = Vec::with_capacity(triangles.len());
    for t in triangles {
        if let Some(v) = t.iter().find(|&&v| v as usize >= positions.len()) {
            return Err(format!("triangle {t:?} names vertex {v}, out of range"));
        }
        tris.push(t.map(|v| {
            let i = &mut index[v as usize];
            if *i == u32::MAX {
                *i = kept.len() as u32;
                kept.push(positions[v as usize]);
            }
            *i
        }));
    }
    Ok((kept, tris))
}

/// The body's frame.
pub(super) struct Frame {
    /// The area-weighted centre of the surface.
    pub centre: DVec3,
    /// Unit up (floor to head).
    pub up: DVec3,
    /// The floor's height along `up`.
    pub floor: f64,
    /// Unit facing.
    pub facing: DVec3,
    /// The character's left (the symmetry plane's normal, signed).
    pub left: DVec3,
    /// The symmetry plane's normal as fitted, and its offset along it.
    pub left0: DVec3,
    pub off: f64,
    /// Height along `up`.
    pub h: f64,
    /// The symmetry residual, % of the height.
    pub sym_pct: f64,
    /// The least of the symmetry, floor and facing confidences.
    pub conf: f64,
    /// What lowered them, in words.
    pub doubts: Vec<String>,
}

impl Frame {
    /// Height above the floor.
    pub(crate) fn hgt(&self, q: DVec3) -> f64 {
        q.dot(self.up) - self.floor
    }

    /// Signed distance to the left of the symmetry plane.
    pub fn side(&self, q: DVec3) -> f64 {
        q.dot(self.left) - self.off * self.left0.dot(self.left)
    }

    /// `q` reflected in the symmetry plane.
    pub fn mirror(&self, q: DVec3) -> DVec3 {
        q - self.left * (2.0 * self.side(q))
    }

    /// The point of the symmetry plane `y` above the floor, `depth` along
    /// the facing.
    pub(crate) fn axis_at(&self, y: f64, depth: f64) -> DVec3 {
        let o = self.off * self.left0.dot(self.left);
        self.left * o + self.facing * depth + self.up * (self.floor + y)
    }
}

/// The centre, the principal axes (area-weighted) and the largest extent
/// along them.
fn centre_and_axes(p: &[DVec3], g: &Graph) -> Result<(DVec3, [DVec3; 3], f64), String> {
    let total: f64 = g.area.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return Err("the surface has no area".into());
    }
    let centre = p.iter().zip(&g.area).map(|(q, a)| *q * *a).sum::<DVec3>() / total;
    let mut cov = [[0.0; 3]; 3];
    for (q, a) in p.iter().zip(&g.area) {
        let d = (*q - centre).to_array();
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += a * d[i] * d[j];
            }
        }
    }
    let axes = principal_axes(cov);
    let extent = |dir: DVec3| {
        let (lo, hi) = p
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
                (a.min(q.dot(dir)), b.max(q.dot(dir)))
            });
        hi - lo
    };
    let size = axes.iter().map(|a| extent(*a)).fold(0.0, f64::max);
    if size.is_nan() || size <= 0.0 {
        return Err("the mesh has no extent".into());
    }
    Ok((centre, axes, size))
}

/// Up: the longest principal direction in the symmetry plane (normal
/// `left0`), snapped to a file axis within 20°.
fn in_plane_up(p: &[DVec3], g: &Graph, centre: DVec3, left0: DVec3) -> DVec3 {
    let mut cov2 = [[0.0; 3]; 3];
    for (q, a) in p.iter().zip(&g.area) {
        let mut d = *q - centre;
        d -= left0 * d.dot(left0);
        let d = d.to_array();
        for i in 0..3 {
            for j in 0..3 {
                cov2[i][j] += a * d[i] * d[j];
            }
        }
    }
    let mut up = principal_axes(cov2)[0];
    let snap = crate::embed::axes::nearest_axis(up);
    let snap = if snap.dot(up) < 0.0 { -snap } else { snap };
    let snap = [snap, -snap]
        .into_iter()
        .max_by(|a, b| a.dot(up).total_cmp(&b.dot(up)))
        .unwrap_or(snap);
    if snap.dot(up) > (20f64).to_radians().cos() && snap.dot(left0).abs() < 0.2 {
        up = snap;
    }
    up
}

/// Steps 1-2: the symmetry plane (each principal plane refined by
/// reflect-and-fit, the best fit), up and its sign (the soles are flat,
/// the head round), facing (the toes reach forward of the shins).
pub(super) fn frame(p: &[DVec3], g: &Graph) -> Result<Frame, String> {
    let (centre, axes, size) = centre_and_axes(p, g)?;

    // 1. The symmetry plane: each principal plane, refined; the best fit.
    let grid = Grid::new(p, size / 60.0);
    let stride = (p.len() / 3000).max(1);
    let sample: Vec<usize> = (0..p.len()).step_by(stride).collect();
    let (left0, off, sym) = axes
        .iter()
        .map(|a| fit_symmetry(p, &sample, &grid, *a, centre.dot(*a), size))
        .min_by(|a, b| a.2.total_cmp(&b.2))
        .unwrap_or((DVec3::X, 0.0, f64::INFINITY));
    // 2. Up: the longest in-plane principal direction, snapped to a file
    // axis within 20°.
    let up = in_plane_up(p, g, centre, left0);
    let left_ax = (left0 - up * left0.dot(up)).normalize_or(left0);
    let (lo, hi) = p
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
            (a.min(q.dot(up)), b.max(q.dot(up)))
        });
    let h = hi - lo;
    // Sign: the soles are flat, the head round.
    let band = 0.02 * h;
    let (mut a_lo, mut a_hi) = (0.0, 0.0);
    for (q, a) in p.iter().zip(&g.area) {
        let y = q.dot(up);
        if y < lo + band {
            a_lo += a;
        }
        if y > hi - band {
            a_hi += a;
        }
    }
    let mut doubts = Vec::new();
    let (floor, up) = if a_lo >= a_hi { (lo, up) } else { (-hi, -up) };
    let flat_ratio = a_lo.max(a_hi) / a_lo.min(a_hi).max(1e-300);
    let hgt = |q: DVec3| q.dot(up) - floor;
    // Facing: the toes reach forward of the shins.
    let fwd0 = left_ax.cross(up);
    let (mut foot, mut fw, mut shin, mut sw) = (0.0, 0.0, 0.0, 0.0);
    for (q, a) in p.iter().zip(&g.area) {
        let y = hgt(*q) / h;
        if y < 0.04 {
            foot += q.dot(fwd0) * a;
            fw += a;
        } else if (0.12..0.2).contains(&y) {
            shin += q.dot(fwd0) * a;
            sw += a;
        }
    }
    let toe_reach = if fw > 0.0 && sw > 0.0 {
        foot / fw - shin / sw
    } else {
        0.0
    };
    let (facing, left) = if toe_reach >= 0.0 {
        (fwd0, left_ax)
    } else {
        (-fwd0, -left_ax)
    };
    let sym_pct = 100.0 * sym / h;
    let c_sym = clamp01(1.0 - (sym_pct - 1.5) / 3.0);
    if c_sym < 1.0 {
        doubts.push(format!(
            "the best symmetry plane leaves reflected points {sym_pct:.1}% of the height from the surface (a body: under 1.5%)"
        ));
    }
    let c_up = clamp01((flat_ratio - 1.2) / 1.0);
    if c_up < 1.0 {
        doubts.push(format!(
            "the floor end is not clear: the flat areas at the two ends differ by a factor {flat_ratio:.2}"
        ));
    }
    let c_face = clamp01(toe_reach.abs() / (0.01 * h));
    if c_face < 1.0 {
        doubts.push(format!(
            "the facing is not clear: the feet reach {:.1}% of the height forward of the shins",
            100.0 * toe_reach.abs() / h
        ));
    }
    Ok(Frame {
        centre,
        up,
        floor,
        facing,
        left,
        left0,
        off,
        h,
        sym_pct,
        conf: c_sym.min(c_up).min(c_face),
        doubts,
    })
}
