//! `surfmotion mocap ...`: positions, convert, rigmap.

use super::ClipOpts;
use anyhow::{Context, bail};
use std::collections::BTreeMap;
use std::path::PathBuf;
use surfmotion::mocap::{Clip, load_clip};

/// Mocap subcommands.
#[derive(clap::Subcommand)]
pub enum Cmd {
    /// World joint positions at chosen frames (forward kinematics). For BVH:
    /// every joint in file order, End Sites excluded. For ASF/AMC: `root` and
    /// the end point of every bone, by ASF bone name.
    Positions(PositionsArgs),
    /// Convert a clip to BVH (e.g. AMC to BVH), optionally resampled.
    Convert(ConvertArgs),
    /// Show the detected rig convention and its map onto the canonical
    /// skeleton; save it as JSON to edit and pass back with --rig-map.
    Rigmap(RigmapArgs),
}

/// Output units of `positions`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq)]
pub enum OutUnits {
    /// The file's own units and axes.
    File,
    /// Metres, Y-up.
    Metres,
}

/// Arguments of `mocap positions`.
#[derive(clap::Args)]
pub struct PositionsArgs {
    /// The clip (.bvh, .amc with its .asf, or .asf for the rest pose).
    pub clip: PathBuf,
    /// Comma-separated 0-based frame indices.
    #[arg(long, value_delimiter = ',', default_value = "0")]
    pub frames: Vec<usize>,
    /// Units of the output.
    #[arg(long, value_enum, default_value = "file")]
    pub units: OutUnits,
    /// Print JSON: {"joints": [...], "frames": {"0": [[x,y,z], ...]}}.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub opts: ClipOpts,
}

/// Arguments of `mocap convert`.
#[derive(clap::Args)]
pub struct ConvertArgs {
    /// Input clip.
    pub input: PathBuf,
    /// Output .bvh.
    pub output: PathBuf,
    /// Resample to this frame rate (slerp of rotations, lerp of translations).
    #[arg(long)]
    pub fps: Option<f64>,
    /// Convert lengths to metres and the up axis to Y.
    #[arg(long)]
    pub metres: bool,
    #[command(flatten)]
    pub opts: ClipOpts,
}

/// Arguments of `mocap rigmap`.
#[derive(clap::Args)]
pub struct RigmapArgs {
    /// The clip.
    pub clip: PathBuf,
    /// Save the map as JSON here.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub opts: ClipOpts,
}

fn load(path: &std::path::Path, o: &ClipOpts) -> anyhow::Result<Clip> {
    Ok(load_clip(path, &o.load_options()?)?)
}

/// Runs a mocap subcommand.
pub fn run(c: Cmd) -> anyhow::Result<()> {
    match c {
        Cmd::Positions(a) => {
            let mut clip = load(&a.clip, &a.opts)?;
            if a.units == OutUnits::Metres {
                clip.to_metres_y_up();
            }
            let n = clip.frame_count();
            let mut frames = BTreeMap::new();
            for &f in &a.frames {
                if f >= n {
                    bail!(
                        "{}: frame {f} out of range (the clip has {n} frames, 0..{})",
                        a.clip.display(),
                        n - 1
                    );
                }
                let p: Vec<[f64; 3]> = clip.points_at(f).iter().map(|v| v.to_array()).collect();
                frames.insert(f, p);
            }
            let names = clip.point_names();
            if a.json {
                let frames: BTreeMap<String, _> = frames
                    .into_iter()
                    .map(|(k, v)| (k.to_string(), v))
                    .collect();
                let out = serde_json::json!({ "joints": names, "frames": frames });
                crate::outln!("{}", serde_json::to_string(&out)?)?;
            } else {
                for (f, p) in frames {
                    crate::outln!("frame {f}")?;
                    for (n, v) in names.iter().zip(p) {
                        crate::outln!("  {n:<24} {:>12.6} {:>12.6} {:>12.6}", v[0], v[1], v[2])?;
                    }
                }
            }
        }
        Cmd::Convert(a) => {
            let mut clip = load(&a.input, &a.opts)?;
            if a.metres {
                clip.to_metres_y_up();
            }
            if let Some(fps) = a.fps {
                if !(fps.is_finite() && fps > 0.0) {
                    bail!("--fps {fps}: expected a positive number");
                }
                clip = clip.resampled(fps);
            }
            if !a
                .output
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("bvh"))
            {
                bail!("{}: only .bvh output is supported", a.output.display());
            }
            surfmotion::mocap::bvh::write_bvh(&clip, &a.output)
                .with_context(|| format!("writing {}", a.output.display()))?;
            eprintln!(
                "wrote {} ({} joints, {} frames at {:.3} fps)",
                a.output.display(),
                clip.joint_count(),
                clip.frame_count(),
                clip.fps()
            );
        }
        Cmd::Rigmap(a) => {
            let opts = a.opts.load_options()?;
            let clip = load_clip(&a.clip, &opts)?;
            let det = match &opts.rig_map {
                // A given map: check that it resolves on this clip.
                Some(m) => {
                    m.resolve(&clip)
                        .with_context(|| format!("{}", a.clip.display()))?;
                    surfmotion::rig::Detection {
                        map: m.clone(),
                        missing: Vec::new(),
                        signature: true,
                    }
                }
                None => surfmotion::rig::detect(&clip.point_names()),
            };
            if let Some(o) = &a.output {
                det.map.save(o)?;
            }
            if a.json {
                crate::outln!("{}", serde_json::to_string_pretty(&det)?)?;
            } else {
                crate::outln!("convention: {}", det.map.convention)?;
                for (k, v) in &det.map.joints {
                    crate::outln!("  {:<12} {v}", k.name())?;
                }
                if !det.missing.is_empty() {
                    let m: Vec<&str> = det.missing.iter().map(|c| c.name()).collect();
                    crate::outln!(
                        "unmapped: {} (save with -o, fill them in, pass back with --rig-map)",
                        m.join(", ")
                    )?;
                }
            }
        }
    }
    Ok(())
}
