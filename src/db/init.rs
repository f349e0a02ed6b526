//! A character's manifest assembled from its files (`db init`): every
//! file is read and checked before anything is written, the up axis and
//! the length unit are guessed when asked (`auto`), and paths inside the
//! database folder are stored relative to it.
//!
//! Messages name the options of [`InitOptions`] in backticks
//! (`` `InitOptions::units` ``); the CLI prints its flags instead.

use super::manifest::{extent, printable};
use super::{DbError, MANIFEST, Manifest, RigSpec, SequenceEntry};
use crate::embed::landmarks::{Landmark, Landmarks};
use crate::embed::rest::{RestChoice, RestOptions, choose_rest_frame};
use crate::mesh::Mesh;
use std::path::{Path, PathBuf};

/// What a manifest is written from. The defaults are `db init`'s.
#[derive(Clone, Debug)]
pub struct InitOptions {
    /// Topology mesh (its positions are the rest frame). Required; default
    /// empty.
    pub mesh: PathBuf,
    /// The captured sequences, (name, path): OBJ folder, .pc2, .mdd, .glb.
    /// Default: none.
    pub sequences: Vec<(String, PathBuf)>,
    /// Character name. Default `None`: the folder's name.
    pub name: Option<String>,
    /// Frames per second of the captures. Default 30.
    pub fps: f64,
    /// Length unit of the files (m, cm, mm, dm, inch, metres per unit, or
    /// `auto`: m, cm or mm, whichever makes the rest frame's largest side
    /// nearest 1.7 m). Default `auto`.
    pub units: String,
    /// Up axis of the files: `y`, `z`, or `auto` (the landmarks'
    /// groin→chin direction decides; y without landmarks). Default `auto`.
    pub up: String,
    /// Landmarks JSON on the rest frame. Default none.
    pub landmarks: Option<PathBuf>,
    /// Explicit part labels JSON. Default none.
    pub parts: Option<PathBuf>,
    /// A rigged glTF whose vertices match the topology. Default none.
    pub gltf_skin: Option<PathBuf>,
    /// A rig map for the glTF skin's joint names. Default none.
    pub rig_map: Option<PathBuf>,
    /// The character is a person's size: its rest frame measures 0.5-3 m
    /// in `units`, else the unit is refused as wrong. Default true.
    pub human_sized: bool,
    /// Overwrite an existing manifest. Default false.
    pub force: bool,
    /// With landmarks and sequences: when the topology's frame has a
    /// contact (a hand on the hip, forearms on the belly), embed the rig on
    /// the clearest frame of the sequences instead
    /// ([`crate::embed::rest::choose_rest_frame`]), written as the
    /// manifest's `[rig] rest`. Default true.
    pub choose_rest: bool,
}

impl Default for InitOptions {
    fn default() -> Self {
        InitOptions {
            mesh: PathBuf::new(),
            sequences: Vec::new(),
            name: None,
            fps: 30.0,
            units: "auto".into(),
            up: "auto".into(),
            landmarks: None,
            parts: None,
            gltf_skin: None,
            rig_map: None,
            human_sized: true,
            force: false,
            choose_rest: true,
        }
    }
}

/// Why a manifest was not written.
#[derive(Debug, thiserror::Error)]
pub enum InitError {
    /// A manifest exists and `force` is not set.
    #[error("{}: a manifest exists already; pass `force` to overwrite it", .0.display())]
    Exists(PathBuf),
    /// An option's value that does not make a manifest; the message names
    /// the option and says what it takes.
    #[error("{0}")]
    Option(String),
    /// A file of an option that could not be read, or does not fit.
    #[error("{option}: {source}")]
    Read {
        /// The option (and the sequence's name), in backticks.
        option: String,
        /// Why.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync + 'static>,
    },
    /// The manifest could not be written.
    #[error(transparent)]
    Db(#[from] DbError),
    /// A folder could not be created or resolved.
    #[error("{}: {source}", path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// The error.
        #[source]
        source: std::io::Error,
    },
}

/// `source` read for `option`.
fn read(
    option: impl Into<String>,
) -> impl FnOnce(Box<dyn std::error::Error + Send + Sync + 'static>) -> InitError {
    let option = option.into();
    move |source| InitError::Read { option, source }
}

/// `p` resolved (links, `.`, `..`); it must exist.
fn canonical(p: &Path) -> Result<PathBuf, InitError> {
    std::fs::canonicalize(p).map_err(|source| InitError::Io {
        path: p.to_path_buf(),
        source,
    })
}

/// The manifest of `opts` for the database folder `dir`, every file read
/// and checked; nothing is written. Paths inside `dir` are stored relative
/// to it, others absolute.
/// What the guesses decided (`auto` read as Z-up, or as cm) is pushed
/// onto `notes`.
pub fn assemble(
    dir: &Path,
    opts: &InitOptions,
    notes: &mut Vec<String>,
) -> Result<Manifest, InitError> {
    assemble_setup(dir, opts, notes).map(|(m, _)| m)
}

/// The rest frame `db init` chose ([`InitOptions::choose_rest`]).
#[derive(Clone, Debug, serde::Serialize)]
pub(crate) struct RestFrame {
    /// The sequence of the frame chosen; `None`: the topology's own
    /// positions.
    pub sequence: Option<String>,
    /// The frame in that sequence (0 for the topology).
    pub frame: usize,
    /// The choice over the topology's frame followed by every frame of
    /// every sequence ([`RestChoice::frame`] indexes that list).
    pub choice: RestChoice,
    /// The frames with a contact, by name: `topology`, `SEQUENCE:A-B`
    /// (a run of frames) or `SEQUENCE:F`.
    pub contact_frames: Vec<String>,
}

/// The runs of consecutive frames among `list` (`at` names each: its
/// sequence, `None` for the topology, and frame) as `topology`,
/// `NAME:A-B` or `NAME:F`.
fn frame_runs(list: &[usize], at: &[(Option<usize>, usize)], names: &[String]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut run: Option<(Option<usize>, usize, usize)> = None;
    let name = |r: (Option<usize>, usize, usize)| match r {
        (None, _, _) => "topology".to_string(),
        (Some(k), a, b) if a == b => format!("{}:{a}", names[k]),
        (Some(k), a, b) => format!("{}:{a}-{b}", names[k]),
    };
    for &i in list {
        let Some(&(seq, f)) = at.get(i) else { continue };
        run = match run {
            Some((s, a, b)) if s == seq && seq.is_some() && f == b + 1 => Some((s, a, f)),
            Some(r) => {
                out.push(name(r));
                Some((seq, f, f))
            }
            None => Some((seq, f, f)),
        };
    }
    out.extend(run.map(name));
    out
}

/// [`assemble`], with the rest frame chosen when
/// [`InitOptions::choose_rest`] and there are landmarks and sequences
/// (written into the manifest's `[rig] rest` when not the topology's).
/// In steps: the options and paths ([`manifest_of`]), the files read and
/// checked ([`check_files`], [`check_sequences`]), the rest frame
/// ([`settle_rest`]), the folder and the relative paths ([`store_in`]).
pub(crate) fn assemble_setup(
    dir: &Path,
    opts: &InitOptions,
    notes: &mut Vec<String>,
) -> Result<(Manifest, Option<RestFrame>), InitError> {
    assemble_setup_with(dir, opts, &RestOptions::default(), notes)
}

/// [`assemble_setup`] with the rest frame chosen by `rule` (the automatic
/// rig's: [`RestOptions::by_pose`], the frame its parts were found on).
pub(crate) fn assemble_setup_with(
    dir: &Path,
    opts: &InitOptions,
    rule: &RestOptions,
    notes: &mut Vec<String>,
) -> Result<(Manifest, Option<RestFrame>), InitError> {
    let mut m = manifest_of(dir, opts)?;
    let topo = check_files(dir, opts, &mut m, notes)?;
    check_sequences(dir, &m, &topo)?;
    let rest = settle_rest(dir, opts, rule, &mut m, &topo, notes)?;
    store_in(dir, &mut m)?;
    Ok((m, rest))
}

/// The manifest of `opts` with every path resolved (absolute), refused
/// when one exists without `force`, a bad name or a path that does not
/// resolve.
fn manifest_of(dir: &Path, opts: &InitOptions) -> Result<Manifest, InitError> {
    let manifest = dir.join(MANIFEST);
    if manifest.exists() && !opts.force {
        return Err(InitError::Exists(manifest));
    }
    if let Some(n) = &opts.name
        && (n.is_empty() || n.len() > 200 || n.chars().any(char::is_control))
    {
        return Err(InitError::Option(format!(
            "`InitOptions::name` \"{}\": expected one line of 1 to 200 bytes, without control characters",
            printable(n, 60)
        )));
    }
    let mut sequences = Vec::new();
    for (name, path) in &opts.sequences {
        sequences.push(SequenceEntry {
            name: name.clone(),
            path: canonical(path)
                .map_err(|e| read(format!("`InitOptions::sequences` {name}"))(e.into()))?,
            fps: None,
        });
    }
    let opt = |p: &Option<PathBuf>, option: &str| {
        p.as_deref()
            .map(canonical)
            .transpose()
            .map_err(|e| read(format!("`InitOptions::{option}`"))(e.into()))
    };
    Ok(Manifest {
        name: opts.name.clone().unwrap_or_default(),
        topology: canonical(&opts.mesh).map_err(|e| read("`InitOptions::mesh`")(e.into()))?,
        fps: opts.fps,
        units: "m".into(),
        up: "y".into(),
        human_sized: opts.human_sized,
        colors: None,
        sequences,
        rig: RigSpec {
            landmarks: opt(&opts.landmarks, "landmarks")?,
            parts: opt(&opts.parts, "parts")?,
            gltf_skin: opt(&opts.gltf_skin, "gltf_skin")?,
            rig_map: opt(&opts.rig_map, "rig_map")?,
            rest: None,
        },
        graph: Default::default(),
        deform: Default::default(),
        spaces: Vec::new(),
    })
}

/// The topology read, the landmarks checked on it, the up axis and unit
/// resolved into `m`, a person-sized rest frame checked; the topology.
fn check_files(
    dir: &Path,
    opts: &InitOptions,
    m: &mut Manifest,
    notes: &mut Vec<String>,
) -> Result<Mesh, InitError> {
    let up = opts.up.to_ascii_lowercase();
    if !matches!(up.as_str(), "y" | "z" | "auto") {
        return Err(InitError::Option(format!(
            "`InitOptions::up` {}: expected y, z or auto",
            opts.up
        )));
    }
    m.validate().map_err(InitError::Option)?;
    // The paths are absolute here, so the folder they resolve against is
    // not used. Loaded with `up = y`: the file's own coordinates.
    let topo = m
        .load_topology(dir)
        .map_err(|e| read("`InitOptions::mesh`")(e.into()))?;
    warn_stray_vertices(&topo, notes);
    // A landmark file that does not read or lacks a required landmark is
    // refused here, before the up axis is read off it (issue 39, item 7:
    // it was accepted and refused only by `retarget`); the checks on the
    // landmarks' places follow once the axis is known.
    if let Some(p) = &m.rig.landmarks {
        Landmarks::load(p, topo.vertex_count())
            .map_err(|e| read("`InitOptions::landmarks`")(e.into()))?;
    }
    m.up = resolve_up(&up, &topo, opts.landmarks.as_deref(), notes)?;
    m.units = resolve_units(&opts.units, &topo, notes);
    // Landmarks fixed to another frame's surface (the automatic rig's,
    // found on the rest frame) are checked on that frame ([`settle_rest`]).
    if let Some(p) = &m.rig.landmarks
        && !on_surface(p, &topo)
    {
        Landmarks::load_checked(p, &topo)
            .map_err(|e| read(format!("`InitOptions::landmarks` {}", p.display()))(e.into()))?;
    }
    // A person-sized character outside 0.5-3 m in the unit is a wrong
    // unit, refused by every verb that opens the database: refused here
    // (issue 39, item 5: one WARN, then a 1.8 cm character retargeted
    // without a word).
    if let Err(DbError::Size {
        metres, suggest, ..
    }) = m.check_size(dir, &topo)
    {
        return Err(InitError::Option(format!(
            "`InitOptions::units` {}: the rest frame is {metres:.3} m tall or wide in {}, not a person's 0.5-3 m: is the unit right?{}; \
             for a character that is not a person's size, set `InitOptions::human_sized` to false",
            opts.units,
            m.units,
            suggest.map_or(String::new(), |(u, v)| format!(
                " (`InitOptions::units` {u} makes it {v:.2} m)"
            ))
        )));
    }
    Ok(topo)
}

/// A vertex in no triangle (a mesh cut with a script leaves them) is
/// rigged (its nearest bone's weight) and, when the character is deformed,
/// carried by its nearest vertex in a triangle ([`crate::mesh::stray`]):
/// said at `db init`, so a user who wants it gone knows it is there.
fn warn_stray_vertices(topo: &Mesh, notes: &mut Vec<String>) {
    let stray = topo.unreferenced();
    if let Some(first) = stray.first() {
        notes.push(format!(
            "{} vertices of the topology are in no triangle (first: vertex {first}): each follows its nearest vertex in a triangle when the character is deformed, and every output keeps it",
            stray.len()
        ));
    }
}

/// The rest frame (with landmarks and sequences), written into `m`'s
/// `[rig] rest` when not the topology's and [`InitOptions::choose_rest`];
/// kept with the contact reported when it is off. What was decided is
/// pushed onto `notes`.
fn settle_rest(
    dir: &Path,
    opts: &InitOptions,
    rule: &RestOptions,
    m: &mut Manifest,
    topo: &Mesh,
    notes: &mut Vec<String>,
) -> Result<Option<RestFrame>, InitError> {
    let mut rest = if m.rig.landmarks.is_some() && !m.sequences.is_empty() {
        choose_rest(dir, m, topo, rule)?
    } else {
        None
    };
    if let Some(r) = rest
        .as_mut()
        .filter(|r| !opts.choose_rest && r.sequence.is_some())
    {
        // Kept as asked: the contact is reported, not handled.
        r.choice.why = format!(
            "kept (`InitOptions::choose_rest` off) although the topology's frame has {} contact(s), {} vertices touching: the touching parts may be wired together; a clearer frame would be {}:{}",
            r.choice.first.contacts.len(),
            r.choice.first.touching,
            r.sequence.as_deref().unwrap_or(""),
            r.frame
        );
        r.choice.contacts = r.choice.first.clone();
        r.sequence = None;
        r.frame = 0;
        notes.push(format!("rest frame: the topology's, {}", r.choice.why));
    } else if let Some(r) = &rest {
        if let Some(s) = &r.sequence {
            m.rig.rest = Some(format!("{s}:{}", r.frame));
            notes.push(format!(
                "rest frame: {s}:{} ({}); the rig is embedded on it (`[rig] rest`)",
                r.frame, r.choice.why
            ));
        } else if !r.choice.first.contacts.is_empty() {
            notes.push(format!("rest frame: the topology's ({})", r.choice.why));
        }
    }
    if let Some(p) = &m.rig.landmarks
        && on_surface(p, topo)
    {
        // Checked on the frame they are embedded on, as `check_files`
        // checks points on the topology.
        let at = crate::db::skeletons::rest_frame(dir, m, topo)?;
        let frame = match at {
            Some(q) => topo
                .with_positions(&q)
                .map_err(|e| InitError::Option(format!("the rest frame: {e}")))?,
            None => topo.clone(),
        };
        Landmarks::load_checked(p, &frame)
            .map_err(|e| read(format!("`InitOptions::landmarks` {}", p.display()))(e.into()))?;
    }
    Ok(rest)
}

/// Whether the landmarks file `p` holds a mark fixed to the surface
/// ([`crate::embed::landmarks::Mark::Surface`]); false when it does not
/// read (refused by the checks that follow).
fn on_surface(p: &Path, topo: &Mesh) -> bool {
    use crate::embed::landmarks::Mark;
    Landmarks::load(p, topo.vertex_count())
        .is_ok_and(|lm| lm.marks.values().any(|m| matches!(m, Mark::Surface(_))))
}

/// The folder `dir` created, `m` named after it when unnamed, and `m`'s
/// paths stored relative to it when inside it (else absolute).
fn store_in(dir: &Path, m: &mut Manifest) -> Result<(), InitError> {
    std::fs::create_dir_all(dir).map_err(|source| InitError::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let dir = canonical(dir)?;
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
    Ok(())
}

/// The rest frame over the topology's positions then every frame of every
/// sequence ([`choose_rest_frame`]); surface distances measured on the
/// topology.
fn choose_rest(
    dir: &Path,
    m: &Manifest,
    topo: &Mesh,
    rule: &RestOptions,
) -> Result<Option<RestFrame>, InitError> {
    let mut seqs = Vec::with_capacity(m.sequences.len());
    for s in &m.sequences {
        let q = m
            .load_sequence(dir, s)
            .map_err(|e| read(format!("`InitOptions::sequences` {}", s.name))(e.into()))?;
        seqs.push(q);
    }
    let mut frames: Vec<&[[f64; 3]]> = vec![topo.positions()];
    let mut at: Vec<(Option<usize>, usize)> = vec![(None, 0)];
    for (k, q) in seqs.iter().enumerate() {
        for f in 0..q.frame_count() {
            frames.push(q.frame(f));
            at.push((Some(k), f));
        }
    }
    let Some(choice) = choose_rest_frame(topo, &frames, rule) else {
        return Ok(None);
    };
    let (seq, frame) = at[choice.frame];
    let names: Vec<String> = m.sequences.iter().map(|s| s.name.clone()).collect();
    Ok(Some(RestFrame {
        sequence: seq.map(|k| m.sequences[k].name.clone()),
        frame,
        contact_frames: frame_runs(&choice.contact_frames, &at, &names),
        choice,
    }))
}

/// Every sequence must share the topology's vertices: one of another
/// mesh is refused, with nothing written (issue 39, item 6: it was
/// written with a warning, exit 0, and refused later by `db build`).
fn check_sequences(dir: &Path, m: &Manifest, topo: &Mesh) -> Result<(), InitError> {
    for s in &m.sequences {
        let (count, noun, triangles) = match m.load_sequence(dir, s) {
            Ok(q) => (
                q.mesh().vertex_count(),
                "vertices",
                q.mesh().triangles() == topo.triangles(),
            ),
            Err(e) => {
                use crate::mesh::io::{MeshFormat, mdd, pc2};
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
                        return Err(read(format!("`InitOptions::sequences` {}", s.name))(
                            e.into(),
                        ));
                    }
                }
            }
        };
        if count != topo.vertex_count() {
            return Err(InitError::Option(format!(
                "`InitOptions::sequences` {} ({}): {count} {noun}, the topology (`InitOptions::mesh`) has {} vertices: a sequence of another mesh? \
                 Every sequence must have the topology's vertices",
                s.name,
                s.path.display(),
                topo.vertex_count()
            )));
        }
        if !triangles {
            return Err(InitError::Option(format!(
                "`InitOptions::sequences` {} ({}): its triangles differ from the topology's (`InitOptions::mesh`): every sequence must share its connectivity",
                s.name,
                s.path.display()
            )));
        }
    }
    Ok(())
}

/// The manifest's up axis for `up` (`y`, `z` or `auto`): the landmarks' body axis
/// (groin to chin) read in the mesh file's coordinates decides `auto`
/// (the axis among +Y and +Z it lies within 45° of), and is checked
/// against an explicit `y`/`z` (a warning when they disagree; `auto` read
/// as Z-up is pushed onto `notes`): a capture whose body stands along +Z
/// written as Y-up retargets into a contorted, tilted character with only
/// indirect warnings (knee hyper-extension, turned-over triangles).
pub(crate) fn resolve_up(
    up: &str,
    topo: &Mesh,
    landmarks: Option<&Path>,
    notes: &mut Vec<String>,
) -> Result<String, InitError> {
    let axis = landmarks.and_then(|p| {
        // An unreadable landmarks file is reported by `db build`, which
        // embeds the rig; here it only leaves the axis undecided.
        let pos = topo.positions();
        // A headless body's chin: the top of its neck.
        let lm = Landmarks::load(p, topo.vertex_count())
            .ok()?
            .completed(pos, topo.triangles());
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
                notes.push(
                    "`InitOptions::up` auto: the landmarks' groin→chin direction is along +Z: the files are read as Z-up".into(),
                );
            }
            axis.into()
        }
        ("auto", Some(Err(b))) => {
            return Err(InitError::Option(format!(
                "`InitOptions::up` auto: the landmarks' groin→chin direction {} is within 45° of neither +Y nor +Z; \
                 the database reads Y-up or Z-up files: turn the mesh and its sequences, or pass `InitOptions::up` y or `InitOptions::up` z",
                describe(b)
            )));
        }
        (given, Some(Ok(axis))) if axis != given => {
            tracing::warn!(
                "`InitOptions::up` {given}, but the landmarks' groin→chin direction is along +{}: is the capture {}-up? (pass `InitOptions::up` {axis} or `InitOptions::up` auto)",
                axis.to_ascii_uppercase(),
                axis.to_ascii_uppercase()
            );
            given.into()
        }
        (given, Some(Err(b))) => {
            tracing::warn!(
                "`InitOptions::up` {given}, but the landmarks' groin→chin direction {} is within 45° of neither +Y nor +Z",
                describe(b)
            );
            given.into()
        }
        (given, _) => given.into(),
    })
}

/// The manifest's length unit for `units`: `auto`
/// takes m, cm or mm, whichever makes the rest frame's size (its bounding
/// box's largest side) nearest 1.7 m (a person; the unit's log distance, so 0.85-3.4 m
/// all read as metres; another unit is pushed onto `notes`); an explicit
/// unit is kept. A capture in
/// millimetres read as metres built a 1.7 km dancer whose retargets
/// reported 4.5 m of ground penetration.
pub(crate) fn resolve_units(units: &str, topo: &Mesh, notes: &mut Vec<String>) -> String {
    // The bounding box's largest side: the height standing, the span in a
    // T-pose (about the height), and the same whatever the up axis.
    let Some(h) = extent(topo.positions()) else {
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
            notes.push(format!(
                "`InitOptions::units` auto: the rest frame is {h:.1} file units tall or wide: read as {name} ({:.2} m)",
                h * u
            ));
        }
        return name.into();
    }
    units.into()
}

#[cfg(test)]
mod tests {
    use super::frame_runs;

    /// Runs of consecutive frames within a sequence, the topology on its
    /// own, a run never across two sequences.
    #[test]
    fn contact_frames_are_named_in_runs() {
        let at = [
            (None, 0),
            (Some(0), 0),
            (Some(0), 1),
            (Some(0), 2),
            (Some(0), 3),
            (Some(1), 0),
            (Some(1), 1),
        ];
        let names = ["a".to_string(), "b".to_string()];
        assert_eq!(
            frame_runs(&[0, 1, 2, 4, 5, 6], &at, &names),
            ["topology", "a:0-1", "a:3", "b:0-1"]
        );
        assert_eq!(frame_runs(&[4, 5], &at, &names), ["a:3", "b:0"]);
        assert!(frame_runs(&[], &at, &names).is_empty());
    }
}
