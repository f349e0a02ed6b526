//! `surfmotion db init|info`.

use std::path::PathBuf;
use surfmotion::jobs::db_info::{self, Listed};
use surfmotion::jobs::skeletons::SkeletonsOptions;
use surfmotion::jobs::{export_skeletons, text};
use surfmotion::util::errtext;

/// Database subcommands.
#[derive(clap::Subcommand)]
#[allow(clippy::large_enum_variant)] // parsed once per run
pub enum Cmd {
    /// Write DIR/character.toml for a character: its topology mesh, its
    /// captured sequences, frame rate, units, up axis and rig annotation.
    #[command(
        after_help = "Example:\n  surfmotion db init samba_db --mesh samba.obj --sequence dance=samba.pc2 --landmarks samba.landmarks.json"
    )]
    Init(super::db_init::InitArgs),
    /// Load every part of a database and report what it holds and what is
    /// wrong (connectivity or frame-rate mismatch, a rest frame not a
    /// person's size in its unit, a landmark file no rig can be embedded
    /// from, ...): exit 1 when it lists a problem. No rig is a note.
    #[command(after_help = "Example:\n  surfmotion db info samba_db")]
    Info(InfoArgs),
    /// Extract the canonical skeleton of every frame of every sequence: the
    /// rig is embedded from the manifest's landmarks, each joint is read off
    /// the frame by its regressor, and the character's one rigid skeleton
    /// (bone lengths calibrated over the database) is fitted to those joints
    /// (--kind regressor: the joints as measured; --kind centroid: the
    /// paper's part centres). Writes per sequence SEQ.skeleton.json and
    /// SEQ.bvh (for any mocap viewer), and rig.json, into --output (default
    /// DIR/skeletons).
    #[command(after_help = "Example:\n  surfmotion db skeleton samba_db")]
    Skeleton(SkeletonArgs),
    /// Build the Surface Motion Graph: compare every frame with every other
    /// (3D shape histograms minimised over rotation about the vertical, or
    /// --measure vertex|skeleton), find transitions by adaptive temporal
    /// filtering (top N per sequence pair, half-window L < 25), and cache the
    /// matrix and graph in DIR/cache. A second build with unchanged inputs
    /// loads the cache and does no work. Settings: the manifest's [graph].
    #[command(
        after_help = "Examples:\n  surfmotion db build samba_db\n  surfmotion inspect samba_db      # is the cache up to date?"
    )]
    Build(BuildArgs),
}

/// Arguments of `db build`.
#[derive(clap::Args)]
pub struct BuildArgs {
    /// The database directory.
    pub dir: PathBuf,
    /// Dissimilarity measure (default: the manifest's [graph] measure, else shape).
    #[arg(long, value_enum)]
    pub measure: Option<super::values::MeasureArg>,
    /// Recompute even if the cache is current.
    #[arg(long)]
    pub force: bool,
    /// Frame similarity: `dense` (every pair, the n² matrix) or `sparse`
    /// (the full measure only near each frame's nearest neighbours, shape
    /// measure; issue 43). Default: sparse from 5,000 frames, dense below.
    #[arg(long, value_name = "dense|sparse")]
    pub similarity: Option<surfmotion::db::build::Method>,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

fn build(a: BuildArgs) -> anyhow::Result<()> {
    let opts = surfmotion::db::BuildOptions {
        measure: a.measure.map(Into::into),
        force: a.force,
        method: a.similarity,
        ..Default::default()
    };
    let (graph, r) = surfmotion::jobs::build_database(&a.dir, &opts, &super::Bars::new())?;
    if a.json {
        return super::emit_json(&r);
    }
    super::emit(&super::flags::as_flags(&text::database(&a.dir, &graph, &r)))
}

/// Arguments of `db skeleton`.
#[derive(clap::Args)]
pub struct SkeletonArgs {
    /// The database directory.
    pub dir: PathBuf,
    /// Output folder (default: DIR/skeletons).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// How joints are read off a frame: `rigid` (default) poses one
    /// skeleton per character, its bone lengths the median over all frames,
    /// nearest the regressor joints in each frame (least squares); `regressor`
    /// gives those joints as measured, `centroid` the paper's part centres.
    #[arg(long, value_enum, default_value_t = surfmotion::jobs::skeletons::SkeletonsOptions::default().kind.into())]
    pub kind: super::values::SkeletonKindArg,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
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

/// Runs a db subcommand.
pub fn run(c: Cmd) -> anyhow::Result<()> {
    match c {
        Cmd::Skeleton(a) => return skeleton(a),
        Cmd::Build(a) => return build(a),
        Cmd::Init(a) => super::db_init::init(a)?,
        Cmd::Info(a) => {
            let mut i = db_info::info(&a.dir)?;
            for p in &mut i.problems {
                *p = super::flags::as_flags(&errtext::without_os_error_numbers(p));
            }
            // A problem is exit 1 ([`db_info::verdict`]).
            let listed = if a.json {
                super::emit_json(&i)?;
                Listed::InJson
            } else {
                super::emit(&text::info(&i))?;
                Listed::Above
            };
            db_info::verdict(&i, &a.dir, listed)?;
        }
    }
    Ok(())
}

fn skeleton(a: SkeletonArgs) -> anyhow::Result<()> {
    let out = a.output.clone().unwrap_or_else(|| a.dir.join("skeletons"));
    surfmotion::jobs::outputs::check_skeleton_outputs("-o", &a.dir, &out)?;
    let opts = SkeletonsOptions {
        kind: a.kind.into(),
        output: a.output.clone(),
    };
    let r = export_skeletons(&a.dir, &opts)?;
    if a.json {
        // Lengths and fit residuals are in the database's units.
        return super::emit_json(&serde_json::to_value(&r)?);
    }
    super::emit(&text::skeletons(&r))
}
