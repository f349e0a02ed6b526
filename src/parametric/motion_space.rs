//! One motion space (Casas et al. 2013, Sec. 3): its sequences in blend
//! order, their time alignment, the hybrid blend's references, the root
//! motion per phase sample and the measured parameters. Built by
//! [`super::space`], read back by [`super::store`]; both go through
//! [`MotionSpace::new`], which checks that the parts agree, so a space in
//! hand is consistent and its fields are read through accessors.

use super::align::Alignment;
use super::hybrid::{HybridBlend, PairRefs};
use super::params::{ParamMap, Parameter, RootSteps, WEIGHT_STEP, blended_step};
use super::transition::{RefFeatures, SIMILARITY_VERTICES, VELOCITY_SECONDS};
use serde::{Deserialize, Serialize};

/// One motion space. Serialised (for the cache) as its [`SpaceParts`]:
/// every field but the blend's reference blocks, which are stored apart.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MotionSpace {
    name: String,
    sequences: Vec<String>,
    parameters: Vec<Parameter>,
    alignment: Alignment,
    #[serde(skip)]
    blend: HybridBlend,
    /// Mirrors `blend.pairs` (the cache stores the weights with the header).
    pairs: Vec<PairRefs>,
    steps: Vec<RootSteps>,
    axis: Option<ParamMap>,
    measured: Vec<[f64; 3]>,
    epsilon: f64,
}

/// The parts of a [`MotionSpace`] apart from its blend, as the cache's
/// header stores them (the same JSON as a serialised space).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct SpaceParts {
    /// Name.
    pub name: String,
    /// Its sequences, in blend order (weight coordinate `u = i` is sequence `i`).
    pub sequences: Vec<String>,
    /// Its parameters; the first is blended, a later `turn` steers.
    pub parameters: Vec<Parameter>,
    /// The time alignment of the sequences.
    pub alignment: Alignment,
    /// ClipNeutral weights per pair of neighbouring sequences (the blend's).
    pub pairs: Vec<PairRefs>,
    /// Root motion of each sequence on the phase grid.
    pub steps: Vec<RootSteps>,
    /// The inverse map of the first parameter.
    pub axis: Option<ParamMap>,
    /// `(u, speed m/s, turn deg/s)` at weight step 0.05.
    pub measured: Vec<[f64; 3]>,
    /// Hybrid tolerance used (metres).
    pub epsilon: f64,
}

impl SpaceParts {
    /// Checks the parts alone: at least one sequence; one root track per
    /// sequence, each on the alignment's phase grid; one pair of
    /// references per neighbouring sequences, each with at least two
    /// increasing weights in `[0, 1]` and one block per weight; the first
    /// parameter's inverse map present exactly when there is a parameter;
    /// finite measurements and tolerance. The error says what disagrees.
    pub fn check(&self) -> Result<(), String> {
        let k = self.alignment.grid;
        let seqs = self.sequences.len();
        if seqs == 0 || k == 0 {
            return Err(format!("{seqs} sequences on a phase grid of {k}"));
        }
        if self.steps.len() != seqs
            || self
                .steps
                .iter()
                .any(|r| r.step.len() != k || r.duration.len() != k)
        {
            return Err(format!(
                "inconsistent header: {} root tracks for {seqs} sequences on a phase grid of {k}",
                self.steps.len()
            ));
        }
        if self.pairs.len() + 1 != seqs {
            return Err(format!(
                "inconsistent header: {} reference pairs for {seqs} sequences",
                self.pairs.len()
            ));
        }
        if let Some(i) = self.pairs.iter().position(|p| !pair_ok(p)) {
            let p = &self.pairs[i];
            return Err(format!(
                "pair {i}: {} reference weights for {} blocks (at least 2, in [0, 1], increasing)",
                p.weights.len(),
                p.blocks.len()
            ));
        }
        if self.axis.is_some() == self.parameters.is_empty() {
            return Err(format!(
                "{} parameters and {} inverse map",
                self.parameters.len(),
                if self.axis.is_some() { "an" } else { "no" }
            ));
        }
        if !self.epsilon.is_finite() || self.measured.iter().flatten().any(|x| !x.is_finite()) {
            return Err("a measurement or the tolerance is not finite".into());
        }
        Ok(())
    }
}

impl MotionSpace {
    /// A space from its parts and its blend, checked: the parts by
    /// [`SpaceParts::check`], then the blend against them — its pairs the
    /// parts' pairs, on the same phase grid, one block per sequence at
    /// least, every block a phase grid of `n` vertices and every pair's
    /// blocks among them. The error says what disagrees (the caller names
    /// the space).
    pub fn new(parts: SpaceParts, blend: HybridBlend) -> Result<Self, String> {
        parts.check()?;
        let k = parts.alignment.grid;
        let per_block = k.saturating_mul(blend.n).saturating_mul(3);
        let named = parts
            .pairs
            .iter()
            .flat_map(|p| p.blocks.iter())
            .all(|&b| b < blend.blocks.len());
        if parts.pairs != blend.pairs
            || blend.grid != k
            || blend.blocks.len() < parts.sequences.len()
            || blend.blocks.iter().any(|b| b.len() != per_block)
            || !named
        {
            return Err(format!(
                "a blend of {} blocks on a phase grid of {} does not match {} sequences on {k}",
                blend.blocks.len(),
                blend.grid,
                parts.sequences.len()
            ));
        }
        let SpaceParts {
            name,
            sequences,
            parameters,
            alignment,
            pairs,
            steps,
            axis,
            measured,
            epsilon,
        } = parts;
        Ok(Self {
            name,
            sequences,
            parameters,
            alignment,
            blend,
            pairs,
            steps,
            axis,
            measured,
            epsilon,
        })
    }

    /// Name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Its sequences, in blend order (weight coordinate `u = i` is sequence `i`).
    pub fn sequences(&self) -> &[String] {
        &self.sequences
    }

    /// Its parameters; the first is blended, a later `turn` steers.
    pub fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    /// The time alignment of the sequences.
    pub fn alignment(&self) -> &Alignment {
        &self.alignment
    }

    /// The hybrid blend.
    pub fn blend(&self) -> &HybridBlend {
        &self.blend
    }

    /// Root motion of each sequence on the phase grid.
    pub fn steps(&self) -> &[RootSteps] {
        &self.steps
    }

    /// The inverse map of the first parameter.
    pub fn axis(&self) -> Option<&ParamMap> {
        self.axis.as_ref()
    }

    /// `(u, speed m/s, turn deg/s)` at weight step 0.05.
    pub fn measured(&self) -> &[[f64; 3]] {
        &self.measured
    }

    /// Hybrid tolerance used (metres).
    pub fn epsilon(&self) -> f64 {
        self.epsilon
    }
    /// Largest weight coordinate (`N − 1`).
    pub(crate) fn u_max(&self) -> f64 {
        self.sequences.len().saturating_sub(1) as f64
    }

    /// Phase samples per cycle.
    pub fn grid(&self) -> usize {
        self.alignment.grid
    }

    /// The measured `[speed, turn]` at `u` (interpolated from the samples).
    pub(crate) fn measured_at(&self, u: f64) -> [f64; 2] {
        let s = &self.measured;
        if s.len() < 2 {
            return s.first().map_or([0.0; 2], |m| [m[1], m[2]]);
        }
        let x = (u / WEIGHT_STEP).clamp(0.0, (s.len() - 1) as f64);
        let k = (x.floor() as usize).min(s.len() - 2);
        let t = x - k as f64;
        [
            s[k][1] + (s[k + 1][1] - s[k][1]) * t,
            s[k][2] + (s[k + 1][2] - s[k][2]) * t,
        ]
    }

    /// The references `(u, block)` sorted by weight coordinate.
    pub fn references(&self) -> Vec<(f64, usize)> {
        if self.pairs.is_empty() {
            return vec![(0.0, 0)];
        }
        let mut out = Vec::new();
        for (a, p) in self.pairs.iter().enumerate() {
            for (k, (&w, &b)) in p.weights.iter().zip(&p.blocks).enumerate() {
                if a > 0 && k == 0 {
                    continue;
                }
                out.push((a as f64 + w, b));
            }
        }
        out
    }

    /// The blended root step at phase sample `k` and weight `u`.
    #[inline]
    pub fn step(&self, u: f64, k: usize) -> [f64; 4] {
        blended_step(&self.steps, u, k)
    }

    /// Plays `frames` frames from `phase` (grid units) at weight `u`:
    /// the new phase and the root motion `(x, z, dθ)` in the body frame at
    /// the start. Integrates step by step (a step's travel spread over its
    /// duration), so steps the time warp made short are passed through,
    /// not skipped.
    pub fn play_phase(&self, u: f64, phase: f64, frames: f64) -> (f64, [f64; 3]) {
        let k = self.grid();
        let mut p = phase.rem_euclid(k as f64);
        let mut left = frames;
        let mut acc = [0.0; 3];
        for _ in 0..4 * k + 4 {
            if left <= 1e-12 {
                break;
            }
            let i = (p.floor() as usize).min(k - 1);
            let [x, z, dh, d] = self.step(u, i);
            let rest = (i + 1) as f64 - p;
            let need = rest * d;
            let (take, dp) = if need <= left {
                (rest, need)
            } else {
                (left / d.max(1e-12), left)
            };
            let take = take.min(rest);
            acc[0] += x * take;
            acc[1] += z * take;
            acc[2] += dh * take;
            left -= dp;
            p += take;
            if p >= (i + 1) as f64 - 1e-12 {
                p = ((i + 1) % k) as f64;
            }
        }
        (p, acc)
    }

    /// The similarity features of the references ([`super::transition`]).
    pub(crate) fn ref_features(&self, fps: f64) -> RefFeatures {
        let n = self.blend.n;
        let stride = n.div_ceil(SIMILARITY_VERTICES).max(1);
        let k = self.grid();
        let refs = self.references();
        let feats = refs
            .iter()
            .map(|&(u, b)| {
                let block = &self.blend.blocks[b];
                (0..k)
                    .map(|i| {
                        let j = (i + 1) % k;
                        let scale = VELOCITY_SECONDS * fps / self.step(u, i)[3].max(1e-6);
                        let mut f = Vec::with_capacity(6 * n.div_ceil(stride));
                        for v in (0..n).step_by(stride) {
                            for c in 0..3 {
                                f.push(block[(i * n + v) * 3 + c]);
                            }
                            for c in 0..3 {
                                let d = block[(j * n + v) * 3 + c] - block[(i * n + v) * 3 + c];
                                f.push((d as f64 * scale) as f32);
                            }
                        }
                        f
                    })
                    .collect()
            })
            .collect();
        RefFeatures {
            u: refs.iter().map(|r| r.0).collect(),
            feats,
        }
    }
}

/// A pair's references: at least two, weights increasing in `[0, 1]`,
/// one block each.
fn pair_ok(p: &PairRefs) -> bool {
    let ordered = p.weights.windows(2).all(|w| w[0] <= w[1])
        && p.weights.iter().all(|w| (0.0..=1.0).contains(w));
    p.weights.len() >= 2 && p.weights.len() == p.blocks.len() && ordered
}
