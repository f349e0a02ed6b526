//! `surfmotion db init|info`.

use anyhow::bail;
use std::path::PathBuf;
use surfmotion::db::info;
use surfmotion::db::init::InitOptions;
use surfmotion::jobs::db_init::{InitSetup, Setup, init_database_with};
use surfmotion::jobs::skeletons::SkeletonsOptions;
use surfmotion::jobs::{export_skeletons, text};

/// Database subcommands.
#[derive(clap::Subcommand)]
#[allow(clippy::large_enum_variant)] // parsed once per run
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
    };
    let (graph, r) = surfmotion::jobs::build_database(&a.dir, &opts, &super::Bars::new())?;
    if a.json {
        return super::emit(&(serde_json::to_string_pretty(&r)? + "\n"));
    }
    super::emit(&text::database(&a.dir, &graph, &r))
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
    /// Keep the topology's positions as the rest frame even when they have
    /// a contact. Without it, with --landmarks and sequences, a topology
    /// frame where the body touches itself far along the surface (a hand on
    /// the hip, forearms on the belly) is replaced by the clearest frame of
    /// the sequences for embedding the rig (written as `[rig] rest`): a
    /// contact in the rest frame wires the touching parts together.
    #[arg(long = "keep-rest-frame")]
    pub keep_rest_frame: bool,
    /// Write a picture of the rig (parts coloured, skeleton drawn), front
    /// and side, on the topology's frame and on the rest frame chosen.
    /// Needs a rig: --landmarks, or sequences to rig the character from.
    #[arg(long, value_name = "FILE.png")]
    pub png: Option<PathBuf>,
    /// Without --landmarks and --gltf-skin, write the manifest without a
    /// rig instead of rigging the character from its capture (the graph,
    /// key-frame search and web export need none; retarget needs a rig).
    #[arg(long = "no-rig", conflicts_with_all = ["landmarks", "gltf_skin"])]
    pub no_rig: bool,
    /// Print the manifest written as JSON, with the setup report under
    /// "setup" (also written as DIR/setup.json with --landmarks).
    #[arg(long)]
    pub json: bool,
    /// Then open a page on 127.0.0.1 (URL printed, Ctrl-C stops) on the rest frame: drag a landmark to re-embed; Save writes NAME.picked.landmarks.json beside the landmark file and the manifest names it when the page stops.
    #[arg(long, requires = "landmarks")]
    pub pick: bool,
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
                super::emit(&text::info(&i))?;
                if !i.problems.is_empty() {
                    return Err(failed(&i, "listed above"));
                }
            }
        }
    }
    Ok(())
}

/// Runs `db init` ([`init_database_with`]): the `NAME=PATH` pairs and the unit
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
        choose_rest: !a.keep_rest_frame,
    };
    let setup = InitSetup {
        png: a.png,
        no_rig: a.no_rig,
        ..InitSetup::default()
    };
    let r = init_database_with(&a.dir, &opts, &setup)?;
    for n in &r.notes {
        crate::errln!("{}", super::flags::as_flags(n));
    }
    if a.json {
        let mut v = serde_json::to_value(&r.manifest)?;
        v["manifest"] = serde_json::to_value(&r.path)?;
        if let Some(s) = &r.setup {
            v["setup"] = serde_json::to_value(s)?;
        }
        crate::outln!("{}", serde_json::to_string_pretty(&v)?)?;
    } else if let Some(s) = &r.setup {
        crate::errln!("{}", super::flags::as_flags(&setup_text(s)));
    }
    crate::errln!(
        "wrote {} ({}); check it with `surfmotion db info {}`",
        r.path.display(),
        super::count(r.manifest.sequences.len(), "sequence"),
        a.dir.display()
    );
    if a.pick {
        let o = surfmotion::jobs::pick::PickOptions::default();
        return super::pick::serve(surfmotion::jobs::pick::open_db(&a.dir, &o)?, false);
    }
    Ok(())
}

/// The setup report as `db init` prints it.
fn setup_text(s: &Setup) -> String {
    let mut out = format!("rest frame: {} ({})\n", s.rest_frame, s.why);
    let contacts = |list: &[surfmotion::jobs::db_init::ContactReport]| {
        list.iter()
            .map(|c| {
                format!(
                    "{} ({} vertices, gap {:.3})",
                    c.parts.join(" ↔ "),
                    c.vertices,
                    c.gap
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    if !s.topology_contacts.is_empty() {
        out += &format!(
            "contacts on the topology's frame: {}\n",
            contacts(&s.topology_contacts)
        );
    }
    if !s.rest_contacts.is_empty() {
        out += &format!(
            "contacts on the rest frame: {}\n",
            contacts(&s.rest_contacts)
        );
    }
    if s.frames_examined > 0 {
        out += &format!(
            "frames with a contact: {} of {}\n",
            s.frames_in_contact, s.frames_examined
        );
    }
    let worst = s
        .rigidity
        .iter()
        .max_by(|a, b| a.rms_percent.total_cmp(&b.rms_percent));
    if let Some(w) = worst {
        out += &format!(
            "part rigidity: the least rigid part is {} ({:.1} % of the height rms off one rigid motion)\n",
            w.part, w.rms_percent
        );
    }
    for p in &s.rigidity {
        for st in &p.stray {
            let shown: Vec<String> = st.vertices.iter().take(8).map(u32::to_string).collect();
            out += &format!(
                "WARN part {}: {} vertices follow {} instead (vertices {}{}; frames {:?})\n",
                p.part,
                st.vertices.len(),
                st.follows,
                shown.join(", "),
                if st.vertices.len() > 8 { ", …" } else { "" },
                st.frames
            );
        }
    }
    for n in &s.rig_notes {
        out += &format!("rig: {n}\n");
    }
    for w in &s.check.warnings {
        out += &format!("WARN rig: {}\n", w.message);
    }
    if let Some(p) = &s.png {
        out += &format!("wrote {}\n", p.display());
    }
    out += &format!("wrote {}", s.path.display());
    out
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
        let v = serde_json::to_value(&r)?;
        return crate::outln!("{}", serde_json::to_string_pretty(&v)?);
    }
    super::emit(&text::skeletons(&r))
}
