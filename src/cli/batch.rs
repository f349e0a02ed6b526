//! `surfmotion batch`: convert a whole mocap library, onto a 4D character
//! (`--db`) or a scan (`--scan --landmarks`), with the per-clip options of
//! `retarget` and `transfer` (the same option groups, flattened).

use super::given::given;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use surfmotion::batch::schedule::ShardSource;
use surfmotion::batch::{BatchSummary, ClipStatus, Converter, Format};
use surfmotion::jobs::batch::{ClipRate, check_folders, outcome_line, report_text, target_inputs};
use surfmotion::jobs::batch_target::{BatchTarget, check_target_options};
use surfmotion::jobs::batch_verdict::none_failed;
use surfmotion::jobs::{BatchEvent, BatchOptions, ScanTransferOptions, batch_folder};
/// Arguments of `batch`.
#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("target").required(true).args(["db", "scan"])))]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct Args {
    /// `batch merge`: the shards' reports into one.
    #[command(subcommand)]
    pub command: Option<Sub>,
    /// Drive this 4D character database (as `retarget`).
    #[arg(long)]
    pub db: Option<PathBuf>,
    /// Or transfer onto this static mesh (as `transfer`; needs --landmarks).
    #[arg(long, requires = "landmarks", value_parser = super::mesh_spec)]
    pub scan: Option<String>,
    /// Landmarks on the scan.
    #[arg(long)]
    pub landmarks: Option<PathBuf>,
    /// The folder of clips: every .bvh and .amc below it (AMC clips use the
    /// .asf beside them). Links are followed; each clip is converted once.
    #[arg(long, required = true)]
    pub mocap_dir: Option<PathBuf>,
    /// Output folder, outside --mocap-dir: one output per clip in the same
    /// folder tree, plus batch.json, batch.html and batch.svg. One run at a
    /// time writes there (shards of one split may share it): batch.lock
    /// holds its pid.
    #[arg(short, long, required = true)]
    pub output: Option<PathBuf>,
    /// Clips converted at once, 1 to 1024 (default: the number of cores).
    // (`--jobs 0` ran one at a time without a word.)
    #[arg(long, value_parser = super::bounded_count(1, 1024))]
    pub jobs: Option<usize>,
    /// Only shard i of n (1-based): a clip goes to shard h mod n + 1, h a
    /// stable hash of its path under --mocap-dir (adding clips never moves
    /// the others). Without it, a Slurm array task takes its shard from
    /// SLURM_ARRAY_TASK_ID, _MIN, _STEP and _COUNT, and a Kubernetes
    /// Indexed Job from JOB_COMPLETION_INDEX with --shard-count; --shard
    /// wins over both (--shard 1/1: the whole library inside an array).
    /// Merge the shards' reports with `batch merge`.
    #[arg(long, value_name = "i/n")]
    pub shard: Option<String>,
    /// The number of shards, for a Kubernetes Indexed Job (its
    /// completions; the index is JOB_COMPLETION_INDEX). A Slurm array
    /// states its own size.
    #[arg(long, value_name = "N", value_parser = super::bounded_count(1, 1_000_000))]
    pub shard_count: Option<usize>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = surfmotion::jobs::BatchOptions::default().format.into())]
    pub format: super::values::FormatArg,
    /// Redo clips whose output is already complete.
    #[arg(long)]
    pub force: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// How each clip is read (as for `retarget` and `transfer`).
    #[command(flatten)]
    pub clip: super::ClipOpts,
    /// Options of a transfer job (with --scan).
    #[command(flatten)]
    pub scan_job: super::transfer::JobOpts,
    /// Options of a retarget job (with --db).
    #[command(flatten)]
    pub retarget_job: super::retarget::JobOpts,
    #[command(flatten)]
    pub glb: super::mesh::SequenceOutputArgs,
}

/// Subcommands of `batch`.
#[derive(clap::Subcommand)]
pub enum Sub {
    /// Merge the reports of a sharded batch (batch-1ofN.json …
    /// batch-NofN.json, in one shared output folder or one folder per
    /// shard) into the report of the whole library: batch.json, .html and
    /// .svg, the clips in the order one unsharded run lists them. Refuses
    /// shards missing or twice, shards of different splits or jobs, and
    /// shards still running or killed, with the reason.
    #[command(
        after_help = "Example (a Slurm array of 4 into one folder, then):\n  surfmotion batch merge out"
    )]
    Merge(MergeArgs),
}

/// Arguments of `batch merge`.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// The output folders of the shards.
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
    /// Where the merged report goes (default: the one folder given).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print the merged summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Runs `batch merge`.
fn run_merge(a: MergeArgs) -> anyhow::Result<()> {
    let r = surfmotion::jobs::batch::merge_batches(&a.dirs, a.output.as_deref())?;
    print_summary(a.json, &r.summary, &r.files, r.text())
}

/// The summary of a run or merge, as JSON or text; refuses a run with
/// failed clips ([`none_failed`]).
fn print_summary(
    json: bool,
    s: &BatchSummary,
    files: &[PathBuf],
    text: String,
) -> anyhow::Result<()> {
    super::report(json, s, || text)?;
    Ok(none_failed(s, files)?)
}

/// Runs `batch`: the retarget or transfer job (loaded or factored once)
/// as the converter of [`batch_folder`]; `m` are `batch`'s matches (which
/// options the command line gave).
pub fn run_batch(a: Args, m: &clap::ArgMatches) -> anyhow::Result<()> {
    if let Some(Sub::Merge(m)) = a.command {
        return run_merge(m);
    }
    let (Some(mocap_dir), Some(output)) = (a.mocap_dir.clone(), a.output.clone()) else {
        anyhow::bail!("give --mocap-dir and -o (or `batch merge DIR...`)");
    };
    let shard = resolve_shard(&a)?;
    check_args(&a, m, &mocap_dir, &output)?;
    let defaults = BatchOptions::default();
    let opts = BatchOptions {
        shard,
        format: Format::from(a.format),
        force: a.force,
        jobs: a.jobs.unwrap_or(defaults.jobs),
        describe: Some(match (&a.db, &a.scan) {
            (Some(db), _) => format!("retarget --db {}", db.display()),
            (None, scan) => format!("transfer --scan {}", scan.as_deref().unwrap_or_default()),
        }),
    };
    let converter = converter(&a)?;
    let term = std::io::stderr().is_terminal();
    let bar = super::progress(0, "clips");
    let rate = ClipRate::default();
    let log = |e: BatchEvent<'_>| {
        let o = match e {
            BatchEvent::Planned(n) => return bar.set_length(n as u64),
            BatchEvent::Clip(o) => o,
        };
        let frames_per_second = rate.add(o);
        let line = outcome_line(o, &super::flags::as_flags);
        if term {
            bar.inc(1);
            bar.set_message(format!("{frames_per_second:.0} frames/s"));
            if o.status == ClipStatus::Failed {
                bar.println(line);
            }
        } else {
            crate::errln!("{line}");
        }
    };
    let r = batch_folder(&mocap_dir, &output, converter.as_ref(), &opts, &log)?;
    bar.finish_and_clear();
    let text = report_text(&r.summary, &r.files, &super::flags::as_flags);
    print_summary(a.json, &r.summary, &r.files, text)
}

/// The shard from `--shard`, a Slurm array or a Kubernetes Indexed Job
/// (said on stderr unless it is a plain `--shard`).
fn resolve_shard(a: &Args) -> anyhow::Result<Option<String>> {
    let env = |k: &str| std::env::var(k).ok();
    let resolved = surfmotion::batch::schedule::resolve(a.shard.as_deref(), a.shard_count, &env)?;
    if let Some((s, source)) = &resolved
        && !matches!(source, ShardSource::Flag { ignored } if ignored.is_empty())
    {
        crate::errln!("{}", super::flags::as_flags(&source.describe(s)));
    }
    Ok(resolved.map(|(s, _)| s.spelled()))
}

/// Refuses options of the other target (given on the command line `m`,
/// whatever their values) and outputs that would land on a clip or an
/// input, before the character loads.
fn check_args(
    a: &Args,
    m: &clap::ArgMatches,
    mocap_dir: &Path,
    output: &Path,
) -> anyhow::Result<()> {
    let format = format!("--format {}", format!("{:?}", a.format).to_lowercase());
    a.glb
        .refuse_unless_glb(matches!(a.format, super::values::FormatArg::Glb), &format)?;
    a.glb
        .refuse_unless_usda(matches!(a.format, super::values::FormatArg::Usda), &format)?;
    let scan = given::<super::transfer::JobOpts>(m).is_empty();
    let retarget = given::<super::retarget::JobOpts>(m).is_empty();
    check_target_options(a.db.is_some(), scan, retarget)?;
    let (db, scan) = (a.db.as_deref(), a.scan.as_deref());
    let files = [&a.landmarks, &a.clip.rig_map, &a.clip.asf];
    let inputs = target_inputs(db, scan, files.into_iter().flatten());
    check_folders(mocap_dir, output, &inputs, Format::from(a.format))
        .map_err(|e| anyhow::anyhow!(super::flags::as_flags(&e.to_string())))
}

/// The retarget job (with --db) or the scan transfer job (with --scan and
/// --landmarks), loaded or factored once for every clip ([`BatchTarget`]).
fn converter(a: &Args) -> anyhow::Result<Box<dyn Converter>> {
    let load = a.clip.load_options()?;
    let target = match (&a.db, &a.scan, &a.landmarks) {
        (Some(db), _, _) => BatchTarget::Database {
            db: db.clone(),
            options: a.retarget_job.job_options(load, &a.glb),
        },
        (None, Some(scan), Some(lm)) => {
            let scan_job = a.scan_job.job()?;
            BatchTarget::Scan {
                scan: scan.clone(),
                groups: scan_job.groups,
                landmarks: lm.clone(),
                options: ScanTransferOptions {
                    markers: scan_job.markers,
                    fps: scan_job.fps,
                    load,
                    glb: a.glb.options(),
                    usd: a.glb.usd_options(),
                    ..Default::default()
                },
            }
        }
        _ => anyhow::bail!("give --db, or --scan with --landmarks"),
    };
    Ok(target.converter(&super::Bars::new())?)
}
