//! The latency and throughput report of a live session: frames in and
//! out, drops, and the time from a frame's arrival to its mesh being
//! ready (a fixed histogram, so an hour-long session keeps its memory flat).

use serde::Serialize;
use std::time::Duration;

/// Histogram bin width (milliseconds).
const BIN_MS: f64 = 0.05;
/// Bins (0 to 2 s; slower frames land in the last).
const BINS: usize = 40_000;

/// Arrival-to-ready latencies, binned.
#[derive(Debug, Clone)]
pub(crate) struct Latencies {
    bins: Vec<u32>,
    count: u64,
    sum_ms: f64,
    max_ms: f64,
}

impl Default for Latencies {
    fn default() -> Self {
        Latencies {
            bins: vec![0; BINS],
            count: 0,
            sum_ms: 0.0,
            max_ms: 0.0,
        }
    }
}

impl Latencies {
    /// Records one latency.
    pub fn add(&mut self, d: Duration) {
        self.add_ms(d.as_secs_f64() * 1e3);
    }

    /// Records one latency given in milliseconds.
    pub(crate) fn add_ms(&mut self, ms: f64) {
        let b = ((ms / BIN_MS) as usize).min(BINS - 1);
        self.bins[b] += 1;
        self.count += 1;
        self.sum_ms += ms;
        self.max_ms = self.max_ms.max(ms);
    }

    /// The `q` quantile (0..1) in milliseconds (bin centre; 0 when empty).
    pub(crate) fn quantile_ms(&self, q: f64) -> f64 {
        if self.count == 0 {
            return 0.0;
        }
        let rank = ((q * self.count as f64).ceil() as u64).clamp(1, self.count);
        let mut seen = 0u64;
        for (i, &c) in self.bins.iter().enumerate() {
            seen += u64::from(c);
            if seen >= rank {
                return (i as f64 + 0.5) * BIN_MS;
            }
        }
        self.max_ms
    }

    /// The summary.
    pub fn summary(&self) -> LatencySummary {
        LatencySummary {
            frames: self.count,
            median_ms: self.quantile_ms(0.5),
            p99_ms: self.quantile_ms(0.99),
            max_ms: self.max_ms,
            mean_ms: if self.count == 0 {
                0.0
            } else {
                self.sum_ms / self.count as f64
            },
        }
    }
}

/// Latency figures (milliseconds).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct LatencySummary {
    /// Frames measured.
    pub frames: u64,
    /// Median.
    pub median_ms: f64,
    /// 99th percentile.
    pub p99_ms: f64,
    /// Largest.
    pub max_ms: f64,
    /// Mean.
    pub mean_ms: f64,
}

/// What happened to the incoming frames.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Counters {
    /// Frames received (valid).
    pub received: u64,
    /// Frames dropped because a newer one was waiting (newest wins) or
    /// never arrived (a gap in the sender's numbering).
    pub dropped: u64,
    /// Frames received twice (same sender number), ignored.
    pub duplicated: u64,
    /// Frames that arrived after a newer one, ignored.
    pub late: u64,
    /// Packets that could not be read, ignored.
    pub malformed: u64,
    /// Senders that connected (TCP) after the first.
    pub reconnects: u64,
}

impl Latencies {
    /// Forgets every latency (keeps the bins' memory).
    pub fn clear(&mut self) {
        self.bins.iter_mut().for_each(|b| *b = 0);
        self.count = 0;
        self.sum_ms = 0.0;
        self.max_ms = 0.0;
    }
}

/// One sample of a long session, taken every `--sample-every` seconds:
/// the rate and the memory, to see both stay flat.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Sample {
    /// Seconds since the first frame arrived.
    pub seconds: f64,
    /// Frames output so far.
    pub frames_out: u64,
    /// Frames received so far.
    pub received: u64,
    /// Frames dropped so far (newest wins).
    pub dropped: u64,
    /// Output frames per second since the previous sample.
    pub output_fps: f64,
    /// Arrival → mesh median since the previous sample (milliseconds).
    pub latency_median_ms: f64,
    /// The process's resident memory (MiB; `None` where the system does
    /// not tell: only Linux's `/proc/self/status` is read).
    pub rss_mib: Option<f64>,
    /// The process's CPU (every thread) per output frame since the
    /// previous sample, milliseconds (`None` without a CPU clock or
    /// without frames): the cost a frame, which other work on the
    /// machine does not inflate as it does the rate.
    pub cpu_ms_per_frame: Option<f64>,
}

/// The process's resident memory in MiB (`VmRSS` of `/proc/self/status`),
/// `None` where it cannot be read.
pub(crate) fn resident_mib() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmRSS:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}
