//! When the live session deforms two frames at once (the two-frame
//! overlap, [`super::SessionOptions::overlap`]), and what it has measured
//! of its own gain.

pub(crate) use crate::util::cpu::process_cpu_seconds;
use std::time::Duration;

/// When the session holds a frame for the two-frame overlap
/// ([`super::SessionOptions::overlap`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Overlap {
    /// Never: every frame is deformed alone as it is decided.
    Off,
    /// Only while the next frame is already there — another frame of the
    /// same push is decided after it, or the stream's next arrival is
    /// already waiting ([`super::Session::set_waiting`]) — and while a
    /// pair is measured to keep more cores busy than a lone frame
    /// ([`PairGain`]). At the real rate, with the session keeping
    /// up, nothing is held (the one-frame path's latency); when frames
    /// queue on two free cores, they are deformed two at a time; with no
    /// core free for the second thread, one at a time again. The default
    /// (session 40: its resident memory measured as flat as `Off`'s, in
    /// the doc of [`super::SessionOptions::overlap`]).
    #[default]
    Queued,
    /// Always: every frame waits for the next (one frame more of latency
    /// at the real rate, whatever the cores).
    Always,
}

/// The least ratio of a pair's cores in use to a lone frame's for
/// [`Overlap::Queued`] to hold a frame: a pair keeps at least this many
/// times the cores busy that a lone frame does (a lone frame's repair is
/// single-threaded, its solves are not). Two free cores measured 1.6-1.9×
/// the frames a second in pairs; one core, 1.0×.
const PAIR_AT_LEAST: f64 = 1.2;

/// The other way is measured again after this many frames one way: a
/// pair after this many lone frames when pairs were measured slow, a lone
/// frame after this many pairs when they were fast (the machine's load
/// changes).
const RETRY_EVERY: u32 = 32;

/// Weight of the newest measurement in the running means.
const NEWEST: f64 = 0.2;

/// The running cores in use (the process's CPU seconds over wall
/// seconds) while a lone frame deforms and while a pair does, and whether
/// a pair is worth holding a frame for.
///
/// The gain of a pair is judged by cores in use rather than by wall time:
/// a frame's deformation cost changes with the phase of the motion (the
/// fold repair's work), so a pair's wall time against the lone frames'
/// running mean compares frames of different costs; the CPU per wall
/// second of each is the same frame's own ratio. With two free cores a
/// pair keeps both busy; with one core (or the second taken by another
/// process) a pair keeps no more busy than a lone frame.
#[derive(Debug, Default)]
pub(crate) struct PairGain {
    single: Option<f64>,
    pair: Option<f64>,
    alone_since_pair: u32,
    pairs_since_alone: u32,
}

impl PairGain {
    /// Records a lone frame's deformation: its wall time and the process's
    /// CPU seconds over it.
    pub(crate) fn single(&mut self, wall: Duration, cpu: f64) {
        if let Some(r) = cores(wall, cpu) {
            self.single = Some(mean(self.single, r));
        }
        self.alone_since_pair = self.alone_since_pair.saturating_add(1);
        self.pairs_since_alone = 0;
    }

    /// Records a pair's deformation: its wall time and the process's CPU
    /// seconds over it.
    pub(crate) fn pair(&mut self, wall: Duration, cpu: f64) {
        if let Some(r) = cores(wall, cpu) {
            self.pair = Some(mean(self.pair, r));
        }
        self.alone_since_pair = 0;
        self.pairs_since_alone = self.pairs_since_alone.saturating_add(1);
    }

    /// True when a frame should be held for a pair: a lone frame
    /// measured and no pair yet, or pairs measured to keep at least
    /// [`PAIR_AT_LEAST`] times the cores busy (but a lone frame again
    /// every [`RETRY_EVERY`] pairs), or measured not to but not tried for
    /// [`RETRY_EVERY`] frames.
    pub(crate) fn worth_holding(&self) -> bool {
        match (self.single, self.pair) {
            (None, _) => false,
            (Some(_), None) => true,
            (Some(s), Some(p)) if p >= PAIR_AT_LEAST * s => self.pairs_since_alone < RETRY_EVERY,
            (Some(_), Some(_)) => self.alone_since_pair >= RETRY_EVERY,
        }
    }
}

/// Cores in use: CPU seconds over wall seconds; `None` when either is not
/// a positive measurement (a platform without CPU clocks, a frame too
/// quick to time).
fn cores(wall: Duration, cpu: f64) -> Option<f64> {
    let w = wall.as_secs_f64();
    (w > 0.0 && cpu > 0.0 && cpu.is_finite()).then(|| cpu / w)
}

/// The process's CPU seconds since `start` (a [`process_cpu_seconds`]
/// reading); 0 where the platform does not say.
pub(crate) fn cpu_since(start: Option<f64>) -> f64 {
    match (start, process_cpu_seconds()) {
        (Some(a), Some(b)) => (b - a).max(0.0),
        _ => 0.0,
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
    fn pairs_are_held_while_they_keep_more_cores_busy_and_retried_when_not() {
        let mut g = PairGain::default();
        assert!(!g.worth_holding(), "nothing measured: a lone frame first");
        // A lone frame: 20 ms of wall, 26 ms of CPU (its solves in parallel).
        g.single(ms(20), 0.026);
        assert!(g.worth_holding(), "no pair measured: try");
        // A pair on two free cores: both busy.
        g.pair(ms(22), 0.042);
        assert!(g.worth_holding(), "1.9 cores against 1.3: hold");
        for _ in 1..RETRY_EVERY {
            g.pair(ms(22), 0.042);
        }
        assert!(
            !g.worth_holding(),
            "a lone frame again after {RETRY_EVERY} pairs"
        );
        // A lone frame of the motion's costlier phase: the ratio stays.
        g.single(ms(60), 0.078);
        assert!(g.worth_holding(), "pairs still keep more cores busy: hold");
        // The second core taken: a pair keeps one core busy, as a lone
        // frame now does.
        for _ in 0..20 {
            g.pair(ms(40), 0.040);
        }
        assert!(!g.worth_holding(), "no more cores busy: one at a time");
        for _ in 0..RETRY_EVERY - 1 {
            g.single(ms(20), 0.020);
            assert!(!g.worth_holding());
        }
        g.single(ms(20), 0.020);
        assert!(
            g.worth_holding(),
            "tried again after {RETRY_EVERY} lone frames"
        );
        g.pair(ms(40), 0.040);
        assert!(!g.worth_holding(), "still no gain: alone again");
    }

    #[test]
    fn frames_without_a_cpu_clock_count_but_do_not_measure() {
        let mut g = PairGain::default();
        g.single(ms(20), 0.0);
        assert!(!g.worth_holding(), "no lone frame measured: never hold");
        g.single(Duration::ZERO, 0.01);
        assert!(!g.worth_holding());
        g.single(ms(20), f64::NAN);
        assert!(!g.worth_holding());
    }
}
