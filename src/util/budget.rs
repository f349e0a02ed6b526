//! Limits on what one job may ask for, checked before anything is allocated
//! (issue 18, item 12): frame rates, and the memory a job's frames need.
//!
//! A typo in a rate (`--input-fps 1e-4`, a BVH `Frame Time` in
//! milliseconds, `--fps 1e9`) or a very long clip asks for millions of
//! frames; holding them aborts the process ("memory allocation of N bytes
//! failed", no exit code). Every such request is estimated first
//! (frames × vertices × bytes) and refused with the numbers when it
//! exceeds the budget.
//!
//! The budget is half of the least of the machine's physical memory
//! (`/proc/meminfo`), the process's address-space limit (`ulimit -v`,
//! `/proc/self/limits`) and its control group's memory limit (cgroup v2
//! `memory.max` or v1 `memory.limit_in_bytes`); 8 GiB where none can be
//! read; or `SURFMOTION_MEMORY_LIMIT` (bytes, or a number with a K, M, G or
//! T suffix, powers of 1024). Without the last two, a job under `ulimit -v`
//! or in a container was accepted against the whole machine's memory and
//! then aborted on an allocation.

use std::fmt;

/// Lowest frame rate accepted anywhere (frames per second): a clip, a
/// database, an output. Below it a frame time is more likely in
/// milliseconds than real.
pub const MIN_FPS: f64 = 1.0;
/// Highest frame rate accepted anywhere (frames per second).
pub const MAX_FPS: f64 = 1000.0;

/// True for a finite rate in [[`MIN_FPS`], [`MAX_FPS`]].
pub fn is_frame_rate(fps: f64) -> bool {
    fps.is_finite() && (MIN_FPS..=MAX_FPS).contains(&fps)
}

/// The environment variable that overrides the memory budget.
pub(crate) const MEMORY_ENV: &str = "SURFMOTION_MEMORY_LIMIT";

/// A memory budget in bytes and where it came from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Budget {
    /// Bytes a job may hold.
    pub bytes: u64,
    /// Where the figure came from (for messages).
    pub source: &'static str,
}

impl Budget {
    /// The budget of this process: [`MEMORY_ENV`] if set and readable, else
    /// half of physical memory, else 8 GiB.
    pub fn current() -> Budget {
        if let Ok(v) = std::env::var(MEMORY_ENV) {
            match parse_bytes(&v) {
                Some(b) => {
                    return Budget {
                        bytes: b,
                        source: "set by SURFMOTION_MEMORY_LIMIT",
                    };
                }
                None => tracing::warn!(
                    "{MEMORY_ENV}={v:?} is not a size (e.g. 8G, 512MB); using the default budget"
                ),
            }
        }
        let limits = [
            (physical_memory(), "half of physical memory"),
            (
                address_space_limit(),
                "half of the address-space limit (ulimit -v)",
            ),
            (
                cgroup_memory_limit(),
                "half of the control group's memory limit",
            ),
        ];
        match limits
            .into_iter()
            .filter_map(|(b, s)| b.map(|b| (b, s)))
            .min_by_key(|(b, _)| *b)
        {
            Some((m, source)) => Budget {
                bytes: m / 2,
                source,
            },
            None => Budget {
                bytes: 8 << 30,
                source: "default",
            },
        }
    }

    /// Refuses `need` bytes for `what` (e.g. "175,000 frames × 9,971
    /// vertices") when it exceeds the budget.
    pub fn check(&self, what: impl FnOnce() -> String, need: u128) -> Result<(), OverBudget> {
        if need > self.bytes as u128 {
            return Err(OverBudget {
                what: what(),
                need,
                budget: *self,
            });
        }
        Ok(())
    }
}

/// Checks `need` bytes against [`Budget::current`].
pub fn check(what: impl FnOnce() -> String, need: u128) -> Result<(), OverBudget> {
    Budget::current().check(what, need)
}

/// Bytes of one vertex position (`[f64; 3]`).
pub(crate) const VERTEX_BYTES: u128 = 24;

/// Refuses a job holding `copies` arrays of `frames` × `vertices`
/// positions (`[f64; 3]`) when they exceed the budget; `what` names the
/// job ("retarget of walk.bvh").
pub(crate) fn check_frames(
    what: &str,
    frames: usize,
    vertices: usize,
    copies: u128,
) -> Result<(), OverBudget> {
    check(
        || {
            format!(
                "{what}: {} frames × {} vertices",
                thousands(frames as u128),
                thousands(vertices as u128)
            )
        },
        (frames as u128) * (vertices as u128) * VERTEX_BYTES * copies.max(1),
    )
}

/// A job that would need more memory than the budget.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "{what} would need about {} of memory, more than the budget of {} ({}; set {MEMORY_ENV} to change it)",
    Bytes(*need),
    Bytes(budget.bytes as u128),
    budget.source
)]
pub struct OverBudget {
    /// What was asked for, with its counts.
    pub what: String,
    /// Bytes it needs.
    pub need: u128,
    /// The budget.
    pub budget: Budget,
}

/// A byte count for people: "41.7 GB".
pub(crate) struct Bytes(pub u128);

impl fmt::Display for Bytes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let b = self.0 as f64;
        let (v, u) = if b >= 1e12 {
            (b / 1e12, "TB")
        } else if b >= 1e9 {
            (b / 1e9, "GB")
        } else if b >= 1e6 {
            (b / 1e6, "MB")
        } else {
            (b / 1e3, "kB")
        };
        write!(f, "{v:.1} {u}")
    }
}

/// A count with thousands separators: "175,000".
pub fn thousands(n: u128) -> String {
    let s = n.to_string();
    let mut out = String::with_capacity(s.len() + s.len() / 3);
    for (i, c) in s.chars().enumerate() {
        if i > 0 && (s.len() - i) % 3 == 0 {
            out.push(',');
        }
        out.push(c);
    }
    out
}

/// `"8G"`, `"512M"`, `"512MB"`, `"2 GiB"`, `"1000000"` → bytes.
pub fn parse_bytes(s: &str) -> Option<u64> {
    let s = s.trim();
    // "512MB", "512MiB", "512M" and "1000B" alike.
    let s = ["iB", "ib", "B", "b"]
        .iter()
        .find_map(|u| s.strip_suffix(u))
        .unwrap_or(s)
        .trim_end();
    let (num, mult) = match s.chars().last()?.to_ascii_uppercase() {
        'K' => (&s[..s.len() - 1], 1u64 << 10),
        'M' => (&s[..s.len() - 1], 1 << 20),
        'G' => (&s[..s.len() - 1], 1 << 30),
        'T' => (&s[..s.len() - 1], 1 << 40),
        _ => (s, 1),
    };
    let v: f64 = num.trim().parse().ok()?;
    (v.is_finite() && v > 0.0).then(|| (v * mult as f64).min(u64::MAX as f64) as u64)
}

/// Physical memory in bytes (Linux `/proc/meminfo`).
fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// The soft address-space limit of this process (`ulimit -v`), from the
/// "Max address space" line of `/proc/self/limits`; `None` when unlimited.
fn address_space_limit() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/self/limits").ok()?;
    limits_address_space(&text)
}

/// The "Max address space" soft limit of a `/proc/self/limits` text.
fn limits_address_space(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// The memory limit of this process's control group: cgroup v2
/// `memory.max` of its own group (from `/proc/self/cgroup`) or of the
/// root, else v1 `memory.limit_in_bytes`; `None` when unlimited ("max", or
/// v1's page-rounded 2^63).
fn cgroup_memory_limit() -> Option<u64> {
    let own = std::fs::read_to_string("/proc/self/cgroup")
        .ok()
        .and_then(|t| {
            t.lines()
                .find_map(|l| l.strip_prefix("0::"))
                .map(|p| format!("/sys/fs/cgroup{}/memory.max", p.trim_end_matches('/')))
        });
    let candidates = own.into_iter().chain([
        "/sys/fs/cgroup/memory.max".to_string(),
        "/sys/fs/cgroup/memory/memory.limit_in_bytes".to_string(),
    ]);
    candidates
        .filter_map(|p| std::fs::read_to_string(p).ok())
        .filter_map(|t| t.trim().parse::<u64>().ok())
        .find(|&b| b < 1 << 60)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_counts_parse_and_print() {
        assert_eq!(parse_bytes("8G"), Some(8 << 30));
        assert_eq!(parse_bytes("512m"), Some(512 << 20));
        assert_eq!(parse_bytes("1000"), Some(1000));
        assert_eq!(parse_bytes("100MB"), Some(100 << 20));
        assert_eq!(parse_bytes("2 GiB"), Some(2 << 30));
        assert_eq!(parse_bytes("1000B"), Some(1000));
        assert_eq!(parse_bytes("-1"), None);
        assert_eq!(parse_bytes("x"), None);
        assert_eq!(Bytes(41_700_000_000).to_string(), "41.7 GB");
        assert_eq!(thousands(175_000), "175,000");
        assert_eq!(thousands(12), "12");
    }

    #[test]
    fn over_budget_names_the_numbers() {
        let b = Budget {
            bytes: 1 << 30,
            source: "test",
        };
        assert!(b.check(|| "small".into(), 1 << 20).is_ok());
        let e = b.check(|| "3 frames".into(), 5 << 30).unwrap_err();
        let s = e.to_string();
        assert!(s.contains("3 frames") && s.contains("5.4 GB") && s.contains("1.1 GB"));
    }

    #[test]
    fn the_address_space_limit_is_read_off_proc_limits() {
        let limited = "Limit                     Soft Limit           Hard Limit           Units     \n\
                       Max stack size            8388608              unlimited            bytes     \n\
                       Max address space         1228800000           unlimited            bytes     \n";
        assert_eq!(limits_address_space(limited), Some(1_228_800_000));
        let unlimited =
            "Max address space         unlimited            unlimited            bytes     \n";
        assert_eq!(limits_address_space(unlimited), None);
        assert_eq!(limits_address_space(""), None);
    }

    #[test]
    fn frame_rates() {
        assert!(is_frame_rate(30.0) && is_frame_rate(1.0) && is_frame_rate(1000.0));
        assert!(!is_frame_rate(0.5) && !is_frame_rate(f64::NAN) && !is_frame_rate(1e6));
    }
}
