//! High-level parametric control (Casas et al. 2013, Sec. 3.1.4): the
//! motion parameters `p = h(w)` of a blend, measured over sampled weights
//! (step 0.05, as the paper), and the inverse map `w = h⁻¹(p)`.
//!
//! Parameters are measured from the blended root motion over one aligned
//! cycle: per phase step, each sequence's horizontal travel (in its body
//! frame) and heading change, and the step's duration in frames, are
//! blended linearly with the weights (time warping: the blended cycle lasts
//! the blend of the cycles' durations, so speed is not linear in `w`); the
//! path is integrated with the heading. Speed is the path length per second
//! (m/s), turn the heading change per second (degrees/s, positive to the
//! left, counter-clockwise seen from above).
//!
//! The inverse map: the paper fits a quadratic; we fit it too and also keep
//! the sampled table (monotone piecewise-linear inverse), measure both
//! round trips `p → w → h(w)` on 201 values across the range, and use the
//! better one. The valid range is the measured one; requests outside it
//! clamp.

use glam::DVec2;
use serde::{Deserialize, Serialize};

/// Weight sampling step of the measurement (the paper's `δw = 0.05`).
pub(crate) const WEIGHT_STEP: f64 = 0.05;

/// A motion parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Parameter {
    /// Travel speed, m/s (path length of the root per second).
    Speed,
    /// Turning rate, degrees per second (left positive).
    Turn,
}

impl Parameter {
    /// All parameters.
    pub const ALL: [Parameter; 2] = [Parameter::Speed, Parameter::Turn];
    /// The name used in manifests and scripts.
    pub fn name(self) -> &'static str {
        match self {
            Parameter::Speed => "speed",
            Parameter::Turn => "turn",
        }
    }
    /// Unit of the values.
    pub fn unit(self) -> &'static str {
        match self {
            Parameter::Speed => "m/s",
            Parameter::Turn => "deg/s",
        }
    }
    /// The smallest span of values over a space's weights that makes the
    /// parameter steerable (0.05 m/s, 2°/s): below it the sequences do not
    /// differ in this parameter (e.g. a sideways walk offered as a turn).
    pub(crate) fn min_span(self) -> f64 {
        match self {
            Parameter::Speed => 0.05,
            Parameter::Turn => 2.0,
        }
    }
    /// Parses a name.
    pub fn parse(s: &str) -> Option<Parameter> {
        Parameter::ALL.into_iter().find(|p| p.name() == s)
    }
}

/// The root motion of one sequence on the phase grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RootSteps {
    /// Per phase step `k → k + 1`: travel `(x, z)` in the body frame at
    /// `k` (metres) and heading change (radians).
    pub step: Vec<[f64; 3]>,
    /// Per phase step, its duration in frames.
    pub duration: Vec<f64>,
}

/// The blended root step `k` at weight coordinate `u` (travel x, z,
/// heading change, duration in frames).
#[inline]
pub(crate) fn blended_step(steps: &[RootSteps], u: f64, k: usize) -> [f64; 4] {
    let last = steps.len().saturating_sub(1);
    let u = u.clamp(0.0, last as f64);
    let a = (u.floor() as usize).min(last.saturating_sub(1));
    let s = if last == 0 { 0.0 } else { u - a as f64 };
    let b = (a + 1).min(last);
    let (x, y) = (&steps[a], &steps[b]);
    let l = |p: f64, q: f64| p + (q - p) * s;
    [
        l(x.step[k][0], y.step[k][0]),
        l(x.step[k][1], y.step[k][1]),
        l(x.step[k][2], y.step[k][2]),
        l(x.duration[k], y.duration[k]),
    ]
}

/// `h(u)`: (speed m/s, turn deg/s) of the blend at `u` over one cycle.
pub fn measure(steps: &[RootSteps], u: f64, fps: f64) -> [f64; 2] {
    let k = steps.first().map_or(0, |s| s.step.len());
    let (mut path, mut turn, mut dur) = (0.0, 0.0, 0.0);
    for i in 0..k {
        let [x, z, dh, d] = blended_step(steps, u, i);
        path += DVec2::new(x, z).length();
        turn += dh;
        dur += d;
    }
    let secs = (dur / fps).max(1e-9);
    [path / secs, turn.to_degrees() / secs]
}

/// Which inverse map is used.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FitKind {
    /// `u = c₀ + c₁ x + c₂ x²`, `x` the parameter normalised to `[−1, 1]`
    /// over the range (the paper's quadratic).
    Quadratic,
    /// Piecewise-linear inverse of the sampled table.
    Table,
}

/// The inverse map `w = h⁻¹(p)` of one parameter of a space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamMap {
    /// The parameter.
    pub parameter: Parameter,
    /// Samples `(u, p)` at step [`WEIGHT_STEP`] per pair of sequences.
    pub samples: Vec<[f64; 2]>,
    /// Quadratic coefficients of `u(x)`, `x = (p − mid) / half`.
    pub quadratic: [f64; 3],
    /// The valid range `[min, max]` of the parameter.
    pub range: [f64; 2],
    /// Largest round-trip error `|h(h⁻¹(p)) − p|` of the quadratic, in the
    /// parameter's unit.
    pub error_quadratic: f64,
    /// The same for the table.
    pub error_table: f64,
    /// The map in use (the one with the smaller round-trip error).
    pub fit: FitKind,
}

impl ParamMap {
    /// Measures parameter `parameter` over the weights of a space with
    /// root motion `steps` (one per sequence) and fits its inverse. Errors
    /// when the parameter does not change monotonically with the weights.
    pub fn fit(parameter: Parameter, steps: &[RootSteps], fps: f64) -> Result<ParamMap, String> {
        let idx = match parameter {
            Parameter::Speed => 0,
            Parameter::Turn => 1,
        };
        let pairs = steps.len().saturating_sub(1);
        let per = (1.0 / WEIGHT_STEP).round() as usize;
        let count = pairs * per + 1;
        let samples: Vec<[f64; 2]> = (0..count)
            .map(|i| {
                let u = i as f64 / per as f64;
                [u, measure(steps, u, fps)[idx]]
            })
            .collect();
        let lo = samples.iter().map(|s| s[1]).fold(f64::INFINITY, f64::min);
        let hi = samples
            .iter()
            .map(|s| s[1])
            .fold(f64::NEG_INFINITY, f64::max);
        if pairs > 0 {
            let inc = samples[count - 1][1] > samples[0][1];
            let monotone = samples.windows(2).all(|w| {
                if inc {
                    w[1][1] > w[0][1]
                } else {
                    w[1][1] < w[0][1]
                }
            });
            if hi - lo < parameter.min_span() {
                return Err(format!(
                    "parameter '{}' spans only {:.3} {} over the space's sequences (from {lo:.3} to {hi:.3}; at least {} needed): its sequences do not differ in {}",
                    parameter.name(),
                    hi - lo,
                    parameter.unit(),
                    parameter.min_span(),
                    parameter.name()
                ));
            }
            if !monotone {
                let list: Vec<String> = (0..=pairs)
                    .map(|i| format!("{:.3}", samples[i * per][1]))
                    .collect();
                return Err(format!(
                    "parameter '{}' does not change monotonically with the blend weights (measured {} {} at the sequences, in order): order the space's sequences by {}, or list another parameter first",
                    parameter.name(),
                    list.join(", "),
                    parameter.unit(),
                    parameter.name()
                ));
            }
        }
        let mid = 0.5 * (lo + hi);
        let half = (0.5 * (hi - lo)).max(1e-12);
        // Least squares for u(x) = c0 + c1 x + c2 x².
        let mut ata = [[0.0f64; 3]; 3];
        let mut atb = [0.0f64; 3];
        for s in &samples {
            let x = (s[1] - mid) / half;
            let row = [1.0, x, x * x];
            for i in 0..3 {
                for j in 0..3 {
                    ata[i][j] += row[i] * row[j];
                }
                atb[i] += row[i] * s[0];
            }
        }
        let quadratic = if pairs == 0 {
            [0.0; 3]
        } else {
            let m = nalgebra::Matrix3::from_fn(|i, j| ata[i][j]);
            let b = nalgebra::Vector3::from_column_slice(&atb);
            m.lu()
                .solve(&b)
                .map(|v| [v[0], v[1], v[2]])
                .unwrap_or([0.0; 3])
        };
        let mut map = ParamMap {
            parameter,
            samples,
            quadratic,
            range: [lo, hi],
            error_quadratic: 0.0,
            error_table: 0.0,
            fit: FitKind::Table,
        };
        if pairs > 0 {
            for kind in [FitKind::Quadratic, FitKind::Table] {
                map.fit = kind;
                let e = (0..=200)
                    .map(|i| {
                        let p = lo + (hi - lo) * i as f64 / 200.0;
                        let (u, _) = map.inverse(p);
                        (measure(steps, u, fps)[idx] - p).abs()
                    })
                    .fold(0.0, f64::max);
                match kind {
                    FitKind::Quadratic => map.error_quadratic = e,
                    FitKind::Table => map.error_table = e,
                }
            }
            map.fit = if map.error_quadratic < map.error_table {
                FitKind::Quadratic
            } else {
                FitKind::Table
            };
        }
        Ok(map)
    }

    /// `h⁻¹(p)`: the weight coordinate for `p`, clamped to the valid range;
    /// the flag says whether `p` was outside it.
    pub fn inverse(&self, p: f64) -> (f64, bool) {
        let [lo, hi] = self.range;
        let tol = 1e-9 * (1.0 + lo.abs().max(hi.abs()));
        let clamped = p < lo - tol || p > hi + tol || !p.is_finite();
        let p = if p.is_finite() { p.clamp(lo, hi) } else { lo };
        let umax = self.samples.last().map_or(0.0, |s| s[0]);
        if self.samples.len() < 2 {
            return (0.0, clamped);
        }
        let u = match self.fit {
            FitKind::Quadratic => {
                let x = (p - 0.5 * (lo + hi)) / (0.5 * (hi - lo)).max(1e-12);
                let [a, b, c] = self.quadratic;
                a + b * x + c * x * x
            }
            FitKind::Table => {
                let inc = self.samples[self.samples.len() - 1][1] > self.samples[0][1];
                let key = |s: &[f64; 2]| if inc { s[1] } else { -s[1] };
                let q = if inc { p } else { -p };
                let j = self
                    .samples
                    .partition_point(|s| key(s) <= q)
                    .clamp(1, self.samples.len() - 1);
                let (a, b) = (self.samples[j - 1], self.samples[j]);
                let (ka, kb) = (key(&a), key(&b));
                let t = if kb > ka {
                    ((q - ka) / (kb - ka)).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                a[0] + (b[0] - a[0]) * t
            }
        };
        (u.clamp(0.0, umax), clamped)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two straight gaits: 1 m per 30-frame cycle and 2 m per 20-frame
    /// cycle (1 and 3 m/s at 30 fps). Speed is rational in w, the table
    /// inverse round-trips within 1 %.
    #[test]
    fn speed_of_time_warped_blend_round_trips() {
        let k = 30;
        let gait = |dist: f64, frames: f64| RootSteps {
            step: vec![[0.0, dist / k as f64, 0.0]; k],
            duration: vec![frames / k as f64; k],
        };
        let steps = [gait(1.0, 30.0), gait(2.0, 20.0)];
        let m = ParamMap::fit(Parameter::Speed, &steps, 30.0).unwrap();
        assert!(
            (m.range[0] - 1.0).abs() < 1e-9 && (m.range[1] - 3.0).abs() < 1e-9,
            "{:?}",
            m.range
        );
        // Halfway in w: 1.5 m in 25 frames = 1.8 m/s, not 2.
        assert!((measure(&steps, 0.5, 30.0)[0] - 1.8).abs() < 1e-9);
        for p in [1.0, 1.3, 2.0, 2.7, 3.0] {
            let (u, c) = m.inverse(p);
            assert!(!c);
            let back = measure(&steps, u, 30.0)[0];
            assert!((back - p).abs() < 0.01 * p, "{p} → {u} → {back}");
        }
        assert!(m.inverse(5.0).1 && (m.inverse(5.0).0 - 1.0).abs() < 1e-9);
    }
}
