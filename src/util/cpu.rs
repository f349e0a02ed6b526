//! CPU clocks: the seconds of CPU the process or the calling thread has
//! run so far, the figure that load does not inflate as it does wall time
//! (the stage reports of `db build`, `live` and the key-frame search).
//! `None` where the platform does not say.

/// CPU seconds of the whole process so far (every thread).
pub(crate) fn process_cpu_seconds() -> Option<f64> {
    clock_seconds(Clock::Process)
}

/// CPU seconds of the calling thread so far.
pub(crate) fn thread_cpu_seconds() -> Option<f64> {
    clock_seconds(Clock::Thread)
}

/// Which CPU clock.
#[derive(Clone, Copy)]
enum Clock {
    Process,
    Thread,
}

/// The seconds of one POSIX CPU clock.
#[cfg(unix)]
fn clock_seconds(clock: Clock) -> Option<f64> {
    let id = match clock {
        Clock::Process => libc::CLOCK_PROCESS_CPUTIME_ID,
        Clock::Thread => libc::CLOCK_THREAD_CPUTIME_ID,
    };
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec for the call's duration.
    let r = unsafe { libc::clock_gettime(id, &mut ts) };
    (r == 0).then_some(ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9)
}

/// No CPU clock here.
#[cfg(not(unix))]
fn clock_seconds(_clock: Clock) -> Option<f64> {
    None
}

#[cfg(test)]
mod tests {
    /// Both clocks read and advance with work done on this thread.
    #[cfg(unix)]
    #[test]
    fn both_clocks_advance_with_work() {
        let (p0, t0) = (super::process_cpu_seconds(), super::thread_cpu_seconds());
        let mut x = 0u64;
        for i in 0..20_000_000u64 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
        }
        std::hint::black_box(x);
        let (p1, t1) = (super::process_cpu_seconds(), super::thread_cpu_seconds());
        assert!(p1.unwrap() > p0.unwrap(), "process clock did not advance");
        assert!(t1.unwrap() > t0.unwrap(), "thread clock did not advance");
    }
}
