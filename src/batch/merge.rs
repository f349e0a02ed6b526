//! Merging the reports of a sharded batch (`batch-1of4.json` …
//! `batch-4of4.json`, in one shared output folder or several) into the
//! report of the whole library, as one unsharded run would have written
//! it: the same clips in the same order, with their outputs, frames,
//! errors and warnings. A split that is not whole is refused with the
//! reason: shards missing, a shard twice, shards of different splits or
//! jobs, a shard still running or killed, a clip in two shards or in a
//! shard it does not belong to (a report of another split rule).

use super::clips::{Shard, shard_of};
use super::summary::BatchSummary;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Why shard reports cannot be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A folder could not be listed, or a report read.
    #[error("{path}: {source}")]
    Read {
        /// The folder or file.
        path: PathBuf,
        /// What the OS said.
        source: std::io::Error,
    },
    /// No `batch-IofN.json` in the folders given.
    #[error(
        "no shard reports (batch-IofN.json) in {0}: give the output folders of a sharded batch"
    )]
    NoReports(String),
    /// A report is not a batch report.
    #[error("{path}: line {line}, column {column}: not a batch report: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// Where.
        line: usize,
        /// Where.
        column: usize,
        /// What serde said.
        message: String,
    },
    /// A report's `shard` is not the one its name says.
    #[error("{path}: its name says shard {named} but it records shard {recorded}")]
    Misnamed {
        /// The file.
        path: PathBuf,
        /// From the name.
        named: String,
        /// From the content.
        recorded: String,
    },
    /// Shards of different splits.
    #[error("shards of different splits cannot be merged: {0}")]
    Splits(String),
    /// One shard twice (two folders ran it).
    #[error("shard {shard} twice: {first} and {second}; merge the folders of one run")]
    Overlap {
        /// `i/n`.
        shard: String,
        /// One report.
        first: PathBuf,
        /// The other.
        second: PathBuf,
    },
    /// Shards missing.
    #[error("missing shard{} {} of {count}: no batch-IofN.json for {} in {dirs}", if .missing.len() == 1 { "" } else { "s" }, .missing.join(", "), if .missing.len() == 1 { "it" } else { "them" })]
    Missing {
        /// The missing `i/n`.
        missing: Vec<String>,
        /// The split.
        count: usize,
        /// The folders searched.
        dirs: String,
    },
    /// A shard has not finished.
    #[error(
        "{path}: shard {shard} has not finished ({clips} clips so far; it still runs or was killed): rerun it, then merge"
    )]
    Unfinished {
        /// The report.
        path: PathBuf,
        /// `i/n`.
        shard: String,
        /// Clips it lists.
        clips: usize,
    },
    /// Shards of different jobs.
    #[error("{first}: {what_first:?}, but {second}: {what_second:?}: shards of different jobs")]
    Different {
        /// One report.
        first: PathBuf,
        /// Its job.
        what_first: String,
        /// The other.
        second: PathBuf,
        /// Its job.
        what_second: String,
    },
    /// A clip in two shards, or in a shard its path does not hash to.
    #[error("{clip}: {why}")]
    Clip {
        /// The clip.
        clip: PathBuf,
        /// What is wrong.
        why: String,
    },
    /// The shards saw libraries of different sizes, or do not add up.
    #[error("{0}")]
    Library(String),
}

/// One shard's report.
#[derive(Debug, Clone)]
pub struct ShardReport {
    /// The file.
    pub path: PathBuf,
    /// The shard its name says.
    pub shard: Shard,
    /// What it holds.
    pub summary: BatchSummary,
}

/// The shard a report's file name says (`batch-2of4.json` → 2/4).
pub(crate) fn shard_of_report(name: &str) -> Option<Shard> {
    let mid = name.strip_prefix("batch-")?.strip_suffix(".json")?;
    let (i, n) = mid.split_once("of")?;
    if i.starts_with('0') || n.starts_with('0') {
        return None;
    }
    Shard::parse(&format!("{i}/{n}")).ok()
}

/// Every shard report (`batch-IofN.json`) in `dirs`, sorted by folder and
/// name.
pub fn find_reports(dirs: &[PathBuf]) -> Result<Vec<PathBuf>, MergeError> {
    let mut found = Vec::new();
    for d in dirs {
        let rd = std::fs::read_dir(d).map_err(|source| MergeError::Read {
            path: d.clone(),
            source,
        })?;
        let mut here: Vec<PathBuf> = rd
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                p.is_file()
                    && shard_of_report(&p.file_name().unwrap_or_default().to_string_lossy())
                        .is_some()
            })
            .collect();
        here.sort();
        found.extend(here);
    }
    if found.is_empty() {
        return Err(MergeError::NoReports(list(dirs)));
    }
    Ok(found)
}

fn list(dirs: &[PathBuf]) -> String {
    dirs.iter()
        .map(|d| d.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Reads one shard report.
pub fn read_report(path: &Path) -> Result<ShardReport, MergeError> {
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    let Some(shard) = shard_of_report(&name) else {
        return Err(MergeError::Misnamed {
            path: path.to_path_buf(),
            named: "none (not batch-IofN.json)".into(),
            recorded: "?".into(),
        });
    };
    let text = crate::util::fsutil::read_text(path).map_err(|e| MergeError::Read {
        path: path.to_path_buf(),
        source: e.source,
    })?;
    let summary: BatchSummary = serde_json::from_str(&text).map_err(|e| MergeError::Parse {
        path: path.to_path_buf(),
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    })?;
    let recorded = summary.shard.clone().unwrap_or_else(|| "none".into());
    if Shard::parse(&recorded).ok() != Some(shard) {
        return Err(MergeError::Misnamed {
            path: path.to_path_buf(),
            named: shard.spelled(),
            recorded,
        });
    }
    Ok(ShardReport {
        path: path.to_path_buf(),
        shard,
        summary,
    })
}

/// The report of the whole library from the reports of every shard of one
/// split (`dirs` names the folders searched, for the messages). The
/// outcomes come in the clips' sorted order, as an unsharded run lists
/// them; `seconds` is the longest shard's (the wall clock when the shards
/// ran at once), `jobs` and the preparations add up; `merged_from` lists
/// the reports.
pub fn merge(reports: &[ShardReport], dirs: &[PathBuf]) -> Result<BatchSummary, MergeError> {
    let Some(first) = reports.first() else {
        return Err(MergeError::NoReports(list(dirs)));
    };
    let mut splits: BTreeMap<usize, Vec<String>> = BTreeMap::new();
    for r in reports {
        splits
            .entry(r.shard.count)
            .or_default()
            .push(r.path.display().to_string());
    }
    if splits.len() > 1 {
        return Err(MergeError::Splits(
            splits
                .iter()
                .map(|(n, files)| format!("of {n}: {}", files.join(", ")))
                .collect::<Vec<_>>()
                .join("; "),
        ));
    }
    let count = first.shard.count;
    let mut by_index: BTreeMap<usize, &ShardReport> = BTreeMap::new();
    for r in reports {
        if let Some(other) = by_index.insert(r.shard.index, r) {
            return Err(MergeError::Overlap {
                shard: r.shard.spelled(),
                first: other.path.clone(),
                second: r.path.clone(),
            });
        }
    }
    let missing: Vec<String> = (1..=count)
        .filter(|i| !by_index.contains_key(i))
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(MergeError::Missing {
            missing,
            count,
            dirs: list(dirs),
        });
    }
    for r in reports {
        if !r.summary.finished {
            return Err(MergeError::Unfinished {
                path: r.path.clone(),
                shard: r.shard.spelled(),
                clips: r.summary.outcomes.len(),
            });
        }
        if r.summary.what != first.summary.what {
            return Err(MergeError::Different {
                first: first.path.clone(),
                what_first: first.summary.what.clone(),
                second: r.path.clone(),
                what_second: r.summary.what.clone(),
            });
        }
        if r.summary.library_clips != first.summary.library_clips {
            return Err(MergeError::Library(format!(
                "{} saw a library of {} clips, {} one of {}: the shards ran on different libraries",
                first.path.display(),
                opt(first.summary.library_clips),
                r.path.display(),
                opt(r.summary.library_clips)
            )));
        }
    }
    let mut owner: BTreeMap<PathBuf, &ShardReport> = BTreeMap::new();
    for r in by_index.values() {
        for o in &r.summary.outcomes {
            let belongs = shard_of(&o.clip, count);
            if belongs != r.shard.index {
                return Err(MergeError::Clip {
                    clip: o.clip.clone(),
                    why: format!(
                        "listed by {} (shard {}) but its path puts it in shard {belongs}/{count}: a report of another split rule; rerun that shard",
                        r.path.display(),
                        r.shard.spelled()
                    ),
                });
            }
            if let Some(other) = owner.insert(o.clip.clone(), r) {
                return Err(MergeError::Clip {
                    clip: o.clip.clone(),
                    why: format!(
                        "listed twice, by {} and {}",
                        other.path.display(),
                        r.path.display()
                    ),
                });
            }
        }
    }
    if let Some(n) = first.summary.library_clips
        && owner.len() != n
    {
        return Err(MergeError::Library(format!(
            "the shards list {} clips of a library of {n}: a shard's report lost clips",
            owner.len()
        )));
    }
    let mut outcomes: Vec<_> = by_index
        .values()
        .flat_map(|r| r.summary.outcomes.iter().cloned())
        .collect();
    outcomes.sort_by(|a, b| a.clip.cmp(&b.clip));
    let seconds = reports
        .iter()
        .map(|r| r.summary.seconds)
        .fold(0.0, f64::max);
    let jobs = reports.iter().map(|r| r.summary.jobs).sum();
    let mut s = BatchSummary::new(first.summary.what.clone(), outcomes, seconds, jobs, None);
    s.factorisations = reports.iter().map(|r| r.summary.factorisations).sum();
    s.prepare_seconds = reports.iter().map(|r| r.summary.prepare_seconds).sum();
    s.library_clips = first.summary.library_clips;
    s.merged_from = by_index.values().map(|r| r.path.clone()).collect();
    Ok(s)
}

fn opt(n: Option<usize>) -> String {
    n.map_or_else(|| "unknown size".into(), |n| n.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::{ClipOutcome, ClipStatus};

    fn outcome(clip: &str) -> ClipOutcome {
        ClipOutcome {
            clip: clip.into(),
            output: Path::new("out").join(clip).with_extension("glb"),
            status: ClipStatus::Done,
            frames: 10,
            seconds: 1.0,
            error_cm: Some(0.5),
            warnings: Vec::new(),
            reason: None,
            fixed_seconds: None,
            earlier: false,
        }
    }

    /// The reports an `n`-way split of `clips` writes.
    fn split(clips: &[&str], n: usize) -> Vec<ShardReport> {
        (1..=n)
            .map(|i| {
                let shard = Shard { index: i, count: n };
                let mine = clips
                    .iter()
                    .filter(|c| shard.contains(Path::new(c)))
                    .map(|c| outcome(c))
                    .collect();
                let mut summary = BatchSummary::new(
                    "retarget --db x".into(),
                    mine,
                    i as f64,
                    1,
                    Some(shard.spelled()),
                );
                summary.library_clips = Some(clips.len());
                ShardReport {
                    path: PathBuf::from(format!("out/batch-{i}of{n}.json")),
                    shard,
                    summary,
                }
            })
            .collect()
    }

    const CLIPS: [&str; 9] = [
        "01/01_01.amc",
        "02/02_01.amc",
        "02/02_02.amc",
        "02/02_03.amc",
        "a.bvh",
        "b.bvh",
        "c/d/e.bvh",
        "walk.bvh",
        "z.fbx",
    ];

    #[test]
    fn a_whole_split_merges_into_the_sorted_library() {
        let r = split(&CLIPS, 4);
        let s = merge(&r, &[]).unwrap();
        let got: Vec<String> = s
            .outcomes
            .iter()
            .map(|o| o.clip.display().to_string())
            .collect();
        assert_eq!(got, CLIPS);
        assert_eq!((s.clips, s.done, s.frames, s.jobs), (9, 9, 90, 4));
        assert_eq!(s.seconds, 4.0);
        assert_eq!(s.shard, None);
        assert_eq!(s.merged_from.len(), 4);
        // Round trip through the JSON the shards write.
        let text = serde_json::to_string(&r[0].summary).unwrap();
        let back: BatchSummary = serde_json::from_str(&text).unwrap();
        assert_eq!(back.outcomes.len(), r[0].summary.outcomes.len());
    }

    #[test]
    fn an_incomplete_or_mixed_split_is_refused_with_the_reason() {
        let r = split(&CLIPS, 4);
        let e = merge(&r[..3], &[PathBuf::from("out")]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "missing shard 4/4 of 4: no batch-IofN.json for it in out"
        );
        let mut twice = r.clone();
        twice.push(r[1].clone());
        assert!(
            merge(&twice, &[])
                .unwrap_err()
                .to_string()
                .contains("shard 2/4 twice")
        );
        let mut mixed = r.clone();
        mixed.push(split(&CLIPS, 3).remove(0));
        assert!(
            merge(&mixed, &[])
                .unwrap_err()
                .to_string()
                .contains("different splits")
        );
        let mut running = r.clone();
        running[2].summary.finished = false;
        assert!(
            merge(&running, &[])
                .unwrap_err()
                .to_string()
                .contains("has not finished")
        );
        let mut other_job = r.clone();
        other_job[3].summary.what = "transfer --scan y".into();
        assert!(
            merge(&other_job, &[])
                .unwrap_err()
                .to_string()
                .contains("different jobs")
        );
        // A clip in the wrong shard (the old sorted-list split) or lost.
        let mut moved = r.clone();
        let c = moved[0].summary.outcomes.pop().unwrap();
        moved[1].summary.outcomes.push(c);
        assert!(
            merge(&moved, &[])
                .unwrap_err()
                .to_string()
                .contains("puts it in shard")
        );
        let mut lost = r.clone();
        let k = lost
            .iter()
            .position(|x| !x.summary.outcomes.is_empty())
            .unwrap();
        lost[k].summary.outcomes.pop();
        assert!(
            merge(&lost, &[])
                .unwrap_err()
                .to_string()
                .contains("lost clips")
        );
        let mut grown = r.clone();
        grown[0].summary.library_clips = Some(10);
        assert!(
            merge(&grown, &[])
                .unwrap_err()
                .to_string()
                .contains("different libraries")
        );
    }

    #[test]
    fn report_names() {
        assert_eq!(
            shard_of_report("batch-2of4.json"),
            Some(Shard { index: 2, count: 4 })
        );
        for bad in [
            "batch.json",
            "batch-5of4.json",
            "batch-02of4.json",
            "batch-2of4.html",
        ] {
            assert_eq!(shard_of_report(bad), None, "{bad}");
        }
    }
}
