//! Volumetric occupancy of a triangle mesh on a regular grid, the input of
//! the volumetric shape histograms (Huang et al. 2010; 2015, Sec. 4.1).
//!
//! The grid is column-major along the vertical axis (Y): every triangle is
//! rasterised onto the horizontal (X, Z) grid of column centres, giving the
//! height and facing of each surface crossing per column; a column is then
//! filled between its sorted crossings by the non-zero winding rule, which
//! also gives the union of self-intersecting parts (a hand pressed into a
//! hip). A column whose crossings do not cancel (an open or inconsistently
//! oriented surface) falls back to even–odd pairing, and a column with an odd
//! number of crossings keeps only its crossing voxels, so holes in a capture
//! never flood the volume. Column centres exactly on a shared edge belong to
//! one triangle only (top-left rule), so watertight meshes give even columns.
//!
//! Cost: O(T + crossings · log + voxels) per frame, no allocation once the
//! scratch has grown.

use glam::DVec3;

/// Reusable buffers of [`occupancy`].
#[derive(Debug, Default, Clone)]
pub struct VoxelScratch {
    crossings: Vec<(u32, f64, i8)>,
}

/// Calls `emit(centre, weight)` for every occupied voxel of the closed mesh
/// `(positions, triangles)` on a grid of spacing `h` (Y-up, anchored at
/// multiples of `h`). Along Y the inside of a column is known exactly, so a
/// voxel's weight is the fraction of its height that is inside (1 within,
/// less at the top and bottom ends); only X and Z are quantised. Returns
/// the total weight, the volume in voxels.
pub fn occupancy(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    h: f64,
    scratch: &mut VoxelScratch,
    mut emit: impl FnMut(DVec3, f64),
) -> f64 {
    if positions.is_empty() || h.is_nan() || h <= 0.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in positions {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    // Column centres at (i + 0.5) h over the horizontal extent.
    let i0 = floor_i64(lo.x / h);
    let k0 = floor_i64(lo.z / h);
    let ni = (floor_i64(hi.x / h) - i0 + 1).max(1) as usize;
    let nk = (floor_i64(hi.z / h) - k0 + 1).max(1) as usize;
    let cx = |i: i64| (i as f64 + 0.5) * h;
    let xs = &mut scratch.crossings;
    xs.clear();
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        // Signed area of the (x, z) projection; its sign is the facing.
        let area = (b.x - a.x) * (c.z - a.z) - (c.x - a.x) * (b.z - a.z);
        if area == 0.0 {
            continue;
        }
        let facing: i8 = if area > 0.0 { 1 } else { -1 };
        // Orient counter-clockwise for the edge tests.
        let (b, c) = if area > 0.0 { (b, c) } else { (c, b) };
        let area = area.abs();
        let xmin = a.x.min(b.x).min(c.x);
        let xmax = a.x.max(b.x).max(c.x);
        let zmin = a.z.min(b.z).min(c.z);
        let zmax = a.z.max(b.z).max(c.z);
        let ia = ceil_i64(xmin / h - 0.5).max(i0);
        let ib = floor_i64(xmax / h - 0.5).min(i0 + ni as i64 - 1);
        let ka = ceil_i64(zmin / h - 0.5).max(k0);
        let kb = floor_i64(zmax / h - 0.5).min(k0 + nk as i64 - 1);
        let edges = [(b, c), (c, a), (a, b)];
        for i in ia..=ib {
            let x = cx(i);
            for k in ka..=kb {
                let z = cx(k);
                let mut w = [0.0; 3];
                let mut inside = true;
                for (e, (p, q)) in edges.iter().enumerate() {
                    let f = (q.x - p.x) * (z - p.z) - (x - p.x) * (q.z - p.z);
                    // Top-left rule: a centre on an edge belongs to the
                    // triangle whose edge points "down" (or right if flat).
                    let owns = f > 0.0 || (f == 0.0 && (q.z < p.z || (q.z == p.z && q.x > p.x)));
                    if !owns {
                        inside = false;
                        break;
                    }
                    w[e] = f;
                }
                if !inside {
                    continue;
                }
                let y = (w[0] * a.y + w[1] * b.y + w[2] * c.y) / area;
                let col = ((i - i0) as usize * nk + (k - k0) as usize) as u32;
                xs.push((col, y, facing));
            }
        }
    }
    xs.sort_unstable_by(|p, q| p.0.cmp(&q.0).then(p.1.total_cmp(&q.1)));
    let mut total = 0.0;
    // Cells [j h, (j+1) h] along Y, weighted by the exact covered length.
    let mut fill = |col: u32, y0: f64, y1: f64, emit: &mut dyn FnMut(DVec3, f64)| {
        let i = i0 + (col as usize / nk) as i64;
        let k = k0 + (col as usize % nk) as i64;
        let (x, z) = (cx(i), cx(k));
        let ja = floor_i64(y0 / h);
        let jb = floor_i64(y1 / h);
        for j in ja..=jb {
            let lo = (j as f64 * h).max(y0);
            let hi = ((j + 1) as f64 * h).min(y1);
            let w = (hi - lo) / h;
            if w > 0.0 {
                emit(DVec3::new(x, cx(j), z), w);
                total += w;
            }
        }
    };
    let mut s = 0;
    while s < xs.len() {
        let col = xs[s].0;
        let mut e = s;
        while e < xs.len() && xs[e].0 == col {
            e += 1;
        }
        let run = &xs[s..e];
        let net: i32 = run.iter().map(|c| c.2 as i32).sum();
        if net == 0 {
            // Non-zero winding.
            let mut wind = 0i32;
            let mut start = 0.0;
            for c in run {
                let before = wind;
                wind += c.2 as i32;
                if before == 0 && wind != 0 {
                    start = c.1;
                } else if before != 0 && wind == 0 {
                    fill(col, start, c.1, &mut emit);
                }
            }
        } else if run.len() % 2 == 0 {
            for p in run.chunks_exact(2) {
                fill(col, p[0].1, p[1].1, &mut emit);
            }
        } else {
            // Leaky column: only the voxels the surface passes through.
            for c in run {
                let y = (c.1 / h).floor() * h;
                fill(col, y, y + h, &mut emit);
            }
        }
        s = e;
    }
    total
}

/// `x.floor() as i64`, equal for every `x` (NaN 0, saturating at the
/// ends), without the library call that `floor` is on a baseline x86-64
/// build (no SSE4.1 `roundsd`): truncate, then step down if that rounded
/// up. `t as f64` is exact wherever `x` has a fraction (|x| < 2⁵²).
#[inline(always)]
pub(crate) fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// `x.ceil() as i64`, equal for every `x`, as [`floor_i64`].
#[inline(always)]
pub(crate) fn ceil_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) < x {
        t.saturating_add(1)
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::shapes::capsule_mesh;

    #[test]
    fn a_closed_box_fills_its_volume() {
        // Unit cube, outward-facing triangles.
        let p: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .map(|v| v * 0.5 + DVec3::splat(0.013))
            .collect();
        let t = [
            [0, 2, 1],
            [1, 2, 3],
            [4, 5, 6],
            [5, 7, 6],
            [0, 1, 4],
            [1, 5, 4],
            [2, 6, 3],
            [3, 6, 7],
            [0, 4, 2],
            [2, 4, 6],
            [1, 3, 5],
            [3, 7, 5],
        ];
        let mut sc = VoxelScratch::default();
        let mut sum = 0.0;
        let h = 0.05;
        let total = occupancy(&p, &t, h, &mut sc, |_, w| sum += w);
        assert!((sum - total).abs() < 1e-9);
        // 10 × 10 columns, each exactly 0.5 / 0.05 = 10 voxels tall.
        assert!((total - 1000.0).abs() < 1e-9, "{total}");
        // Reversed orientation fills the same volume.
        let flipped: Vec<[u32; 3]> = t.iter().map(|t| [t[0], t[2], t[1]]).collect();
        assert!((occupancy(&p, &flipped, h, &mut sc, |_, _| ()) - 1000.0).abs() < 1e-9);
        // An open box (top removed) keeps only its crossing voxels.
        let open: Vec<[u32; 3]> = [&t[..6], &t[8..]].concat();
        assert!((occupancy(&p, &open, h, &mut sc, |_, _| ()) - 100.0).abs() < 1e-9);
    }

    #[test]
    fn capsule_volume_matches_its_formula() {
        let (r, len) = (0.1, 0.4);
        let m = capsule_mesh(r, len, 48, 24);
        let p: Vec<DVec3> = m
            .positions()
            .iter()
            .map(|p| DVec3::from_array(*p))
            .collect();
        let h = 0.005;
        let n = occupancy(
            &p,
            m.triangles(),
            h,
            &mut VoxelScratch::default(),
            |_, _| (),
        );
        let vol = n * h * h * h;
        let exact = std::f64::consts::PI * r * r * (len + 4.0 / 3.0 * r);
        assert!((vol / exact - 1.0).abs() < 0.03, "{vol} vs {exact}");
    }

    #[test]
    fn floor_and_ceil_equal_the_library_ones() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.0 - f64::EPSILON,
            -1.0 + f64::EPSILON,
            2f64.powi(52) + 0.5,
            -(2f64.powi(52)) - 0.5,
            2f64.powi(53),
            2f64.powi(63),
            -(2f64.powi(63)),
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
        ];
        // A deterministic spread of magnitudes and fractions.
        let mut rng = crate::similarity::test_rng::XorShift::new(0x9E37_79B9_7F4A_7C15);
        for _ in 0..100_000 {
            let v = rng.next_u64();
            let scale = 2f64.powi((v % 80) as i32 - 20);
            xs.push(((v >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * scale);
        }
        for x in xs {
            assert_eq!(floor_i64(x), x.floor() as i64, "floor {x:e}");
            assert_eq!(ceil_i64(x), x.ceil() as i64, "ceil {x:e}");
        }
    }
}
