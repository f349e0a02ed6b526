//! Median, 95th percentile and maximum of a per-frame series: how every
//! plausibility check is summarised per sequence.

use serde::Serialize;

/// Order statistics of a series (its own units). All zero for an empty one.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct EvalSummary {
    /// Median.
    pub median: f64,
    /// 95th percentile (nearest rank on the sorted values).
    pub p95: f64,
    /// Largest value.
    pub max: f64,
}

/// The old name of [`EvalSummary`] (before session 40: one name per concept,
/// issue 40 — `Summary` named an evaluation's order statistics and two other things).
#[deprecated(note = "renamed EvalSummary")]
pub type Summary = EvalSummary;

impl EvalSummary {
    /// The summary of `values` (non-finite values are skipped). Sorts a copy:
    /// O(n log n).
    pub fn of(values: &[f64]) -> EvalSummary {
        let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return EvalSummary::default();
        }
        v.sort_by(f64::total_cmp);
        let pick = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
        EvalSummary {
            median: pick(0.5),
            p95: pick(0.95),
            max: v[v.len() - 1],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_statistics_of_a_ramp() {
        let v: Vec<f64> = (0..=100).map(f64::from).collect();
        let s = EvalSummary::of(&v);
        assert_eq!((s.median, s.p95, s.max), (50.0, 95.0, 100.0));
        assert_eq!(EvalSummary::of(&[f64::NAN]), EvalSummary::default());
    }
}
