//! The character database manifest, `character.toml`.
//!
//! A database is a directory holding a manifest that names the topology mesh,
//! the captured sequences (OBJ folders, PC2/MDD caches, glTF files), their
//! frame rate, units and up axis, optional vertex colours, and the rig
//! annotation. Paths are relative to the directory unless absolute.
//!
//! ```toml
//! name = "samba"
//! topology = "samba.obj"
//! fps = 30.0
//! units = "m"
//! up = "y"
//!
//! [[sequence]]
//! name = "dance"
//! path = "samba.pc2"
//!
//! [rig]
//! landmarks = "landmarks.json"
//! ```

use crate::graph::{GraphEdits, TransitionOptions};
use crate::mesh::io::{LoadOptions, MeshFormat, load_sequence, obj::read_obj, ply::read_ply};
use crate::mesh::{Mesh, MeshError, MeshSequence};
use crate::similarity::Measure;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The highest frame rate a manifest may name (frames per second): a
/// larger one is a typo that would make `retarget` resample to billions of
/// frames. The lowest is [`crate::util::budget::MIN_FPS`].
pub const MAX_FPS: f64 = crate::util::budget::MAX_FPS;

/// True for text with NUL bytes or many invalid UTF-8 sequences (read
/// lossily as U+FFFD): a binary file, whose bytes must not be echoed into
/// a message (issue 18, item 17).
pub(crate) fn looks_binary(text: &str) -> bool {
    let head: Vec<char> = text.chars().take(4096).collect();
    let bad = head
        .iter()
        .filter(|&&c| c == '\u{FFFD}' || (c.is_control() && !c.is_whitespace()))
        .count();
    text.contains('\0') || (bad >= 4 && bad * 100 >= head.len())
}

/// `s` with control and replacement characters escaped and at most `max`
/// characters kept (for echoing file contents into messages).
pub fn printable(s: &str, max: usize) -> String {
    let mut out = String::new();
    for (k, c) in s.chars().enumerate() {
        if k >= max {
            out.push('…');
            break;
        }
        if c.is_control() || c == '\u{FFFD}' {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// A name read from a file (a sequence's) becomes part of output file
/// names (`DIR/NAME.bvh`) and of `SEQ:FRAME` specs: it must be a plain
/// name, never a path. Regression (issue 18, item 11): a sequence named
/// `../../escaped` made `db skeleton` write outside its output folder.
pub(crate) fn check_name(name: &str) -> Result<(), &'static str> {
    if name.is_empty() {
        return Err("empty");
    }
    if name.len() > 200 {
        return Err("longer than 200 bytes");
    }
    if name.starts_with('.') {
        return Err("starts with '.'");
    }
    if name
        .chars()
        .any(|c| matches!(c, '/' | '\\' | ':' | '\0') || c.is_control())
    {
        return Err("contains a path separator, ':' or a control character");
    }
    Ok(())
}

/// File name of the manifest inside a database directory.
pub const MANIFEST: &str = "character.toml";

/// The sizes of a person in metres (the rest frame's bounding box's
/// largest side: the height standing, about the height in a T-pose): a
/// manifest whose `units` put a person-sized character ([`Manifest::human_sized`])
/// outside them is refused by [`Manifest::load`]. Regression (issue 39,
/// item 5): `units = "cm"` on a mesh in metres built a 1.8 cm dancer that
/// `retarget` wrote without a word.
pub(crate) const HUMAN_SIZE_M: std::ops::RangeInclusive<f64> = 0.5..=3.0;

/// One captured sequence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequenceEntry {
    /// Name, unique in the database.
    pub name: String,
    /// OBJ folder, PC2/MDD cache or glTF file.
    pub path: PathBuf,
    /// Frame rate of this sequence if it differs from the database's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fps: Option<f64>,
}

/// The skeletal annotation of the character (any one source is enough).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigSpec {
    /// Landmarks on the rest frame (JSON: named points or vertex indices).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub landmarks: Option<PathBuf>,
    /// Explicit part labels (JSON `{part: [vertex ids]}`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parts: Option<PathBuf>,
    /// A rigged glTF whose vertices match the topology by position.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gltf_skin: Option<PathBuf>,
    /// A rig map (canonical joint → skin joint name) for `gltf_skin` when
    /// its joint names are not detected.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rig_map: Option<PathBuf>,
    /// The frame the rig is embedded on, `SEQUENCE:FRAME`, when not the
    /// topology's own positions: written by `db init` when the topology's
    /// frame has a contact (a hand on the hip) and another frame is clear
    /// ([`crate::embed::rest`]). The landmarks stay marked on the topology.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest: Option<String>,
}

impl RigSpec {
    /// True when no rig source is given.
    pub fn is_empty(&self) -> bool {
        self.landmarks.is_none() && self.parts.is_none() && self.gltf_skin.is_none()
    }
}

fn default_fps() -> f64 {
    30.0
}
fn default_units() -> String {
    "m".into()
}
fn default_up() -> String {
    "y".into()
}
fn default_true() -> bool {
    true
}
fn is_true(b: &bool) -> bool {
    *b
}

/// How the Surface Motion Graph is built (`[graph]`; every field optional).
///
/// ```toml
/// [graph]
/// measure = "shape"        # shape | vertex | skeleton
/// top_n = 4                # transitions per ordered sequence pair
/// max_window = 24          # largest half-window L (frames)
/// min_window = 4           # smallest half-window L (frames)
/// min_gap = 10             # within a sequence, smallest |m - n|
/// velocity_weight = 1.0    # λ of the vertex measure
/// forbid = ["walk -> jog"] # never create these sequence edges (* = any)
/// remove = ["walk:30 -> jog:12"]  # drop single transitions
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GraphSpec {
    /// Dissimilarity measure. Default: shape.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measure: Option<Measure>,
    /// Transitions per ordered sequence pair. Default: 4.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub top_n: Option<usize>,
    /// Largest half-window L. Default: 24.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_window: Option<usize>,
    /// Smallest half-window L. Default: 4 (the paper's Fig. 4; see
    /// [`TransitionOptions`](crate::graph::transitions::TransitionOptions)).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_window: Option<usize>,
    /// Smallest jump inside one sequence. Default: 10.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_gap: Option<usize>,
    /// Velocity weight λ of the vertex measure. Default: 1.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub velocity_weight: Option<f64>,
    /// Sequence edges never to create, `"from -> to"`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub forbid: Vec<String>,
    /// Transitions to drop, `"from:m -> to:n"`.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub remove: Vec<String>,
}

impl GraphSpec {
    /// True when nothing is set.
    pub fn is_default(&self) -> bool {
        *self == GraphSpec::default()
    }
    /// The transition options, defaults filled in.
    pub fn transition_options(&self) -> TransitionOptions {
        let d = TransitionOptions::default();
        TransitionOptions {
            top_n: self.top_n.unwrap_or(d.top_n),
            max_window: self.max_window.unwrap_or(d.max_window),
            min_window: self.min_window.unwrap_or(d.min_window),
            min_gap: self.min_gap.unwrap_or(d.min_gap),
        }
    }
    /// The user's edits.
    pub fn edits(&self) -> GraphEdits {
        GraphEdits {
            forbid: self.forbid.clone(),
            remove: self.remove.clone(),
        }
    }
}

/// Overrides of the deformation's automatic choices (`[deform]`).
///
/// ```toml
/// [deform]
/// constraints = "constraints.json"          # JSON array of vertex ids
/// examples = ["walk:10", "walk:40", "jog:7"] # example frames for every part
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DeformSpec {
    /// Constraint vertices (a JSON array of vertex ids) instead of the
    /// automatic mid-bone choice.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub constraints: Option<PathBuf>,
    /// Example frames `SEQUENCE:FRAME` instead of the automatic choice.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub examples: Vec<String>,
}

impl DeformSpec {
    /// True when nothing is set.
    pub fn is_default(&self) -> bool {
        *self == DeformSpec::default()
    }
}

/// A parametric motion space (`[[space]]`; Casas et al. 2013, Sec. 3.1):
/// related sequences blended into one motion steered by parameters.
///
/// ```toml
/// [[space]]
/// name = "locomotion"
/// sequences = ["walk", "run"]   # ordered along the blend weight
/// parameters = ["speed", "turn"] # the first is the blended one; turn steers
/// epsilon_mm = 5.0              # hybrid blending tolerance (default 5)
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceEntry {
    /// Name, unique among spaces.
    pub name: String,
    /// The space's sequences (names of `[[sequence]]` entries), in the
    /// order of the parameter they are blended for.
    pub sequences: Vec<String>,
    /// Parameters (`speed`, `turn`): the first is mapped to blend weights;
    /// `turn` after it steers the heading.
    #[serde(default)]
    pub parameters: Vec<String>,
    /// Largest hybrid-blending error in millimetres. Default: 5.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub epsilon_mm: Option<f64>,
}

/// The manifest.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// Character name.
    pub name: String,
    /// The topology mesh (its positions are the rest frame).
    pub topology: PathBuf,
    /// Frames per second of the captures. Default: 30.
    #[serde(default = "default_fps")]
    pub fps: f64,
    /// Length unit of the files (`m`, `cm`, `mm`, `dm`, `inch`). Default: m.
    #[serde(default = "default_units")]
    pub units: String,
    /// Up axis of the files (`y` or `z`). Default: y.
    #[serde(default = "default_up")]
    pub up: String,
    /// True when the character is a person's size: its rest frame, in
    /// `units`, must measure [`HUMAN_SIZE_M`] (0.5-3 m) along its
    /// bounding box's largest side, or every reader refuses the database
    /// (a wrong `units`). Set `human_sized = false` for a figurine, a
    /// giant or an animal. Default: true.
    #[serde(default = "default_true", skip_serializing_if = "is_true")]
    pub human_sized: bool,
    /// Per-vertex colours (a mesh with the topology's vertex count), if separate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colors: Option<PathBuf>,
    /// Captured sequences.
    #[serde(default, rename = "sequence")]
    pub sequences: Vec<SequenceEntry>,
    /// Rig annotation.
    #[serde(default, skip_serializing_if = "RigSpec::is_empty")]
    pub rig: RigSpec,
    /// Surface Motion Graph settings.
    #[serde(default, skip_serializing_if = "GraphSpec::is_default")]
    pub graph: GraphSpec,
    /// Deformation overrides.
    #[serde(default, skip_serializing_if = "DeformSpec::is_default")]
    pub deform: DeformSpec,
    /// Parametric motion spaces.
    #[serde(default, rename = "space", skip_serializing_if = "Vec::is_empty")]
    pub spaces: Vec<SpaceEntry>,
}

/// Errors of the database layer.
#[derive(Debug, thiserror::Error)]
pub enum DbError {
    /// The manifest is missing or malformed.
    #[error("{path}: {msg}")]
    Manifest {
        /// The manifest file.
        path: PathBuf,
        /// What is wrong.
        msg: String,
    },
    /// A mesh file failed to load.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Writing failed.
    #[error(transparent)]
    Io(#[from] crate::util::fsutil::FsError),
    /// The rig could not be embedded.
    #[error(transparent)]
    Rig(#[from] crate::embed::EmbedError),
    /// A graph edit in the manifest names something that does not exist.
    #[error("character.toml: {0}")]
    Graph(#[from] crate::graph::smg::EditError),
    /// The database's cache (similarity matrix, graph) could not be
    /// written: a database never built, in a read-only folder (issue
    /// 46.12: the error said only "Read-only file system").
    #[error(
        "{source}: the database's cache is built once, in the database's folder, and cannot be written in {}; build it (`db build`) where it can be written (copy the database to a writable folder first)",
        dir.display()
    )]
    CacheUnwritable {
        /// The database folder.
        dir: PathBuf,
        /// The write that failed.
        source: crate::util::fsutil::FsError,
    },
    /// A person-sized character whose rest frame, in the manifest's
    /// `units`, is not a person's size ([`HUMAN_SIZE_M`]): a wrong unit.
    #[error("{path}: {}", size_message(*metres, units, *suggest))]
    Size {
        /// The manifest.
        path: PathBuf,
        /// The rest frame's size in metres (bounding box's largest side).
        metres: f64,
        /// The manifest's `units`.
        units: String,
        /// A unit that makes it a person's size, and the size it gives.
        suggest: Option<(&'static str, f64)>,
    },
}

impl DbError {
    /// A failed write of the cache of the database at `dir`: refused
    /// permission or a read-only file system is [`DbError::CacheUnwritable`].
    pub(crate) fn cache_write(dir: &std::path::Path, e: crate::util::fsutil::FsError) -> DbError {
        use std::io::ErrorKind as K;
        match e.source.kind() {
            K::PermissionDenied | K::ReadOnlyFilesystem => DbError::CacheUnwritable {
                dir: dir.to_path_buf(),
                source: e,
            },
            _ => DbError::Io(e),
        }
    }
}

/// The text of [`DbError::Size`] (also a `db info` problem).
pub(crate) fn size_message(metres: f64, units: &str, suggest: Option<(&str, f64)>) -> String {
    let hint = suggest.map_or(String::new(), |(u, m)| {
        format!(" (units = \"{u}\" makes it {m:.2} m)")
    });
    format!(
        "the rest frame is {metres:.3} m tall or wide with units = \"{}\", not a person's {}-{} m: \
         is the unit right?{hint}; for a character that is not a person's size, set human_sized = false in the manifest",
        printable(units, 20),
        HUMAN_SIZE_M.start(),
        HUMAN_SIZE_M.end()
    )
}

/// The largest side of the bounding box of `positions` (finite
/// coordinates only), in their units; `None` for an empty or flat-to-a-point set.
pub fn extent(positions: &[[f64; 3]]) -> Option<f64> {
    let h = (0..3)
        .map(|axis| {
            let (lo, hi) = positions
                .iter()
                .map(|p| p[axis])
                .filter(|v| v.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                });
            hi - lo
        })
        .fold(f64::NEG_INFINITY, f64::max);
    (h > 0.0 && h.is_finite()).then_some(h)
}

impl Manifest {
    /// Opens the database in `dir`: [`Manifest::read`], then the checks
    /// that need the topology: a person-sized character
    /// ([`Manifest::human_sized`]) must be a person's size in the
    /// manifest's `units` ([`Manifest::check_size`]). Every verb that reads
    /// a database opens it here, so all refuse a wrong unit alike.
    pub fn load(dir: &Path) -> Result<Manifest, DbError> {
        let m = Self::read(dir)?;
        if m.human_sized {
            let topo = m.load_topology(dir)?;
            m.check_size(dir, &topo)?;
        }
        Ok(m)
    }

    /// [`Manifest::load`] for a caller that needs the topology too: it is
    /// read once, checked ([`Manifest::check_size`]) and returned with the
    /// manifest (issue 39: [`crate::db::Character::load_with`] read it
    /// three times, twice only for the size check).
    pub fn open(dir: &Path) -> Result<(Manifest, Mesh), DbError> {
        let m = Self::read(dir)?;
        let topo = m.load_topology(dir)?;
        m.check_size(dir, &topo)?;
        Ok((m, topo))
    }

    /// The rest frame's size in metres: the largest side of the topology's
    /// bounding box in the manifest's `units` (`None`: no extent).
    pub(crate) fn size_metres(&self, topology: &Mesh) -> Option<f64> {
        let u = crate::mocap::units::parse_unit(&self.units)?;
        extent(topology.positions()).map(|h| h * u.metres_per_unit)
    }

    /// Refuses a person-sized character ([`Manifest::human_sized`]) whose
    /// rest frame `topology` is outside [`HUMAN_SIZE_M`] in the manifest's
    /// `units` ([`DbError::Size`], with a unit that fits if one does).
    /// `dir` names the manifest in the error.
    pub fn check_size(&self, dir: &Path, topology: &Mesh) -> Result<(), DbError> {
        if !self.human_sized {
            return Ok(());
        }
        let Some(metres) = self.size_metres(topology) else {
            return Ok(());
        };
        if HUMAN_SIZE_M.contains(&metres) {
            return Ok(());
        }
        let file = extent(topology.positions()).unwrap_or(0.0);
        let suggest = crate::mocap::units::parse_unit(&self.units).and_then(|_| {
            ["m", "cm", "mm", "dm", "inch"]
                .into_iter()
                .filter_map(|u| {
                    let m = file * crate::mocap::units::parse_unit(u)?.metres_per_unit;
                    HUMAN_SIZE_M.contains(&m).then_some((u, m))
                })
                .min_by(|a, b| (a.1 / 1.7).ln().abs().total_cmp(&(b.1 / 1.7).ln().abs()))
        });
        Err(DbError::Size {
            path: dir.join(MANIFEST),
            metres,
            units: self.units.clone(),
            suggest,
        })
    }

    /// Reads `DIR/character.toml` and checks its fields (not the files it
    /// names: [`Manifest::load`] opens the database).
    pub fn read(dir: &Path) -> Result<Manifest, DbError> {
        // A file given for the folder (the manifest itself, a clip) said
        // "DIR/character.toml: Not a directory".
        if dir.is_file() {
            let hint = match dir.parent() {
                Some(p) if dir.file_name().is_some_and(|n| n == MANIFEST) => format!(
                    "; the database is the folder that holds it: {}",
                    if p.as_os_str().is_empty() {
                        ".".into()
                    } else {
                        p.display().to_string()
                    }
                ),
                _ => " (`surfmotion db init` writes one)".into(),
            };
            return Err(DbError::Manifest {
                path: dir.to_path_buf(),
                msg: format!("is a file, not a database folder{hint}"),
            });
        }
        let path = dir.join(MANIFEST);
        let text = crate::util::fsutil::read_small_text(&path).map_err(|e| DbError::Manifest {
            path: path.clone(),
            msg: format!(
                "{} (is this a database directory? `surfmotion db init` writes one)",
                e.source
            ),
        })?;
        if looks_binary(&text) {
            return Err(DbError::Manifest {
                path,
                msg: "not a text file (binary data): expected a TOML manifest".into(),
            });
        }
        let m: Manifest = toml::from_str(&text).map_err(|e| DbError::Manifest {
            path: path.clone(),
            msg: printable(&e.to_string().replace('\n', " "), 400),
        })?;
        m.validate()
            .map_err(|msg| DbError::Manifest { path, msg })?;
        Ok(m)
    }

    /// Checks values that TOML types cannot.
    pub fn validate(&self) -> Result<(), String> {
        // The character's name is printed on one line (`db info`) and
        // shown by the web page: one line of text (`db init --name` took
        // a newline, and `db info` printed the name over two lines).
        if self.name.len() > 200 || self.name.chars().any(char::is_control) {
            return Err(format!(
                "name = \"{}\": expected one line of at most 200 bytes, without control characters",
                printable(&self.name, 60)
            ));
        }
        if !crate::util::budget::is_frame_rate(self.fps) {
            return Err(format!(
                "fps = {} is not a frame rate (expected a number in [{}, {MAX_FPS}])",
                self.fps,
                crate::util::budget::MIN_FPS
            ));
        }
        if crate::mocap::units::parse_unit(&self.units).is_none() {
            return Err(format!(
                "units = '{}': expected m, cm, mm, dm, inch or a number of metres",
                self.units
            ));
        }
        if !matches!(self.up.to_ascii_lowercase().as_str(), "y" | "z") {
            return Err(format!("up = '{}': expected y or z", self.up));
        }
        let mut names = std::collections::HashSet::new();
        for s in &self.sequences {
            check_name(&s.name).map_err(|why| format!("sequence name {:?}: {why}", s.name))?;
            if !names.insert(s.name.as_str()) {
                return Err(format!("two sequences are called '{}'", s.name));
            }
            if let Some(f) = s.fps
                && !crate::util::budget::is_frame_rate(f)
            {
                return Err(format!(
                    "sequence '{}': fps = {f} is not a frame rate (expected a number in [{}, {MAX_FPS}])",
                    s.name,
                    crate::util::budget::MIN_FPS
                ));
            }
        }
        self.validate_spaces(&names)?;
        let g = &self.graph;
        if let Some(w) = g.velocity_weight
            && !(w.is_finite() && w >= 0.0)
        {
            return Err(format!(
                "[graph] velocity_weight = {w}: expected a number ≥ 0"
            ));
        }
        let t = g.transition_options();
        if t.top_n == 0 || t.min_window == 0 || t.min_window > t.max_window {
            return Err(format!(
                "[graph]: need top_n ≥ 1 and 1 ≤ min_window ≤ max_window (got top_n = {}, min_window = {}, max_window = {})",
                t.top_n, t.min_window, t.max_window
            ));
        }
        Ok(())
    }

    /// Checks the `[[space]]` entries against the sequence names.
    fn validate_spaces(&self, sequences: &std::collections::HashSet<&str>) -> Result<(), String> {
        let mut names = std::collections::HashSet::new();
        for sp in &self.spaces {
            let at = format!("[[space]] '{}'", printable(&sp.name, 60));
            check_name(&sp.name).map_err(|why| format!("{at}: name {why}"))?;
            if !names.insert(sp.name.as_str()) {
                return Err(format!("two spaces are called '{}'", sp.name));
            }
            if sp.sequences.is_empty() {
                return Err(format!(
                    "{at}: sequences is empty (name one or more [[sequence]] entries)"
                ));
            }
            let mut seen = std::collections::HashSet::new();
            for q in &sp.sequences {
                if !sequences.contains(q.as_str()) {
                    return Err(format!(
                        "{at}: no sequence '{}' in this manifest",
                        printable(q, 60)
                    ));
                }
                if !seen.insert(q.as_str()) {
                    return Err(format!("{at}: sequence '{q}' is listed twice"));
                }
            }
            let mut params = std::collections::HashSet::new();
            for (k, p) in sp.parameters.iter().enumerate() {
                if !matches!(p.as_str(), "speed" | "turn") {
                    return Err(format!(
                        "{at}: unknown parameter '{}' (expected speed or turn)",
                        printable(p, 60)
                    ));
                }
                if !params.insert(p.as_str()) {
                    return Err(format!("{at}: parameter '{p}' is listed twice"));
                }
                if p == "speed" && k > 0 {
                    return Err(format!("{at}: speed must be the first (blended) parameter"));
                }
            }
            if let Some(e) = sp.epsilon_mm
                && !(e.is_finite() && e > 0.0 && e <= 1000.0)
            {
                return Err(format!(
                    "{at}: epsilon_mm = {e}: expected a number in (0, 1000]"
                ));
            }
        }
        Ok(())
    }

    /// Refuses a manifest without `[[space]]` entries where a parametric
    /// motion space is needed, saying how to declare one (with this
    /// database's sequence names). `dir` names the manifest. Regression
    /// (issue 39, item 9): `play` on such a database said `unknown key
    /// "speed" (expected t, space)`, blaming the script.
    pub(crate) fn require_spaces(&self, dir: &Path) -> Result<(), DbError> {
        if !self.spaces.is_empty() {
            return Ok(());
        }
        let seqs: Vec<String> = self
            .sequences
            .iter()
            .take(2)
            .map(|s| format!("\"{}\"", printable(&s.name, 40)))
            .collect();
        let seqs = if seqs.is_empty() {
            "\"walk\", \"run\"".to_string()
        } else {
            seqs.join(", ")
        };
        Err(DbError::Manifest {
            path: dir.join(MANIFEST),
            msg: format!(
                "the database declares no [[space]] (a parametric motion space, which parametric motion steers): \
                 add one to the manifest, e.g. [[space]] name = \"locomotion\" sequences = [{seqs}] parameters = [\"speed\"] \
                 (each on its own line; sequences names [[sequence]] entries; see the README's \"Parametric motion\")"
            ),
        })
    }

    /// Writes the manifest to `DIR/character.toml`, atomically.
    pub fn save(&self, dir: &Path) -> Result<(), DbError> {
        let text = toml::to_string_pretty(self).map_err(|e| DbError::Manifest {
            path: dir.join(MANIFEST),
            msg: e.to_string(),
        })?;
        crate::util::fsutil::write_bytes_atomic(&dir.join(MANIFEST), text.as_bytes())?;
        Ok(())
    }

    /// A path of the manifest resolved against the database directory.
    pub fn resolve(dir: &Path, p: &Path) -> PathBuf {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            dir.join(p)
        }
    }

    /// Loads the topology mesh.
    pub fn load_topology(&self, dir: &Path) -> Result<Mesh, DbError> {
        let p = Self::resolve(dir, &self.topology);
        Ok(match MeshFormat::of(&p) {
            Some(MeshFormat::Ply) => read_ply(&p)?,
            Some(MeshFormat::Obj) => read_obj(&p)?,
            _ => load_sequence(&p.to_string_lossy(), &LoadOptions::default())?.frame_mesh(0),
        })
    }

    /// Loads one sequence, with the topology for point caches.
    pub fn load_sequence(&self, dir: &Path, s: &SequenceEntry) -> Result<MeshSequence, DbError> {
        let topo = Self::resolve(dir, &self.topology);
        let p = Self::resolve(dir, &s.path);
        let opts = LoadOptions {
            topology: Some(topo),
            fps: Some(s.fps.unwrap_or(self.fps)),
        };
        Ok(load_sequence(&p.to_string_lossy(), &opts)?)
    }
}

/// Summary of one sequence for `db info`.
#[derive(Debug, Clone, Serialize)]
pub struct SequenceInfo {
    /// Name.
    pub name: String,
    /// Frames (0 if it failed to load).
    pub frames: usize,
    /// Frames per second used.
    pub fps: f64,
}

/// What `db info` reports.
#[derive(Debug, Clone, Serialize)]
pub struct DbInfo {
    /// Character name.
    pub name: String,
    /// Topology vertex count.
    pub vertices: usize,
    /// Topology triangle count.
    pub triangles: usize,
    /// Sequences.
    pub sequences: Vec<SequenceInfo>,
    /// Total frames.
    pub total_frames: usize,
    /// Problems found (connectivity or frame-rate mismatch, a rest frame
    /// not a person's size, a landmark file no rig can be embedded from,
    /// a missing file, ...): the database cannot be used as it is.
    pub problems: Vec<String>,
    /// What the database lacks for some uses only (no rig: mocap-driven
    /// synthesis needs one; the graph and key-frame paths do not).
    pub notes: Vec<String>,
}

/// Loads every part of a database and reports what it holds and what is wrong.
pub fn info(dir: &Path) -> Result<DbInfo, DbError> {
    let m = Manifest::read(dir)?;
    let topo = m.load_topology(dir)?;
    let mut problems: Vec<String> = topo
        .problems()
        .into_iter()
        .map(|p| format!("topology: {p}"))
        .collect();
    let mut notes = Vec::new();
    if let Err(DbError::Size {
        metres,
        units,
        suggest,
        ..
    }) = m.check_size(dir, &topo)
    {
        problems.push(format!(
            "topology: {}",
            size_message(metres, &units, suggest)
        ));
    }
    let mut seqs = Vec::new();
    for s in &m.sequences {
        let fps = s.fps.unwrap_or(m.fps);
        match m.load_sequence(dir, s) {
            Ok(q) => {
                if q.mesh().triangles() != topo.triangles()
                    || q.mesh().vertex_count() != topo.vertex_count()
                {
                    problems.push(format!(
                        "sequence '{}': connectivity differs from the topology ({} vertices / {} triangles vs {} / {})",
                        s.name,
                        q.mesh().vertex_count(),
                        q.mesh().triangle_count(),
                        topo.vertex_count(),
                        topo.triangle_count()
                    ));
                }
                if let Some(file_fps) = q.fps
                    && (file_fps - fps).abs() > 1e-3 * fps
                {
                    problems.push(format!(
                        "sequence '{}': the file says {file_fps:.3} fps, the manifest {fps}",
                        s.name
                    ));
                }
                seqs.push(SequenceInfo {
                    name: s.name.clone(),
                    frames: q.frame_count(),
                    fps,
                });
            }
            Err(e) => {
                problems.push(format!("sequence '{}': {e}", s.name));
                seqs.push(SequenceInfo {
                    name: s.name.clone(),
                    frames: 0,
                    fps,
                });
            }
        }
    }
    if m.sequences.is_empty() {
        problems.push("no sequences".into());
    }
    if m.rig.is_empty() {
        notes.push(
            "no rig: add [rig] landmarks, parts or gltf_skin (needed for mocap-driven synthesis)"
                .into(),
        );
    }
    for (what, p) in [
        ("landmarks", &m.rig.landmarks),
        ("parts", &m.rig.parts),
        ("gltf_skin", &m.rig.gltf_skin),
        ("rig_map", &m.rig.rig_map),
        ("colors", &m.colors),
    ] {
        if let Some(p) = p
            && !Manifest::resolve(dir, p).exists()
        {
            problems.push(format!(
                "{what}: {} does not exist",
                Manifest::resolve(dir, p).display()
            ));
        }
    }
    // A landmark file no rig can be embedded from (a required landmark
    // missing, landmarks of another mesh) was accepted here and refused
    // only by `db skeleton`, `retarget` or `transfer` (issue 39, item 7).
    if let Some(p) = &m.rig.landmarks {
        let p = Manifest::resolve(dir, p);
        if p.exists()
            && let Err(e) = crate::embed::landmarks::Landmarks::load_checked(&p, &topo)
        {
            problems.push(format!("landmarks: {e}"));
        }
    }
    Ok(DbInfo {
        name: m.name.clone(),
        vertices: topo.vertex_count(),
        triangles: topo.triangle_count(),
        total_frames: seqs.iter().map(|s| s.frames).sum(),
        sequences: seqs,
        problems,
        notes,
    })
}

#[cfg(test)]
mod tests {

    /// Regression (issue 46, item 12): `keyframe`/`db build` on a database
    /// never built, in a read-only folder, said only "Read-only file
    /// system". A refused cache write now says that the cache is written
    /// once, where, and what to do; other write errors stay as they were.
    #[test]
    fn an_unwritable_cache_says_the_cache_must_be_built_where_it_can_be_written() {
        use std::io::{Error, ErrorKind};
        let dir = Path::new("/data/db");
        for kind in [ErrorKind::ReadOnlyFilesystem, ErrorKind::PermissionDenied] {
            let e = crate::util::fsutil::FsError {
                path: dir.join("cache/similarity-shape.bin"),
                source: Error::from(kind),
            };
            let msg = DbError::cache_write(dir, e).to_string();
            assert!(
                msg.contains("cache/similarity-shape.bin")
                    && msg.contains("cache is built once")
                    && msg.contains("db build")
                    && msg.contains("writable folder"),
                "{msg}"
            );
        }
        let e = crate::util::fsutil::FsError {
            path: dir.join("cache/graph-shape.json"),
            source: Error::from(ErrorKind::StorageFull),
        };
        assert!(matches!(DbError::cache_write(dir, e), DbError::Io(_)));
    }

    use super::*;

    /// Regression (issue 19): `[graph] min_window` was documented with
    /// default 2 while the code used 4. The documented defaults of the
    /// transition fields (field docs and the TOML example) are the ones a
    /// manifest without them gets.
    #[test]
    fn graph_spec_documented_defaults_are_the_real_ones() {
        let src = include_str!("manifest.rs");
        let t = GraphSpec::default().transition_options();
        for (field, value) in [
            ("top_n", t.top_n),
            ("max_window", t.max_window),
            ("min_window", t.min_window),
            ("min_gap", t.min_gap),
        ] {
            let example = format!("/// {field} = ");
            let line = src
                .lines()
                .find_map(|l| l.trim_start().strip_prefix(example.as_str()))
                .unwrap_or_else(|| panic!("{field} missing from the TOML example"));
            let documented: usize = line.split_whitespace().next().unwrap().parse().unwrap();
            assert_eq!(documented, value, "TOML example of {field}");
            // The field's doc: the comment lines just above `pub {field}:`.
            let decl = format!("pub {field}: Option<usize>,");
            let at = src.find(&decl).unwrap();
            let doc_default = src[..at]
                .rsplit("Default: ")
                .next()
                .unwrap()
                .split(|c: char| !c.is_ascii_digit())
                .next()
                .unwrap();
            assert_eq!(
                doc_default.parse::<usize>().unwrap(),
                value,
                "doc of {field}"
            );
        }
    }

    #[test]
    fn toml_round_trip_and_validation() {
        let m = Manifest {
            name: "x".into(),
            topology: "t.obj".into(),
            fps: 25.0,
            units: "cm".into(),
            up: "z".into(),
            human_sized: false,
            colors: None,
            sequences: vec![SequenceEntry {
                name: "a".into(),
                path: "a.pc2".into(),
                fps: None,
            }],
            rig: RigSpec {
                landmarks: Some("l.json".into()),
                ..Default::default()
            },
            graph: GraphSpec {
                measure: Some(Measure::Vertex),
                forbid: vec!["a -> *".into()],
                ..Default::default()
            },
            deform: DeformSpec {
                examples: vec!["a:3".into()],
                ..Default::default()
            },
            spaces: vec![SpaceEntry {
                name: "loco".into(),
                sequences: vec!["a".into()],
                parameters: vec!["speed".into()],
                epsilon_mm: None,
            }],
        };
        let text = toml::to_string_pretty(&m).unwrap();
        let back: Manifest = toml::from_str(&text).unwrap();
        assert_eq!(back, m);
        let mut bad = m.clone();
        bad.units = "furlong".into();
        assert!(bad.validate().is_err());
        let mut dup = m.clone();
        dup.sequences.push(dup.sequences[0].clone());
        assert!(dup.validate().unwrap_err().contains("two sequences"));
        // Defaults.
        let min: Manifest = toml::from_str("name = \"m\"\ntopology = \"m.obj\"\n").unwrap();
        assert_eq!(
            (min.fps, min.units.as_str(), min.up.as_str()),
            (30.0, "m", "y")
        );
    }

    /// Regression (issue 18, items 11 and 12): names from a manifest are
    /// names, never paths; frame rates are bounded.
    #[test]
    fn sequence_names_are_names_and_rates_are_bounded() {
        let base = "name = \"m\"\ntopology = \"m.obj\"\n";
        for bad in [
            "../../escaped",
            "a/b",
            "a\\\\b",
            ".hidden",
            "",
            "x:3",
            "a\\u0000b",
        ] {
            let text = format!("{base}[[sequence]]\nname = \"{bad}\"\npath = \"a.pc2\"\n");
            let m: Manifest = toml::from_str(&text).unwrap();
            assert!(m.validate().is_err(), "{bad:?} accepted");
        }
        let ok: Manifest = toml::from_str(&format!(
            "{base}[[sequence]]\nname = \"walk_01-fast (take 2)\"\npath = \"a.pc2\"\n"
        ))
        .unwrap();
        ok.validate().unwrap();
        for fps in ["1e6", "0", "-30", "nan"] {
            let m: Manifest = toml::from_str(&format!("fps = {fps}\n{base}")).unwrap();
            assert!(m.validate().is_err(), "fps {fps} accepted");
        }
    }
}
