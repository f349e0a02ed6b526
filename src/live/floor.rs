//! The live session's running floor (issue 45, fidelity): the floor the
//! pose kernel stands the stream on, estimated over every frame seen so
//! far rather than over the analysis window alone.
//!
//! Offline the kernel's floor is the 5th percentile of the clip's lowest
//! foot joint; a few seconds' window found it a few millimetres off from
//! one window to the next (samba 131_02, frame 53: 5.03 vs the clip's
//! 5.68 cm), and a foot touches within 3 cm of it, so contacts and the
//! body's lift changed from frame to frame. [`RunningFloor`] keeps the
//! same percentile over all frames seen (in 1 mm bins: memory bounded by
//! the range of heights, not the stream's length) and moves its estimate
//! towards it by at most [`RunningFloor::step`] a frame once frames are
//! being output, so that it converges and then stays put.

use std::collections::BTreeMap;

/// Bin width of the heights kept (metres).
const BIN: f64 = 0.001;

/// A running estimate of a stream's floor (levelled heights, metres).
#[derive(Debug, Clone, PartialEq)]
pub struct RunningFloor {
    /// Per 1 mm bin of height: the frames in it and their heights' sum.
    bins: BTreeMap<i64, (u64, f64)>,
    /// Frames counted.
    count: u64,
    /// The estimate given to the kernel.
    estimate: Option<f64>,
    /// The most the estimate moves per frame once it is held (metres).
    pub step: f64,
}

impl RunningFloor {
    /// An empty estimate moving at most `step` metres a frame once held.
    pub fn new(step: f64) -> Self {
        RunningFloor {
            bins: BTreeMap::new(),
            count: 0,
            estimate: None,
            step,
        }
    }

    /// Counts a frame's lowest foot joint height `low` (levelled, metres;
    /// a non-finite height is left out).
    pub fn add(&mut self, low: f64) {
        if !low.is_finite() {
            return;
        }
        let b = (low / BIN).floor() as i64;
        let e = self.bins.entry(b).or_insert((0, 0.0));
        e.0 += 1;
        e.1 += low;
        self.count += 1;
    }

    /// The 5th percentile of the heights counted (the kernel's rule: the
    /// height of rank `n / 20` in ascending order), as the mean height of
    /// the 1 mm bin holding that rank; `None` before any.
    pub fn target(&self) -> Option<f64> {
        let rank = self.count / 20;
        let mut seen = 0;
        for (n, sum) in self.bins.values() {
            seen += n;
            if seen > rank {
                return Some(sum / *n as f64);
            }
        }
        None
    }

    /// Moves the estimate to the target: all the way while `free` (no frame
    /// output yet: nothing stood on the old estimate), else by at most
    /// `step`. Returns the estimate.
    pub fn update(&mut self, free: bool) -> Option<f64> {
        let t = self.target()?;
        let e = match self.estimate {
            Some(e) if !free => e + (t - e).clamp(-self.step, self.step),
            _ => t,
        };
        self.estimate = Some(e);
        Some(e)
    }

    /// Bins held (the memory: about 40 bytes each).
    pub fn bins(&self) -> usize {
        self.bins.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_target_is_the_fifth_percentile_and_the_estimate_moves_by_at_most_a_step() {
        let mut f = RunningFloor::new(0.0005);
        for i in 0..100 {
            f.add(0.05 + 0.001 * i as f64 + 0.0002);
        }
        // Rank 5 of 0.0502, 0.0512, ...: 0.0552.
        assert!((f.target().unwrap() - 0.0552).abs() < 1e-9);
        assert_eq!(f.update(true), f.target());
        for _ in 0..100 {
            f.add(0.0);
        }
        // Now rank 10 of 200: a height of 0.
        assert_eq!(f.target(), Some(0.0));
        let e = f.update(false).unwrap();
        assert!((e - 0.0547).abs() < 1e-9, "{e}");
        f.add(f64::NAN);
        assert_eq!(f.count, 200);
    }
}
