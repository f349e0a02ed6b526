//! Temporal alignment of the sequences of one motion space (Casas et al.
//! 2013, Sec. 3.1: "individual mesh sequences are temporally aligned by a
//! continuous time-warp function ... such that t ∈ [0, 1]").
//!
//! Cycle-aware dynamic time warping on a vertex measure: each sequence's
//! motion cycle is found from its body frames ([`super::local`]) as the
//! smallest lag at which the sequence repeats itself (the mean squared
//! distance of frames `f` and `f + lag` at its lowest local minimum in
//! 0.4-2.5 s), starting where the cycle closes best. Every other sequence's
//! cycle is then warped onto the first one's by DTW over all cyclic
//! offsets (the start of a cycle is arbitrary), with the endpoints fixed.
//! A sequence that does not repeat is one "cycle" from its first to its
//! last frame. The result maps a normalised phase `φ ∈ [0, 1]` to a time
//! in each sequence, sampled on a grid of `K` phases (`K` = the longest
//! cycle in frames, so no sequence is undersampled).
//!
//! Cost: `O(T₀ · T_i²)` per sequence (all offsets), on a few hundred
//! vertices per frame.

use super::local::{RootTrack, local_frame};
use serde::{Deserialize, Serialize};

/// Vertices of the measure per frame (at most; evenly strided).
pub(crate) const FEATURE_VERTICES: usize = 400;

/// One sequence's cycle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cycle {
    /// First frame of the cycle.
    pub start: usize,
    /// Length in frames, fractional (refined by a parabola through the
    /// repetition measure at the best lag and its neighbours).
    pub period: f64,
    /// True when the sequence repeats itself; false: the cycle is the
    /// whole sequence (played in a loop with a jump).
    pub cyclic: bool,
    /// RMS distance (metres) between the cycle's first and closing frames.
    pub closure: f64,
}

/// The alignment of a space's sequences.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Alignment {
    /// Phase samples per cycle, `K`.
    pub grid: usize,
    /// Each sequence's cycle.
    pub cycles: Vec<Cycle>,
    /// Each sequence's cyclic offset (frames) against the first one's cycle.
    pub offsets: Vec<usize>,
    /// Per sequence, `K + 1` unwrapped times (frames) of the phases
    /// `k / K`, `k = 0..=K`; the last is the first plus the period.
    pub times: Vec<Vec<f64>>,
    /// Per sequence, the RMS vertex distance (metres) along its warping
    /// path to the first sequence (0 for the first).
    pub cost: Vec<f64>,
}

impl Alignment {
    /// Sequence `i`'s frame at unwrapped time `t`, wrapped into its cycle:
    /// `(floor frame, next frame, fraction)`.
    pub fn wrapped(&self, i: usize, t: f64) -> (usize, usize, f64) {
        let c = &self.cycles[i];
        let p = c.period.max(1.0);
        let r = (t - c.start as f64).rem_euclid(p);
        let r = if r >= p { 0.0 } else { r };
        let a = r.floor();
        let f = c.start + a as usize;
        (f, f + 1, r - a)
    }
}

/// Per-frame features: the body frame of every `stride`-th vertex, f32.
pub(crate) fn features(frames: &[[f64; 3]], n: usize, track: &RootTrack) -> Vec<Vec<f32>> {
    let count = frames.len() / n.max(1);
    let stride = n.div_ceil(FEATURE_VERTICES).max(1);
    let mut buf = vec![[0.0; 3]; n];
    (0..count)
        .map(|f| {
            local_frame(frames, n, track, f, &mut buf);
            buf.iter()
                .step_by(stride)
                .flat_map(|p| p.map(|x| x as f32))
                .collect()
        })
        .collect()
}

/// Mean squared distance per vertex between two feature vectors.
fn dist(a: &[f32], b: &[f32]) -> f64 {
    let s: f32 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    3.0 * s as f64 / a.len().max(1) as f64
}

/// The cycle of one sequence (see the module doc).
pub(crate) fn detect_cycle(feat: &[Vec<f32>], fps: f64) -> Cycle {
    let len = feat.len();
    let whole = |len: usize| Cycle {
        start: 0,
        period: len.saturating_sub(1).max(1) as f64,
        cyclic: false,
        closure: if len > 1 {
            dist(&feat[0], &feat[len - 1]).sqrt()
        } else {
            0.0
        },
    };
    if len < 4 {
        return whole(len);
    }
    let lo = ((0.4 * fps).round() as usize).max(2);
    let hi = ((2.5 * fps).round() as usize).min((len - 1) * 2 / 3);
    if hi <= lo + 1 {
        return whole(len);
    }
    let d: Vec<f64> = (lo..=hi)
        .map(|lag| {
            (0..len - lag)
                .map(|f| dist(&feat[f], &feat[f + lag]))
                .sum::<f64>()
                / (len - lag) as f64
        })
        .collect();
    // Spread of the sequence: twice the mean squared distance to its mean frame.
    let dim = feat[0].len();
    let mut mean = vec![0.0f64; dim];
    for f in feat {
        for (m, x) in mean.iter_mut().zip(f) {
            *m += *x as f64 / len as f64;
        }
    }
    let mean32: Vec<f32> = mean.iter().map(|&x| x as f32).collect();
    let spread = 2.0 * feat.iter().map(|f| dist(f, &mean32)).sum::<f64>() / len as f64;
    let dmin = d.iter().cloned().fold(f64::INFINITY, f64::min);
    if dmin.is_nan() || dmin >= 0.3 * spread {
        return whole(len);
    }
    // The smallest local minimum near the best (a whole-frame lag misses a
    // fractional period by up to half a frame, which a fast motion feels:
    // the tolerance is relative to the sequence's spread too).
    let mut pick = None;
    for k in 0..d.len() {
        let left = k == 0 || d[k] <= d[k - 1];
        let right = k + 1 == d.len() || d[k] <= d[k + 1];
        if left && right && d[k] <= dmin * 1.15 + 0.05 * spread + 1e-12 {
            pick = Some(k);
            break;
        }
    }
    let k = pick.unwrap_or(0);
    let lag = lo + k;
    // Parabolic refinement of the lag.
    let frac = if k > 0 && k + 1 < d.len() {
        let (a, b, c) = (d[k - 1], d[k], d[k + 1]);
        let den = a - 2.0 * b + c;
        if den > 1e-15 {
            (0.5 * (a - c) / den).clamp(-0.5, 0.5)
        } else {
            0.0
        }
    } else {
        0.0
    };
    let period = lag as f64 + frac;
    let need = period.ceil() as usize;
    if need + 1 >= len {
        return whole(len);
    }
    let (start, closure) = (0..len - need)
        .map(|s| (s, dist(&feat[s], &feat[s + lag])))
        .fold((0, f64::INFINITY), |b, x| if x.1 < b.1 { x } else { b });
    Cycle {
        start,
        period,
        cyclic: true,
        closure: closure.sqrt(),
    }
}

/// DTW of `a` rows (0..=ta) against `b` columns (0..=tb) with cell costs
/// `cost(a, b)`; returns the mean cell cost along the best path and, per
/// row, the mean column of the path's cells in that row.
fn dtw(ta: usize, tb: usize, cost: impl Fn(usize, usize) -> f64) -> (f64, Vec<f64>) {
    let (ra, rb) = (ta + 1, tb + 1);
    let mut acc = vec![f64::INFINITY; ra * rb];
    let mut steps = vec![0u32; ra * rb];
    for i in 0..ra {
        for j in 0..rb {
            let c = cost(i, j);
            let (best, s) = if i == 0 && j == 0 {
                (0.0, 0)
            } else {
                let mut b = (f64::INFINITY, 0u32);
                if i > 0 && j > 0 && acc[(i - 1) * rb + j - 1] < b.0 {
                    b = (acc[(i - 1) * rb + j - 1], steps[(i - 1) * rb + j - 1]);
                }
                if i > 0 && acc[(i - 1) * rb + j] < b.0 {
                    b = (acc[(i - 1) * rb + j], steps[(i - 1) * rb + j]);
                }
                if j > 0 && acc[i * rb + j - 1] < b.0 {
                    b = (acc[i * rb + j - 1], steps[i * rb + j - 1]);
                }
                b
            };
            acc[i * rb + j] = best + c;
            steps[i * rb + j] = s + 1;
        }
    }
    // Backtrack.
    let mut sum = vec![0.0f64; ra];
    let mut cnt = vec![0.0f64; ra];
    let (mut i, mut j) = (ta, tb);
    loop {
        sum[i] += j as f64;
        cnt[i] += 1.0;
        if i == 0 && j == 0 {
            break;
        }
        let mut best = (f64::INFINITY, i, j);
        if i > 0 && j > 0 && acc[(i - 1) * rb + j - 1] < best.0 {
            best = (acc[(i - 1) * rb + j - 1], i - 1, j - 1);
        }
        if i > 0 && acc[(i - 1) * rb + j] < best.0 {
            best = (acc[(i - 1) * rb + j], i - 1, j);
        }
        if j > 0 && acc[i * rb + j - 1] < best.0 {
            best = (acc[i * rb + j - 1], i, j - 1);
        }
        (i, j) = (best.1, best.2);
    }
    let total = acc[ra * rb - 1] / steps[ra * rb - 1].max(1) as f64;
    let mut rows: Vec<f64> = sum.iter().zip(&cnt).map(|(s, c)| s / c.max(1.0)).collect();
    for k in 1..rows.len() {
        rows[k] = rows[k].max(rows[k - 1]);
    }
    (total, rows)
}

/// Aligns the sequences whose features are `feats` (each sequence's
/// per-frame features, [`features`]) at `fps`.
pub fn align(feats: &[Vec<Vec<f32>>], fps: f64) -> Alignment {
    let cycles: Vec<Cycle> = feats.iter().map(|f| detect_cycle(f, fps)).collect();
    let grid = cycles
        .iter()
        // A period a hair above a whole frame count needs no extra sample.
        .map(|c| (c.period - 0.01).ceil().max(1.0) as usize)
        .max()
        .unwrap_or(1)
        .max(2);
    let c0 = &cycles[0];
    let t0 = (c0.period.round() as usize).max(1);
    let mut offsets = vec![0];
    let mut times = vec![
        (0..=grid)
            .map(|k| c0.start as f64 + k as f64 * c0.period / grid as f64)
            .collect::<Vec<f64>>(),
    ];
    let mut costs = vec![0.0];
    for (i, f) in feats.iter().enumerate().skip(1) {
        let ci = &cycles[i];
        let ti = (ci.period.round() as usize).max(1);
        // DTW runs on whole frames; its columns are rescaled to the
        // fractional period.
        let scale = ci.period / ti as f64;
        let offs: Vec<usize> = if ci.cyclic && c0.cyclic {
            (0..ti).collect()
        } else {
            vec![0]
        };
        let mut best: Option<(f64, usize, Vec<f64>)> = None;
        for o in offs {
            let (c, rows) = dtw(t0, ti, |a, b| {
                let fb = if ci.cyclic {
                    ci.start + (o + b) % ti
                } else {
                    ci.start + b
                };
                dist(&feats[0][c0.start + a], &f[fb])
            });
            if best.as_ref().is_none_or(|b| c < b.0) {
                best = Some((c, o, rows));
            }
        }
        let (c, o, rows) = best.unwrap_or((0.0, 0, vec![0.0; t0 + 1]));
        let at = |a: f64| {
            let k = (a.floor() as usize).min(t0.saturating_sub(1));
            let fr = a - k as f64;
            rows[k] * (1.0 - fr) + rows[(k + 1).min(t0)] * fr
        };
        times.push(
            (0..=grid)
                .map(|k| {
                    ci.start as f64 + (o as f64 + at(k as f64 * t0 as f64 / grid as f64)) * scale
                })
                .collect(),
        );
        offsets.push(o);
        costs.push(c.sqrt());
    }
    Alignment {
        grid,
        cycles,
        offsets,
        times,
        cost: costs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A feature that is a pure function of phase: a sequence at period 30
    /// and one at period 20, started half a cycle later, align at the
    /// matching phases and find their periods.
    #[test]
    fn two_speeds_of_one_cycle_align_phase_to_phase() {
        let fps = 30.0;
        let feat = |phase: f64| -> Vec<f32> {
            let a = phase * std::f64::consts::TAU;
            vec![a.sin() as f32, a.cos() as f32, (2.0 * a).sin() as f32 * 0.5]
        };
        let s0: Vec<Vec<f32>> = (0..100).map(|f| feat(f as f64 / 30.0)).collect();
        let s1: Vec<Vec<f32>> = (0..80).map(|f| feat(f as f64 / 20.0 + 0.5)).collect();
        let al = align(&[s0, s1], fps);
        assert!(
            (al.cycles[0].period - 30.0).abs() < 0.2,
            "{}",
            al.cycles[0].period
        );
        assert!(
            (al.cycles[1].period - 20.0).abs() < 0.2,
            "{}",
            al.cycles[1].period
        );
        assert_eq!(al.grid, 30);
        for k in 0..=al.grid {
            let p0 = (al.times[0][k] / 30.0).rem_euclid(1.0);
            let p1 = (al.times[1][k] / 20.0 + 0.5).rem_euclid(1.0);
            let d = (p0 - p1 + 0.5).rem_euclid(1.0) - 0.5;
            assert!(d.abs() < 0.06, "grid {k}: phases {p0} vs {p1}");
        }
        // Frames are 1/20 of a cycle apart: DTW matches them to within half a step.
        assert!(al.cost[1] < 0.15, "{}", al.cost[1]);
    }
}
