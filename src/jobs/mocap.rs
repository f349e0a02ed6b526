//! `mocap positions|convert|procedural|rigmap`: a clip's joint positions,
//! its conversion to BVH, the project's procedural clips, and a clip's rig
//! map onto the canonical skeleton.

use crate::mocap::{Clip, UpAxis};
use crate::rig::{Detection, LoadOptions, load_clip};
use crate::synth::Gait;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::JobError;

/// World joint positions of a clip at chosen frames.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Positions {
    /// The clip's length unit.
    pub units: String,
    /// Metres per unit.
    pub metres_per_unit: f64,
    /// Why that unit (read from the file, given, or guessed).
    pub units_reason: String,
    /// The up axis, `y` or `z`.
    pub up: &'static str,
    /// The points' names (joints and bone ends), in file order.
    pub joints: Vec<String>,
    /// Each frame asked for: a position per point.
    pub frames: BTreeMap<usize, Vec<[f64; 3]>>,
}

impl Positions {
    /// The text of `mocap positions`: the units and up axis, then per
    /// frame one line per point (name, x, y, z to the micro-unit).
    pub fn text(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "units: {} ({}), {}-up",
            self.units, self.units_reason, self.up
        );
        for (f, pts) in &self.frames {
            let _ = writeln!(s, "frame {f}");
            for (n, v) in self.joints.iter().zip(pts) {
                let _ = writeln!(s, "  {n:<24} {:>12.6} {:>12.6} {:>12.6}", v[0], v[1], v[2]);
            }
        }
        s
    }
}

/// The world positions of `clip`'s points at `frames` (in metres, Y-up
/// when `metres`, else in the file's units and axes).
pub fn positions(
    clip: &Path,
    load: &LoadOptions,
    frames: &[usize],
    metres: bool,
) -> Result<Positions, JobError> {
    let path = clip;
    let mut clip = load_clip(path, load)?;
    if metres {
        clip.to_metres_y_up();
    }
    let n = clip.frame_count();
    let mut out = BTreeMap::new();
    for &f in frames {
        if f >= n {
            return Err(JobError::Input {
                path: path.to_path_buf(),
                msg: format!(
                    "frame {f} out of range (the clip has {n} frames, 0..{})",
                    n.saturating_sub(1)
                ),
            });
        }
        out.insert(f, clip.points_at(f).iter().map(|v| v.to_array()).collect());
    }
    Ok(Positions {
        units: clip.units.name.clone(),
        metres_per_unit: clip.units.metres_per_unit,
        units_reason: clip.units.reason.clone(),
        up: up_name(clip.up),
        joints: clip.point_names(),
        frames: out,
    })
}

fn up_name(up: UpAxis) -> &'static str {
    if up == UpAxis::Z { "z" } else { "y" }
}

/// A clip written as BVH.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Converted {
    /// The file written.
    pub output: PathBuf,
    /// Its joints.
    pub joints: usize,
    /// Its frames.
    pub frames: usize,
    /// Its frame rate.
    pub fps: f64,
}

/// Writes `input` as the BVH `output` (written atomically; never over the
/// input), in metres and Y-up when `metres`, resampled to `fps` if given.
pub fn convert(
    input: &Path,
    load: &LoadOptions,
    output: &Path,
    fps: Option<f64>,
    metres: bool,
) -> Result<Converted, JobError> {
    check_convert_output(input, output)?;
    let mut clip = load_clip(input, load)?;
    if metres {
        clip.to_metres_y_up();
    }
    if let Some(fps) = fps {
        clip = clip
            .try_resampled(fps)
            .map_err(|e| context(input.display().to_string(), e.into()))?;
    }
    crate::mocap::bvh::write_bvh(&clip, output)
        .map_err(|e| context(format!("writing {}", output.display()), e.into()))?;
    Ok(Converted {
        output: output.to_path_buf(),
        joints: clip.joint_count(),
        frames: clip.frame_count(),
        fps: clip.fps(),
    })
}

/// Refuses an `output` of [`convert`] that is not a .bvh or is the `input`.
pub fn check_convert_output(input: &Path, output: &Path) -> Result<(), JobError> {
    if !output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bvh"))
    {
        return Err(JobError::Input {
            path: output.to_path_buf(),
            msg: "only .bvh output is supported".into(),
        });
    }
    // As `mesh convert` does: the input is never overwritten (it was,
    // silently, re-serialised in place).
    if let (Ok(i), Ok(o)) = (input.canonicalize(), output.canonicalize())
        && i == o
    {
        return Err(JobError::Input {
            path: output.to_path_buf(),
            msg: format!(
                "writing it would overwrite the input {}; choose another output name",
                input.display()
            ),
        });
    }
    Ok(())
}

/// Refuses an `output` of [`rigmap`] over what it reads: the `clip`,
/// its `asf` and the `rig_map` given (`-o` onto the clip replaced it with
/// the JSON map; onto the map it read, rewrote it in place; both exit 0).
pub fn check_rigmap_output(
    clip: &Path,
    asf: Option<&Path>,
    rig_map: Option<&Path>,
    output: &Path,
) -> Result<(), JobError> {
    let mut inputs = vec![clip.to_path_buf()];
    inputs.extend(asf.map(Path::to_path_buf));
    inputs.extend(rig_map.map(Path::to_path_buf));
    Ok(crate::mesh::io::refuse_overwriting(&inputs, output)?)
}

fn context(what: String, e: JobError) -> JobError {
    JobError::Context {
        what,
        source: Box::new(e),
    }
}

/// What `mocap procedural` writes.
#[derive(Clone, Debug)]
pub struct ProceduralOptions {
    /// A folder (one GAIT.bvh per gait) or, with one gait, a .bvh file.
    pub output: PathBuf,
    /// The gaits (none: all).
    pub gaits: Vec<Gait>,
    /// Length of each clip in seconds (default 4).
    pub seconds: f64,
    /// Frames per second (default 30).
    pub fps: f64,
}

impl Default for ProceduralOptions {
    fn default() -> Self {
        ProceduralOptions {
            output: PathBuf::new(),
            gaits: Vec::new(),
            seconds: 4.0,
            fps: 30.0,
        }
    }
}

/// One procedural clip written.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ProceduralClip {
    /// The file.
    pub path: PathBuf,
    /// The gait.
    pub gait: &'static str,
    /// Its frames.
    pub frames: usize,
    /// Its frame rate.
    pub fps: f64,
}

/// Writes the procedural clips of `o`, calling `written` after each.
pub fn procedural(
    o: &ProceduralOptions,
    written: &mut dyn FnMut(&ProceduralClip),
) -> Result<Vec<ProceduralClip>, JobError> {
    if !(o.fps.is_finite()
        && o.fps > 0.0
        && o.seconds.is_finite()
        && o.seconds > 0.0
        && o.seconds * o.fps < 1e6)
    {
        return Err(JobError::Usage(format!(
            "`ProceduralOptions::seconds` {} `ProceduralOptions::fps` {}: expected positive numbers (under a million frames)",
            o.seconds, o.fps
        )));
    }
    let gaits = if o.gaits.is_empty() {
        Gait::ALL.to_vec()
    } else {
        o.gaits.clone()
    };
    let is_bvh = o
        .output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bvh"));
    // `-o x.obj` made a folder named x.obj (an existing folder with a dot
    // in its name is taken as given).
    if o.output.extension().is_some() && !is_bvh && !o.output.is_dir() {
        return Err(JobError::Usage(format!(
            "`ProceduralOptions::output` {}: expected a .bvh file (with one `ProceduralOptions::gaits`) or a folder name without extension",
            o.output.display()
        )));
    }
    let single = gaits.len() == 1 && is_bvh;
    if !single {
        super::outputs::check_output_folder(
            "`ProceduralOptions::output`",
            &o.output,
            "one clip per gait goes into a folder; with one `ProceduralOptions::gaits`, `ProceduralOptions::output` may name a .bvh",
        )?;
    }
    let mut out = Vec::new();
    for g in gaits {
        let clip = crate::synth::gait_clip(g, o.seconds, o.fps);
        let path = if single {
            o.output.clone()
        } else {
            o.output.join(format!("{}.bvh", g.name()))
        };
        crate::mocap::bvh::write_bvh(&clip, &path)?;
        let c = ProceduralClip {
            path,
            gait: g.name(),
            frames: clip.frame_count(),
            fps: o.fps,
        };
        written(&c);
        out.push(c);
    }
    Ok(out)
}

/// The rig map of `clip`: `load`'s map, checked to place every joint on
/// the clip, else the detected one; saved as JSON to `output` if given.
pub fn rigmap(
    clip: &Path,
    load: &LoadOptions,
    output: Option<&Path>,
) -> Result<Detection, JobError> {
    let c: Clip = load_clip(clip, load)?;
    let named = |e: crate::rig::RigError| context(clip.display().to_string(), e.into());
    let det = match &load.rig_map {
        // A given map: check that it places every joint on this clip.
        Some(m) => {
            m.rest_pose(&c).map_err(named)?;
            Detection::from_map(
                m.clone(),
                crate::rig::Provenance::MapFile,
                1.0,
                "from the map file",
            )
        }
        None => crate::rig::detect_clip(&c).map_err(named)?,
    };
    if let Some(o) = output {
        det.map.save(o)?;
    }
    Ok(det)
}
