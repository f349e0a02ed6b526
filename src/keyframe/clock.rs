//! The query clock: the calling thread's CPU time, so that a query's cost
//! can be measured on a busy machine (wall time there is mostly the time
//! spent waiting for a core; issue 20's "query time ≤ 50 ms on 2 cores").
//!
//! On Linux the first field of `/proc/thread-self/schedstat` is the
//! thread's run time in nanoseconds (the scheduler's `sum_exec_runtime`);
//! elsewhere, or when the file cannot be read, there is no figure
//! (`None`) and the reports give the wall time alone. Work the search
//! hands to other threads (the opt-in [`super::lattice::LatticeOptions::parallel_from`])
//! is not counted.

/// CPU seconds the calling thread has run so far, or `None` where the
/// platform does not say.
pub fn thread_cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: u64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns as f64 * 1e-9)
}

/// A stopwatch of both clocks.
#[derive(Debug, Clone, Copy)]
pub struct Stopwatch {
    wall: std::time::Instant,
    cpu: Option<f64>,
}

impl Stopwatch {
    /// Starts both clocks.
    pub fn start() -> Stopwatch {
        Stopwatch {
            cpu: thread_cpu_seconds(),
            wall: std::time::Instant::now(),
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
