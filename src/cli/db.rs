//! `surfmotion db init|info`.

use anyhow::{Context, bail};
use std::path::{Path, PathBuf};
use surfmotion::db::{MANIFEST, Manifest, RigSpec, SequenceEntry, info};
use surfmotion::embed::frames::SkeletonKind;
use surfmotion::jobs::export_skeletons;
use surfmotion::jobs::skeletons::SkeletonsOptions;
use surfmotion::mesh::Mesh;

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
                *p = super::without_os_error_numbers(p);
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

/// Runs `db init`. Every file is read before anything is written: a mesh
/// path that is a folder of BVH clips, a BVH or a file that does not parse
/// is refused here, naming the file, with nothing left behind (it used to
/// be written into the manifest and refused only by `db info`).
fn init(a: InitArgs) -> anyhow::Result<()> {
    super::output_folder(
        "",
        &a.dir,
        "db init writes the database's character.toml into a folder",
    )?;
    let manifest = a.dir.join(MANIFEST);
    if manifest.exists() && !a.force {
        bail!(
            "{}: a manifest exists already; pass --force to overwrite it",
            manifest.display()
        );
    }
    if !a.units.eq_ignore_ascii_case("auto") {
        super::length_unit("--input-units", &a.units)?;
    }
    if let Some(n) = &a.name
        && (n.is_empty() || n.len() > 200 || n.chars().any(char::is_control))
    {
        bail!(
            "--name \"{}\": expected one line of 1 to 200 bytes, without control characters",
            surfmotion::db::manifest::printable(n, 60)
        );
    }
    let canonical = |p: &Path| std::fs::canonicalize(p).with_context(|| format!("{}", p.display()));
    let mut sequences = Vec::new();
    for s in &a.sequences {
        let Some((name, path)) = s.split_once('=') else {
            bail!("--sequence '{s}': expected NAME=PATH");
        };
        sequences.push(SequenceEntry {
            name: name.to_string(),
            path: canonical(Path::new(path)).with_context(|| format!("--sequence {name}"))?,
            fps: None,
        });
    }
    let opt = |p: &Option<PathBuf>| p.as_deref().map(canonical).transpose();
    let mut m = Manifest {
        name: a.name.clone().unwrap_or_default(),
        topology: canonical(&a.mesh).context("--mesh")?,
        fps: a.fps,
        units: "m".into(),
        up: "y".into(),
        human_sized: !a.not_human_sized,
        colors: None,
        sequences,
        rig: RigSpec {
            landmarks: opt(&a.landmarks).context("--landmarks")?,
            parts: opt(&a.parts).context("--parts")?,
            gltf_skin: opt(&a.gltf_skin).context("--gltf-skin")?,
            rig_map: opt(&a.rig_map).context("--rig-map")?,
        },
        graph: Default::default(),
        deform: Default::default(),
        spaces: Vec::new(),
    };
    let up = a.up.to_ascii_lowercase();
    if !matches!(up.as_str(), "y" | "z" | "auto") {
        bail!("--up {}: expected y, z or auto", a.up);
    }
    if let Err(msg) = m.validate() {
        bail!("{msg}");
    }
    // The paths are absolute here, so the folder they resolve against is
    // not used. Loaded with `up = y`: the file's own coordinates.
    let topo = m.load_topology(&a.dir).context("--mesh")?;
    // A landmark file that does not read or lacks a required landmark is
    // refused here, before the up axis is read off it (issue 39, item 7:
    // it was accepted and refused only by `retarget`); the checks on the
    // landmarks' places follow once the axis is known.
    if let Some(p) = &m.rig.landmarks {
        use surfmotion::embed::landmarks::Landmarks;
        Landmarks::load(p, topo.vertex_count()).context("--landmarks")?;
    }
    m.up = resolve_up(&up, &topo, a.landmarks.as_deref())?;
    m.units = resolve_units(&a.units, &topo);
    if let Some(p) = &m.rig.landmarks {
        surfmotion::embed::landmarks::Landmarks::load_checked(p, &topo)
            .with_context(|| format!("--landmarks {}", p.display()))?;
    }
    // A person-sized character outside 0.5-3 m in the unit is a wrong
    // unit, refused by every verb that opens the database: refused here
    // (issue 39, item 5: one WARN, then a 1.8 cm character retargeted
    // without a word).
    if let Err(surfmotion::db::DbError::Size {
        metres, suggest, ..
    }) = m.check_size(&a.dir, &topo)
    {
        bail!(
            "--input-units {}: the rest frame is {metres:.3} m tall or wide in {}, not a person's 0.5-3 m: is the unit right?{}; \
             for a character that is not a person's size, pass --not-human-sized",
            a.units,
            m.units,
            suggest.map_or(String::new(), |(u, v)| format!(
                " (--input-units {u} makes it {v:.2} m)"
            ))
        );
    }
    // Every sequence must share the topology's vertices: one of another
    // mesh is refused, with nothing written (issue 39, item 6: it was
    // written with a warning, exit 0, and refused later by `db build`).
    for s in &m.sequences {
        let (count, noun, triangles) = match m.load_sequence(&a.dir, s) {
            Ok(q) => (
                q.mesh().vertex_count(),
                "vertices",
                q.mesh().triangles() == topo.triangles(),
            ),
            Err(e) => {
                use surfmotion::mesh::io::{MeshFormat, mdd, pc2};
                // A point cache of another vertex count does not load
                // against this topology: read it on its own.
                let cache = match MeshFormat::of(&s.path) {
                    Some(MeshFormat::Pc2) => pc2::read_pc2(&s.path).ok(),
                    Some(MeshFormat::Mdd) => mdd::read_mdd(&s.path).ok(),
                    _ => None,
                };
                match cache {
                    Some(c) if c.points != topo.vertex_count() => {
                        (c.points, "points per frame", true)
                    }
                    _ => {
                        return Err(
                            anyhow::Error::from(e).context(format!("--sequence {}", s.name))
                        );
                    }
                }
            }
        };
        if count != topo.vertex_count() {
            bail!(
                "--sequence {} ({}): {count} {noun}, the topology (--mesh) has {} vertices: a sequence of another mesh? \
                 Every sequence must have the topology's vertices",
                s.name,
                s.path.display(),
                topo.vertex_count()
            );
        }
        if !triangles {
            bail!(
                "--sequence {} ({}): its triangles differ from the topology's (--mesh): every sequence must share its connectivity",
                s.name,
                s.path.display()
            );
        }
    }
    std::fs::create_dir_all(&a.dir).with_context(|| format!("{}", a.dir.display()))?;
    let dir = canonical(&a.dir)?;
    if m.name.is_empty() {
        m.name = dir
            .file_name()
            .map_or_else(|| "character".into(), |n| n.to_string_lossy().into_owned());
        // A folder name with a newline or a tab: the name is one line.
        if m.name.chars().any(char::is_control) {
            m.name = m.name.replace(char::is_control, " ");
        }
    }
    // Stored relative to the database when inside it, else absolute.
    let store = |p: &Path| {
        p.strip_prefix(&dir)
            .map_or_else(|_| p.to_path_buf(), Path::to_path_buf)
    };
    m.topology = store(&m.topology);
    for s in &mut m.sequences {
        s.path = store(&s.path);
    }
    for p in [
        &mut m.rig.landmarks,
        &mut m.rig.parts,
        &mut m.rig.gltf_skin,
        &mut m.rig.rig_map,
    ]
    .into_iter()
    .flatten()
    {
        *p = store(p);
    }
    m.save(&a.dir)?;
    if a.json {
        let mut v = serde_json::to_value(&m)?;
        v["manifest"] = serde_json::to_value(&manifest)?;
        crate::outln!("{}", serde_json::to_string_pretty(&v)?)?;
    }
    crate::errln!(
        "wrote {} ({}); check it with `surfmotion db info {}`",
        manifest.display(),
        super::count(m.sequences.len(), "sequence"),
        a.dir.display()
    );
    Ok(())
}

/// The manifest's up axis for `db init --up UP`: the landmarks' body axis
/// (groin to chin) read in the mesh file's coordinates decides `auto`
/// (the axis among +Y and +Z it lies within 45° of), and is checked
/// against an explicit `y`/`z`: a capture whose body stands along +Z
/// written as Y-up retargets into a contorted, tilted character with only
/// indirect warnings (knee hyper-extension, turned-over triangles).
fn resolve_up(up: &str, topo: &Mesh, landmarks: Option<&Path>) -> anyhow::Result<String> {
    use surfmotion::embed::landmarks::{Landmark, Landmarks};
    let axis = landmarks.and_then(|p| {
        // An unreadable landmarks file is reported by `db build`, which
        // embeds the rig; here it only leaves the axis undecided.
        let lm = Landmarks::load(p, topo.vertex_count()).ok()?;
        let pos = topo.positions();
        let (c, g) = (
            lm.point(Landmark::Chin, pos)?,
            lm.point(Landmark::Groin, pos)?,
        );
        let b = [c[0] - g[0], c[1] - g[1], c[2] - g[2]];
        let n = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
        (n > 0.0 && n.is_finite()).then(|| [b[0] / n, b[1] / n, b[2] / n])
    });
    let cos45 = std::f64::consts::FRAC_1_SQRT_2;
    let found = axis.map(|b| {
        if b[1] >= cos45 {
            Ok("y")
        } else if b[2] >= cos45 {
            Ok("z")
        } else {
            Err(b)
        }
    });
    let describe = |b: [f64; 3]| format!("({:.2}, {:.2}, {:.2})", b[0], b[1], b[2]);
    Ok(match (up, found) {
        ("auto", None) => "y".into(),
        ("auto", Some(Ok(axis))) => {
            if axis == "z" {
                crate::errln!(
                    "--up auto: the landmarks' groin→chin direction is along +Z: the files are read as Z-up"
                );
            }
            axis.into()
        }
        ("auto", Some(Err(b))) => bail!(
            "--up auto: the landmarks' groin→chin direction {} is within 45° of neither +Y nor +Z; \
             the database reads Y-up or Z-up files: turn the mesh and its sequences, or pass --up y or --up z",
            describe(b)
        ),
        (given, Some(Ok(axis))) if axis != given => {
            tracing::warn!(
                "--up {given}, but the landmarks' groin→chin direction is along +{}: is the capture {}-up? (pass --up {axis} or --up auto)",
                axis.to_ascii_uppercase(),
                axis.to_ascii_uppercase()
            );
            given.into()
        }
        (given, Some(Err(b))) => {
            tracing::warn!(
                "--up {given}, but the landmarks' groin→chin direction {} is within 45° of neither +Y nor +Z",
                describe(b)
            );
            given.into()
        }
        (given, _) => given.into(),
    })
}

/// The manifest's length unit for `db init --input-units UNIT`: `auto`
/// takes m, cm or mm, whichever makes the rest frame's size (its bounding
/// box's largest side) nearest 1.7 m (a person; the unit's log distance, so 0.85-3.4 m
/// all read as metres); an explicit unit that makes the body shorter than
/// 0.3 m or taller than 3 m is kept with a warning. A capture in
/// millimetres read as metres built a 1.7 km dancer whose retargets
/// reported 4.5 m of ground penetration.
fn resolve_units(units: &str, topo: &Mesh) -> String {
    // The bounding box's largest side: the height standing, the span in a
    // T-pose (about the height), and the same whatever the up axis.
    let Some(h) = surfmotion::db::manifest::extent(topo.positions()) else {
        return if units.eq_ignore_ascii_case("auto") {
            "m".into()
        } else {
            units.into()
        };
    };
    if units.eq_ignore_ascii_case("auto") {
        let off = |u: f64| (h * u / 1.7).ln().abs();
        let (u, name) = [(1.0, "m"), (0.01, "cm"), (0.001, "mm")]
            .into_iter()
            .min_by(|a, b| off(a.0).total_cmp(&off(b.0)))
            .unwrap_or((1.0, "m"));
        if name != "m" {
            crate::errln!(
                "--input-units auto: the rest frame is {h:.1} file units tall or wide: read as {name} ({:.2} m)",
                h * u
            );
        }
        return name.into();
    }
    units.into()
}

fn skeleton(a: SkeletonArgs) -> anyhow::Result<()> {
    // Checked before the skeletons are extracted: `-o FILE` said
    // "FILE/rig.json: File exists (os error 17)" after the work.
    let out = a.output.clone().unwrap_or_else(|| a.dir.join("skeletons"));
    super::output_folder(
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
        super::refuse_colliding(&super::database_inputs(&a.dir), &outputs)?;
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
