//! `surfmotion batch`: convert a whole mocap library, onto a 4D character
//! (`--db`) or a scan (`--scan --landmarks`).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;
use surfmotion::batch::{
    ClipOutcome, ClipStatus, Converted, Format, RunOptions, Shard, Summary, find_clips, run,
    write_summary,
};
use surfmotion::eval::velocity_error;
use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::glb::GlbOptions;
use surfmotion::mesh::io::{SaveOptions, save_sequence_with};
use surfmotion::retarget::character::Character;
use surfmotion::retarget::query::{load_mocap, to_character};
use surfmotion::retarget::{RetargetOptions, synthesise};
use surfmotion::rig::embed::landmarks::Landmarks;
use surfmotion::skeleton::Pose;
use surfmotion::transfer::{
    Job, MarkerOptions, MarkerSpec, TransferOptions, mocap_motion, prepare, transfer,
};

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
    /// .asf beside them).
    #[arg(long)]
    pub mocap_dir: PathBuf,
    /// Output folder: one output per clip in the same folder tree, plus
    /// batch.json, batch.html and batch.svg.
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
    /// Output frame rate for scans (a database uses its own).
    #[arg(long, default_value_t = 30.0, value_parser = super::frame_rate)]
    pub fps: f64,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub glb: super::mesh::GlbArgs,
}

type Convert = Box<dyn Fn(&Path, &Path) -> Result<Converted, String> + Sync>;

fn retarget_converter(db: &Path, glb: GlbOptions) -> anyhow::Result<(Convert, String)> {
    let ch = Character::load(db, &super::db::Bars::new())?;
    let what = format!("retarget --db {}", db.display());
    let f = move |clip: &Path, out: &Path| -> Result<Converted, String> {
        let fps = ch.manifest.fps;
        let mocap = load_mocap(clip, &Default::default(), fps).map_err(|e| e.to_string())?;
        if mocap.poses.is_empty() {
            return Err("the clip has no frames".into());
        }
        let r = synthesise(
            &ch,
            &mocap.poses,
            &mocap.reference,
            fps,
            &RetargetOptions::default(),
        )
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

fn transfer_converter(
    scan: &str,
    landmarks: &Path,
    fps: f64,
    glb: GlbOptions,
) -> anyhow::Result<(Convert, String)> {
    let seq = surfmotion::mesh::io::load_sequence(scan, &Default::default())?;
    let mesh = seq.frame_mesh(0);
    let lm = Landmarks::load(landmarks, mesh.vertex_count())?;
    let prepared = prepare(&mesh, MarkerSpec::Landmarks(&lm, MarkerOptions::default()))?;
    // Factored once for every clip.
    let (confluent, _) = Job::factor_mocap(&prepared)?;
    let what = format!("transfer --scan {scan}");
    let f = move |clip: &Path, out: &Path| -> Result<Converted, String> {
        let mocap = load_mocap(clip, &Default::default(), fps).map_err(|e| e.to_string())?;
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
    let all =
        find_clips(&a.mocap_dir).map_err(|e| anyhow::anyhow!("{}: {e}", a.mocap_dir.display()))?;
    let clips = match shard {
        Some(s) => s.select(&all),
        None => all,
    };
    let (convert, what) = match (&a.db, &a.scan, &a.landmarks) {
        (Some(db), _, _) => retarget_converter(db, a.glb.options())?,
        (None, Some(scan), Some(lm)) => transfer_converter(scan, lm, a.fps, a.glb.options())?,
        _ => anyhow::bail!("give --db, or --scan with --landmarks"),
    };
    std::fs::create_dir_all(&a.output)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.output.display()))?;
    let opts = RunOptions {
        jobs: a.jobs.unwrap_or_else(|| RunOptions::default().jobs),
        force: a.force,
        format: a.format,
    };
    let term = std::io::stderr().is_terminal();
    let bar = super::progress(clips.len() as u64, "clips");
    let frames_done = std::sync::atomic::AtomicUsize::new(0);
    let t0 = Instant::now();
    let log = |o: &ClipOutcome| {
        let f = frames_done.fetch_add(o.frames, std::sync::atomic::Ordering::Relaxed) + o.frames;
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
    let outcomes = run(&a.mocap_dir, &clips, &a.output, &opts, &convert, &log);
    bar.finish_and_clear();
    let s = Summary::new(
        what,
        outcomes,
        t0.elapsed().as_secs_f64(),
        opts.jobs,
        a.shard.clone(),
    );
    let files = write_summary(&a.output, &s)?;
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
