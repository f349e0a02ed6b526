//! `surfmotion db init|info`.

use anyhow::{Context, bail};
use std::path::{Path, PathBuf};
use surfmotion::db::{MANIFEST, Manifest, RigSpec, SequenceEntry, info};

/// Database subcommands.
#[derive(clap::Subcommand)]
pub enum Cmd {
    /// Write DIR/character.toml for a character: its topology mesh, its
    /// captured sequences, frame rate, units, up axis and rig annotation.
    Init(InitArgs),
    /// Load every part of a database and report what it holds and what is
    /// wrong (connectivity or frame-rate mismatch, missing rig, ...).
    Info(InfoArgs),
}

/// Arguments of `db init`.
#[derive(clap::Args)]
pub struct InitArgs {
    /// The database directory (created if missing).
    pub dir: PathBuf,
    /// Topology mesh (its positions are the rest frame).
    #[arg(long)]
    pub mesh: PathBuf,
    /// A captured sequence as NAME=PATH (OBJ folder, .pc2, .mdd, .glb); repeatable.
    #[arg(long = "sequence", value_name = "NAME=PATH")]
    pub sequences: Vec<String>,
    /// Character name (default: the directory name).
    #[arg(long)]
    pub name: Option<String>,
    /// Frames per second of the captures.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f64,
    /// Length unit of the files (m, cm, mm, dm, inch).
    #[arg(long, default_value = "m")]
    pub units: String,
    /// Up axis of the files (y or z).
    #[arg(long, default_value = "y")]
    pub up: String,
    /// Landmarks JSON on the rest frame.
    #[arg(long)]
    pub landmarks: Option<PathBuf>,
    /// Explicit part labels JSON.
    #[arg(long)]
    pub parts: Option<PathBuf>,
    /// A rigged glTF whose vertices match the topology.
    #[arg(long = "gltf-skin")]
    pub gltf_skin: Option<PathBuf>,
    /// Overwrite an existing manifest.
    #[arg(long)]
    pub force: bool,
}

/// Arguments of `db info`.
#[derive(clap::Args)]
pub struct InfoArgs {
    /// The database directory.
    pub dir: PathBuf,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
}

/// A path as the manifest should store it: relative to `dir` when inside it, else absolute.
fn store_path(dir: &Path, p: &Path) -> anyhow::Result<PathBuf> {
    let abs = std::fs::canonicalize(p).with_context(|| format!("{}", p.display()))?;
    let d = std::fs::canonicalize(dir).with_context(|| format!("{}", dir.display()))?;
    Ok(abs.strip_prefix(&d).map(Path::to_path_buf).unwrap_or(abs))
}

/// Runs a db subcommand.
pub fn run(c: Cmd) -> anyhow::Result<()> {
    match c {
        Cmd::Init(a) => {
            std::fs::create_dir_all(&a.dir).with_context(|| format!("{}", a.dir.display()))?;
            if a.dir.join(MANIFEST).exists() && !a.force {
                bail!(
                    "{}: a manifest exists already; pass --force to overwrite it",
                    a.dir.join(MANIFEST).display()
                );
            }
            let mut sequences = Vec::new();
            for s in &a.sequences {
                let Some((name, path)) = s.split_once('=') else {
                    bail!("--sequence '{s}': expected NAME=PATH");
                };
                sequences.push(SequenceEntry {
                    name: name.to_string(),
                    path: store_path(&a.dir, Path::new(path))?,
                    fps: None,
                });
            }
            let opt = |p: &Option<PathBuf>| p.as_ref().map(|p| store_path(&a.dir, p)).transpose();
            let name = a.name.clone().unwrap_or_else(|| {
                std::fs::canonicalize(&a.dir)
                    .ok()
                    .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
                    .unwrap_or_else(|| "character".into())
            });
            let m = Manifest {
                name,
                topology: store_path(&a.dir, &a.mesh)?,
                fps: a.fps,
                units: a.units.clone(),
                up: a.up.to_ascii_lowercase(),
                colors: None,
                sequences,
                rig: RigSpec {
                    landmarks: opt(&a.landmarks)?,
                    parts: opt(&a.parts)?,
                    gltf_skin: opt(&a.gltf_skin)?,
                },
            };
            if let Err(msg) = m.validate() {
                bail!("{msg}");
            }
            m.save(&a.dir)?;
            eprintln!(
                "wrote {} ({} sequences); check it with `surfmotion db info {}`",
                a.dir.join(MANIFEST).display(),
                m.sequences.len(),
                a.dir.display()
            );
        }
        Cmd::Info(a) => {
            let i = info(&a.dir)?;
            if a.json {
                crate::outln!("{}", serde_json::to_string_pretty(&i)?)?;
            } else {
                crate::outln!(
                    "{} ({} vertices, {} triangles)",
                    i.name,
                    i.vertices,
                    i.triangles
                )?;
                for s in &i.sequences {
                    crate::outln!(
                        "  sequence {:<16} {:>6} frames at {} fps",
                        s.name,
                        s.frames,
                        s.fps
                    )?;
                }
                crate::outln!("  total    {:>23} frames", i.total_frames)?;
                for p in &i.problems {
                    crate::outln!("  problem: {p}")?;
                }
            }
        }
    }
    Ok(())
}
