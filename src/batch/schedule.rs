//! Which shard a batch runs, from the scheduler that started it: an explicit
//! `--shard i/n`, a Slurm job array (`SLURM_ARRAY_TASK_ID`, `_MIN`, `_STEP`,
//! `_COUNT`, `_MAX`) or a Kubernetes Indexed Job (`JOB_COMPLETION_INDEX`
//! with a shard count given), with no wrapper script. The environment is
//! passed in as a lookup, so the rules are pure functions.
//!
//! Rules: an explicit shard wins over the environment (it is said which
//! variables were ignored); a shard count that disagrees with the explicit
//! shard or with the Slurm array, a Slurm array and an Indexed Job that
//! name different shards, a task id outside its array, an index without a
//! count and a count without an index are errors of one line.

use super::clips::Shard;

/// Where a batch's shard came from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ShardSource {
    /// `--shard i/n`; the scheduler variables it overrode, if any
    /// (`SLURM_ARRAY_TASK_ID=3`).
    Flag {
        /// The variables set but not used.
        ignored: Vec<String>,
    },
    /// A Slurm job array.
    Slurm {
        /// `SLURM_ARRAY_TASK_ID`.
        id: u64,
        /// `SLURM_ARRAY_TASK_MIN` (0 when unset).
        min: u64,
        /// `SLURM_ARRAY_TASK_STEP` (1 when unset).
        step: u64,
    },
    /// A Kubernetes Indexed Job.
    Kubernetes {
        /// `JOB_COMPLETION_INDEX` (0-based).
        index: u64,
    },
}

impl ShardSource {
    /// How the shard was chosen, for a notice (`shard 2/4 from
    /// SLURM_ARRAY_TASK_ID=1 (array from 0, step 1)`).
    pub fn describe(&self, shard: &Shard) -> String {
        let s = shard.spelled();
        match self {
            ShardSource::Flag { ignored } if ignored.is_empty() => {
                format!("shard {s} (`BatchOptions::shard`)")
            }
            ShardSource::Flag { ignored } => format!(
                "shard {s} from `BatchOptions::shard`, which wins over {}",
                ignored.join(", ")
            ),
            ShardSource::Slurm { id, min, step } => format!(
                "shard {s} from the Slurm array: SLURM_ARRAY_TASK_ID={id} (array from {min}, step {step}, {} tasks)",
                shard.count
            ),
            ShardSource::Kubernetes { index } => format!(
                "shard {s} from the Kubernetes Indexed Job: JOB_COMPLETION_INDEX={index} of {}",
                shard.count
            ),
        }
    }
}

/// Why no shard could be chosen.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ShardError {
    /// `--shard` is not `i/n` with 1 ≤ i ≤ n.
    #[error("{0}")]
    Flag(String),
    /// A scheduler variable is not a whole number.
    #[error("{var}={value:?}: not a whole number")]
    NotANumber {
        /// The variable.
        var: &'static str,
        /// Its value.
        value: String,
    },
    /// Two sources name different splits or shards.
    #[error("{0}")]
    Conflict(String),
    /// Something needed is missing.
    #[error("{0}")]
    Missing(String),
    /// The task is not in its array, or the array is not a stepped range.
    #[error("{0}")]
    Array(String),
}

const K8S_VAR: &str = "JOB_COMPLETION_INDEX";

fn number(
    env: &dyn Fn(&str) -> Option<String>,
    var: &'static str,
) -> Result<Option<u64>, ShardError> {
    match env(var) {
        None => Ok(None),
        Some(v) if v.trim().is_empty() => Ok(None),
        Some(v) => v
            .trim()
            .parse()
            .map(Some)
            .map_err(|_| ShardError::NotANumber { var, value: v }),
    }
}

/// The shard of a Slurm array task: (0-based index, count, source).
fn slurm(
    env: &dyn Fn(&str) -> Option<String>,
    count_flag: Option<usize>,
) -> Result<Option<(u64, u64, ShardSource)>, ShardError> {
    let Some(id) = number(env, "SLURM_ARRAY_TASK_ID")? else {
        return Ok(None);
    };
    let min = number(env, "SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
    let step = number(env, "SLURM_ARRAY_TASK_STEP")?.unwrap_or(1).max(1);
    let max = number(env, "SLURM_ARRAY_TASK_MAX")?;
    let count = number(env, "SLURM_ARRAY_TASK_COUNT")?;
    let from_range = max.filter(|&m| m >= min).map(|m| (m - min) / step + 1);
    let count = match (count, from_range) {
        (Some(c), Some(r)) if c != r => {
            return Err(ShardError::Array(format!(
                "SLURM_ARRAY_TASK_COUNT={c} but the array {min}-{}:{step} holds {r} tasks: a split needs an evenly stepped range (an array 0-{}); or give `BatchOptions::shard` i/n",
                max.unwrap_or(0),
                c.saturating_sub(1)
            )));
        }
        (Some(c), _) | (None, Some(c)) => c,
        (None, None) => match count_flag {
            Some(c) => c as u64,
            None => {
                return Err(ShardError::Missing(format!(
                    "SLURM_ARRAY_TASK_ID={id} is set but not SLURM_ARRAY_TASK_COUNT or _MAX: give `shard_count` N (the array's size) or `BatchOptions::shard` i/n"
                )));
            }
        },
    };
    if let Some(c) = count_flag
        && c as u64 != count
    {
        return Err(ShardError::Conflict(format!(
            "`shard_count` {c} disagrees with the Slurm array of {count} tasks (SLURM_ARRAY_TASK_COUNT); leave `shard_count` out"
        )));
    }
    if id < min || (id - min) % step != 0 || (id - min) / step >= count {
        return Err(ShardError::Array(format!(
            "SLURM_ARRAY_TASK_ID={id} is not task 0..{count} of an array from {min} in steps of {step}: a split needs an evenly stepped range; or give `BatchOptions::shard` i/n"
        )));
    }
    Ok(Some((
        (id - min) / step,
        count,
        ShardSource::Slurm { id, min, step },
    )))
}

/// The shard of this run: `flag` (`--shard i/n`) if given, else the
/// scheduler's (`env` looks a variable up, e.g. `|k| std::env::var(k).ok()`);
/// `count` is the shard count (`--shard-count` on the command line). None: the whole library.
pub fn resolve(
    flag: Option<&str>,
    count: Option<usize>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<Option<(Shard, ShardSource)>, ShardError> {
    if count == Some(0) {
        return Err(ShardError::Flag("`shard_count` 0: need at least 1".into()));
    }
    if let Some(f) = flag {
        let shard = Shard::parse(f).map_err(ShardError::Flag)?;
        if let Some(c) = count
            && c != shard.count
        {
            return Err(ShardError::Conflict(format!(
                "`BatchOptions::shard` {f} and `shard_count` {c} name different splits; give one"
            )));
        }
        let ignored = ["SLURM_ARRAY_TASK_ID", K8S_VAR]
            .iter()
            .filter_map(|v| env(v).map(|x| format!("{v}={x}")))
            .collect();
        return Ok(Some((shard, ShardSource::Flag { ignored })));
    }
    let s = slurm(env, count)?;
    let k = match number(env, K8S_VAR)? {
        None => None,
        Some(index) => {
            let n = match (count, &s) {
                (Some(c), _) => c as u64,
                (None, Some((_, c, _))) => *c,
                (None, None) => {
                    return Err(ShardError::Missing(format!(
                        "{K8S_VAR}={index} is set (a Kubernetes Indexed Job) but not `shard_count`: give the Job's completions, e.g. `shard_count` N"
                    )));
                }
            };
            if index >= n {
                return Err(ShardError::Array(format!(
                    "{K8S_VAR}={index} is not below `shard_count` {n}"
                )));
            }
            Some((index, n, ShardSource::Kubernetes { index }))
        }
    };
    let chosen = match (s, k) {
        (Some(a), Some(b)) if (a.0, a.1) != (b.0, b.1) => {
            return Err(ShardError::Conflict(format!(
                "the Slurm array says shard {}/{} and {K8S_VAR} says {}/{}; unset one or give `BatchOptions::shard` i/n",
                a.0 + 1,
                a.1,
                b.0 + 1,
                b.1
            )));
        }
        (Some(a), _) => a,
        (None, Some(b)) => b,
        (None, None) => {
            return match count {
                Some(c) => Err(ShardError::Missing(format!(
                    "`shard_count` {c} needs a shard index: {K8S_VAR} (a Kubernetes Indexed Job), SLURM_ARRAY_TASK_ID (a Slurm array) or `BatchOptions::shard` i/{c}"
                ))),
                None => Ok(None),
            };
        }
    };
    let (index, n, source) = chosen;
    let shard = Shard {
        index: index as usize + 1,
        count: n as usize,
    };
    Ok(Some((shard, source)))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(vars: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k: &str| {
            vars.iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    }

    fn shard(flag: Option<&str>, count: Option<usize>, vars: &[(&str, &str)]) -> Option<String> {
        resolve(flag, count, &env(vars))
            .unwrap()
            .map(|(s, _)| s.spelled())
    }

    fn error(flag: Option<&str>, count: Option<usize>, vars: &[(&str, &str)]) -> String {
        let e = resolve(flag, count, &env(vars)).unwrap_err().to_string();
        assert!(!e.contains('\n'), "one line: {e}");
        e
    }

    const ARRAY_0_3: [(&str, &str); 4] = [
        ("SLURM_ARRAY_TASK_ID", "2"),
        ("SLURM_ARRAY_TASK_MIN", "0"),
        ("SLURM_ARRAY_TASK_MAX", "3"),
        ("SLURM_ARRAY_TASK_COUNT", "4"),
    ];

    #[test]
    fn slurm_arrays_from_any_first_index_and_step() {
        assert_eq!(shard(None, None, &[]), None);
        assert_eq!(shard(None, None, &ARRAY_0_3).as_deref(), Some("3/4"));
        // --array=1-8: task 1 is the first shard.
        let one_based = [
            ("SLURM_ARRAY_TASK_ID", "1"),
            ("SLURM_ARRAY_TASK_MIN", "1"),
            ("SLURM_ARRAY_TASK_MAX", "8"),
            ("SLURM_ARRAY_TASK_COUNT", "8"),
        ];
        assert_eq!(shard(None, None, &one_based).as_deref(), Some("1/8"));
        // --array=100-106:2 (task 104 is the third of four).
        let stepped = [
            ("SLURM_ARRAY_TASK_ID", "104"),
            ("SLURM_ARRAY_TASK_MIN", "100"),
            ("SLURM_ARRAY_TASK_MAX", "106"),
            ("SLURM_ARRAY_TASK_STEP", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        assert_eq!(shard(None, None, &stepped).as_deref(), Some("3/4"));
        // The count agreeing is fine; disagreeing is a conflict.
        assert_eq!(shard(None, Some(4), &ARRAY_0_3).as_deref(), Some("3/4"));
        assert!(error(None, Some(5), &ARRAY_0_3).contains("disagrees"));
        // --array=0,3,7: not a range a split can use.
        let listed = [
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_MAX", "7"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ];
        assert!(error(None, None, &listed).contains("evenly stepped"));
        let outside = [
            ("SLURM_ARRAY_TASK_ID", "9"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        assert!(error(None, None, &outside).contains("not task"));
        let junk = [
            ("SLURM_ARRAY_TASK_ID", "x"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
        ];
        assert!(error(None, None, &junk).contains("whole number"));
    }

    #[test]
    fn kubernetes_indexed_jobs_need_the_count() {
        let k = [("JOB_COMPLETION_INDEX", "0")];
        assert_eq!(shard(None, Some(5), &k).as_deref(), Some("1/5"));
        assert!(error(None, None, &k).contains("`shard_count`"));
        assert!(error(None, Some(5), &[("JOB_COMPLETION_INDEX", "5")]).contains("not below"));
        assert!(error(None, Some(3), &[]).contains("needs a shard index"));
        // A Slurm array and an Indexed Job that agree; that disagree.
        let both = [
            ("SLURM_ARRAY_TASK_ID", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("JOB_COMPLETION_INDEX", "2"),
        ];
        assert_eq!(shard(None, None, &both).as_deref(), Some("3/4"));
        let clash = [
            ("SLURM_ARRAY_TASK_ID", "2"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("JOB_COMPLETION_INDEX", "1"),
        ];
        assert!(error(None, None, &clash).contains("says shard 3/4"));
    }

    #[test]
    fn an_explicit_shard_wins_and_says_what_it_overrode() {
        let (s, src) = resolve(Some("1/2"), None, &env(&ARRAY_0_3))
            .unwrap()
            .unwrap();
        assert_eq!(s.spelled(), "1/2");
        assert_eq!(
            src,
            ShardSource::Flag {
                ignored: vec!["SLURM_ARRAY_TASK_ID=2".into()]
            }
        );
        assert!(src.describe(&s).contains("wins over SLURM_ARRAY_TASK_ID=2"));
        assert!(error(Some("1/2"), Some(3), &[]).contains("different splits"));
        assert!(error(Some("3/2"), None, &[]).contains("1 ≤ i ≤ n"));
        assert!(error(None, Some(0), &[]).contains("at least 1"));
    }
}
