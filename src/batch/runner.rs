//! Running a batch: clips in parallel (a rayon pool of `jobs` threads, each
//! clip's work inside it), skipping clips whose output is complete, and
//! turning every failure — an error or a panic — into a reported outcome.
//!
//! Outputs are complete or absent: single files are written atomically;
//! PC2 counts as complete only with its topology OBJ beside it; an OBJ
//! folder is written under a unique temporary name
//! (`.surfmotion-XXXXXX-partial`, removed on failure) and renamed when
//! finished.

use super::clips::{Format, Planned, TEMP_PREFIX};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options for [`run`].
#[derive(Debug, Clone, Copy)]
pub struct RunOptions {
    /// Clips converted at once. Default: the number of cores.
    pub jobs: usize,
    /// Redo clips whose output exists. Default: false.
    pub force: bool,
    /// Output format. Default: GLB.
    pub format: Format,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            jobs: std::thread::available_parallelism().map_or(1, |n| n.get()),
            force: false,
            format: Format::Glb,
        }
    }
}

/// What a converter reports for one clip.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Converted {
    /// Frames written.
    pub frames: usize,
    /// Joint-velocity error of the result against the clip (cm/frame).
    pub error_cm: Option<f64>,
    /// The plausibility warnings of the result (as `eval` prints them).
    pub warnings: Vec<ClipWarning>,
    /// Seconds of the clip's conversion that are no per-frame work, when
    /// measured: the wall clock minus the solve (retrieval, blending,
    /// deformation; or the transfer), the frames written and the
    /// plausibility measure. What stays: the clip read and mapped, the
    /// pose kernel, the output opened.
    pub fixed_seconds: Option<f64>,
}

/// What a converter prepared once for all its clips (the character's or
/// the scan's factorisations).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Preparation {
    /// Times the system was factored (1 when every clip shared one
    /// preparation).
    pub factorisations: usize,
    /// Seconds preparing (once).
    pub seconds: f64,
}

/// One plausibility warning of a clip's result.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct ClipWarning {
    /// What is wrong (`turned_over`, `off_ring`, `head`, `penetration`,
    /// `floating`, `knee`, `feet`, `repair`, `other`).
    pub kind: String,
    /// How many (triangles turned over in the worst frame, triangle-frames
    /// left by the repair, vertices off their ring), when it counts things.
    pub count: Option<usize>,
    /// The frame where it is worst, when known.
    pub worst_frame: Option<usize>,
    /// The warning as `eval` words it.
    pub message: String,
}

impl ClipWarning {
    /// The warnings of a plausibility report, each with its kind, count
    /// and worst frame.
    pub fn of(p: &crate::tools::eval::Plausibility) -> Vec<ClipWarning> {
        p.warnings
            .iter()
            .map(|m| {
                let (kind, count, worst_frame) = if m.contains("turned over against the rest frame")
                {
                    (
                        "turned_over",
                        Some(p.turned_over.max_in_a_frame),
                        Some(p.turned_over.worst_frame),
                    )
                } else if m.contains("stay turned over") {
                    (
                        "repair",
                        p.turned_over.deformation.as_ref().map(|d| d.after),
                        None,
                    )
                } else if m.contains("one-ring") {
                    ("off_ring", Some(1), Some(p.off_ring.frame))
                } else if m.starts_with("head") {
                    ("head", None, None)
                } else if m.starts_with("ground penetration") {
                    ("penetration", None, None)
                } else if m.starts_with("floating") {
                    ("floating", None, None)
                } else if m.starts_with("knee") {
                    ("knee", None, None)
                } else if m.starts_with("feet") || m.starts_with("foot") {
                    ("feet", None, None)
                } else {
                    ("other", None, None)
                };
                ClipWarning {
                    kind: kind.into(),
                    count,
                    worst_frame,
                    message: m.clone(),
                }
            })
            .collect()
    }
}

/// How a clip ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClipStatus {
    /// Converted now.
    Done,
    /// Its output was already complete.
    Skipped,
    /// It could not be converted.
    Failed,
}

/// One clip's outcome.
#[derive(Debug, Clone, Serialize, serde::Deserialize)]
pub struct ClipOutcome {
    /// The clip, relative to the mocap folder.
    pub clip: PathBuf,
    /// The output.
    pub output: PathBuf,
    /// How it ended.
    pub status: ClipStatus,
    /// Frames written (0 unless done).
    pub frames: usize,
    /// Seconds spent.
    pub seconds: f64,
    /// Joint-velocity error (cm/frame), if measured.
    pub error_cm: Option<f64>,
    /// The result's plausibility warnings (none when it was not measured).
    #[serde(default)]
    pub warnings: Vec<ClipWarning>,
    /// Why it failed.
    pub reason: Option<String>,
    /// Seconds that are no per-frame work ([`Converted::fixed_seconds`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed_seconds: Option<f64>,
    /// True when frames, seconds and error of a skipped clip come from the
    /// report of the run that wrote its output.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub earlier: bool,
}

impl ClipOutcome {
    /// A clip not (yet) converted: skipped, nothing written or measured;
    /// the run fills in what it does.
    pub fn skipped(clip: PathBuf, output: PathBuf) -> Self {
        ClipOutcome {
            clip,
            output,
            status: ClipStatus::Skipped,
            frames: 0,
            seconds: 0.0,
            error_cm: None,
            warnings: Vec::new(),
            reason: None,
            fixed_seconds: None,
            earlier: false,
        }
    }
}

/// True when the output of a clip exists in full.
pub fn complete(out: &Path, format: Format) -> bool {
    match format {
        Format::Glb | Format::Usda => out.is_file(),
        Format::Pc2 => out.is_file() && out.with_extension("obj").is_file(),
        Format::Obj => out.is_dir(),
    }
}

/// One kind of conversion of a clip (a retarget through a database, a
/// transfer onto a scan: [`crate::jobs`]); a new batch job is one impl.
pub trait Converter: Sync {
    /// What the run does, for the report (`retarget onto DIR`); a caller
    /// may name it in its own words ([`crate::jobs::BatchOptions::describe`]).
    fn describe(&self) -> String;
    /// Converts `clip` (a path to the clip) into `output`, which it must
    /// write (for OBJ folders, the folder it is given). Errors are the
    /// message the report keeps.
    fn convert(&self, clip: &Path, output: &Path) -> Result<Converted, String>;
    /// What was prepared once for every clip. Default: nothing.
    fn preparation(&self) -> Preparation {
        Preparation::default()
    }
}

/// Converts the `clips` of a plan (relative to `src`) into their outputs.
/// `convert(clip, output)` does one clip and must write `output` (for OBJ
/// folders, the folder it is given); `done` is called as each clip ends,
/// from any thread. Outcomes come back in clip order.
pub fn run(
    src: &Path,
    clips: &[Planned],
    opts: &RunOptions,
    convert: &(dyn Fn(&Path, &Path) -> Result<Converted, String> + Sync),
    done: &(dyn Fn(&ClipOutcome) + Sync),
) -> Vec<ClipOutcome> {
    let one = |p: &Planned| {
        let (rel, out) = (&p.clip, &p.output);
        let t = Instant::now();
        let mut o = ClipOutcome::skipped(rel.clone(), out.clone());
        if !opts.force && complete(out, opts.format) {
            done(&o);
            return o;
        }
        let r = convert_one(&src.join(rel), out, opts.format, convert);
        o.seconds = t.elapsed().as_secs_f64();
        match r {
            Ok(c) => {
                o.status = ClipStatus::Done;
                o.frames = c.frames;
                o.error_cm = c.error_cm;
                o.warnings = c.warnings;
                o.fixed_seconds = c.fixed_seconds;
            }
            Err(e) => {
                o.status = ClipStatus::Failed;
                o.reason = Some(e);
            }
        }
        done(&o);
        o
    };
    match rayon::ThreadPoolBuilder::new()
        .num_threads(opts.jobs.max(1))
        .build()
    {
        Ok(pool) => pool.install(|| clips.par_iter().map(one).collect()),
        Err(_) => clips.iter().map(one).collect(),
    }
}

fn convert_one(
    clip: &Path,
    out: &Path,
    format: Format,
    convert: &(dyn Fn(&Path, &Path) -> Result<Converted, String> + Sync),
) -> Result<Converted, String> {
    if let Some(parent) = out.parent() {
        std::fs::create_dir_all(parent).map_err(|e| format!("{}: {e}", parent.display()))?;
    }
    // OBJ frames go to a fresh folder of their own beside the output (no
    // dot after the prefix, so the writer sees a folder, not an extension),
    // removed with its contents if the clip fails.
    let partial = match format {
        Format::Obj => Some(
            tempfile::Builder::new()
                .prefix(&format!("{TEMP_PREFIX}pid{}o", std::process::id()))
                .suffix("-partial")
                .tempdir_in(out.parent().unwrap_or(Path::new(".")))
                .map_err(|e| format!("{}: {e}", out.display()))?,
        ),
        _ => None,
    };
    let target = partial.as_ref().map_or(out, |t| t.path());
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| convert(clip, target)))
        .unwrap_or_else(|p| {
            let msg = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Err(format!("internal error: {msg}"))
        })?;
    if let Some(t) = partial {
        if out.is_dir() {
            // Only a folder of an earlier run's OBJ frames is replaced: a
            // file of the user's (or an input) in it is never removed.
            if let Some(foreign) = foreign_file(out) {
                return Err(format!(
                    "{}: holds {}, which no batch wrote; move it away or choose another -o (the clip's frames were not written)",
                    out.display(),
                    foreign.display()
                ));
            }
            std::fs::remove_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
        }
        std::fs::rename(t.path(), out).map_err(|e| format!("{}: {e}", out.display()))?;
        // Renamed away: nothing left for the guard to remove.
        let _ = t.keep();
    }
    Ok(r)
}

/// The first entry of `dir` that is not an OBJ frame a writer names
/// (`frame_<digits>.obj`, a regular file), if any.
fn foreign_file(dir: &Path) -> Option<std::path::PathBuf> {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return Some(dir.to_path_buf());
    };
    rd.flatten()
        .find(|e| {
            let name = e.file_name();
            let frame = name
                .to_str()
                .and_then(|n| n.strip_prefix("frame_"))
                .and_then(|n| n.strip_suffix(".obj"))
                .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
            !(frame && e.file_type().is_ok_and(|t| t.is_file()))
        })
        .map(|e| e.path())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 46's class (an output that deletes the user's files): an OBJ
    /// clip's output folder was removed whole before the new frames were
    /// renamed in, whatever else it held.
    #[test]
    fn a_batch_obj_output_keeps_the_users_files() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("walk-bvh");
        std::fs::create_dir_all(&out).unwrap();
        std::fs::write(out.join("frame_0000.obj"), b"old").unwrap();
        std::fs::write(out.join("notes.txt"), b"mine").unwrap();
        let convert = |_: &Path, o: &Path| {
            std::fs::write(o.join("frame_0000.obj"), b"new").unwrap();
            Ok(Converted {
                frames: 1,
                error_cm: None,
                warnings: Vec::new(),
                fixed_seconds: None,
            })
        };
        let e = convert_one(Path::new("walk.bvh"), &out, Format::Obj, &convert).unwrap_err();
        assert!(e.contains("notes.txt"), "{e}");
        assert_eq!(std::fs::read(out.join("notes.txt")).unwrap(), b"mine");
        assert_eq!(std::fs::read(out.join("frame_0000.obj")).unwrap(), b"old");
        // An earlier run's frames alone are replaced.
        std::fs::remove_file(out.join("notes.txt")).unwrap();
        convert_one(Path::new("walk.bvh"), &out, Format::Obj, &convert).unwrap();
        assert_eq!(std::fs::read(out.join("frame_0000.obj")).unwrap(), b"new");
        let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(left.len(), 1, "a temporary stayed");
    }

    #[test]
    fn failures_and_panics_are_outcomes_and_finished_clips_are_skipped() {
        let dir = tempfile::tempdir().unwrap();
        let names: Vec<PathBuf> = ["a.bvh", "sub/b.bvh", "c.bvh"].map(PathBuf::from).to_vec();
        let (clips, _) = crate::batch::clips::plan(&names, dir.path(), Format::Glb).unwrap();
        let opts = RunOptions {
            jobs: 2,
            force: false,
            format: Format::Glb,
        };
        let convert = |clip: &Path, out: &Path| {
            let name = clip.file_name().unwrap().to_str().unwrap();
            match name {
                "a.bvh" => Err("bad clip".to_string()),
                "c.bvh" => panic!("boom"),
                _ => {
                    std::fs::write(out, b"x").unwrap();
                    Ok(Converted {
                        frames: 3,
                        error_cm: None,
                        warnings: Vec::new(),
                        fixed_seconds: None,
                    })
                }
            }
        };
        let go = || run(Path::new("src"), &clips, &opts, &convert, &|_| {});
        let r = go();
        let st: Vec<ClipStatus> = r.iter().map(|o| o.status).collect();
        assert_eq!(
            st,
            [ClipStatus::Failed, ClipStatus::Done, ClipStatus::Failed]
        );
        assert!(r[2].reason.as_deref().unwrap().contains("boom"));
        assert!(dir.path().join("sub/b.glb").is_file());
        let again = go();
        assert_eq!(again[1].status, ClipStatus::Skipped);
    }
}
