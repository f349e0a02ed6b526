//! `inspect`: what any supported file holds, what was assumed, and problems.

mod database;
mod dot;
mod other;

pub use database::{CacheEntry, CacheReport, DatabaseReport, DbSequence, DbSkeleton};

use crate::batch::summary::count;
use crate::mesh::io::{MeshFormat, gltf::read_gltf};
use crate::mesh::{Bounds, MeshError};
use crate::mocap::{MocapError, MocapFormat, Units, UpAxis, units::rest_extent};
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

/// What a JSON input holds (landmarks or Confluent markers).
#[derive(Debug, Clone, Serialize)]
pub struct JsonReport {
    /// The file.
    pub path: PathBuf,
    /// What it is ([`json_kind`]): `landmarks`, `markers`, `rig`, `rig
    /// map`, `skeletons`, `graph cache` or a `retarget|transfer|keyframe
    /// report`.
    pub format: String,
    /// One line per fact.
    pub lines: Vec<String>,
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
}

/// Error of [`inspect`].
#[derive(Debug, thiserror::Error)]
pub enum InspectError {
    /// A mocap reader failed.
    #[error(transparent)]
    Mocap(#[from] MocapError),
    /// A mesh reader failed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A bad landmark or marker file.
    #[error("{0}")]
    Json(String),
    /// Not a format we read.
    #[error(
        "{0}: unknown file type (mocap: .bvh .amc .asf; meshes: .obj .ply .pc2 .mdd .gltf .glb or a folder of .obj; a database folder or its cache; the JSON files, manifests, caches, Graphviz graphs, pictures and web sites the tool writes)"
    )]
    Unknown(PathBuf),
    /// A mesh path that is not UTF-8: mesh paths are read as text
    /// (`SEQ.pc2:FRAME`), and a lossy copy named another file ("No such
    /// file or directory" for a file that is there).
    #[error("{}: a mesh file name that is not UTF-8 is not supported; rename it", .0.display())]
    NotUtf8(PathBuf),
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
    if let Some(fmt) = MocapFormat::of(path) {
        let clip = load_clip(path, &opts.mocap)?;
        let det = match &opts.mocap.rig_map {
            Some(m) => Ok(crate::rig::Detection::from_map(
                m.clone(),
                crate::rig::Source::MapFile,
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
        return Ok(Report::Mocap(MocapReport {
            path: path.to_path_buf(),
            format: format!("{fmt:?}").to_lowercase(),
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
        }));
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
    Ok(Report::Mesh(MeshReport {
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
    }))
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

/// What kind of JSON file `v` is, by its content: every JSON file the
/// project reads or writes has its own top-level keys. `None`: none of
/// them (a file is never read as landmarks unless it has a landmark name;
/// `inspect DB/cache/graph-shape.json` said `unknown landmark "graph"`).
pub fn json_kind(v: &serde_json::Value) -> Option<&'static str> {
    if let Some(a) = v.as_array() {
        let triple = |x: &serde_json::Value| x.as_array().is_some_and(|p| p.len() == 3);
        return if !a.is_empty() && a.iter().all(triple) {
            Some("pose")
        } else if !a.is_empty() && a.iter().all(|r| r.get("t").is_some()) {
            Some("play script")
        } else {
            None
        };
    }
    let o = v.as_object()?;
    let has = |k: &str| o.contains_key(k);
    let kind = if has("key")
        && o.get("graph")
            .is_some_and(|g| g.get("transitions").is_some())
    {
        "graph cache"
    } else if o.get("markers").is_some_and(|m| m.is_array()) {
        "markers"
    } else if has("vertex_count") && has("joints") && has("skin") {
        "rig"
    } else if has("convention") && o.get("joints").is_some_and(|j| j.is_object()) {
        "rig map"
    } else if has("sequence") && has("joints") && o.get("frames").is_some_and(|f| f.is_array()) {
        "skeletons"
    } else if has("keys") && has("segments") && has("targets") {
        "keyframe report"
    } else if has("keys") && has("distances") && has("times") && has("reachable") {
        "keyframe grid report"
    } else if has("outcomes") && has("clips_per_minute") {
        "batch report"
    } else if has("per_second") && has("realtime_factor") {
        "play report"
    } else if o.get("format").and_then(|f| f.as_str()) == Some("surfmotion-web") {
        "web site manifest"
    } else if has("retrieval") && has("frames") {
        "retarget report"
    } else if has("transfer") && has("scan") {
        "transfer report"
    } else if !o.is_empty()
        && o.iter()
            .all(|(k, v)| crate::embed::parts::Part::from_name(k).is_some() && v.is_array())
        && o.values()
            .flat_map(|v| v.as_array().into_iter().flatten())
            .all(|x| x.is_u64())
    {
        "parts"
    } else if o
        .keys()
        .any(|k| crate::embed::landmarks::Landmark::from_name(k).is_some())
    {
        "landmarks"
    } else {
        return None;
    };
    Some(kind)
}

/// Landmarks (`{name: vertex | [x, y, z]}`), markers (`{"markers": […]}`),
/// and the other JSON files the project writes (rig, rig map, graph cache,
/// skeletons, reports), told apart by [`json_kind`].
fn inspect_json(path: &Path) -> Result<JsonReport, InspectError> {
    use crate::embed::landmarks::{Landmark, Landmarks, Mark};
    let err = |e: String| InspectError::Json(e);
    let text = crate::fsutil::read_text(path).map_err(|e| err(e.to_string()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| err(format!("{}: {e}", path.display())))?;
    let mut lines = Vec::new();
    let Some(format) = json_kind(&v) else {
        let keys = match v.as_object() {
            Some(o) if o.is_empty() => "an empty object".to_string(),
            Some(o) => format!(
                "top-level keys {}",
                o.keys().take(8).cloned().collect::<Vec<_>>().join(", ")
            ),
            None => "not an object".to_string(),
        };
        return Err(err(format!(
            "{}: unknown JSON ({keys}); inspect reads landmarks, markers, rigs, rig maps, skeletons, poses, play scripts, graph caches, web site manifests and retarget, transfer, keyframe, grid, batch and play reports",
            path.display()
        )));
    };
    // A file that has a kind's keys but not its values is malformed, not
    // that kind ("a keyframe report: 238 frames at NaN fps", exit 0, for a
    // report whose `fps` was `[[[[1e308]]]]`).
    if let Err(why) = check_fields(&v, format) {
        return Err(err(format!(
            "{}: a malformed {format}: {why}",
            path.display()
        )));
    }
    let num = |v: &serde_json::Value, k: &str| v.get(k).and_then(|x| x.as_f64());
    let len =
        |v: &serde_json::Value, k: &str| v.get(k).and_then(|x| x.as_array()).map_or(0, |a| a.len());
    let len_of = |v: &serde_json::Value| v.as_array().map_or(0, |a| a.len());
    match format {
        "markers" => {
            let f = crate::transfer::MarkerFile::parse(&text, path, usize::MAX)
                .map_err(|e| err(e.to_string()))?;
            lines.push(format!(
                "{} markers{}",
                f.markers.len(),
                f.triangle_count
                    .map(|t| format!(" on a mesh of {t} triangles"))
                    .unwrap_or_default()
            ));
            let mut per: std::collections::BTreeMap<String, usize> = Default::default();
            for m in &f.markers {
                let b = m
                    .bone
                    .map_or("(no bone)".to_string(), |b| b.name().to_string());
                *per.entry(b).or_default() += 1;
            }
            lines.push(format!(
                "by bone: {}",
                per.iter()
                    .map(|(b, n)| format!("{b} {n}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        "landmarks" => {
            let lm = Landmarks::parse(&text, path, usize::MAX).map_err(|e| err(e.to_string()))?;
            for (l, m) in &lm.marks {
                lines.push(match m {
                    Mark::Vertex(i) => format!("{:<11} vertex {i}", l.name()),
                    Mark::Point(p) => {
                        format!("{:<11} point [{}, {}, {}]", l.name(), p[0], p[1], p[2])
                    }
                });
            }
            let optional: Vec<&str> = Landmark::ALL
                .iter()
                .filter(|l| !lm.marks.contains_key(l))
                .map(|l| l.name())
                .collect();
            if !optional.is_empty() {
                lines.push(format!(
                    "not given (optional, placed by body proportions): {}",
                    optional.join(", ")
                ));
            }
        }
        "graph cache" => {
            let g = &v["graph"];
            lines.push(format!(
                "the Surface Motion Graph cached by `db build` (measure {}); rebuilt whenever the database changes",
                g["measure"].as_str().unwrap_or("?")
            ));
            let seqs = named_frames(g, "len");
            lines.push(format!("{} sequences: {}", seqs.len(), seqs.join(", ")));
            lines.push(format!(
                "{} transitions, {} edges",
                len(g, "transitions"),
                len(g, "edges")
            ));
        }
        "rig" => {
            lines.push(format!(
                "a rig embedded by `rig embed`: {} joints on a mesh of {} vertices, {:.3} m tall",
                len(&v, "joints"),
                v["vertex_count"],
                num(&v, "height").unwrap_or(f64::NAN)
            ));
            for n in v["notes"].as_array().into_iter().flatten() {
                lines.push(format!("note: {}", n.as_str().unwrap_or_default()));
            }
        }
        "parts" => {
            let o = v.as_object().into_iter().flatten();
            lines.push(format!(
                "part labels (`db init --parts`): {}",
                o.map(|(k, ids)| format!("{k} {}", len_of(ids)))
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        "pose" => {
            let n = len_of(&v);
            lines.push(format!(
                "a key-frame pose (`keyframe --from POSE.json`): {n} joints [x, y, z] in metres, Y up{}",
                if n == crate::rig::Canonical::COUNT {
                    String::new()
                } else {
                    format!(" (keyframe needs {})", crate::rig::Canonical::COUNT)
                }
            ));
        }
        "play script" => {
            let a = v.as_array().map_or(&[][..], |a| a.as_slice());
            let last = a.iter().filter_map(|r| r["t"].as_f64()).fold(0.0, f64::max);
            let mut spaces: Vec<&str> = a.iter().filter_map(|r| r["space"].as_str()).collect();
            spaces.dedup();
            lines.push(format!(
                "a `play` script: {} over {} s, spaces {}; `play --db DB --script` checks it against the database's spaces",
                count(a.len(), "request"),
                crate::parametric::script::short_number(last),
                if spaces.is_empty() { "-".to_string() } else { spaces.join(", ") }
            ));
            // The times `play` refuses whatever the database ("1 request
            // over 1e308 s" was printed as if the script were sound).
            use crate::parametric::script::{MAX_SECONDS, short_number};
            let mut before = 0.0;
            for (i, r) in a.iter().enumerate() {
                let Some(t) = r["t"].as_f64() else {
                    lines.push(format!(
                        "problem: request {i}: no \"t\" (seconds); `play` refuses it"
                    ));
                    break;
                };
                if !(0.0..=MAX_SECONDS).contains(&t) || t < before {
                    lines.push(format!(
                        "problem: request {i}: t = {}: expected seconds in [0, {MAX_SECONDS}], in time order; `play` refuses it",
                        short_number(t)
                    ));
                    break;
                }
                before = t;
            }
        }
        "keyframe grid report" => {
            let keys: Vec<&str> = v["keys"]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(|k| k.as_str())
                .collect();
            lines.push(format!(
                "a key-frame grid (`keyframe --grid --report`): {}, {} × {}",
                keys.join(" -> "),
                count(len(&v, "distances"), "distance"),
                count(len(&v, "times"), "time")
            ));
            lines.push(format!(
                "reachable {}, unreachable {}; query time {:.2} ms mean",
                v["reachable"]["distance_m"]["count"],
                v["unreachable"]["distance_m"]["count"],
                num(&v, "query_ms_mean").unwrap_or(f64::NAN)
            ));
        }
        "batch report" => {
            lines.push(format!(
                "a `batch` report: {}: {}, {} converted, {} already done, {} failed{}",
                v["what"].as_str().unwrap_or("?"),
                count(len(&v, "outcomes"), "clip"),
                v["done"],
                v["skipped"],
                v["failed"],
                if v["finished"] == false {
                    " (the run did not finish)"
                } else {
                    ""
                }
            ));
        }
        "play report" => {
            lines.push(format!(
                "a `play` report: {} at {} fps ({:.2} s), {}, {}",
                count(v["frames"].as_u64().unwrap_or(0) as usize, "frame"),
                num(&v, "fps").unwrap_or(f64::NAN),
                num(&v, "seconds").unwrap_or(f64::NAN),
                count(len(&v, "transitions"), "transition"),
                count(len(&v, "notices"), "notice")
            ));
        }
        "web site manifest" => {
            let seqs = named_frames(&v, "frames");
            lines.push(format!(
                "the manifest of a site written by `web export` ({} mode, character '{}'): geometry {}, max vertex error {:.3} mm",
                v["mode"].as_str().unwrap_or("?"),
                v["name"].as_str().unwrap_or("?"),
                v["geometry"].as_str().unwrap_or("?"),
                1e3 * num(&v, "max_error").unwrap_or(f64::NAN)
            ));
            lines.push(format!(
                "{}: {}",
                count(seqs.len(), "sequence"),
                seqs.join(", ")
            ));
        }
        "rig map" => {
            lines.push(format!(
                "a rig map (`mocap rigmap`, for --rig-map): convention {}, {} canonical joints mapped",
                v["convention"].as_str().unwrap_or("?"),
                v["joints"].as_object().map_or(0, |o| o.len())
            ));
        }
        "skeletons" => {
            lines.push(format!(
                "per-frame skeletons of sequence {}: {} frames at {} fps, {} joints",
                v["sequence"].as_str().unwrap_or("?"),
                len(&v, "frames"),
                num(&v, "fps").unwrap_or(f64::NAN),
                len(&v, "joints")
            ));
        }
        _ => {
            lines.push(format!(
                "a {format}: {} frames at {} fps",
                v["frames"],
                num(&v, "fps").unwrap_or(f64::NAN)
            ));
            if let (Some(d), Some(t)) = (num(&v, "distance"), num(&v, "time")) {
                lines.push(format!(
                    "travelled {d:.3} m in {t:.3} s over {}, {}",
                    count(len(&v, "segments"), "segment"),
                    count(len(&v, "transitions"), "transition")
                ));
            }
        }
    }
    Ok(JsonReport {
        path: path.to_path_buf(),
        format: format.into(),
        lines,
    })
}

/// What a field of a file [`inspect`] recognises must hold.
#[derive(Debug, Clone, Copy)]
enum Field {
    /// A whole number ≥ 0.
    Count,
    /// A frame rate ([`crate::budget::is_frame_rate`]).
    Fps,
    /// A finite number.
    Number,
    /// A string.
    Text,
    /// `true` or `false`.
    Flag,
    /// An array.
    List,
    /// An array of finite numbers.
    Numbers,
    /// An array of strings.
    Texts,
    /// An object.
    Object,
}

impl Field {
    fn holds(self, x: &serde_json::Value) -> bool {
        let finite = |x: &serde_json::Value| x.as_f64().is_some_and(f64::is_finite);
        match self {
            Field::Count => x.is_u64(),
            Field::Fps => x.as_f64().is_some_and(crate::budget::is_frame_rate),
            Field::Number => finite(x),
            Field::Text => x.is_string(),
            Field::Flag => x.is_boolean(),
            Field::List => x.is_array(),
            Field::Numbers => x.as_array().is_some_and(|a| a.iter().all(finite)),
            Field::Texts => x
                .as_array()
                .is_some_and(|a| a.iter().all(|s| s.is_string())),
            Field::Object => x.is_object(),
        }
    }

    fn expected(self) -> String {
        match self {
            Field::Count => "a whole number".into(),
            Field::Fps => format!(
                "a frame rate of {}-{} fps",
                crate::budget::MIN_FPS,
                crate::budget::MAX_FPS
            ),
            Field::Number => "a finite number".into(),
            Field::Text => "a string".into(),
            Field::Flag => "true or false".into(),
            Field::List => "an array".into(),
            Field::Numbers => "an array of finite numbers".into(),
            Field::Texts => "an array of strings".into(),
            Field::Object => "an object".into(),
        }
    }
}

/// The fields each kind of file [`json_kind`] recognises must hold, as the
/// tool writes them (those `inspect` reads and those that identify it).
fn fields_of(kind: &str) -> &'static [(&'static str, Field)] {
    use Field::*;
    match kind {
        "keyframe report" => &[
            ("keys", Texts),
            ("fps", Fps),
            ("frames", Count),
            ("distance", Number),
            ("time", Number),
            ("cost", Object),
            ("segments", List),
            ("transitions", List),
        ],
        "keyframe grid report" => &[
            ("keys", Texts),
            ("distances", Numbers),
            ("times", Numbers),
            ("reachable", Object),
            ("unreachable", Object),
            ("query_ms_mean", Number),
        ],
        "batch report" => &[
            ("what", Text),
            ("finished", Flag),
            ("done", Count),
            ("skipped", Count),
            ("failed", Count),
            ("clips_per_minute", Number),
            ("outcomes", List),
        ],
        "play report" => &[
            ("frames", Count),
            ("fps", Fps),
            ("seconds", Number),
            ("realtime_factor", Number),
            ("per_second", List),
            ("transitions", List),
            ("notices", List),
        ],
        "retarget report" => &[
            ("frames", Count),
            ("fps", Fps),
            ("retrieval", Object),
            ("jumps", List),
            ("steps", List),
        ],
        "transfer report" => &[
            ("frames", Count),
            ("fps", Fps),
            ("scan", Object),
            ("transfer", Object),
        ],
        "skeletons" => &[
            ("sequence", Text),
            ("fps", Fps),
            ("frames", List),
            ("joints", List),
        ],
        "graph cache" => &[("key", Count), ("graph", Object)],
        "rig" => &[("vertex_count", Count), ("joints", List)],
        "rig map" => &[("convention", Text), ("joints", Object)],
        _ => &[],
    }
}

/// `Err` naming the first field of `v` that does not hold what a `kind`
/// file holds there (missing, or of another type or range).
fn check_fields(v: &serde_json::Value, kind: &str) -> Result<(), String> {
    for &(key, field) in fields_of(kind) {
        match v.get(key) {
            None => return Err(format!("no field \"{key}\" ({})", field.expected())),
            Some(x) if !field.holds(x) => {
                let mut found = x.to_string();
                if found.len() > 40 {
                    found = format!("{}…", found.chars().take(40).collect::<String>());
                }
                return Err(format!(
                    "field \"{key}\" is {found}, expected {}",
                    field.expected()
                ));
            }
            _ => {}
        }
    }
    Ok(())
}

/// `name (N frames)` of each entry of `v["sequences"]`, its frame count
/// read from the key `frames` (a graph cache calls it `len`).
fn named_frames(v: &serde_json::Value, frames: &str) -> Vec<String> {
    v["sequences"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|s| {
            format!(
                "{} ({} frames)",
                s["name"].as_str().unwrap_or("?"),
                s[frames]
            )
        })
        .collect()
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
                for (n, d) in &r.animations {
                    let _ = writeln!(s, "  animation   '{n}' {d:.2} s");
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
