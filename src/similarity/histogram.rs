//! 3D volumetric shape histograms and their rotation-minimised distance
//! (Huang et al. 2015, Sec. 4.1, Eq. 1; Huang et al. 2010).
//!
//! A frame's occupied voxels ([`super::voxel`]) are binned in spherical
//! coordinates `(r, θ, φ)` about their centre of mass, `(5, 10, 20)` bins:
//! `r` uniform on `[0, r_max]` (one `r_max` per database, the last bin takes
//! anything beyond), `θ` the angle from the vertical, `φ` the azimuth. Each
//! voxel is shared linearly between neighbouring bins (soft binning), which
//! removes most of the voxel grid's aliasing under rotation. The
//! histogram is normalised to unit sum, so the distance does not depend on
//! the voxel size. The dissimilarity (Eq. 1)
//!
//! `c(M_r, M_s) = min_φ ‖H(M_r) − H(M_s, φ)‖₂`
//!
//! is minimised over rotation about the vertical axis with the paper's
//! fine-histogram method: φ is first binned 10× finer (200 bins); the fine
//! histogram shifted by `s ∈ 0..10` fine bins and re-binned (with a hat
//! kernel, see [`describe`]) gives 10 coarse histograms, and every coarse circular shift `c ∈ 0..20` of each is
//! compared, so all 200 rotations in steps of 1.8° are searched. The coarse
//! shifts are done at once as a circular cross-correlation over φ in the
//! Fourier domain: each frame stores, for each `s`, the 11 DFT coefficients
//! of each of its 50 `(r, θ)` rings (f32, 45 KB per frame), and a pair costs
//! `10 · (11 · 50 + 20 · 11)` complex multiply–adds, accumulated in f64.
//! `‖a − b‖² = ‖a‖² + ‖b‖² − 2⟨a, b⟩` uses norms taken from the same stored
//! spectra (Parseval), so a frame's distance to itself is 0 to rounding.

use super::voxel::{VoxelScratch, occupancy};
use glam::DVec3;

/// Radial bins.
pub const R_BINS: usize = 5;
/// Polar (from vertical) bins.
pub const THETA_BINS: usize = 10;
/// Azimuthal bins.
pub const PHI_BINS: usize = 20;
/// Fine azimuthal bins per coarse bin (the rotation search step).
pub const PHI_SUB: usize = 10;
/// `(r, θ)` rings.
pub const RINGS: usize = R_BINS * THETA_BINS;
/// Non-redundant DFT coefficients of a real signal of `PHI_BINS` samples.
pub const FREQS: usize = PHI_BINS / 2 + 1;
/// Rings padded to whole 4-lanes. (Public, hidden, for the first
/// version's binning, the oracle of the bit-identity tests in
/// `tests/it/db/histogram_reference.rs`; likewise [`SUB_STRIDE`],
/// [`freq_weight`], [`dft_table`].)
#[doc(hidden)]
pub const RING_PAD: usize = RINGS.div_ceil(4) * 4;
/// f32 values per sub-shift: `FREQS × (re, im) × RING_PAD`.
#[doc(hidden)]
pub const SUB_STRIDE: usize = FREQS * 2 * RING_PAD;
/// f32 values of one frame's descriptor.
pub const DESCRIPTOR_LEN: usize = PHI_SUB * SUB_STRIDE;

/// The database-wide binning: voxel size and outer radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapeGrid {
    /// Voxel edge (metres or file units).
    pub voxel: f64,
    /// Outer radius of the last radial bin.
    pub r_max: f64,
}

/// Reusable buffers for [`describe`].
#[derive(Debug, Default, Clone)]
pub struct ShapeScratch {
    voxels: VoxelScratch,
    points: Vec<(DVec3, f64)>,
    fine: Vec<f64>,
}

/// Writes the descriptor of one frame (Y-up positions) into `out`
/// (`DESCRIPTOR_LEN` values) and the squared norm of each sub-shifted
/// histogram into `norms`. Returns the volume in voxels.
pub fn describe(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    grid: &ShapeGrid,
    scratch: &mut ShapeScratch,
    out: &mut [f32],
    norms: &mut [f64; PHI_SUB],
) -> f64 {
    let ShapeScratch {
        voxels,
        points,
        fine,
    } = scratch;
    points.clear();
    let mut volume = occupancy(positions, triangles, grid.voxel, voxels, |p, w| {
        points.push((p, w))
    });
    if points.is_empty() {
        // No volume: fall back to the vertices themselves.
        points.extend(positions.iter().map(|p| (*p, 1.0)));
        volume = positions.len() as f64;
    }
    describe_weighted(points, grid, fine, out, norms);
    volume
}

/// [`describe`] for weighted sample points (voxels, or area-weighted
/// surface points), binned about their weighted centre.
///
/// Equal bit for bit to the first version
/// (kept outside the library as the oracle of the bit-identity tests,
/// `tests/it/db/histogram_reference.rs`; the cached similarities were
/// computed with it), at less cost: a sample's azimuth
/// (`atan2`, the fine φ bin and its share) is computed again only when its
/// horizontal offset from the centre changes — voxels come column by
/// column ([`super::voxel::occupancy`]), so once per column, not per
/// voxel —; the fine histogram is stored φ-major (`[fine φ][ring]`), so a
/// column adds into two runs of 50 values; and the coarse re-binning
/// ([`spectra`]) runs over all rings at once from a tap table made once.
/// The additions into every bin happen in the same order as before, so the
/// sums are the same.
pub fn describe_weighted(
    points: &[(DVec3, f64)],
    grid: &ShapeGrid,
    fine: &mut Vec<f64>,
    out: &mut [f32],
    norms: &mut [f64; PHI_SUB],
) {
    bin_fine(points, grid, fine);
    spectra(fine, out, norms);
}

/// Fine φ bins.
const NFINE: usize = PHI_BINS * PHI_SUB;

/// A sample's share of the fine φ bins: bins `f0` and `f1 = f0 + 1`
/// (circular), `ff` going to `f1`.
#[derive(Debug, Clone, Copy)]
struct Azimuth {
    f0: usize,
    f1: usize,
    ff: f64,
}

impl Azimuth {
    /// The azimuth of the offset `(dx, dz)` from the centre (φ measured
    /// from +x towards −z), shared linearly between the two nearest fine
    /// bin centres.
    #[inline]
    fn of(dx: f64, dz: f64) -> Azimuth {
        let phi = (-dz).atan2(dx).rem_euclid(std::f64::consts::TAU);
        let x = phi / std::f64::consts::TAU * NFINE as f64 - 0.5;
        let xf = x.floor();
        let f0 = (xf as i64).rem_euclid(NFINE as i64) as usize;
        Azimuth {
            f0,
            f1: (f0 + 1) % NFINE,
            ff: x - xf,
        }
    }
}

/// A value `x` in bin units shared linearly between the two nearest of
/// `n` bin centres (clamped at the ends): `(i, i + 1, share of i + 1)`.
/// The clamped value is not negative (or NaN, which both give 0), so its
/// truncation is its floor: no library call.
#[inline(always)]
fn soft(x: f64, n: usize) -> (usize, usize, f64) {
    let x = (x - 0.5).clamp(0.0, (n - 1) as f64);
    let i = (x as usize).min(n - 1);
    (i, (i + 1).min(n - 1), x - i as f64)
}

/// The fine histogram (`NFINE × RINGS`, φ-major, unit sum) of the weighted
/// samples about their weighted centre, soft-binned in `r`, `θ` and fine
/// `φ`: each sample is shared linearly between the two nearest bin centres
/// of each, so the histogram varies continuously with the mesh and the
/// voxel grid's aliasing (a sample crossing a bin edge) does not show as
/// noise.
fn bin_fine(points: &[(DVec3, f64)], grid: &ShapeGrid, fine: &mut Vec<f64>) {
    let mass: f64 = points.iter().map(|p| p.1).sum();
    let centre = points.iter().map(|(p, w)| *p * *w).sum::<DVec3>() / mass.max(f64::MIN_POSITIVE);
    fine.clear();
    fine.resize(RINGS * NFINE, 0.0);
    let unit = 1.0 / mass.max(f64::MIN_POSITIVE);
    // The horizontal offset (bits) the azimuth was last computed for.
    let mut last = None;
    let mut az = Azimuth::of(0.0, 0.0);
    for (p, w) in points.iter() {
        let d = *p - centre;
        let key = (d.x.to_bits(), d.z.to_bits());
        if last != Some(key) {
            az = Azimuth::of(d.x, d.z);
            last = Some(key);
        }
        let r = d.length();
        let theta = if r > 0.0 {
            (d.y / r).clamp(-1.0, 1.0).acos()
        } else {
            0.0
        };
        let (r0, r1, fr) = soft(r / grid.r_max * R_BINS as f64, R_BINS);
        let (t0, t1, ft) = soft(theta / std::f64::consts::PI * THETA_BINS as f64, THETA_BINS);
        let (row0, row1) = (az.f0 * RINGS, az.f1 * RINGS);
        let m = unit * w;
        for (ri, wr) in [(r0, 1.0 - fr), (r1, fr)] {
            for (ti, wt) in [(t0, 1.0 - ft), (t1, ft)] {
                let ring = ri * THETA_BINS + ti;
                let v = m * wr * wt;
                fine[row0 + ring] += v * (1.0 - az.ff);
                fine[row1 + ring] += v * az.ff;
            }
        }
    }
}

/// Taps of the coarse re-binning: a coarse φ bin `c` of the histogram
/// shifted by `s` fine bins is `Σ_t w_t · fine[(c · PHI_SUB + t − PHI_SUB/2
/// − s) mod NFINE]` over `t < 2 · PHI_SUB`, with the hat weights `w_t`
/// (linear interpolation between coarse bin centres, a partition of unity:
/// a box would put a sharp, grid-aliased edge at every coarse φ boundary).
const TAPS: usize = 2 * PHI_SUB;

/// The hat weights `w_t` of [`TAPS`], computed as the first version did.
fn tap_weights() -> [f64; TAPS] {
    let sub = PHI_SUB as i64;
    std::array::from_fn(|t| {
        let i = t as i64 - sub / 2;
        1.0 - ((i as f64 - (sub as f64 - 1.0) / 2.0) / sub as f64).abs()
    })
}

/// Writes the descriptor (the DFT over coarse φ of each ring, for each of
/// the `PHI_SUB` sub-shifts) of the fine histogram `fine` (φ-major) into
/// `out`, and each sub-shift's squared norm (Parseval on the stored,
/// rounded spectra) into `norms`. Every ring is done at once (the ring is
/// the inner, contiguous index); each value is summed in the first
/// version's order.
fn spectra(fine: &[f64], out: &mut [f32], norms: &mut [f64; PHI_SUB]) {
    let (cos, sin) = dft_table();
    let taps = tap_weights();
    out[..DESCRIPTOR_LEN].fill(0.0);
    let mut coarse = [[0.0f64; RINGS]; PHI_BINS];
    for (s, norm) in norms.iter_mut().enumerate() {
        for (c, acc) in coarse.iter_mut().enumerate() {
            // The empty sum of `Iterator::sum` for floats.
            *acc = [-0.0; RINGS];
            for (t, w) in taps.iter().enumerate() {
                let j = (c * PHI_SUB + NFINE + t - PHI_SUB / 2 - s) % NFINE;
                let row = &fine[j * RINGS..(j + 1) * RINGS];
                for (a, f) in acc.iter_mut().zip(row) {
                    *a += w * f;
                }
            }
        }
        let block = &mut out[s * SUB_STRIDE..(s + 1) * SUB_STRIDE];
        for k in 0..FREQS {
            let mut re = [0.0f64; RINGS];
            let mut im = [0.0f64; RINGS];
            for (c, v) in coarse.iter().enumerate() {
                let (ck, sk) = (cos[k][c], sin[k][c]);
                for ring in 0..RINGS {
                    re[ring] += v[ring] * ck;
                    im[ring] -= v[ring] * sk;
                }
            }
            for ring in 0..RINGS {
                block[(2 * k) * RING_PAD + ring] = re[ring] as f32;
                block[(2 * k + 1) * RING_PAD + ring] = im[ring] as f32;
            }
        }
        // Parseval on the stored (rounded) spectra.
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

/// Values of [`magnitudes`]: one per `(frequency, ring)`.
pub(crate) const MAGNITUDES_LEN: usize = FREQS * RINGS;

/// The rotation-invariant part of a descriptor of [`describe`]: the
/// magnitude of each φ-frequency of each `(r, θ)` ring (sub-shift 0),
/// scaled so that the Euclidean distance between two frames' magnitudes is
/// at most their Eq. 1 distance at any rotation (a rotation about the
/// vertical only turns each coefficient's phase: `|a − e^{iφk} b| ≥ ||a| −
/// |b||`, Parseval's weights as in [`ShapeKernel::distance`]). Writes
/// [`MAGNITUDES_LEN`] values into `out`. The cheap descriptor of the
/// sparse similarity ([`super::sparse`]).
pub(crate) fn magnitudes(desc: &[f32], out: &mut [f32]) {
    for k in 0..FREQS {
        let w = (freq_weight(k) / PHI_BINS as f64).sqrt();
        for ring in 0..RINGS {
            let re = desc[(2 * k) * RING_PAD + ring] as f64;
            let im = desc[(2 * k + 1) * RING_PAD + ring] as f64;
            out[k * RINGS + ring] = (w * (re * re + im * im).sqrt()) as f32;
        }
    }
}

/// Weight of coefficient `k` in a sum over the full spectrum of a real
/// signal: 1 for the DC and Nyquist terms, 2 for the others.
#[doc(hidden)]
pub fn freq_weight(k: usize) -> f64 {
    if k == 0 || 2 * k == PHI_BINS {
        1.0
    } else {
        2.0
    }
}

/// `cos(2π k c / N)`, `sin(2π k c / N)` for `k < FREQS`, `c < PHI_BINS`.
#[doc(hidden)]
pub fn dft_table() -> ([[f64; PHI_BINS]; FREQS], [[f64; PHI_BINS]; FREQS]) {
    let mut cos = [[0.0; PHI_BINS]; FREQS];
    let mut sin = [[0.0; PHI_BINS]; FREQS];
    for k in 0..FREQS {
        for c in 0..PHI_BINS {
            let a = std::f64::consts::TAU * (k * c) as f64 / PHI_BINS as f64;
            cos[k][c] = a.cos();
            sin[k][c] = a.sin();
        }
    }
    (cos, sin)
}

/// Precomputed tables of [`distance`].
#[derive(Debug, Clone)]
pub(crate) struct ShapeKernel {
    /// `w_k cos(2π k c / N) / N` and `w_k sin(..) / N`, `[c][k]`.
    cos: [[f64; FREQS]; PHI_BINS],
    sin: [[f64; FREQS]; PHI_BINS],
}

impl Default for ShapeKernel {
    fn default() -> Self {
        let (c, s) = dft_table();
        let n = PHI_BINS as f64;
        ShapeKernel {
            cos: std::array::from_fn(|sh| std::array::from_fn(|k| freq_weight(k) * c[k][sh] / n)),
            sin: std::array::from_fn(|sh| std::array::from_fn(|k| freq_weight(k) * s[k][sh] / n)),
        }
    }
}

impl ShapeKernel {
    /// Eq. 1: the smallest L2 distance between frame `a`'s histogram and
    /// frame `b`'s over the 200 rotations about the vertical axis, with the
    /// rotation (radians) that achieves it. `a`, `b` are descriptors of
    /// [`describe`], `norm_a`, `norms_b` their squared norms.
    pub fn distance(
        &self,
        a: &[f32],
        norm_a: f64,
        b: &[f32],
        norms_b: &[f64; PHI_SUB],
    ) -> (f64, f64) {
        #[cfg(target_arch = "x86_64")]
        {
            if std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma") {
                // SAFETY: the CPU has the features the function is built for.
                return unsafe { self.distance_avx2(a, norm_a, b, norms_b) };
            }
        }
        self.distance_body(a, norm_a, b, norms_b)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn distance_avx2(
        &self,
        a: &[f32],
        norm_a: f64,
        b: &[f32],
        norms_b: &[f64; PHI_SUB],
    ) -> (f64, f64) {
        self.distance_body(a, norm_a, b, norms_b)
    }

    #[inline(always)]
    fn distance_body(
        &self,
        a: &[f32],
        norm_a: f64,
        b: &[f32],
        norms_b: &[f64; PHI_SUB],
    ) -> (f64, f64) {
        let a = &a[..SUB_STRIDE];
        let mut best = (f64::INFINITY, 0.0);
        for (s, norm_b) in norms_b.iter().enumerate() {
            let bs = &b[s * SUB_STRIDE..(s + 1) * SUB_STRIDE];
            let mut gr = [0.0; FREQS];
            let mut gi = [0.0; FREQS];
            for k in 0..FREQS {
                let ar = &a[2 * k * RING_PAD..(2 * k + 1) * RING_PAD];
                let ai = &a[(2 * k + 1) * RING_PAD..(2 * k + 2) * RING_PAD];
                let br = &bs[2 * k * RING_PAD..(2 * k + 1) * RING_PAD];
                let bi = &bs[(2 * k + 1) * RING_PAD..(2 * k + 2) * RING_PAD];
                let mut re = [0.0f64; 4];
                let mut im = [0.0f64; 4];
                for q in 0..RING_PAD / 4 {
                    for l in 0..4 {
                        let i = 4 * q + l;
                        let (xr, xi) = (ar[i] as f64, ai[i] as f64);
                        let (yr, yi) = (br[i] as f64, bi[i] as f64);
                        re[l] += xr * yr + xi * yi;
                        im[l] += xr * yi - xi * yr;
                    }
                }
                gr[k] = (re[0] + re[1]) + (re[2] + re[3]);
                gi[k] = (im[0] + im[1]) + (im[2] + im[3]);
            }
            for c in 0..PHI_BINS {
                let mut r = 0.0;
                for k in 0..FREQS {
                    r += gr[k] * self.cos[c][k] + gi[k] * self.sin[c][k];
                }
                let d2 = norm_a + norm_b - 2.0 * r;
                if d2 < best.0 {
                    let fine = c * PHI_SUB + s;
                    best = (
                        d2,
                        std::f64::consts::TAU * fine as f64 / (PHI_BINS * PHI_SUB) as f64,
                    );
                }
            }
        }
        (best.0.max(0.0).sqrt(), best.1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synth::shapes::capsule_mesh;
    use glam::DQuat;

    fn posed(turn: f64, bend: f64) -> Vec<DVec3> {
        // A capsule with one side pushed out: not rotationally symmetric.
        let m = capsule_mesh(0.15, 0.8, 32, 8);
        m.positions()
            .iter()
            .map(|p| {
                let mut v = DVec3::from_array(*p);
                if v.x > 0.05 {
                    v.x += bend * (v.y + 0.6);
                }
                DQuat::from_rotation_y(turn) * v + DVec3::new(0.3, 0.0, -0.2)
            })
            .collect()
    }

    fn descriptor(p: &[DVec3]) -> (Vec<f32>, [f64; PHI_SUB]) {
        let m = capsule_mesh(0.15, 0.8, 32, 8);
        let grid = ShapeGrid {
            voxel: 0.02,
            r_max: 0.8,
        };
        let mut out = vec![0.0; DESCRIPTOR_LEN];
        let mut norms = [0.0; PHI_SUB];
        let n = describe(
            p,
            m.triangles(),
            &grid,
            &mut ShapeScratch::default(),
            &mut out,
            &mut norms,
        );
        assert!(n > 1000.0);
        (out, norms)
    }

    #[test]
    fn self_distance_is_zero_and_rotation_is_found() {
        let k = ShapeKernel::default();
        let (a, na) = descriptor(&posed(0.0, 0.3));
        let (d, _) = k.distance(&a, na[0], &a, &na);
        assert!(d < 1e-6, "{d}");
        // Turned about the vertical by 90° (a whole number of fine bins).
        let (b, nb) = descriptor(&posed(std::f64::consts::FRAC_PI_2, 0.3));
        let (c, nc) = descriptor(&posed(0.0, 0.0));
        let (d_rot, angle) = k.distance(&a, na[0], &b, &nb);
        let (d_shape, _) = k.distance(&a, na[0], &c, &nc);
        let diff = (angle - 1.5 * std::f64::consts::PI)
            .abs()
            .min((angle - std::f64::consts::FRAC_PI_2).abs());
        assert!(diff < 0.05, "angle {angle}");
        // Turning costs little next to a change of shape.
        assert!(d_rot < 0.25 * d_shape, "{d_rot} vs {d_shape}");
        // Symmetric up to the fine-shift approximation.
        let (d_back, _) = k.distance(&b, nb[0], &a, &na);
        assert!(
            (d_back - d_rot).abs() <= 0.25 * d_rot + 1e-6,
            "{d_back} {d_rot}"
        );
        // Norms agree with the descriptor of the unshifted histogram.
        assert!(na.iter().all(|n| (n / na[0] - 1.0).abs() < 0.2));
    }
}
