//! `surfmotion db init|info`.

use anyhow::bail;
use std::path::PathBuf;
use surfmotion::db::init::InitOptions;
use surfmotion::db::{Manifest, info};
use surfmotion::embed::frames::SkeletonKind;
use surfmotion::jobs::skeletons::SkeletonsOptions;
use surfmotion::jobs::{export_skeletons, init_database};

/// Database subcommands.
#[derive(clap::Subcommand)]
pub enum Cmd {
    /// Write DIR/character.toml for a character: its topology mesh, its
    /// captured sequences, frame rate, units, up axis and rig annotation.
    #[command(
        after_help = "Example:\n  surfmotion db init samba_db --mesh samba.obj --sequence dance=samba.pc2 --landmarks samba.landmarks.json"
    )]
    Init(InitArgs),
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
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Progress bars for a build.
pub struct Bars(std::sync::Mutex<Option<indicatif::ProgressBar>>);

impl Bars {
    /// No bar yet.
    pub fn new() -> Bars {
        Bars(std::sync::Mutex::new(None))
    }
}

impl surfmotion::db::BuildProgress for Bars {
    fn start(&self, what: &str, total: u64) {
        if let Ok(mut b) = self.0.lock() {
            *b = Some(super::progress(total, what));
        }
    }
    fn advance(&self, k: u64) {
        if let Ok(b) = self.0.lock()
            && let Some(b) = b.as_ref()
        {
            b.inc(k);
        }
    }
    fn finish(&self) {
        if let Ok(mut b) = self.0.lock()
            && let Some(b) = b.take()
        {
            b.finish_and_clear();
        }
    }
}

fn build(a: BuildArgs) -> anyhow::Result<()> {
    let opts = surfmotion::db::BuildOptions {
        measure: a.measure.map(Into::into),
        force: a.force,
    };
    let (graph, r) = surfmotion::jobs::build_database(&a.dir, &opts, &Bars::new())?;
    if a.json {
        return super::emit(&(serde_json::to_string_pretty(&r)? + "\n"));
    }
    let mut out = format!(
        "{}: {} in {}, measure {} ({})\n",
        a.dir.display(),
        super::count(r.frames, "frame"),
        super::count(r.sequences.len(), "sequence"),
        r.measure.name(),
        r.unit
    );
    if r.similarity_cached {
        out += "similarity: cached\n";
    } else {
        out += &format!(
            "similarity: {} pairs in {:.2} s (descriptors {:.2} s, {:.1} µs per pair)\n",
            r.pairs,
            r.pairs_seconds + r.describe_seconds,
            r.describe_seconds,
            1e6 * r.pairs_seconds / (r.pairs.max(1) as f64)
        );
    }
    out += &format!(
        "graph: {} on {}{} in {:.3} s\n",
        super::count(r.transitions, "transition"),
        super::count(r.edges, "sequence edge"),
        if r.graph_cached { " (cached)" } else { "" },
        r.graph_seconds
    );
    for t in graph.transitions.iter().take(40) {
        out += &format!(
            "  {}:{} -> {}:{}  L = {:2}  cost {:.4}\n",
            graph.sequences[t.from].name, t.m, graph.sequences[t.to].name, t.n, t.window, t.cost
        );
    }
    if graph.transitions.len() > 40 {
        out += &format!(
            "  ... (`surfmotion graph {} --json` lists all)\n",
            a.dir.display()
        );
    }
    for e in &graph.removed {
        out += &format!("  removed by the manifest: {e}\n");
    }
    out += &format!("cache: {}\n", r.cache.display());
    super::emit(&out)
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
    #[arg(long, value_enum, default_value_t = super::values::SkeletonKindArg::Rigid)]
    pub kind: super::values::SkeletonKindArg,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
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
    #[arg(long, default_value_t = 30.0, value_parser = super::frame_rate)]
    pub fps: f64,
    /// Length unit of the files (m, cm, mm, dm, inch, metres per unit, or
    /// auto: m, cm or mm, whichever makes the rest frame's largest side
    /// nearest 1.7 m), written as the manifest's `units`. (`--units` was its name
    /// before.)
    #[arg(
        long = "input-units",
        alias = "units",
        value_name = "UNIT",
        default_value = "auto"
    )]
    pub units: String,
    /// Up axis of the files: y, z, or auto (the landmarks' groin→chin
    /// direction decides; y without landmarks). An explicit axis the
    /// landmarks contradict is written as given, with a warning.
    #[arg(long, default_value = "auto")]
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
    /// A rig map for the glTF skin's joint names (when not detected).
    #[arg(long = "rig-map", requires = "gltf_skin")]
    pub rig_map: Option<PathBuf>,
    /// The character is not a person's size (a figurine, a giant, an
    /// animal): its rest frame may measure outside 0.5-3 m in
    /// --input-units (written as the manifest's `human_sized = false`).
    /// Without it such a size is refused as a wrong unit.
    #[arg(long = "not-human-sized")]
    pub not_human_sized: bool,
    /// Overwrite an existing manifest.
    #[arg(long)]
    pub force: bool,
    /// Print the manifest written as JSON.
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
        Cmd::Init(a) => init(a)?,
        Cmd::Info(a) => {
            let mut i = info(&a.dir)?;
            for p in &mut i.problems {
                *p = super::flags::as_flags(&super::without_os_error_numbers(p));
            }
            // A problem is exit 1, so that scripts can rely on `db info`
            // (issue 39, item 6: it listed problems and exited 0).
            let failed = |i: &surfmotion::db::DbInfo, where_: &str| {
                anyhow::anyhow!(
                    "{}: {} ({where_})",
                    a.dir.display(),
                    super::count(i.problems.len(), "problem")
                )
            };
            if a.json {
                crate::outln!("{}", serde_json::to_string_pretty(&i)?)?;
                if !i.problems.is_empty() {
                    return Err(failed(&i, "\"problems\" in the JSON"));
                }
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
                for n in &i.notes {
                    crate::outln!("  note: {n}")?;
                }
                if !i.problems.is_empty() {
                    return Err(failed(&i, "listed above"));
                }
            }
        }
    }
    Ok(())
}

/// Runs `db init` ([`init_database`]): the `NAME=PATH` pairs and the unit
/// are parsed here, everything else is the library's.
fn init(a: InitArgs) -> anyhow::Result<()> {
    let mut sequences = Vec::new();
    for s in &a.sequences {
        let Some((name, path)) = s.split_once('=') else {
            bail!("--sequence '{s}': expected NAME=PATH");
        };
        sequences.push((name.to_string(), PathBuf::from(path)));
    }
    if !a.units.eq_ignore_ascii_case("auto") {
        super::length_unit("--input-units", &a.units)?;
    }
    let opts = InitOptions {
        mesh: a.mesh,
        sequences,
        name: a.name,
        fps: a.fps,
        units: a.units,
        up: a.up,
        landmarks: a.landmarks,
        parts: a.parts,
        gltf_skin: a.gltf_skin,
        rig_map: a.rig_map,
        human_sized: !a.not_human_sized,
        force: a.force,
    };
    let r = init_database(&a.dir, &opts)?;
    for n in &r.notes {
        crate::errln!("{}", super::flags::as_flags(n));
    }
    if a.json {
        let mut v = serde_json::to_value(&r.manifest)?;
        v["manifest"] = serde_json::to_value(&r.path)?;
        crate::outln!("{}", serde_json::to_string_pretty(&v)?)?;
    }
    crate::errln!(
        "wrote {} ({}); check it with `surfmotion db info {}`",
        r.path.display(),
        super::count(r.manifest.sequences.len(), "sequence"),
        a.dir.display()
    );
    Ok(())
}

fn skeleton(a: SkeletonArgs) -> anyhow::Result<()> {
    // Checked before the skeletons are extracted: `-o FILE` said
    // "FILE/rig.json: File exists (os error 17)" after the work.
    let out = a.output.clone().unwrap_or_else(|| a.dir.join("skeletons"));
    surfmotion::jobs::outputs::check_output_folder(
        "-o",
        &out,
        "db skeleton writes rig.json and each sequence's SEQ.skeleton.json and SEQ.bvh into a folder",
    )?;
    if let Ok(m) = Manifest::load(&a.dir) {
        let mut outputs = vec![("-o", out.join("rig.json"))];
        for s in &m.sequences {
            outputs.push(("-o", out.join(format!("{}.skeleton.json", s.name))));
            outputs.push(("-o", out.join(format!("{}.bvh", s.name))));
        }
        surfmotion::jobs::outputs::refuse_colliding(
            &surfmotion::jobs::outputs::database_inputs(&a.dir),
            &outputs,
        )?;
    }
    let opts = SkeletonsOptions {
        kind: a.kind.into(),
        output: a.output.clone(),
    };
    let r = export_skeletons(&a.dir, &opts)?;
    if a.json {
        // Lengths and fit residuals are in the database's units.
        crate::outln!(
            "{}",
            serde_json::to_string_pretty(&serde_json::to_value(&r)?)?
        )?;
        return Ok(());
    }
    let frames: usize = r.sequences.iter().map(|s| s.frames).sum();
    // Millimetres per model unit, from the manifest's units.
    let mm = Manifest::load(&a.dir)
        .ok()
        .and_then(|m| surfmotion::mocap::units::parse_unit(&m.units))
        .map_or(1e3, |u| 1e3 * u.metres_per_unit);
    crate::outln!(
        "embedded the rig and extracted {} ({}) in {:.3} s → {}",
        super::count(frames, "skeleton"),
        SkeletonKind::from(a.kind),
        r.seconds,
        r.output.display()
    )?;
    for s in &r.sequences {
        crate::outln!(
            "  {}: {} frames; bone lengths within {:.1}% of their median (worst: {})",
            s.sequence,
            s.frames,
            100.0 * s.worst_deviation,
            s.worst_bone
        )?;
        if let Some(f) = &s.rigid {
            crate::outln!(
                "    rigid fit to the regressor joints (whose bones vary by up to {:.1}%, {}): \
                 joints off by {:.1} mm RMS in the median frame, {:.1} mm RMS in the worst, \
                 {:.1} mm at most",
                100.0 * f.regressor_worst_deviation,
                f.regressor_worst_bone,
                mm * f.fit_rms_median,
                mm * f.fit_rms_max,
                mm * f.fit_joint_max,
            )?;
        }
    }
    for n in &r.notes {
        crate::outln!("  note: {n}")?;
    }
    Ok(())
}
