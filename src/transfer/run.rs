//! Transferring a whole clip: signs chosen in frame order, then the frames
//! solved in parallel (rayon across frames, one workspace per thread,
//! `Par::Seq` inside each solve).

use super::confluent::{Confluent, orient_frames};
use super::signs::SignMode;
use super::source::MarkerMotion;
use crate::drive::FrameSink;
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Options for [`transfer`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TransferOptions {
    /// How marker quaternion signs are chosen. Default: consistent.
    pub signs: SignMode,
}

/// What a transfer did.
#[derive(Debug, Clone, Serialize, Default)]
pub struct TransferStats {
    /// Frames written.
    pub frames: usize,
    /// Markers used.
    pub markers: usize,
    /// Frames where some marker turned more than 160° from the reference
    /// pose (the paper's singular case, `|w|` small), handled by the sign
    /// choice.
    pub singular_frames: usize,
    /// The largest number of triangles in one frame whose interpolated
    /// quaternion nearly vanished (0 when no collapse threatens).
    pub max_weak_triangles: usize,
    /// Seconds solving all frames (wall clock, writing excluded).
    pub solve_seconds: f64,
}

/// Frames solved together by [`transfer_into`] (in parallel) before they
/// are handed on: the memory of a streamed transfer is this many frames of
/// the scan, whatever the clip's length.
pub const CHUNK_FRAMES: usize = 64;

/// Poses the scan for every frame of `motion` (its rotations are re-signed
/// in place). Returns positions, frames × vertices, row-major. `progress`
/// is called with the number of frames finished so far (from any thread).
/// Holds every frame: [`transfer_into`] with a streaming sink does not.
pub fn transfer(
    c: &Confluent,
    motion: &mut MarkerMotion,
    opts: &TransferOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> (Vec<[f64; 3]>, TransferStats) {
    let n = c.vertex_count();
    let mut out: Vec<[f64; 3]> = Vec::with_capacity(motion.frames() * n);
    let Ok(stats) = transfer_into(c, motion, opts, progress, &mut out);
    (out, stats)
}

/// [`transfer`] into any [`FrameSink`]: frames are solved [`CHUNK_FRAMES`]
/// at a time (in parallel) and handed to `sink` in frame order, so a clip
/// of any length needs the memory of one chunk when the sink streams
/// (issue 18, item 12). The first error of the sink stops the transfer and
/// is returned.
pub fn transfer_into<S: FrameSink>(
    c: &Confluent,
    motion: &mut MarkerMotion,
    opts: &TransferOptions,
    progress: &(dyn Fn(usize) + Sync),
    mut sink: S,
) -> Result<TransferStats, S::Error> {
    let m = motion.markers;
    let singular = orient_frames(&mut motion.rotations, m, opts.signs);
    let n = c.vertex_count();
    let frames = motion.frames();
    let chunk = CHUNK_FRAMES.min(frames.max(1));
    let mut buf = vec![[0.0; 3]; chunk * n];
    let done = std::sync::atomic::AtomicUsize::new(0);
    let mut solve_seconds = 0.0;
    let motion = &*motion;
    let mut weak = 0;
    // The shifts given to the (up to two) frames before this chunk, once
    // some frame's is known.
    let mut given: Vec<f64> = Vec::new();
    for first in (0..frames).step_by(chunk) {
        let count = chunk.min(frames - first);
        let t = Instant::now();
        let w = buf[..count * n]
            .par_chunks_mut(n.max(1))
            .enumerate()
            .map_init(
                || c.workspace(),
                |ws, (k, o)| {
                    let (r, tg) = motion.frame(first + k);
                    let s = c.frame(r, tg, ws, o);
                    progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                    s.weak_triangles
                },
            )
            .max()
            .unwrap_or(0);
        solve_seconds += t.elapsed().as_secs_f64();
        weak = weak.max(w);
        if let Some(feet) = &motion.feet {
            let known: Vec<Option<f64>> = (0..count)
                .map(|k| feet.shift(first + k, &buf[k * n..(k + 1) * n]))
                .collect();
            let shifts = chunk_shifts(&known, &mut given, feet.fps);
            for (k, d) in shifts.iter().enumerate() {
                for p in &mut buf[k * n..(k + 1) * n] {
                    for (x, u) in p.iter_mut().zip(feet.up) {
                        *x += d * u;
                    }
                }
            }
        }
        for k in 0..count {
            sink.push(&buf[k * n..(k + 1) * n])?;
        }
    }
    let stats = TransferStats {
        frames,
        markers: m,
        singular_frames: singular,
        max_weak_triangles: weak,
        solve_seconds,
    };
    Ok(stats)
}

/// The vertical shift of each frame of a chunk ([`super::source::FootGround`]),
/// `known` where a foot touches the floor (the shift standing the
/// touching feet on it: each frame's lower bound), and smooth over time:
/// the lowest vertex of a foot passes from the heel to the toes as it
/// rolls, and the shift that stood it on the floor frame by frame made a
/// CMU walk's vertical motion rough (02_02 onto the samba scan: the
/// centroid's vertical acceleration p95 1.09 → 1.83 cm/frame²). The
/// shifts `s` minimise `Σ (s_f − t_f)² + SMOOTHING Σ (Δ²s_f)²` (a
/// Whittaker smoother of the interpolated shifts `t`, [`interpolate_shifts`])
/// subject to `s_f ≥ known_f` (no touching foot below the floor), the
/// second differences running on from the shifts `given` to the frames
/// before the chunk: frames are handed on chunk by chunk, so a shift is
/// never revised once given. Updates `given` (its last two).
fn chunk_shifts(known: &[Option<f64>], given: &mut Vec<f64>, fps: f64) -> Vec<f64> {
    let mut carried = given.last().copied();
    let t = interpolate_shifts(known, &mut carried);
    if carried.is_none() {
        return t;
    }
    // The cut-off is a time: the weight of second differences in frames
    // grows as the fourth power of the frame rate.
    let rate = if fps.is_finite() && fps > 0.0 {
        fps / 30.0
    } else {
        1.0
    };
    let out = smooth_above(&t, known, given, SMOOTHING * rate.powi(4));
    given.extend_from_slice(&out);
    let keep = given.len().saturating_sub(2);
    given.drain(..keep);
    out
}

/// The weight of the second differences in [`chunk_shifts`] (frames at
/// 30 fps, scaled to the clip's rate by [`chunk_shifts`]; shifts in metres): a Whittaker smoother's
/// cut-off period of about `2π·SMOOTHING^¼` ≈ 8 frames (0.28 s), shorter
/// than a step (15-20 frames), longer than the heel-to-toes switches of
/// the lowest vertex (one frame).
const SMOOTHING: f64 = 3.0;

/// The shifts of a chunk before smoothing: the `known` ones; between two
/// known ones, linear; before the chunk's first, linear from `carried`
/// (the shift given to the frame before the chunk), or the first when
/// there is none; after the last, the last held (the next chunk's frames
/// go on from it). Sets `carried` to the last once any is known.
fn interpolate_shifts(known: &[Option<f64>], carried: &mut Option<f64>) -> Vec<f64> {
    let count = known.len();
    let pts: Vec<(f64, f64)> = known
        .iter()
        .enumerate()
        .filter_map(|(k, d)| d.map(|d| (k as f64, d)))
        .collect();
    let before = carried.map(|d| (-1.0, d));
    let out: Vec<f64> = (0..count)
        .map(|k| {
            let x = k as f64;
            let prev = pts.iter().rev().find(|p| p.0 <= x).copied().or(before);
            let next = pts.iter().find(|p| p.0 >= x).copied();
            match (prev, next) {
                (Some(a), Some(b)) if b.0 > a.0 => a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0),
                (Some(a), _) => a.1,
                (None, Some(b)) => b.1,
                (None, None) => 0.0,
            }
        })
        .collect();
    if carried.is_some() || !pts.is_empty() {
        *carried = out.last().copied().or(*carried);
    }
    out
}

/// `argmin Σ (s_f − t_f)² + lambda Σ (Δ²s)²` subject to `s_f ≥ lower_f`
/// where given, the second differences starting from the fixed values
/// `before` (the frames before `t`, oldest first). Active set: a frame
/// below its bound is fixed on it and the rest solved again (at most once
/// per frame); the system is banded (bandwidth 2) and solved by Cholesky.
fn smooth_above(t: &[f64], lower: &[Option<f64>], before: &[f64], lambda: f64) -> Vec<f64> {
    let n = t.len();
    let b = before.len();
    // All values, the fixed ones first; `fixed[i]` for the frames of `t`.
    let mut x: Vec<f64> = before.iter().copied().chain(t.iter().copied()).collect();
    let mut fixed = vec![false; n];
    for _ in 0..=n {
        // Unknowns: the free frames of `t`, in order.
        let free: Vec<usize> = (0..n).filter(|&i| !fixed[i]).collect();
        let m = free.len();
        let mut slot = vec![usize::MAX; n];
        for (k, &i) in free.iter().enumerate() {
            slot[i] = k;
        }
        // Band of the normal matrix: a[k][d] = A(k, k − d), d = 0, 1, 2.
        let mut a = vec![[0.0f64; 3]; m];
        let mut rhs = vec![0.0; m];
        for (k, &i) in free.iter().enumerate() {
            a[k][0] += 1.0;
            rhs[k] += t[i];
        }
        let unknown =
            |j: usize| -> Option<usize> { (j >= b && !fixed[j - b]).then(|| slot[j - b]) };
        const C: [f64; 3] = [1.0, -2.0, 1.0];
        for j in 0..(b + n).saturating_sub(2) {
            for (p, cp) in C.iter().enumerate() {
                let Some(u) = unknown(j + p) else { continue };
                for (q, cq) in C.iter().enumerate() {
                    let w = lambda * cp * cq;
                    match unknown(j + q) {
                        Some(v) if v <= u => a[u][u - v] += w,
                        Some(_) => {}
                        None => rhs[u] -= w * x[j + q],
                    }
                }
            }
        }
        let s = band_cholesky_solve(&mut a, &rhs);
        for (k, &i) in free.iter().enumerate() {
            x[b + i] = s[k];
        }
        let mut any = false;
        for i in 0..n {
            if let Some(l) = lower[i] {
                if !fixed[i] && x[b + i] < l {
                    fixed[i] = true;
                    x[b + i] = l;
                    any = true;
                }
            }
        }
        if !any {
            break;
        }
    }
    x[b..].to_vec()
}

/// Solves `A s = rhs` for a symmetric positive-definite `A` of bandwidth 2
/// given as `a[k][d] = A(k, k − d)` (overwritten by its Cholesky factor).
fn band_cholesky_solve(a: &mut [[f64; 3]], rhs: &[f64]) -> Vec<f64> {
    let m = a.len();
    for k in 0..m {
        for d in (0..3).rev() {
            if d > k {
                continue;
            }
            let j = k - d;
            // A(k, j) − Σ_{i < j} L(k, i) L(j, i), i within both bands.
            let mut v = a[k][d];
            for i in j.saturating_sub(2).max(k.saturating_sub(2))..j {
                v -= a[k][k - i] * a[j][j - i];
            }
            a[k][d] = if d == 0 {
                v.max(1e-300).sqrt()
            } else {
                v / a[j][0]
            };
        }
    }
    let mut y = rhs.to_vec();
    for k in 0..m {
        for d in 1..3.min(k + 1) {
            y[k] -= a[k][d] * y[k - d];
        }
        y[k] /= a[k][0];
    }
    for k in (0..m).rev() {
        for d in 1..3 {
            if k + d < m {
                y[k] -= a[k + d][d] * y[k + d];
            }
        }
        y[k] /= a[k][0];
    }
    y
}

#[cfg(test)]
mod tests {
    use super::{chunk_shifts, interpolate_shifts, smooth_above};

    #[test]
    fn shifts_interpolate_across_chunks_and_hold_at_the_ends() {
        let mut c = None;
        let a = interpolate_shifts(&[None, Some(1.0), None, Some(3.0), None], &mut c);
        assert_eq!(a, vec![1.0, 1.0, 2.0, 3.0, 3.0]);
        assert_eq!(c, Some(3.0));
        // The gap over the boundary: held before it, then linear from the
        // frame before this chunk to the next known one.
        let b = interpolate_shifts(&[None, None, None, Some(7.0)], &mut c);
        assert_eq!(b, vec![4.0, 5.0, 6.0, 7.0]);
        let mut none = None;
        assert_eq!(interpolate_shifts(&[None, None], &mut none), vec![0.0, 0.0]);
        assert_eq!(none, None);
        let mut given = Vec::new();
        assert_eq!(
            chunk_shifts(&[None, None], &mut given, 30.0),
            vec![0.0, 0.0]
        );
        assert!(given.is_empty());
    }

    /// A dense solve of the same problem without bounds, to check the
    /// banded one.
    fn dense(t: &[f64], before: &[f64], lambda: f64) -> Vec<f64> {
        let (b, n) = (before.len(), t.len());
        let mut a = vec![vec![0.0; n]; n];
        let mut r = t.to_vec();
        for (i, row) in a.iter_mut().enumerate() {
            row[i] += 1.0;
        }
        let c = [1.0, -2.0, 1.0];
        for j in 0..(b + n).saturating_sub(2) {
            for p in 0..3 {
                if j + p < b {
                    continue;
                }
                for q in 0..3 {
                    let w = lambda * c[p] * c[q];
                    if j + q < b {
                        r[j + p - b] -= w * before[j + q];
                    } else {
                        a[j + p - b][j + q - b] += w;
                    }
                }
            }
        }
        // Gaussian elimination.
        for k in 0..n {
            for i in k + 1..n {
                let f = a[i][k] / a[k][k];
                let (top, bottom) = a.split_at_mut(i);
                for (x, y) in bottom[0][k..].iter_mut().zip(&top[k][k..]) {
                    *x -= f * y;
                }
                r[i] -= f * r[k];
            }
        }
        let mut s = vec![0.0; n];
        for k in (0..n).rev() {
            let v: f64 = (k + 1..n).map(|j| a[k][j] * s[j]).sum();
            s[k] = (r[k] - v) / a[k][k];
        }
        s
    }

    #[test]
    fn the_smoothed_shift_is_the_whittaker_solution_and_stays_above_its_bounds() {
        let t: Vec<f64> = (0..23).map(|i| ((i * 7919) % 13) as f64 * 0.01).collect();
        for before in [vec![], vec![0.05], vec![0.02, 0.07]] {
            let free = smooth_above(&t, &vec![None; t.len()], &before, 3.0);
            let want = dense(&t, &before, 3.0);
            for (a, b) in free.iter().zip(&want) {
                assert!((a - b).abs() < 1e-12, "{a} vs {b}");
            }
        }
        // The lowest vertex alternating heel / toes frame by frame: the
        // shift keeps every frame's touching foot on or above the floor
        // and its second differences are under a quarter of the raw ones
        // (the unbounded smoother passes 1 / (1 + 16·3) of an alternation;
        // the bound keeps some).
        let raw: Vec<f64> = (0..40)
            .map(|i| if i % 2 == 0 { 0.02 } else { 0.0 })
            .collect();
        let known: Vec<Option<f64>> = raw.iter().map(|&d| Some(d)).collect();
        let s = smooth_above(&raw, &known, &[], 3.0);
        let d2 = |v: &[f64]| {
            v.windows(3)
                .map(|w| (w[0] - 2.0 * w[1] + w[2]).abs())
                .fold(0.0, f64::max)
        };
        for (a, b) in s.iter().zip(&raw) {
            assert!(a >= b, "{a} below its bound {b}");
            assert!(a - b <= 0.02 + 1e-12);
        }
        assert!(d2(&s) < 0.25 * d2(&raw), "{} vs {}", d2(&s), d2(&raw));
    }
}
