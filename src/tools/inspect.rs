//! `inspect`: what any supported file holds, what was assumed, and problems.

mod database;
mod db_files;
mod dot;
mod error;
mod fbx;
mod json;
mod other;
mod place;
mod rig_cache;

pub use database::{CacheEntry, CacheReport, DatabaseReport, DbSequence, DbSkeleton};
pub use db_files::LoadCacheReport;
pub use error::InspectError;
pub use json::{JsonReport, json_kind};
pub use rig_cache::RigCacheReport;

use json::inspect_json;

use crate::mesh::Bounds;
use crate::mesh::io::{MeshFormat, gltf::read_gltf};
use crate::mocap::{MocapFormat, Units, UpAxis, units::rest_extent};
use crate::rig::{LoadOptions, load_clip};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What a mocap file holds.
#[derive(Debug, Clone, Serialize)]
pub struct MocapReport {
    /// The file.
    pub path: PathBuf,
    /// `bvh`, `amc` or `asf`.
    pub format: String,
    /// Joint count.
    pub joints: usize,
    /// Joint names in file order.
    pub joint_names: Vec<String>,
    /// Frame count.
    pub frames: usize,
    /// Frames per second.
    pub fps: f64,
    /// Seconds from first to last frame.
    pub duration_s: f64,
    /// Length unit assumed, and why.
    pub units: Units,
    /// Up axis assumed.
    pub up: UpAxis,
    /// Why.
    pub up_reason: String,
    /// Largest span of the rest skeleton, in metres.
    pub rest_extent_m: f64,
    /// Rig convention detected (a known convention only when all its names
    /// match; `unknown convention, mapped by structure|names`; or
    /// `not a humanoid: <reason>`).
    pub convention: String,
    /// Canonical joints the convention could not map.
    pub unmapped_canonical: Vec<String>,
    /// Per canonical joint: the clip's joint, its source and confidence
    /// (empty when not a humanoid).
    pub rig_joints: Vec<crate::rig::JointReport>,
    /// Canonical joints placed by a derivation rule (no joint in the clip).
    pub derived_canonical: Vec<String>,
    /// How left and right were decided.
    pub sides: String,
    /// Notes on the rig structure: the pose it was read on when the rest
    /// skeleton is not a standing body, chains off the chest it ignored
    /// (empty: none).
    #[serde(skip_serializing_if = "String::is_empty")]
    pub structure_pose: String,
    /// Problems found while reading.
    pub warnings: Vec<String>,
}

/// What a mesh file holds.
#[derive(Debug, Clone, Serialize)]
pub struct MeshReport {
    /// The file.
    pub path: PathBuf,
    /// Format name.
    pub format: String,
    /// Vertex count.
    pub vertices: usize,
    /// Triangle count.
    pub triangles: usize,
    /// Frames (1 for a static mesh).
    pub frames: usize,
    /// Frames per second, if known.
    pub fps: Option<f64>,
    /// Bounds over all frames (file units).
    pub bounds: Bounds,
    /// Whether vertices carry colours.
    pub colors: bool,
    /// Groups and their triangle counts.
    pub groups: Vec<(String, u32)>,
    /// Skin joints (glTF).
    pub skin_joints: Vec<String>,
    /// The skin's rig convention, as for clips (a known convention; `unknown
    /// convention, mapped by structure|names`; or `not a humanoid: <reason>`).
    /// Empty without a skin.
    pub skin_convention: String,
    /// Per canonical joint: the skin joint, its source and confidence
    /// (empty without a skin or when not a humanoid).
    pub skin_rig_joints: Vec<crate::rig::JointReport>,
    /// How the skin's left and right were decided.
    pub skin_sides: String,
    /// Morph targets (glTF).
    pub morph_targets: usize,
    /// Animations and durations (glTF).
    pub animations: Vec<(String, f32)>,
    /// Problems (degenerate or duplicate triangles, unreferenced vertices, ...).
    pub problems: Vec<String>,
}

/// The report of [`inspect`].
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Report {
    /// A mocap clip.
    Mocap(MocapReport),
    /// A mesh or sequence.
    Mesh(MeshReport),
    /// A landmark or marker file.
    Json(JsonReport),
    /// Any other file the tool reads or writes (a database manifest, web
    /// geometry, a site, a cache, a picture, a Graphviz graph), described
    /// in lines.
    File(JsonReport),
    /// A character database folder.
    Database(DatabaseReport),
    /// The cache folder of a character database.
    Cache(CacheReport),
    /// A database's rig cache (`cache/rig.json`, written by loads).
    RigCache(RigCacheReport),
    /// A load's other cache files (`cache/frames.bin`, `poses-KIND.bin`,
    /// `plausibility-reference.json`, `content-hashes.json`).
    LoadCache(LoadCacheReport),
}

/// Options for [`inspect`].
#[derive(Debug, Clone, Default)]
pub struct InspectOptions {
    /// Passed to the mocap loader.
    pub mocap: LoadOptions,
    /// Passed to the mesh loader.
    pub mesh: crate::mesh::io::LoadOptions,
}

/// Reads `path` and reports what it holds.
pub fn inspect(path: &Path, opts: &InspectOptions) -> Result<Report, InspectError> {
    // A glTF is a character first: its report lists the animations a
    // clip reader's `take` chooses among.
    if let Some(fmt) = MocapFormat::of(path).filter(|f| *f != MocapFormat::Gltf) {
        return inspect_mocap(path, fmt, opts).map(Report::Mocap);
    }
    // Before the JSON files: a rig cache is a header line, then the rig.
    if rig_cache::is_rig_cache(path) {
        return rig_cache::inspect_rig_cache(path).map(Report::RigCache);
    }
    if let Some(kind) = db_files::kind_of(path) {
        return db_files::inspect_load_cache(path, kind).map(Report::LoadCache);
    }
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"))
    {
        return inspect_json(path).map(Report::Json);
    }
    // A database folder holds OBJ files, but is not a sequence of them.
    if database::is_database(path) {
        return database::inspect_database(path).map(Report::Database);
    }
    if let Some(db) = database::database_of_cache(path) {
        return database::inspect_cache(path, &db).map(Report::Cache);
    }
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("dot") || e.eq_ignore_ascii_case("gv"))
    {
        return dot::inspect_dot(path).map(Report::File);
    }
    if let Some(r) = other::inspect_other(path) {
        return r.map(Report::File);
    }
    inspect_mesh(path, opts).map(Report::Mesh)
}

/// A mocap clip: its joints, frames, units and axes, and its rig detection
/// (or the map file's).
fn inspect_mocap(
    path: &Path,
    fmt: MocapFormat,
    opts: &InspectOptions,
) -> Result<MocapReport, InspectError> {
    let clip = load_clip(path, &opts.mocap)?;
    let det = match &opts.mocap.rig_map {
        Some(m) => Ok(crate::rig::Detection::from_map(
            m.clone(),
            crate::rig::Provenance::MapFile,
            1.0,
            "from the map file",
        )),
        None => crate::rig::detect_clip(&clip),
    };
    let mut structure_pose = String::new();
    let (convention, unmapped_canonical, rig_joints, derived_canonical, sides) = match det {
        Ok(d) => (
            d.map.convention.clone(),
            d.missing.iter().map(|c| c.name().to_string()).collect(),
            d.joints,
            d.derived.iter().map(|c| c.name().to_string()).collect(),
            {
                structure_pose = d.structure_pose;
                d.sides
            },
        ),
        Err(e) => (
            e.to_string(),
            crate::rig::Canonical::ALL
                .iter()
                .map(|c| c.name().to_string())
                .collect(),
            Vec::new(),
            Vec::new(),
            String::new(),
        ),
    };
    Ok(MocapReport {
        path: path.to_path_buf(),
        format: match fmt {
            MocapFormat::Fbx => fbx::describe(path, opts.mocap.take.as_deref()),
            _ => format!("{fmt:?}").to_lowercase(),
        },
        joints: clip.joint_count(),
        joint_names: clip.point_names(),
        frames: clip.frame_count(),
        fps: clip.fps(),
        duration_s: clip.duration(),
        rest_extent_m: rest_extent(&clip) * clip.units.metres_per_unit,
        units: clip.units.clone(),
        up: clip.up,
        up_reason: clip.up_reason.clone(),
        convention,
        unmapped_canonical,
        rig_joints,
        derived_canonical,
        sides,
        structure_pose,
        warnings: clip.warnings.clone(),
    })
}

/// A mesh or mesh sequence (OBJ, PLY, point caches, glTF with its skin,
/// morph targets and animations).
fn inspect_mesh(path: &Path, opts: &InspectOptions) -> Result<MeshReport, InspectError> {
    let spec = path
        .to_str()
        .ok_or_else(|| InspectError::NotUtf8(path.to_path_buf()))?
        .to_string();
    if let Some(e) = crate::mesh::io::bad_frame_ref(&spec) {
        return Err(e.into());
    }
    let (p, _) = crate::mesh::io::split_frame_ref(&spec);
    let Some(fmt) = MeshFormat::of(&p) else {
        return Err(InspectError::Unknown(path.to_path_buf()));
    };
    let (mut skin_joints, mut morph_targets, mut animations, mut problems) =
        (Vec::new(), 0, Vec::new(), Vec::new());
    let (mut skin_convention, mut skin_rig_joints, mut skin_sides) =
        (String::new(), Vec::new(), String::new());
    if matches!(fmt, MeshFormat::Gltf | MeshFormat::Glb) {
        let a = read_gltf(&p)?;
        skin_joints = a
            .skin
            .as_ref()
            .map(|s| s.joint_names.clone())
            .unwrap_or_default();
        if a.skin.is_some() {
            match crate::rig::load::detect_skin(&a) {
                Ok(d) => {
                    skin_convention = d.map.convention.clone();
                    skin_rig_joints = d.joints;
                    skin_sides = d.sides;
                }
                Err(e) => skin_convention = e.to_string(),
            }
        }
        morph_targets = a.morph_targets.len();
        animations = a.animations.clone();
        problems = a.problems.clone();
    }
    let seq = crate::mesh::io::load_sequence(&spec, &opts.mesh)?;
    let m = seq.mesh();
    problems.extend(m.problems());
    Ok(MeshReport {
        path: path.to_path_buf(),
        format: format!("{fmt:?}").to_lowercase(),
        vertices: m.vertex_count(),
        triangles: m.triangle_count(),
        frames: seq.frame_count(),
        fps: seq.fps,
        bounds: seq.bounds(),
        colors: m.colors().is_some(),
        groups: m
            .groups()
            .iter()
            .map(|g| (g.name.clone(), g.end - g.start))
            .collect(),
        skin_joints,
        skin_convention,
        skin_rig_joints,
        skin_sides,
        morph_targets,
        animations,
        problems,
    })
}

/// A rig detection as text: the convention, how sides were decided, then
/// one line per canonical joint (joint or rule, source, confidence).
pub fn detection_text(d: &crate::rig::Detection) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "convention: {}", d.map.convention);
    if !d.sides.is_empty() {
        let _ = writeln!(s, "left/right: {}", d.sides);
    }
    if !d.structure_pose.is_empty() {
        let _ = writeln!(s, "structure: {}", d.structure_pose);
    }
    for j in &d.joints {
        let what = match (&j.joint, d.map.derived.get(&j.canonical)) {
            (Some(n), _) => n.clone(),
            (None, Some(r)) => {
                format!("derived ({})", serde_json::to_string(r).unwrap_or_default())
            }
            (None, None) => "-".into(),
        };
        let _ = writeln!(
            s,
            "  {:<12} {:<32} {:<10} {:.2}",
            j.canonical.name(),
            what,
            format!("{:?}", j.source).to_lowercase(),
            j.confidence
        );
    }
    s
}

impl Report {
    /// A human-readable summary.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        match self {
            Report::Mocap(r) => {
                let _ = writeln!(s, "{} ({})", r.path.display(), r.format);
                let _ = writeln!(s, "  joints      {}", r.joints);
                let _ = writeln!(
                    s,
                    "  frames      {} at {:.3} fps ({:.2} s)",
                    r.frames, r.fps, r.duration_s
                );
                let _ = writeln!(
                    s,
                    "  units       {} = {} m per unit ({})",
                    r.units.name, r.units.metres_per_unit, r.units.reason
                );
                let _ = writeln!(s, "  up axis     {:?} ({})", r.up, r.up_reason);
                let _ = writeln!(
                    s,
                    "  rest size   {:.2} m (largest span of the rest skeleton)",
                    r.rest_extent_m
                );
                let _ = writeln!(s, "  convention  {}", r.convention);
                if !r.unmapped_canonical.is_empty() && !r.rig_joints.is_empty() {
                    let _ = writeln!(s, "  unmapped    {}", r.unmapped_canonical.join(", "));
                }
                if !r.structure_pose.is_empty() {
                    let _ = writeln!(s, "  structure   {}", r.structure_pose);
                }
                write_mapping(&mut s, &r.sides, &r.rig_joints);
                let _ = writeln!(s, "  joint names {}", r.joint_names.join(" "));
                for w in &r.warnings {
                    let _ = writeln!(s, "  warning: {w}");
                }
            }
            Report::Mesh(r) => {
                let _ = writeln!(s, "{} ({})", r.path.display(), r.format);
                let _ = writeln!(s, "  vertices    {}", r.vertices);
                let _ = writeln!(s, "  triangles   {}", r.triangles);
                let fps = r.fps.map(|f| format!(" at {f:.3} fps")).unwrap_or_default();
                let _ = writeln!(s, "  frames      {}{fps}", r.frames);
                let b = r.bounds;
                let _ = writeln!(
                    s,
                    "  bounds      [{:.4} {:.4} {:.4}] .. [{:.4} {:.4} {:.4}] (diagonal {:.4}, file units)",
                    b.min[0],
                    b.min[1],
                    b.min[2],
                    b.max[0],
                    b.max[1],
                    b.max[2],
                    b.diagonal()
                );
                let _ = writeln!(s, "  colours     {}", if r.colors { "yes" } else { "no" });
                if !r.groups.is_empty() {
                    let g: Vec<String> = r
                        .groups
                        .iter()
                        .take(12)
                        .map(|(n, c)| format!("{n}({c})"))
                        .collect();
                    let more = if r.groups.len() > 12 {
                        format!(" … {} groups", r.groups.len())
                    } else {
                        String::new()
                    };
                    let _ = writeln!(s, "  groups      {}{more}", g.join(" "));
                }
                if !r.skin_joints.is_empty() {
                    let _ = writeln!(
                        s,
                        "  skin        {} joints: {}",
                        r.skin_joints.len(),
                        r.skin_joints.join(" ")
                    );
                    let _ = writeln!(s, "  convention  {}", r.skin_convention);
                    write_mapping(&mut s, &r.skin_sides, &r.skin_rig_joints);
                }
                if r.morph_targets > 0 {
                    let _ = writeln!(s, "  morph       {} targets", r.morph_targets);
                }
                for (i, (n, d)) in r.animations.iter().enumerate() {
                    let _ = writeln!(s, "  animation   {i} '{n}' {d:.2} s");
                }
                for p in &r.problems {
                    let _ = writeln!(s, "  problem: {p}");
                }
            }
            Report::Json(r) | Report::File(r) => {
                let _ = writeln!(s, "{} ({})", r.path.display(), r.format);
                for l in &r.lines {
                    let _ = writeln!(s, "  {l}");
                }
            }
            Report::Database(r) => s = r.to_text(),
            Report::Cache(r) => s = r.to_text(),
            Report::RigCache(r) => s = r.to_text(),
            Report::LoadCache(r) => s = r.to_text(),
        }
        s
    }
}

/// The joint mapping's lines of a text report: how left and right were
/// decided, then each canonical joint with its joint, source and confidence.
fn write_mapping(s: &mut String, sides: &str, joints: &[crate::rig::JointReport]) {
    use std::fmt::Write as _;
    if !sides.is_empty() {
        let _ = writeln!(s, "  left/right  {sides}");
    }
    for j in joints {
        let _ = writeln!(
            s,
            "    {:<12} {:<28} {:<10} {:.2}",
            j.canonical.name(),
            j.joint.as_deref().unwrap_or("(derived)"),
            format!("{:?}", j.source).to_lowercase(),
            j.confidence
        );
    }
}
