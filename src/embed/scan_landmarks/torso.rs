//! Steps 5 and 7 of the automatic landmarks: the groin where the legs
//! split, the chin at the front of the neck below the head.

use super::frame::Frame;
use super::geometry::{Graph, clamp01};
use crate::embed::section::{cross_section, encloses, part_loop};
use glam::DVec3;

/// The area-weighted mean depth (along the facing) of the vertices that
/// `keep` selects; `fallback` when none is.
fn mean_depth(p: &[DVec3], g: &Graph, f: &Frame, keep: impl Fn(DVec3) -> bool) -> f64 {
    let (mut s, mut w) = (0.0, 0.0);
    for (q, a) in p.iter().zip(&g.area) {
        if keep(*q) {
            s += q.dot(f.facing) * a;
            w += a;
        }
    }
    if w > 0.0 {
        s / w
    } else {
        f.centre.dot(f.facing)
    }
}

/// Step 5: the lowest horizontal section (from 25 % of the height up)
/// whose loop encloses the mid-plane point between the legs, refined by
/// bisection; `(groin, confidence, how)`.
pub(super) fn groin(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    p: &[DVec3],
    g: &Graph,
    f: &Frame,
) -> (DVec3, f64, String) {
    let (h, up) = (f.h, f.up);
    let depth_of_legs = mean_depth(p, g, f, |q| (0.25..0.35).contains(&(f.hgt(q) / h)));
    let axis_at = |y: f64| f.axis_at(y, depth_of_legs);
    let mut groin = None;
    let mut k = 0.25;
    while k < 0.7 {
        let q = axis_at(k * h);
        let loops = cross_section(positions, triangles, q, up);
        if loops
            .iter()
            .any(|l| l.points.len() >= 3 && encloses(l, q, up))
        {
            // The crotch point: the lowest point of that loop's surface
            // near the axis; refine between the last gap and here.
            let (mut a, mut b) = ((k - 0.005) * h, k * h);
            for _ in 0..8 {
                let m = 0.5 * (a + b);
                let qm = axis_at(m);
                let inside = cross_section(positions, triangles, qm, up)
                    .iter()
                    .any(|l| l.points.len() >= 3 && encloses(l, qm, up));
                if inside { b = m } else { a = m }
            }
            groin = Some(axis_at(b));
            break;
        }
        k += 0.005;
    }
    match groin {
        Some(q) => {
            let y = f.hgt(q) / h;
            // Human crotch heights: 0.40-0.52 H.
            let c = clamp01(1.0 - ((y - 0.46).abs() - 0.08).max(0.0) / 0.1);
            (
                q,
                c,
                format!("where the legs split, {:.0}% of the height up", 100.0 * y),
            )
        }
        None => (
            axis_at(0.47 * h),
            0.0,
            "the legs do not split below 70% of the height; placed at 47%".to_string(),
        ),
    }
}

/// Step 7: the neck's narrowest section below the head top `head_pt`,
/// its front; `(chin, confidence, how)`.
pub(super) fn chin(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    p: &[DVec3],
    g: &Graph,
    f: &Frame,
    head_pt: Option<DVec3>,
) -> (DVec3, f64, String) {
    let (h, up) = (f.h, f.up);
    let (side, hgt) = (|q: DVec3| f.side(q), |q: DVec3| f.hgt(q));
    let top_h = head_pt.map_or(h, hgt);
    let head_depth = mean_depth(p, g, f, |q| {
        hgt(q) > top_h - 0.06 * h && side(q).abs() < 0.06 * h
    });
    let mut neck: Option<(f64, f64)> = None;
    let mut y = top_h - 0.25 * h;
    while y < top_h - 0.06 * h {
        let q = f.axis_at(y, head_depth);
        if let Some(l) = part_loop(positions, triangles, q, up, q)
            && encloses(&l, q, up)
            && neck.is_none_or(|n| l.length < n.1)
        {
            neck = Some((y, l.length));
        }
        y += 0.005 * h;
    }
    match neck {
        Some((ny, len)) => {
            let q = f.axis_at(ny, head_depth);
            let front = part_loop(positions, triangles, q, up, q)
                .and_then(|l| {
                    l.points
                        .iter()
                        .copied()
                        .filter(|x| side(*x).abs() < 0.03 * h)
                        .max_by(|a, b| a.dot(f.facing).total_cmp(&b.dot(f.facing)))
                })
                .unwrap_or(q);
            let neck_w = len / std::f64::consts::PI / h;
            // A neck is 5-9 % of the height across.
            let c = clamp01(1.0 - (neck_w - 0.09).max(0.0) / 0.05);
            (
                front,
                c,
                format!(
                    "the front of the neck's narrowest section below the head ({:.0}% of the height up, {:.1}% across)",
                    100.0 * ny / h,
                    100.0 * neck_w
                ),
            )
        }
        None => (
            f.axis_at(0.87 * h, head_depth),
            0.0,
            "no neck section found; placed at 87% of the height".into(),
        ),
    }
}
