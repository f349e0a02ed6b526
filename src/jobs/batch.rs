//! Converting a folder of clips with any [`Converter`] (the retarget and
//! transfer jobs implement it): find and plan the clips (renaming or
//! refusing colliding outputs), take the folder's lock, skip what earlier
//! runs finished, convert in parallel, and write the reports after every
//! clip. Notices (renamed outputs, a stale lock or temporaries removed) are
//! raised as `tracing` events with target [`NOTICE`] and kept in the report.

use crate::batch::{
    ClipOutcome, ClipStatus, Converter, Earlier, Format, MergeError, RunOptions, Shard, Summary,
    clean_temporaries, find_clips, find_reports, lock_folder, merge, plan, read_report,
    report_stem, run, write_summary,
};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// The `tracing` target of notices a front end shows as plain lines.
pub const NOTICE: &str = "surfmotion::notice";

/// Options of [`batch_folder`].
#[derive(Debug, Clone)]
pub struct BatchOptions {
    /// Clips converted at once. Default: the number of cores.
    pub jobs: usize,
    /// Only this shard (`i/n`). Default: all clips.
    pub shard: Option<String>,
    /// Output format. Default: GLB.
    pub format: Format,
    /// Redo clips whose output is complete. Default: false.
    pub force: bool,
}

impl Default for BatchOptions {
    fn default() -> Self {
        let r = RunOptions::default();
        BatchOptions {
            jobs: r.jobs,
            shard: None,
            format: r.format,
            force: r.force,
        }
    }
}

/// What can stop a batch before its clips run (a failing clip does not).
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// The shard is not `i/n`.
    #[error("{0}")]
    Shard(String),
    /// The mocap folder cannot be listed.
    #[error("{path}: {source}")]
    List {
        /// The folder.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Outputs collide.
    #[error(transparent)]
    Collision(#[from] crate::batch::CollisionError),
    /// Another run holds the folder.
    #[error(transparent)]
    Lock(#[from] crate::batch::LockError),
    /// A report could not be written.
    #[error(transparent)]
    Fs(#[from] crate::util::fsutil::FsError),
}

/// The report of [`batch_folder`].
#[derive(Debug, Clone)]
pub struct BatchReport {
    /// The summary (also written as JSON, HTML, SVG).
    pub summary: Summary,
    /// The report files written.
    pub files: Vec<PathBuf>,
    /// Notices raised (also as `tracing` events with target [`NOTICE`]).
    pub notices: Vec<String>,
}

fn notice(notices: &mut Vec<String>, msg: String) {
    tracing::warn!(target: "surfmotion::notice", "{msg}");
    notices.push(msg);
}

/// What [`batch_folder`] tells its caller as it goes.
pub enum BatchEvent<'a> {
    /// The clips to convert (this shard's), once planned.
    Planned(usize),
    /// A clip ended (from any thread).
    Clip(&'a ClipOutcome),
}

/// Converts every clip under `mocap_dir` with `converter` into `output`
/// (one output per clip in the same folder tree, plus `batch.json`,
/// `batch.html`, `batch.svg`). `progress` hears the plan and each clip's
/// end. Failed clips are in the summary, not an error.
pub fn batch_folder(
    mocap_dir: &Path,
    output: &Path,
    converter: &dyn Converter,
    opts: &BatchOptions,
    progress: &(dyn Fn(BatchEvent<'_>) + Sync),
) -> Result<BatchReport, BatchError> {
    let shard = match &opts.shard {
        Some(s) => Some(Shard::parse(s).map_err(BatchError::Shard)?),
        None => None,
    };
    // `02/4` is shard 2/4 and writes batch-2of4.json.
    let shard_name = shard.map(|s| s.spelled());
    let library_clips = |s: &mut Summary, n: usize| {
        if shard.is_some() {
            s.library_clips = Some(n);
        }
    };
    let mut notices = Vec::new();
    let all = find_clips(mocap_dir).map_err(|source| BatchError::List {
        path: mocap_dir.to_path_buf(),
        source,
    })?;
    // Outputs of the whole library, so every shard names them alike; clips
    // that would write one output are renamed or refused before any work.
    let (planned, renamed) = plan(&all, output, opts.format)?;
    if !renamed.is_empty() {
        notice(
            &mut notices,
            format!(
                "{} would write the same output; named with their extension:\n  {}",
                crate::batch::summary::count(renamed.len(), "clip"),
                renamed.join("\n  ")
            ),
        );
    }
    let library = planned.len();
    let clips = match shard {
        Some(s) => s.select(&planned),
        None => planned,
    };
    std::fs::create_dir_all(output).map_err(|source| crate::util::fsutil::FsError {
        path: output.to_path_buf(),
        source,
    })?;
    let stem = report_stem(shard_name.as_deref());
    let lock = lock_folder(output, &stem, shard_name.as_deref())?;
    for p in &lock.stale_removed {
        notice(
            &mut notices,
            format!("removed the stale lock {} (its run is gone)", p.display()),
        );
    }
    if lock.alone {
        let (gone, bytes) = clean_temporaries(output);
        if !gone.is_empty() {
            notice(
                &mut notices,
                format!(
                    "removed {} unfinished temporar{} ({:.1} MB) left by a killed run",
                    gone.len(),
                    if gone.len() == 1 { "y" } else { "ies" },
                    bytes as f64 / 1e6
                ),
            );
        }
    }
    progress(BatchEvent::Planned(clips.len()));
    let what = converter.describe();
    let run_opts = RunOptions {
        jobs: opts.jobs,
        force: opts.force,
        format: opts.format,
    };
    // The report keeps what earlier runs recorded for the outputs they
    // wrote, and is rewritten after every clip.
    let earlier = Earlier::load(output, &format!("{stem}.json"));
    let index: std::collections::HashMap<PathBuf, usize> = clips
        .iter()
        .enumerate()
        .map(|(i, p)| (p.clip.clone(), i))
        .collect();
    let slots: Mutex<Vec<Option<ClipOutcome>>> = Mutex::new(
        clips
            .iter()
            .map(|p| {
                let mut o = ClipOutcome {
                    clip: p.clip.clone(),
                    output: p.output.clone(),
                    status: ClipStatus::Skipped,
                    frames: 0,
                    seconds: 0.0,
                    error_cm: None,
                    warnings: Vec::new(),
                    reason: None,
                    fixed_seconds: None,
                    earlier: false,
                };
                earlier.fill(&mut o);
                (!opts.force && o.earlier && crate::batch::runner::complete(&p.output, opts.format))
                    .then_some(o)
            })
            .collect(),
    );
    let t0 = Instant::now();
    let progress_report = |slots: &[Option<ClipOutcome>]| {
        let mut s = Summary::new(
            what.clone(),
            slots.iter().flatten().cloned().collect(),
            t0.elapsed().as_secs_f64(),
            run_opts.jobs,
            shard_name.clone(),
        );
        s.finished = false;
        library_clips(&mut s, library);
        s.set_preparation(converter.preparation());
        // All three files, each atomically: a killed run leaves a JSON,
        // page and plot of what it finished (issue 18, item 3).
        if let Err(e) = write_summary(output, &s) {
            tracing::warn!("report not updated: {e}");
        }
    };
    if let Ok(slots) = slots.lock() {
        progress_report(&slots);
    }
    let log = |o: &ClipOutcome| {
        let mut o = o.clone();
        earlier.fill(&mut o);
        if let Ok(mut slots) = slots.lock()
            && let Some(&i) = index.get(&o.clip)
        {
            slots[i] = Some(o.clone());
            // A skipped output was listed before the run (when its earlier
            // record is known): rewrite only for news.
            if o.status != ClipStatus::Skipped {
                progress_report(&slots);
            }
        }
        progress(BatchEvent::Clip(&o));
    };
    let convert = |clip: &Path, out: &Path| converter.convert(clip, out);
    let mut outcomes = run(mocap_dir, &clips, &run_opts, &convert, &log);
    for o in &mut outcomes {
        earlier.fill(o);
    }
    let summary = Summary::new(
        what,
        outcomes,
        t0.elapsed().as_secs_f64(),
        run_opts.jobs,
        shard_name.clone(),
    );
    let mut summary = summary;
    summary.set_preparation(converter.preparation());
    library_clips(&mut summary, library);
    let files = write_summary(output, &summary)?;
    drop(lock);
    Ok(BatchReport {
        summary,
        files,
        notices,
    })
}

/// What can stop [`merge_batches`].
#[derive(Debug, thiserror::Error)]
pub enum MergeBatchError {
    /// The shard reports do not make one whole split.
    #[error(transparent)]
    Merge(#[from] MergeError),
    /// Several folders and no output folder for the merged report.
    #[error("the shards' reports are in {0} folders: give -o, the folder for the merged report")]
    NoOutput(usize),
    /// The output folder holds the report of an unsharded run.
    #[error(
        "{0}: the report of an unsharded run, which the merged report would replace; merge into another folder (-o) or remove it"
    )]
    WouldReplace(PathBuf),
    /// A report could not be written.
    #[error(transparent)]
    Fs(#[from] crate::util::fsutil::FsError),
}

/// The report of [`merge_batches`].
#[derive(Debug, Clone)]
pub struct MergeReport {
    /// The merged summary (also written as `batch.json`, `.html`, `.svg`).
    pub summary: Summary,
    /// The files written.
    pub files: Vec<PathBuf>,
    /// The shard reports read.
    pub reports: Vec<PathBuf>,
}

/// Merges the shard reports (`batch-IofN.json`) found in `dirs` into the
/// report of the whole library (`batch.json`, `batch.html`, `batch.svg`)
/// in `output`, or in the one folder of `dirs` when `output` is None.
/// Refuses, with the reason, a split with shards missing or twice, shards
/// of different splits or jobs, unfinished shards, and an output folder
/// whose `batch.json` is an unsharded run's own report.
pub fn merge_batches(
    dirs: &[PathBuf],
    output: Option<&Path>,
) -> Result<MergeReport, MergeBatchError> {
    let out = match (output, dirs) {
        (Some(o), _) => o.to_path_buf(),
        (None, [one]) => one.clone(),
        (None, many) => return Err(MergeBatchError::NoOutput(many.len())),
    };
    let paths = find_reports(dirs)?;
    let reports = paths
        .iter()
        .map(|p| read_report(p))
        .collect::<Result<Vec<_>, _>>()?;
    let summary = merge(&reports, dirs)?;
    let own = out.join("batch.json");
    if own.is_file() {
        let text = crate::util::fsutil::read_text(&own)?;
        let merged = serde_json::from_str::<Summary>(&text)
            .map(|s| !s.merged_from.is_empty())
            .unwrap_or(false);
        if !merged {
            return Err(MergeBatchError::WouldReplace(own));
        }
    }
    std::fs::create_dir_all(&out).map_err(|source| crate::util::fsutil::FsError {
        path: out.clone(),
        source,
    })?;
    let files = write_summary(&out, &summary)?;
    Ok(MergeReport {
        summary,
        files,
        reports: paths,
    })
}
