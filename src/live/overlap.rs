//! When the live session deforms two frames at once (the two-frame
//! overlap, [`super::SessionOptions::overlap`]), and what it has measured
//! of its own gain.

use std::time::Duration;

/// When the session holds a frame for the two-frame overlap
/// ([`super::SessionOptions::overlap`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Overlap {
    /// Never: every frame is deformed alone as it is decided.
    #[default]
    Off,
    /// Only while the next frame is already there — another frame of the
    /// same push is decided after it, or the stream's next arrival is
    /// already waiting ([`super::Session::set_waiting`]) — and while a
    /// pair is measured to deform faster than two frames one after the
    /// other ([`PairGain`]). At the real rate, with the session keeping
    /// up, nothing is held (the one-frame path's latency); when frames
    /// queue on two free cores, they are deformed two at a time; with no
    /// core free for the second thread, one at a time again.
    Queued,
    /// Always: every frame waits for the next (one frame more of latency
    /// at the real rate, whatever the cores).
    Always,
}

/// The pair's least measured gain for [`Overlap::Queued`] to hold a
/// frame: two frames deformed in a pair at most this fraction of the
/// time two lone frames take (a quarter more frames a second). Below
/// it the held frame's added latency buys little rate.
const PAIR_AT_MOST: f64 = 0.8;

/// The other way is measured again after this many frames one way: a
/// pair after this many lone frames when pairs were measured slow, a lone
/// frame after this many pairs when they were fast (the machine's load
/// changes).
const RETRY_EVERY: u32 = 32;

/// Weight of the newest measurement in the running means.
const NEWEST: f64 = 0.2;

/// The running wall times of a lone frame's deformation and of a pair's,
/// and whether a pair is worth holding a frame for.
#[derive(Debug, Default)]
pub(crate) struct PairGain {
    single: Option<f64>,
    pair: Option<f64>,
    alone_since_pair: u32,
    pairs_since_alone: u32,
}

impl PairGain {
    /// Records a lone frame's deformation wall time.
    pub(crate) fn single(&mut self, wall: Duration) {
        self.single = Some(mean(self.single, wall.as_secs_f64()));
        self.alone_since_pair = self.alone_since_pair.saturating_add(1);
        self.pairs_since_alone = 0;
    }

    /// Records a pair's deformation wall time.
    pub(crate) fn pair(&mut self, wall: Duration) {
        self.pair = Some(mean(self.pair, wall.as_secs_f64()));
        self.alone_since_pair = 0;
        self.pairs_since_alone = self.pairs_since_alone.saturating_add(1);
    }

    /// True when a frame should be held for a pair: a lone frame
    /// measured and no pair yet, or pairs measured faster than two lone
    /// frames by [`PAIR_AT_MOST`] (but a lone frame again every
    /// [`RETRY_EVERY`] pairs), or measured slower but not tried for
    /// [`RETRY_EVERY`] frames.
    pub(crate) fn worth_holding(&self) -> bool {
        match (self.single, self.pair) {
            (None, _) => false,
            (Some(_), None) => true,
            (Some(s), Some(p)) if p <= PAIR_AT_MOST * 2.0 * s => {
                self.pairs_since_alone < RETRY_EVERY
            }
            (Some(_), Some(_)) => self.alone_since_pair >= RETRY_EVERY,
        }
    }
}

/// The running mean `old` with the newest `x`.
fn mean(old: Option<f64>, x: f64) -> f64 {
    old.map_or(x, |m| m + NEWEST * (x - m))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ms(x: u64) -> Duration {
        Duration::from_millis(x)
    }

    #[test]
    fn pairs_are_held_while_they_gain_and_retried_when_they_do_not() {
        let mut g = PairGain::default();
        assert!(!g.worth_holding(), "nothing measured: a lone frame first");
        g.single(ms(20));
        assert!(g.worth_holding(), "no pair measured: try");
        g.pair(ms(22));
        assert!(g.worth_holding(), "a pair in 22 ms against 2 × 20: hold");
        for _ in 1..RETRY_EVERY {
            g.pair(ms(22));
        }
        assert!(
            !g.worth_holding(),
            "a lone frame again after {RETRY_EVERY} pairs"
        );
        g.single(ms(20));
        assert!(g.worth_holding(), "pairs still faster: hold");
        // The second core taken: pairs take as long as two lone frames.
        for _ in 0..20 {
            g.pair(ms(40));
        }
        assert!(!g.worth_holding(), "pairs no faster: one at a time");
        for _ in 0..RETRY_EVERY - 1 {
            g.single(ms(20));
            assert!(!g.worth_holding());
        }
        g.single(ms(20));
        assert!(
            g.worth_holding(),
            "tried again after {RETRY_EVERY} lone frames"
        );
        g.pair(ms(40));
        assert!(!g.worth_holding(), "still slow: alone again");
    }
}
