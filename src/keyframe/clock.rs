//! The query clock: the calling thread's CPU time, so that a query's cost
//! can be measured on a busy machine (wall time there is mostly the time
//! spent waiting for a core; issue 20's "query time ≤ 50 ms on 2 cores").
//!
//! On Unix the clock is `clock_gettime(CLOCK_THREAD_CPUTIME_ID)`, the
//! thread's run time to the nanosecond (the scheduler's own account, read
//! up to the moment of the call; the first field of
//! `/proc/thread-self/schedstat` is the same count but only brought up to
//! date at the scheduler's ticks: a 0.4 ms query read 0 there);
//! elsewhere, or when the call fails, there is no figure (`None`)
//! and the reports give the wall time alone. Work the search hands to
//! other threads (the opt-in
//! [`super::options::LatticeOptions::parallel_from`]) is not counted.

use crate::util::cpu::thread_cpu_seconds;

/// A stopwatch of both clocks.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Stopwatch {
    wall: std::time::Instant,
    cpu: Option<f64>,
}

impl Stopwatch {
    /// Starts both clocks.
    /// (The wall clock first: the CPU interval lies within the wall one.)
    pub fn start() -> Stopwatch {
        let wall = std::time::Instant::now();
        Stopwatch {
            cpu: thread_cpu_seconds(),
            wall,
        }
    }
    /// Wall seconds since the start.
    pub fn wall(&self) -> f64 {
        self.wall.elapsed().as_secs_f64()
    }
    /// The calling thread's CPU seconds since the start (`None` where the
    /// platform does not say; call it on the thread that started it).
    pub fn cpu(&self) -> Option<f64> {
        let now = thread_cpu_seconds()?;
        Some((now - self.cpu?).max(0.0))
    }
}
