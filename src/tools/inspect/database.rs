//! `inspect DB` and `inspect DB/cache`: what a character database holds
//! (sequences, frames, skeletons) and the state of its cache (which files
//! `db build` wrote, whether each is up to date with the database, the
//! graph's size). `inspect` used to refuse the folder and call the cache
//! folder "no .obj files".
//!
//! Up to date means the key a cache file carries is the key its inputs hash
//! to now ([`crate::db::cache`]): computing it reads every sequence file
//! once, as `db build` does before it reuses a cache.

use super::error::InspectError;
use crate::db::Manifest;
use crate::db::build::{
    cached_frames, default_measure, graph_key, graph_path, read_graph_cache, scan_options,
    similarity_key, similarity_path, sparse_key, sparse_path,
};
use crate::db::cache::cache_dir;
use crate::similarity::Measure;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A sequence of a database.
#[derive(Debug, Clone, Serialize)]
pub struct DbSequence {
    /// Name.
    pub name: String,
    /// Frames (0 when it does not load: see `problems`).
    pub frames: usize,
    /// Frames per second.
    pub fps: f64,
}

/// A per-frame skeleton file in the database folder (`db skeleton` writes
/// `skeletons/SEQ.skeleton.json`, `synth` the ground truth
/// `truth/SEQ.skeleton.json`).
#[derive(Debug, Clone, Serialize)]
pub struct DbSkeleton {
    /// The file.
    pub file: PathBuf,
    /// Its sequence.
    pub sequence: String,
    /// Frames it holds (`None`: it does not read).
    pub frames: Option<usize>,
    /// `matches the sequence`, or what is wrong.
    pub state: String,
}

/// A file of the cache folder.
#[derive(Debug, Clone, Serialize)]
pub struct CacheEntry {
    /// The file.
    pub file: PathBuf,
    /// `similarity matrix (MEASURE)`, `graph (MEASURE)`, `parametric
    /// model`, `rig cache (...)`, a load's `frame cache (...)`, `skeleton
    /// cache (...)`, `plausibility reference (...)`, `content-hash memo
    /// (...)`, or `not a file db build writes`.
    pub what: String,
    /// Whether `db build` (or `play`) would use it as it is.
    pub up_to_date: bool,
    /// `up to date`, or why not (stale, unreadable).
    pub state: String,
    /// A graph's transitions.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub transitions: Option<usize>,
    /// A graph's sequence edges.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edges: Option<usize>,
    /// A graph's frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub frames: Option<usize>,
    /// An up-to-date sparse similarity's sequence-pair scan (issue 43):
    /// the full scan or the reach, and the estimates it was chosen from.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scan: Option<String>,
}

/// What a database folder holds.
#[derive(Debug, Clone, Serialize)]
pub struct DatabaseReport {
    /// The folder.
    pub path: PathBuf,
    /// Character name.
    pub name: String,
    /// Frames per second of the manifest.
    pub fps: f64,
    /// Length unit of the meshes.
    pub units: String,
    /// Up axis.
    pub up: String,
    /// Topology file.
    pub topology: PathBuf,
    /// Topology vertex count.
    pub vertices: usize,
    /// Topology triangle count.
    pub triangles: usize,
    /// Sequences.
    pub sequences: Vec<DbSequence>,
    /// Frames in all sequences.
    pub total_frames: usize,
    /// The rig the manifest names (`landmarks FILE`, ...; empty: none).
    pub rig: Vec<String>,
    /// Per-frame skeleton files found.
    pub skeletons: Vec<DbSkeleton>,
    /// The measure `db build`, `graph` and `retarget` use by default.
    pub measure: String,
    /// The cache folder.
    pub cache_dir: PathBuf,
    /// Its files.
    pub cache: Vec<CacheEntry>,
    /// Problems `db info` reports (a rest frame not a person's size, a
    /// landmark file no rig can be embedded from, ...).
    pub problems: Vec<String>,
    /// Notes `db info` reports (no rig).
    pub notes: Vec<String>,
}

/// What a database's cache folder holds.
#[derive(Debug, Clone, Serialize)]
pub struct CacheReport {
    /// The cache folder.
    pub path: PathBuf,
    /// Its database.
    pub database: PathBuf,
    /// The measure `db build` uses by default.
    pub measure: String,
    /// Its files.
    pub cache: Vec<CacheEntry>,
}

use super::place::header_key;
pub(crate) use super::place::{database_of_cache, is_database};

fn err(e: impl std::fmt::Display) -> InspectError {
    InspectError::Json(e.to_string())
}

/// Reads the database `dir`: its manifest, every sequence (as `db info`),
/// its skeleton files and its cache.
pub(crate) fn inspect_database(dir: &Path) -> Result<DatabaseReport, InspectError> {
    // Read, not opened: what would refuse it (a wrong unit) is listed
    // among the problems.
    let m = Manifest::read(dir).map_err(err)?;
    let info = crate::db::info(dir).map_err(err)?;
    let sequences: Vec<DbSequence> = info
        .sequences
        .iter()
        .map(|s| DbSequence {
            name: s.name.clone(),
            frames: s.frames,
            fps: s.fps,
        })
        .collect();
    let rig = super::place::rig_files(&m);
    let mut skeletons = Vec::new();
    for sub in ["skeletons", "truth"] {
        let Ok(rd) = std::fs::read_dir(dir.join(sub)) else {
            continue;
        };
        let mut files: Vec<PathBuf> = rd
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.to_string_lossy().ends_with(".skeleton.json"))
            .collect();
        files.sort();
        skeletons.extend(files.into_iter().map(|f| skeleton_file(f, &sequences)));
    }
    Ok(DatabaseReport {
        path: dir.to_path_buf(),
        name: m.name.clone(),
        fps: m.fps,
        units: m.units.clone(),
        up: m.up.clone(),
        topology: m.topology.clone(),
        vertices: info.vertices,
        triangles: info.triangles,
        total_frames: info.total_frames,
        sequences,
        rig,
        skeletons,
        measure: default_measure(&m).name().into(),
        cache_dir: cache_dir(dir),
        cache: cache_entries(dir, &m)?,
        problems: info.problems,
        notes: info.notes,
    })
}

/// Reads the cache folder of the database `db`.
pub(crate) fn inspect_cache(path: &Path, db: &Path) -> Result<CacheReport, InspectError> {
    let m = Manifest::read(db).map_err(err)?;
    Ok(CacheReport {
        path: path.to_path_buf(),
        database: db.to_path_buf(),
        measure: default_measure(&m).name().into(),
        cache: cache_entries(db, &m)?,
    })
}

/// A skeleton file's frames against its sequence's.
fn skeleton_file(file: PathBuf, sequences: &[DbSequence]) -> DbSkeleton {
    let name = file.file_name().map(|n| n.to_string_lossy().into_owned());
    let sequence = name
        .as_deref()
        .and_then(|n| n.strip_suffix(".skeleton.json"))
        .unwrap_or_default()
        .to_string();
    let frames = crate::util::fsutil::read_small_text(&file)
        .map_err(|e| e.to_string())
        .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).map_err(|e| e.to_string()))
        .and_then(|v| {
            v["frames"]
                .as_array()
                .map(Vec::len)
                .ok_or_else(|| "no \"frames\" list".to_string())
        });
    let state = match (&frames, sequences.iter().find(|s| s.name == sequence)) {
        (Err(why), _) => format!("does not read: {why}"),
        (Ok(_), None) => "no sequence of that name in the manifest".into(),
        (Ok(_), Some(s)) if s.frames == 0 => "its sequence does not load (see the problems)".into(),
        (Ok(f), Some(s)) if *f == s.frames => "matches the sequence".into(),
        (Ok(f), Some(s)) => format!(
            "{f} frames, the sequence has {}: made before the sequence changed",
            s.frames
        ),
    };
    DbSkeleton {
        file,
        sequence,
        frames: frames.ok(),
        state,
    }
}

/// Every file of the cache folder of `dir`, with its state.
fn cache_entries(dir: &Path, m: &Manifest) -> Result<Vec<CacheEntry>, InspectError> {
    let cdir = cache_dir(dir);
    let Ok(rd) = std::fs::read_dir(&cdir) else {
        return Ok(Vec::new());
    };
    let mut files: Vec<PathBuf> = rd.filter_map(|e| e.ok().map(|e| e.path())).collect();
    files.sort();
    // Keys are computed once a measure (each reads every sequence).
    let mut keys: BTreeMap<&'static str, Result<u64, String>> = BTreeMap::new();
    let mut key_of = |measure: Measure| {
        keys.entry(measure.name())
            .or_insert_with(|| similarity_key(dir, m, measure).map_err(|e| e.to_string()))
            .clone()
    };
    let measures = [
        Measure::Shape,
        Measure::Vertex,
        Measure::Skeleton,
        Measure::Colour,
    ];
    let mut out = Vec::new();
    for file in files {
        let mut e = CacheEntry {
            file: file.clone(),
            what: "not a file db build writes".into(),
            up_to_date: false,
            state: "left alone by the tool".into(),
            transitions: None,
            edges: None,
            frames: None,
            scan: None,
        };
        let judge = |e: &mut CacheEntry, found: Result<u64, String>, want: Result<u64, String>| {
            (e.up_to_date, e.state) = match (found, want) {
                (Err(why), _) => (false, format!("unreadable ({why}): `db build` rebuilds it")),
                (_, Err(why)) => (false, format!("cannot tell: {why}")),
                (Ok(f), Ok(w)) if f == w => (true, "up to date".into()),
                _ => (
                    false,
                    "stale: the database changed since it was built; `db build` rebuilds it".into(),
                ),
            }
        };
        if let Some(measure) = measures
            .into_iter()
            .find(|&q| file == similarity_path(dir, q))
        {
            e.what = format!("similarity matrix ({})", measure.name());
            judge(&mut e, header_key(&file, b"SMSIM001"), key_of(measure));
            // A key does not make the contents right: read it as `db
            // build` does before reusing it.
            if e.up_to_date
                && let Ok(k) = key_of(measure)
                && let Err(why) = check_matrix(&file, k, m)
            {
                (e.up_to_date, e.state) =
                    (false, format!("damaged ({why}): `db build` rebuilds it"));
            }
        } else if let Some(measure) = measures.into_iter().find(|&q| file == sparse_path(dir, q)) {
            e.what = format!("sparse similarity ({})", measure.name());
            // The scan rule on the frames the file says it holds (its key
            // vouches for the count).
            let (opts, choice) = scan_options(m, cached_frames(dir, measure));
            let want = key_of(measure).map(|k| sparse_key(k, &opts));
            judge(&mut e, header_key(&file, b"SMSPA001"), want.clone());
            if e.up_to_date {
                e.scan = Some(choice.describe());
            }
            // Opened as `db build` opens it before reuse.
            if e.up_to_date
                && let Ok(k) = want
                && let Err(why) = crate::db::cache::read_sparse(&file, k)
            {
                (e.up_to_date, e.state) =
                    (false, format!("damaged ({why}): `db build` rebuilds it"));
            }
        } else if let Some(measure) = measures.into_iter().find(|&q| file == graph_path(dir, q)) {
            e.what = format!("graph ({})", measure.name());
            let read = read_graph_cache(&file);
            if let Ok((_, g)) = &read {
                e.transitions = Some(g.transitions().len());
                e.edges = Some(g.edges().len());
                e.frames = Some(g.sequences().iter().map(|s| s.len).sum());
            }
            let found = read.as_ref().map(|(k, _)| *k).map_err(Clone::clone);
            let frames = e.frames.unwrap_or(0);
            let found_key = found.as_ref().ok().copied();
            let (want, sparse) = graph_want(m, found_key, key_of(measure), frames);
            judge(&mut e, found, want);
            // Checked against its similarity, as `db build` does.
            if e.up_to_date
                && let (Ok((_, g)), Ok(k)) = (&read, key_of(measure))
                && let Err(why) = validate_graph(dir, m, measure, g, k, sparse)
            {
                (e.up_to_date, e.state) =
                    (false, format!("damaged ({why}): `db build` rebuilds it"));
            }
        } else if file == crate::db::rig_cache::rig_path(dir) {
            e.what = super::rig_cache::what(m);
            (e.up_to_date, e.state) = super::rig_cache::entry_state(&file, dir, m);
        } else if let Some(kind) = super::db_files::kind_in(&file, dir) {
            e.what = kind.what();
            (e.up_to_date, e.state) = super::db_files::entry_state(&file, kind, dir, m);
        } else if file == crate::parametric::store::cache_path(dir) {
            e.what = "parametric model (`play`)".into();
            let want =
                crate::parametric::store::key(dir, m, &crate::parametric::MotionOptions::default())
                    .map_err(|e| e.to_string());
            judge(&mut e, header_key(&file, b"SMPAR001"), want);
            // A key does not make the contents right: read it as `play`
            // does (a tampered block count said "up to date").
            if e.up_to_date
                && let Err(why) = crate::parametric::store::check_file(dir, m, &file)
            {
                (e.up_to_date, e.state) = (
                    false,
                    format!("damaged ({why}): `play` or `db build` rebuilds it"),
                );
            }
        }
        out.push(e);
    }
    Ok(out)
}

/// The key a graph cache must carry to be current, and whether that is the
/// key of a graph built on the sparse similarity: `db build` keys a graph by
/// the similarity it was built from — the dense matrix's key, or the sparse
/// similarity's ([`sparse_key`]) for a database of
/// [`crate::db::build::SPARSE_FRAMES`] frames or more (issue 43: judged
/// with the dense key alone, every sparse database's graph read "stale"),
/// its scan chosen for the graph's `frames`.
fn graph_want(
    m: &Manifest,
    found: Option<u64>,
    dense: Result<u64, String>,
    frames: usize,
) -> (Result<u64, String>, bool) {
    match dense {
        Err(why) => (Err(why), false),
        Ok(k) => {
            let sparse = graph_key(m, sparse_key(k, &scan_options(m, frames).0));
            if found == Some(sparse) {
                (Ok(sparse), true)
            } else {
                (Ok(graph_key(m, k)), false)
            }
        }
    }
}

/// A current graph checked against the similarity it was built from (the
/// dense matrix or the sparse similarity of `dense_key`), as `db build`
/// checks it before reuse; no similarity cache to check against: `Ok`.
fn validate_graph(
    dir: &Path,
    m: &Manifest,
    measure: Measure,
    g: &crate::graph::SurfaceMotionGraph,
    dense_key: u64,
    sparse: bool,
) -> Result<(), String> {
    if sparse {
        let frames = g.sequences().iter().map(|s| s.len).sum();
        let skey = sparse_key(dense_key, &scan_options(m, frames).0);
        match crate::db::cache::read_sparse(&sparse_path(dir, measure), skey) {
            Ok(Some(s)) => g.validate(&s),
            _ => Ok(()),
        }
    } else {
        match crate::db::cache::read_matrix(&similarity_path(dir, measure), dense_key) {
            Ok(Some(mat)) => g.validate(&mat),
            _ => Ok(()),
        }
    }
}

/// A similarity cache of key `key` read whole and checked as `db build`
/// checks it before reuse: its spans are the manifest's sequences and
/// every value a finite distance.
fn check_matrix(path: &Path, key: u64, m: &Manifest) -> Result<(), String> {
    let Some(mat) = crate::db::cache::read_matrix(path, key)? else {
        return Ok(());
    };
    let names = mat.spans.len() == m.sequences.len()
        && mat
            .spans
            .iter()
            .zip(&m.sequences)
            .all(|(s, q)| s.name == q.name);
    if !names {
        return Err("its sequences are not the manifest's".into());
    }
    if !(0..mat.len()).all(|a| mat.row(a).iter().all(|v| v.is_finite() && *v >= 0.0)) {
        return Err("a value that is not a finite distance".into());
    }
    Ok(())
}

/// The cache lines of a text report.
fn write_cache(s: &mut String, measure: &str, cache: &[CacheEntry]) {
    if cache.is_empty() {
        let _ = writeln!(
            s,
            "  cache       empty: `surfmotion db build` fills it (measure {measure})"
        );
    }
    for e in cache {
        let name = e.file.file_name().unwrap_or_default().to_string_lossy();
        let size = match (e.transitions, e.edges, e.frames) {
            (Some(t), Some(g), Some(f)) => format!(
                ", {} between {}, {}",
                crate::batch::summary::count(t, "transition"),
                crate::batch::summary::count(f, "frame"),
                crate::batch::summary::count(g, "sequence edge")
            ),
            _ => String::new(),
        };
        let _ = writeln!(s, "  cache       {name}: {}{size}; {}", e.what, e.state);
        if let Some(scan) = &e.scan {
            let _ = writeln!(s, "              scan: {scan}");
        }
    }
}

impl DatabaseReport {
    /// A human-readable summary.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{} (character database '{}')",
            self.path.display(),
            self.name
        );
        let _ = writeln!(
            s,
            "  topology    {} ({} vertices, {} triangles), units {}, up {}",
            self.topology.display(),
            self.vertices,
            self.triangles,
            self.units,
            self.up
        );
        for q in &self.sequences {
            let _ = writeln!(
                s,
                "  sequence    {} ({} frames at {} fps)",
                q.name, q.frames, q.fps
            );
        }
        let _ = writeln!(
            s,
            "  frames      {} in {}",
            self.total_frames,
            crate::batch::summary::count(self.sequences.len(), "sequence")
        );
        let _ = writeln!(
            s,
            "  rig         {}",
            if self.rig.is_empty() {
                "none".into()
            } else {
                self.rig.join(", ")
            }
        );
        if self.skeletons.is_empty() {
            let _ = writeln!(
                s,
                "  skeletons   none: `surfmotion db skeleton {}` writes them",
                self.path.display()
            );
        }
        for k in &self.skeletons {
            let _ = writeln!(s, "  skeleton    {}: {}", k.file.display(), k.state);
        }
        write_cache(&mut s, &self.measure, &self.cache);
        for p in &self.problems {
            let _ = writeln!(s, "  problem: {p}");
        }
        for n in &self.notes {
            let _ = writeln!(s, "  note: {n}");
        }
        s
    }
}

impl CacheReport {
    /// A human-readable summary.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{} (the cache of the database {})",
            self.path.display(),
            self.database.display()
        );
        write_cache(&mut s, &self.measure, &self.cache);
        s
    }
}
