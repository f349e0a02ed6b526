//! The shape histogram's binning as it was written first (one `atan2`,
//! `acos` and `rem_euclid` per sample, the coarse re-binning with an
//! integer modulo per tap), kept verbatim outside the library as the
//! oracle that `surfmotion::similarity::histogram::describe_weighted` must
//! equal bit for bit: the cached similarities and graphs of every database
//! were computed with it, so a descriptor that differed in its last bit
//! would change their keys' meaning. Read by the bit-identity tests
//! (`db::sparse`) and, through `#[path]`, by `benches/similarity.rs` (the
//! binning's "before"); Huang et al. 2015, Sec. 4.1, Eq. 1 (see
//! `surfmotion::similarity::histogram` for the method).

use glam::DVec3;
use surfmotion::similarity::histogram::{
    DESCRIPTOR_LEN, FREQS, PHI_BINS, PHI_SUB, R_BINS, RING_PAD, RINGS, SUB_STRIDE, ShapeGrid,
    THETA_BINS, dft_table, freq_weight,
};

/// `surfmotion::similarity::histogram::describe_weighted` as first written.
pub fn describe_weighted(
    points: &[(DVec3, f64)],
    grid: &ShapeGrid,
    fine: &mut Vec<f64>,
    out: &mut [f32],
    norms: &mut [f64; PHI_SUB],
) {
    let mass: f64 = points.iter().map(|p| p.1).sum();
    let centre = points.iter().map(|(p, w)| *p * *w).sum::<DVec3>() / mass.max(f64::MIN_POSITIVE);
    let nfine = PHI_BINS * PHI_SUB;
    fine.clear();
    fine.resize(RINGS * nfine, 0.0);
    let unit = 1.0 / mass.max(f64::MIN_POSITIVE);
    for (p, w) in points.iter() {
        let d = *p - centre;
        let r = d.length();
        let theta = if r > 0.0 {
            (d.y / r).clamp(-1.0, 1.0).acos()
        } else {
            0.0
        };
        let phi = (-d.z).atan2(d.x).rem_euclid(std::f64::consts::TAU);
        let [(r0, r1, fr), (t0, t1, ft)] = [
            (r / grid.r_max * R_BINS as f64, R_BINS),
            (theta / std::f64::consts::PI * THETA_BINS as f64, THETA_BINS),
        ]
        .map(|(x, n)| {
            let x = (x - 0.5).clamp(0.0, (n - 1) as f64);
            let i = (x.floor() as usize).min(n - 1);
            (i, (i + 1).min(n - 1), x - i as f64)
        });
        let x = phi / std::f64::consts::TAU * nfine as f64 - 0.5;
        let xf = x.floor();
        let ff = x - xf;
        let f0 = (xf as i64).rem_euclid(nfine as i64) as usize;
        let f1 = (f0 + 1) % nfine;
        let m = unit * w;
        for (ri, wr) in [(r0, 1.0 - fr), (r1, fr)] {
            for (ti, wt) in [(t0, 1.0 - ft), (t1, ft)] {
                let base = (ri * THETA_BINS + ti) * nfine;
                let v = m * wr * wt;
                fine[base + f0] += v * (1.0 - ff);
                fine[base + f1] += v * ff;
            }
        }
    }
    let (cos, sin) = dft_table();
    out[..DESCRIPTOR_LEN].fill(0.0);
    for (s, norm) in norms.iter_mut().enumerate() {
        let block = &mut out[s * SUB_STRIDE..(s + 1) * SUB_STRIDE];
        for ring in 0..RINGS {
            let f = &fine[ring * nfine..(ring + 1) * nfine];
            let coarse: [f64; PHI_BINS] = std::array::from_fn(|c| {
                let sub = PHI_SUB as i64;
                (-sub / 2..sub + sub / 2)
                    .map(|i| {
                        let w = 1.0 - ((i as f64 - (sub as f64 - 1.0) / 2.0) / sub as f64).abs();
                        let j = (c as i64 * sub + i - s as i64).rem_euclid(nfine as i64);
                        w * f[j as usize]
                    })
                    .sum()
            });
            for k in 0..FREQS {
                let (mut re, mut im) = (0.0, 0.0);
                for (c, v) in coarse.iter().enumerate() {
                    re += v * cos[k][c];
                    im -= v * sin[k][c];
                }
                block[(2 * k) * RING_PAD + ring] = re as f32;
                block[(2 * k + 1) * RING_PAD + ring] = im as f32;
            }
        }
        let mut n2 = 0.0;
        for k in 0..FREQS {
            let w = freq_weight(k);
            for ring in 0..RINGS {
                let re = block[(2 * k) * RING_PAD + ring] as f64;
                let im = block[(2 * k + 1) * RING_PAD + ring] as f64;
                n2 += w * (re * re + im * im);
            }
        }
        *norm = n2 / PHI_BINS as f64;
    }
}

/// Reusable buffers of [`describe`], as the first version kept them.
#[derive(Debug, Default, Clone)]
pub struct Scratch {
    voxels: surfmotion::similarity::voxel::VoxelScratch,
    points: Vec<(DVec3, f64)>,
    fine: Vec<f64>,
}

/// `surfmotion::similarity::histogram::describe` with the first version's
/// binning: the same occupied voxels (`surfmotion::similarity::voxel::
/// occupancy`, the vertices where a
/// frame has no volume), binned by [`describe_weighted`]. Returns the
/// volume in voxels.
pub fn describe(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    grid: &ShapeGrid,
    scratch: &mut Scratch,
    out: &mut [f32],
    norms: &mut [f64; PHI_SUB],
) -> f64 {
    let Scratch {
        voxels,
        points,
        fine,
    } = scratch;
    points.clear();
    let mut volume = surfmotion::similarity::voxel::occupancy(
        positions,
        triangles,
        grid.voxel,
        voxels,
        |p, w| points.push((p, w)),
    );
    if points.is_empty() {
        points.extend(positions.iter().map(|p| (*p, 1.0)));
        volume = positions.len() as f64;
    }
    describe_weighted(points, grid, fine, out, norms);
    volume
}
