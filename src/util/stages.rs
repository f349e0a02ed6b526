//! A run's stages one after another, each with its wall and CPU seconds
//! (issue 43: what a `retarget` spends before its first frame — loading,
//! mapping, factoring — separated from what it spends per clip). Each
//! [`Stages::lap`] closes the stage that ran since the previous lap (or
//! the start), so the stages leave no gap between the first and the last
//! lap. CPU is the whole process's (every thread: the stages run one after
//! another, their parallel work inside them), the figure that load does
//! not inflate as it does wall time.

use serde::Serialize;
use std::time::Instant;

/// One stage: its name and its seconds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stage {
    /// What ran.
    pub stage: &'static str,
    /// Wall seconds.
    pub wall: f64,
    /// CPU seconds of the process (0 where the platform has no CPU clock).
    pub cpu: f64,
}

/// Stages being timed: the clock runs from [`Stages::start`].
#[derive(Debug, Clone)]
pub struct Stages {
    done: Vec<Stage>,
    wall: Instant,
    cpu: f64,
}

impl Default for Stages {
    fn default() -> Self {
        Stages::start()
    }
}

/// CPU seconds of the process so far (every thread; 0 without a clock).
pub fn process_cpu() -> f64 {
    super::cpu::process_cpu_seconds().unwrap_or(0.0)
}

impl Stages {
    /// The clock started now, no stage done.
    pub fn start() -> Stages {
        Stages {
            done: Vec::new(),
            wall: Instant::now(),
            cpu: process_cpu(),
        }
    }

    /// Closes the stage `stage` that ran since the previous lap (or the
    /// start).
    pub fn lap(&mut self, stage: &'static str) {
        let (wall, cpu) = (Instant::now(), process_cpu());
        self.done.push(Stage {
            stage,
            wall: (wall - self.wall).as_secs_f64(),
            cpu: (cpu - self.cpu).max(0.0),
        });
        self.wall = wall;
        self.cpu = cpu;
    }

    /// The stages done, in order.
    pub fn stages(&self) -> &[Stage] {
        &self.done
    }

    /// The stages done, in order, taken.
    pub fn into_stages(self) -> Vec<Stage> {
        self.done
    }
}

/// Wall and CPU seconds summed over `stages`.
pub fn sum(stages: &[Stage]) -> (f64, f64) {
    stages
        .iter()
        .fold((0.0, 0.0), |(w, c), s| (w + s.wall, c + s.cpu))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Laps close consecutive stages: their wall seconds add up to the
    /// time from the start to the last lap, and CPU work lands in the
    /// stage that did it.
    #[test]
    fn laps_leave_no_gap_and_cpu_lands_where_it_was_spent() {
        let t = Instant::now();
        let mut s = Stages::start();
        s.lap("nothing");
        let mut x = 0u64;
        for i in 0..30_000_000u64 {
            x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
        }
        std::hint::black_box(x);
        s.lap("work");
        let whole = t.elapsed().as_secs_f64();
        let names: Vec<&str> = s.stages().iter().map(|s| s.stage).collect();
        assert_eq!(names, ["nothing", "work"]);
        let (wall, cpu) = sum(s.stages());
        assert!(wall <= whole, "{wall} > {whole}");
        if cfg!(unix) {
            assert!(s.stages()[1].cpu > s.stages()[0].cpu, "{:?}", s.stages());
            assert!(cpu > 0.0);
        }
    }
}
