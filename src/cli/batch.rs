//! `surfmotion batch`: convert a whole mocap library, onto a 4D character
//! (`--db`) or a scan (`--scan --landmarks`), with the per-clip options of
//! `retarget` and `transfer` (the same option groups, flattened).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;
use surfmotion::batch::{
    ClipOutcome, ClipStatus, Converted, Earlier, Format, RunOptions, Shard, Summary,
    clean_temporaries, find_clips, lock_folder, plan, report_stem, run, write_json, write_summary,
};
use surfmotion::eval::velocity_error;
use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::glb::GlbOptions;
use surfmotion::mesh::io::{SaveOptions, save_sequence_with};
use surfmotion::retarget::character::Character;
use surfmotion::retarget::query::{load_mocap, to_character};
use surfmotion::retarget::{RetargetOptions, synthesise};
use surfmotion::rig::LoadOptions;
use surfmotion::rig::embed::landmarks::Landmarks;
use surfmotion::skeleton::Pose;
use surfmotion::transfer::{Job, MarkerSpec, TransferOptions, mocap_motion, prepare, transfer};

/// Arguments of `batch`.
#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("target").required(true).args(["db", "scan"])))]
pub struct Args {
    /// Drive this 4D character database (as `retarget`).
    #[arg(long)]
    pub db: Option<PathBuf>,
    /// Or transfer onto this static mesh (as `transfer`; needs --landmarks).
    #[arg(long, requires = "landmarks")]
    pub scan: Option<String>,
    /// Landmarks on the scan.
    #[arg(long)]
    pub landmarks: Option<PathBuf>,
    /// The folder of clips: every .bvh and .amc below it (AMC clips use the
    /// .asf beside them). Links are followed; each clip is converted once.
    #[arg(long)]
    pub mocap_dir: PathBuf,
    /// Output folder: one output per clip in the same folder tree, plus
    /// batch.json, batch.html and batch.svg. One run at a time writes there
    /// (shards of one split may share it): batch.lock holds its pid.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Clips converted at once (default: the number of cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Only shard i of n (1-based), e.g. `--shard $SLURM_ARRAY_TASK_ID/8`:
    /// clip k of the sorted list goes to shard k mod n + 1.
    #[arg(long, value_name = "i/n")]
    pub shard: Option<String>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = Format::Glb)]
    pub format: Format,
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

type Convert = Box<dyn Fn(&Path, &Path) -> Result<Converted, String> + Sync>;

/// The retarget job of one clip, `retarget`'s options `opts` and `load`.
fn retarget_converter(
    db: &Path,
    opts: RetargetOptions,
    load: LoadOptions,
    glb: GlbOptions,
) -> anyhow::Result<(Convert, String)> {
    let ch = Character::load(db, &super::db::Bars::new())?;
    let what = format!("retarget --db {}", db.display());
    let f = move |clip: &Path, out: &Path| -> Result<Converted, String> {
        let fps = ch.manifest.fps;
        let mocap = load_mocap(clip, &load, fps).map_err(|e| e.to_string())?;
        if mocap.poses.is_empty() {
            return Err("the clip has no frames".into());
        }
        let r = synthesise(&ch, &mocap.poses, &mocap.reference, fps, &opts)
            .map_err(|e| e.to_string())?;
        let frames = r.positions.len() / ch.n.max(1);
        let query = to_character(&ch.rest_pose, &mocap.reference, &mocap.poses);
        let skel: Vec<Pose> = r
            .positions
            .chunks(ch.n.max(1))
            .map(|p| ch.rig.skeleton(p))
            .collect();
        let e = velocity_error(&query, &skel);
        let seq = MeshSequence::new(ch.topology_metres(), r.positions, Some(fps))
            .map_err(|e| e.to_string())?;
        let so = SaveOptions {
            fps: Some(fps),
            glb,
        };
        save_sequence_with(&seq, out, &so).map_err(|e| e.to_string())?;
        Ok(Converted {
            frames,
            error_cm: Some(e.mean_cm),
        })
    };
    Ok((Box::new(f), what))
}

/// The transfer job of one clip onto `scan` (prepared and factored once),
/// with `transfer`'s options `job` and `load`.
fn transfer_converter(
    scan: &str,
    landmarks: &Path,
    job: super::transfer::ScanJob,
    load: LoadOptions,
    glb: GlbOptions,
) -> anyhow::Result<(Convert, String)> {
    let mesh = super::load_mesh_groups(scan, &job.groups)?;
    let lm = Landmarks::load(landmarks, mesh.vertex_count())?;
    let prepared = prepare(&mesh, MarkerSpec::Landmarks(&lm, job.markers))?;
    let fps = job.fps;
    // Factored once for every clip.
    let (confluent, _) = Job::factor_mocap(&prepared)?;
    let what = format!("transfer --scan {scan}");
    let f = move |clip: &Path, out: &Path| -> Result<Converted, String> {
        let mocap = load_mocap(clip, &load, fps).map_err(|e| e.to_string())?;
        if mocap.poses.is_empty() {
            return Err("the clip has no frames".into());
        }
        let mut motion =
            mocap_motion(&prepared, &mocap.poses, &mocap.reference).map_err(|e| e.to_string())?;
        let (pos, stats) = transfer(
            &confluent,
            &mut motion,
            &TransferOptions::default(),
            &|_| {},
        );
        let n = prepared.mesh.vertex_count();
        let rig = prepared.rig.as_ref().ok_or("no rig")?;
        let rest: Pose = rig.joints.map(glam::DVec3::from_array);
        let query = to_character(&rest, &mocap.reference, &mocap.poses);
        let skel: Vec<Pose> = pos.chunks(n.max(1)).map(|p| rig.skeleton(p)).collect();
        let e = velocity_error(&query, &skel);
        let seq =
            MeshSequence::new(prepared.mesh.clone(), pos, Some(fps)).map_err(|e| e.to_string())?;
        let so = SaveOptions {
            fps: Some(fps),
            glb,
        };
        save_sequence_with(&seq, out, &so).map_err(|e| e.to_string())?;
        Ok(Converted {
            frames: stats.frames,
            error_cm: Some(e.mean_cm),
        })
    };
    Ok((Box::new(f), what))
}

/// Runs `batch`.
pub fn run_batch(a: Args) -> anyhow::Result<()> {
    let shard = match &a.shard {
        Some(s) => Some(Shard::parse(s).map_err(anyhow::Error::msg)?),
        None => None,
    };
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
    let load = a.clip.load_options()?;
    let scan_job = a.scan_job.job()?;
    let retarget_opts = a.retarget_job.options();
    let all =
        find_clips(&a.mocap_dir).map_err(|e| anyhow::anyhow!("{}: {e}", a.mocap_dir.display()))?;
    // Outputs of the whole library, so every shard names them alike; clips
    // that would write one output are renamed or refused before any work.
    let (planned, renamed) = plan(&all, &a.output, a.format)?;
    if !renamed.is_empty() {
        eprintln!(
            "{} clips would write the same output; named with their extension:\n  {}",
            renamed.len(),
            renamed.join("\n  ")
        );
    }
    let clips = match shard {
        Some(s) => s.select(&planned),
        None => planned,
    };
    std::fs::create_dir_all(&a.output)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.output.display()))?;
    let stem = report_stem(a.shard.as_deref());
    let lock = lock_folder(&a.output, &stem, a.shard.as_deref())?;
    for p in &lock.stale_removed {
        eprintln!("removed the stale lock {} (its run is gone)", p.display());
    }
    if lock.alone {
        let (gone, bytes) = clean_temporaries(&a.output);
        if !gone.is_empty() {
            eprintln!(
                "removed {} unfinished temporar{} ({:.1} MB) left by a killed run",
                gone.len(),
                if gone.len() == 1 { "y" } else { "ies" },
                bytes as f64 / 1e6
            );
        }
    }
    let (convert, what) = match (&a.db, &a.scan, &a.landmarks) {
        (Some(db), _, _) => retarget_converter(db, retarget_opts, load, a.glb.options())?,
        (None, Some(scan), Some(lm)) => {
            transfer_converter(scan, lm, scan_job, load, a.glb.options())?
        }
        _ => anyhow::bail!("give --db, or --scan with --landmarks"),
    };
    let opts = RunOptions {
        jobs: a.jobs.unwrap_or_else(|| RunOptions::default().jobs),
        force: a.force,
        format: a.format,
    };
    // The report keeps what earlier runs recorded for the outputs they
    // wrote, and is rewritten after every clip.
    let earlier = Earlier::load(&a.output, &format!("{stem}.json"));
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
                    reason: None,
                    earlier: false,
                };
                earlier.fill(&mut o);
                (!a.force && o.earlier && surfmotion::batch::runner::complete(&p.output, a.format))
                    .then_some(o)
            })
            .collect(),
    );
    let term = std::io::stderr().is_terminal();
    let bar = super::progress(clips.len() as u64, "clips");
    let frames_done = std::sync::atomic::AtomicUsize::new(0);
    let t0 = Instant::now();
    let progress_report = |slots: &[Option<ClipOutcome>]| {
        let mut s = Summary::new(
            what.clone(),
            slots.iter().flatten().cloned().collect(),
            t0.elapsed().as_secs_f64(),
            opts.jobs,
            a.shard.clone(),
        );
        s.finished = false;
        if let Err(e) = write_json(&a.output, &s) {
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
                o.reason.as_deref().unwrap_or("")
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
            eprintln!("{line}");
        }
    };
    let mut outcomes = run(&a.mocap_dir, &clips, &opts, &convert, &log);
    bar.finish_and_clear();
    for o in &mut outcomes {
        earlier.fill(o);
    }
    let s = Summary::new(
        what,
        outcomes,
        t0.elapsed().as_secs_f64(),
        opts.jobs,
        a.shard.clone(),
    );
    let files = write_summary(&a.output, &s)?;
    drop(lock);
    if a.json {
        super::emit(&(serde_json::to_string_pretty(&s)? + "\n"))?;
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
                o.reason.as_deref().unwrap_or("")
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
