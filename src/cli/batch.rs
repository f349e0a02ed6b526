//! `surfmotion batch`: convert a whole mocap library, onto a 4D character
//! (`--db`) or a scan (`--scan --landmarks`), with the per-clip options of
//! `retarget` and `transfer` (the same option groups, flattened).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;
use surfmotion::batch::schedule::ShardSource;
use surfmotion::batch::{ClipStatus, Converter, Format};
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::jobs::{
    BatchEvent, BatchOptions, RetargetJob, RetargetJobOptions, ScanTransferJob,
    ScanTransferOptions, batch_folder,
};
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
    #[arg(long, value_enum, default_value_t = super::values::FormatArg::Glb)]
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
    pub glb: super::mesh::GlbArgs,
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
    let s = &r.summary;
    if a.json {
        super::emit(&(serde_json::to_string_pretty(s)? + "\n"))?;
    } else {
        super::emit(&format!(
            "merged {}: {}\nreport: {}\n",
            surfmotion::batch::summary::count(r.reports.len(), "shard report"),
            s.line(),
            r.files
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ))?;
    }
    anyhow::ensure!(
        s.failed == 0,
        "{} of {} clips failed (see {})",
        s.failed,
        s.clips,
        r.files[0].display()
    );
    Ok(())
}

/// Runs `batch`: the retarget or transfer job (loaded or factored once)
/// as the converter of [`batch_folder`].
pub fn run_batch(a: Args) -> anyhow::Result<()> {
    if let Some(Sub::Merge(m)) = a.command {
        return run_merge(m);
    }
    let (Some(mocap_dir), Some(output)) = (a.mocap_dir.clone(), a.output.clone()) else {
        anyhow::bail!("give --mocap-dir and -o (or `batch merge DIR...`)");
    };
    let resolved =
        surfmotion::batch::schedule::resolve(a.shard.as_deref(), a.shard_count, &|k: &str| {
            std::env::var(k).ok()
        })?;
    if let Some((s, source)) = &resolved
        && !matches!(source, ShardSource::Flag { ignored } if ignored.is_empty())
    {
        crate::errln!("{}", source.describe(s));
    }
    let shard = resolved.map(|(s, _)| s.spelled());
    a.glb.refuse_unless_glb(
        matches!(a.format, super::values::FormatArg::Glb),
        &format!("--format {}", format!("{:?}", a.format).to_lowercase()),
    )?;
    if a.db.is_some() {
        anyhow::ensure!(
            a.scan_job.is_default(),
            "--group, --marker-count, --marker-margin and --fps apply to --scan (a database has its own frame rate)"
        );
    } else {
        anyhow::ensure!(
            a.retarget_job.is_default(),
            "--deform, --no-deform, --t-skel, --w-retr, --no-interpolate and --no-blend apply to --db"
        );
    }
    // Said before the character loads: "X: Not a directory (os error
    // 20)" for a clip given as the folder, "/dev/full: File exists (os
    // error 17)" for a file as -o.
    if mocap_dir.exists() && !mocap_dir.is_dir() {
        anyhow::bail!(
            "--mocap-dir {}: a file, not a folder (batch converts every clip under a folder; `retarget` or `transfer` converts one)",
            mocap_dir.display()
        );
    }
    surfmotion::jobs::outputs::check_output_folder(
        "-o",
        &output,
        "batch writes one output per clip and batch.json, .html and .svg into a folder",
    )?;
    surfmotion::jobs::outputs::refuse_output_in_clip_folder("-o", &output, &mocap_dir)?;
    let format = Format::from(a.format);
    let mut inputs = Vec::new();
    if let Some(db) = &a.db {
        inputs.extend(surfmotion::jobs::outputs::database_inputs(db));
    }
    if let Some(scan) = &a.scan {
        inputs.extend(surfmotion::mesh::io::input_files(scan, None));
    }
    inputs.extend(a.landmarks.clone());
    inputs.extend(a.clip.rig_map.clone());
    inputs.extend(a.clip.asf.clone());
    surfmotion::jobs::outputs::refuse_outputs_over_inputs(
        &inputs, &mocap_dir, "-o", &output, format,
    )?;
    let load = a.clip.load_options()?;
    let scan_job = a.scan_job.job()?;
    let retarget_opts = a.retarget_job.options();
    let mut opts = BatchOptions {
        shard,
        format,
        force: a.force,
        ..Default::default()
    };
    if let Some(j) = a.jobs {
        opts.jobs = j;
    }
    let converter: Box<dyn Converter> = match (&a.db, &a.scan, &a.landmarks) {
        (Some(db), _, _) => Box::new(RetargetJob::load(
            db,
            RetargetJobOptions {
                retarget: retarget_opts,
                character: a.retarget_job.character(),
                load,
                glb: a.glb.options(),
            },
            &super::Bars::new(),
        )?),
        (None, Some(scan), Some(lm)) => {
            let mesh = super::load_mesh_groups(scan, &scan_job.groups)?;
            let landmarks = Landmarks::load(lm, mesh.vertex_count())?;
            let opts = ScanTransferOptions {
                markers: scan_job.markers,
                fps: scan_job.fps,
                load,
                glb: a.glb.options(),
                ..Default::default()
            };
            Box::new(ScanTransferJob::prepare(&mesh, &landmarks, scan, opts)?)
        }
        _ => anyhow::bail!("give --db, or --scan with --landmarks"),
    };
    let term = std::io::stderr().is_terminal();
    let bar = super::progress(0, "clips");
    let frames_done = std::sync::atomic::AtomicUsize::new(0);
    let t0 = Instant::now();
    let log = |e: BatchEvent<'_>| {
        let o = match e {
            BatchEvent::Planned(n) => return bar.set_length(n as u64),
            BatchEvent::Clip(o) => o,
        };
        let f = if o.status == ClipStatus::Done {
            frames_done.fetch_add(o.frames, std::sync::atomic::Ordering::Relaxed) + o.frames
        } else {
            frames_done.load(std::sync::atomic::Ordering::Relaxed)
        };
        let line = match o.status {
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
                super::flags::as_flags(o.reason.as_deref().unwrap_or(""))
            ),
        };
        if term {
            bar.inc(1);
            bar.set_message(format!(
                "{:.0} frames/s",
                f as f64 / t0.elapsed().as_secs_f64().max(1e-9)
            ));
            if o.status == ClipStatus::Failed {
                bar.println(line);
            }
        } else {
            crate::errln!("{line}");
        }
    };
    let r = batch_folder(&mocap_dir, &output, converter.as_ref(), &opts, &log)?;
    bar.finish_and_clear();
    let (s, files) = (&r.summary, &r.files);
    if a.json {
        super::emit(&(serde_json::to_string_pretty(s)? + "\n"))?;
    } else {
        let mut out = format!(
            "{}\nreport: {}\n",
            s.line(),
            files
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", ")
        );
        for o in s.outcomes.iter().filter(|o| o.status == ClipStatus::Failed) {
            out += &format!(
                "failed: {}: {}\n",
                o.clip.display(),
                super::flags::as_flags(o.reason.as_deref().unwrap_or(""))
            );
        }
        super::emit(&out)?;
    }
    anyhow::ensure!(
        s.failed == 0,
        "{} of {} clips failed (see {})",
        s.failed,
        s.clips,
        files[0].display()
    );
    Ok(())
}
