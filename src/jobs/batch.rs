//! Converting a folder of clips with any [`Converter`] (the retarget and
//! transfer jobs implement it): find and plan the clips (renaming or
//! refusing colliding outputs), take the folder's lock, skip what earlier
//! runs finished, convert in parallel, and write the reports after every
//! clip. Notices (renamed outputs, a stale lock or temporaries removed) are
//! raised as `tracing` events with target [`NOTICE`] and kept in the report.

use crate::batch::{
    BatchSummary, ClipOutcome, ClipStatus, Converter, Earlier, FolderLock, Format, MergeError,
    Planned, RunOptions, Shard, clean_temporaries, find_clips, find_reports, lock_folder, merge,
    plan, read_report, report_stem, run, write_summary,
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
    /// What the report says was run (the CLI gives its command line,
    /// `retarget --db DIR`). Default: the converter's
    /// [`Converter::describe`](crate::batch::Converter::describe).
    pub describe: Option<String>,
}

impl Default for BatchOptions {
    fn default() -> Self {
        let r = RunOptions::default();
        BatchOptions {
            jobs: r.jobs,
            shard: None,
            format: r.format,
            force: r.force,
            describe: None,
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
    /// The clips' folder is a file.
    #[error(
        "`mocap_dir` {}: a file, not a folder (batch converts every clip under a folder; `retarget` or `transfer` converts one)",
        .0.display()
    )]
    NotAFolder(PathBuf),
    /// An output folder or file that cannot be written.
    #[error(transparent)]
    Output(#[from] crate::jobs::outputs::OutputError),
}

/// The report of [`batch_folder`].
#[derive(Debug, Clone)]
pub struct BatchReport {
    /// The summary (also written as JSON, HTML, SVG).
    pub summary: BatchSummary,
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
    let mut notices = Vec::new();
    let (clips, library) = select_clips(mocap_dir, output, opts.format, shard, &mut notices)?;
    std::fs::create_dir_all(output).map_err(|source| crate::util::fsutil::FsError {
        path: output.to_path_buf(),
        source,
    })?;
    // `02/4` is shard 2/4 and writes batch-2of4.json.
    let shard_name = shard.map(|s| s.spelled());
    let stem = report_stem(shard_name.as_deref());
    let lock = take_folder(output, &stem, shard_name.as_deref(), &mut notices)?;
    progress(BatchEvent::Planned(clips.len()));
    // The report keeps what earlier runs recorded for the outputs they
    // wrote, and is rewritten after every clip.
    let earlier = Earlier::load(output, &format!("{stem}.json"));
    let index: std::collections::HashMap<PathBuf, usize> = clips
        .iter()
        .enumerate()
        .map(|(i, p)| (p.clip.clone(), i))
        .collect();
    let slots = Mutex::new(finished_earlier(&clips, &earlier, opts));
    let reports = Reports {
        output,
        what: opts
            .describe
            .clone()
            .unwrap_or_else(|| converter.describe()),
        run_opts: RunOptions {
            jobs: opts.jobs,
            force: opts.force,
            format: opts.format,
        },
        shard_name,
        library: shard.map(|_| library),
        converter,
        t0: Instant::now(),
    };
    if let Ok(slots) = slots.lock() {
        reports.progress(&slots);
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
                reports.progress(&slots);
            }
        }
        progress(BatchEvent::Clip(&o));
    };
    let convert = |clip: &Path, out: &Path| converter.convert(clip, out);
    let mut outcomes = run(mocap_dir, &clips, &reports.run_opts, &convert, &log);
    for o in &mut outcomes {
        earlier.fill(o);
    }
    let summary = reports.summary(outcomes);
    let files = write_summary(output, &summary)?;
    drop(lock);
    Ok(BatchReport {
        summary,
        files,
        notices,
    })
}

/// The clips under `mocap_dir` with their outputs in `output`, this
/// shard's only, and the library's count. Outputs are planned for the
/// whole library, so every shard names them alike; clips that would
/// write one output are renamed (a notice) or refused before any work.
fn select_clips(
    mocap_dir: &Path,
    output: &Path,
    format: Format,
    shard: Option<Shard>,
    notices: &mut Vec<String>,
) -> Result<(Vec<Planned>, usize), BatchError> {
    let all = find_clips(mocap_dir).map_err(|source| BatchError::List {
        path: mocap_dir.to_path_buf(),
        source,
    })?;
    let (planned, renamed) = plan(&all, output, format)?;
    if !renamed.is_empty() {
        notice(
            notices,
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
    Ok((clips, library))
}

/// The output folder's lock; stale locks removed and, when this run is
/// alone there, the temporaries of killed runs (notices both).
fn take_folder(
    output: &Path,
    stem: &str,
    shard: Option<&str>,
    notices: &mut Vec<String>,
) -> Result<FolderLock, BatchError> {
    let lock = lock_folder(output, stem, shard)?;
    for p in &lock.stale_removed {
        notice(
            notices,
            format!("removed the stale lock {} (its run is gone)", p.display()),
        );
    }
    if lock.alone {
        let (gone, bytes) = clean_temporaries(output);
        if !gone.is_empty() {
            notice(
                notices,
                format!(
                    "removed {} unfinished temporar{} ({:.1} MB) left by a killed run",
                    gone.len(),
                    if gone.len() == 1 { "y" } else { "ies" },
                    bytes as f64 / 1e6
                ),
            );
        }
    }
    Ok(lock)
}

/// Per clip, its outcome when an earlier run finished its output (and
/// `force` is off): the clips the run will skip.
fn finished_earlier(
    clips: &[Planned],
    earlier: &Earlier,
    opts: &BatchOptions,
) -> Vec<Option<ClipOutcome>> {
    clips
        .iter()
        .map(|p| {
            let mut o = ClipOutcome::skipped(p.clip.clone(), p.output.clone());
            earlier.fill(&mut o);
            (!opts.force && o.earlier && crate::batch::runner::complete(&p.output, opts.format))
                .then_some(o)
        })
        .collect()
}

/// What a batch's summaries share: the converter, the options, the shard
/// and the clock.
struct Reports<'a> {
    output: &'a Path,
    what: String,
    run_opts: RunOptions,
    shard_name: Option<String>,
    /// The library's clip count, when this is a shard.
    library: Option<usize>,
    converter: &'a dyn Converter,
    t0: Instant,
}

impl Reports<'_> {
    /// The summary of `outcomes` at this point of the run.
    fn summary(&self, outcomes: Vec<ClipOutcome>) -> BatchSummary {
        let mut s = BatchSummary::new(
            self.what.clone(),
            outcomes,
            self.t0.elapsed().as_secs_f64(),
            self.run_opts.jobs,
            self.shard_name.clone(),
        );
        s.set_preparation(self.converter.preparation());
        if self.library.is_some() {
            s.library_clips = self.library;
        }
        s
    }

    /// The unfinished report of the clips ended so far. All three files,
    /// each atomically: a killed run leaves a JSON, page and plot of what
    /// it finished (issue 18, item 3).
    fn progress(&self, slots: &[Option<ClipOutcome>]) {
        let mut s = self.summary(slots.iter().flatten().cloned().collect());
        s.finished = false;
        if let Err(e) = write_summary(self.output, &s) {
            tracing::warn!("report not updated: {e}");
        }
    }
}

/// Refuses, before any work, a `mocap_dir` that is a file, an `output`
/// that cannot be a folder or lies in the clips' folder, and outputs that
/// would land on one of `inputs` (the database's or scan's files).
pub fn check_folders(
    mocap_dir: &Path,
    output: &Path,
    inputs: &[PathBuf],
    format: Format,
) -> Result<(), BatchError> {
    // Said before the character loads: "X: Not a directory (os error
    // 20)" for a clip given as the folder, "/dev/full: File exists (os
    // error 17)" for a file as -o.
    if mocap_dir.exists() && !mocap_dir.is_dir() {
        return Err(BatchError::NotAFolder(mocap_dir.to_path_buf()));
    }
    use crate::jobs::outputs;
    outputs::check_output_folder(
        "-o",
        output,
        "batch writes one output per clip and batch.json, .html and .svg into a folder",
    )?;
    outputs::refuse_output_in_clip_folder("-o", output, mocap_dir)?;
    outputs::refuse_outputs_over_inputs(inputs, mocap_dir, "-o", output, format)?;
    Ok(())
}

/// The input files a batch must not write over: the database's (`db`) or
/// the scan's files and `others` (landmarks, rig map, ASF).
pub fn target_inputs<'a>(
    db: Option<&Path>,
    scan: Option<&str>,
    others: impl Iterator<Item = &'a PathBuf>,
) -> Vec<PathBuf> {
    let mut inputs = Vec::new();
    if let Some(db) = db {
        inputs.extend(crate::jobs::outputs::database_inputs(db));
    }
    if let Some(scan) = scan {
        inputs.extend(crate::mesh::io::input_files(scan, None));
    }
    inputs.extend(others.cloned());
    inputs
}

/// The line a front end prints when a clip ends; `flags` maps option
/// names in a failure's reason to the front end's spelling.
pub fn outcome_line(o: &ClipOutcome, flags: &dyn Fn(&str) -> String) -> String {
    match o.status {
        ClipStatus::Done => format!(
            "done {} ({} frames, {:.1} s)",
            o.clip.display(),
            o.frames,
            o.seconds
        ),
        ClipStatus::Skipped => format!("skipped {} (output complete)", o.clip.display()),
        ClipStatus::Failed => format!(
            "FAILED {}: {}",
            o.clip.display(),
            flags(o.reason.as_deref().unwrap_or(""))
        ),
    }
}

/// Frames converted per second since the clock started, over the clips
/// ended so far (any thread).
#[derive(Debug)]
pub struct ClipRate {
    frames: std::sync::atomic::AtomicUsize,
    t0: Instant,
}

impl Default for ClipRate {
    fn default() -> Self {
        ClipRate {
            frames: 0.into(),
            t0: Instant::now(),
        }
    }
}

impl ClipRate {
    /// Counts a clip's frames (if it was converted); returns the rate.
    pub fn add(&self, o: &ClipOutcome) -> f64 {
        use std::sync::atomic::Ordering::Relaxed;
        let f = if o.status == ClipStatus::Done {
            self.frames.fetch_add(o.frames, Relaxed) + o.frames
        } else {
            self.frames.load(Relaxed)
        };
        f as f64 / self.t0.elapsed().as_secs_f64().max(1e-9)
    }
}

/// The text summary of a batch: its line, the report files and every
/// failed clip with its reason (`flags` as in [`outcome_line`]).
pub fn report_text(s: &BatchSummary, files: &[PathBuf], flags: &dyn Fn(&str) -> String) -> String {
    let mut out = format!("{}\nreport: {}\n", s.line(), joined(files));
    for o in s.outcomes.iter().filter(|o| o.status == ClipStatus::Failed) {
        out += &format!(
            "failed: {}: {}\n",
            o.clip.display(),
            flags(o.reason.as_deref().unwrap_or(""))
        );
    }
    out
}

fn joined(files: &[PathBuf]) -> String {
    files
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(", ")
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
    pub summary: BatchSummary,
    /// The files written.
    pub files: Vec<PathBuf>,
    /// The shard reports read.
    pub reports: Vec<PathBuf>,
}

impl MergeReport {
    /// The text summary: the shards merged, the summary line, the files.
    pub fn text(&self) -> String {
        format!(
            "merged {}: {}\nreport: {}\n",
            crate::batch::summary::count(self.reports.len(), "shard report"),
            self.summary.line(),
            joined(&self.files)
        )
    }
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
        let merged = serde_json::from_str::<BatchSummary>(&text)
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
