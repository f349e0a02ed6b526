//! `inspect` of the cache files a database's loads write beside `db
//! build`'s (issue 43): the frame cache `cache/frames.bin`, the skeleton
//! caches `cache/poses-KIND.bin`, the plausibility reference
//! `cache/plausibility-reference.json` and the content-hash memo
//! `cache/content-hashes.json` — what each is, which database, the key it
//! was written under against the one the next load wants (up to date or
//! stale), and, for a file cut short or changed, a one-line error naming
//! it (damaged in the database's listing). Before, the listing called them
//! "not a file db build writes" and `inspect` of the binary files said
//! "not a cache the tool writes".

use super::error::InspectError;
use crate::db::Manifest;
use crate::db::build::{
    cached_frames, default_measure, graph_key, graph_path, read_graph_cache, scan_options,
    similarity_key, similarity_path, sparse_key, sparse_path,
};
use crate::db::frames::{
    CacheHead, FrameCacheError, frames_path, keys, poses_kind_of, poses_path, read_frames_head,
    read_poses, read_poses_head, skeleton_kind_name, verify_frames,
};
use crate::embed::frames::SkeletonKind;
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Which of a load's cache files a path is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LoadCache {
    /// `cache/frames.bin`.
    Frames,
    /// `cache/poses-KIND.bin`.
    Poses(SkeletonKind),
    /// `cache/plausibility-reference.json`.
    Reference,
    /// `cache/content-hashes.json`.
    Memo,
    /// `cache/examples.json`.
    Examples,
}

impl LoadCache {
    /// What the file is, in a few words.
    pub(crate) fn name(self) -> String {
        match self {
            LoadCache::Frames => "frame cache".into(),
            LoadCache::Poses(k) => format!("skeleton cache ({})", skeleton_kind_name(k)),
            LoadCache::Reference => "plausibility reference".into(),
            LoadCache::Memo => "content-hash memo".into(),
            LoadCache::Examples => "example memo".into(),
        }
    }

    /// What the file holds and who writes it (the listing's `what`).
    pub(crate) fn what(self) -> String {
        match self {
            LoadCache::Frames => "frame cache (every frame in metres, Y-up, as f64, and each frame's lowest point; memory-mapped by loads: `retarget`, `play`, ...; written by the first)".into(),
            LoadCache::Poses(k) => format!(
                "skeleton cache ({} joints of every frame, metres, Y-up; written by the first load that reads them)",
                skeleton_kind_name(k)
            ),
            LoadCache::Reference => "plausibility reference (the database's own head, feet, floor and surface figures a retarget's checks are held to; written by the first `retarget`)".into(),
            LoadCache::Memo => "content-hash memo (the hashes of the database's files over 1 MiB by path, length and times, so a key does not read them again; not a key itself)".into(),
            LoadCache::Examples => "example memo (the part deformation's example frames of each region, chosen once per database; written by the first `retarget`)".into(),
        }
    }
}

/// What a load's cache file is and whether the next load reads it.
#[derive(Debug, Clone, Serialize)]
pub struct LoadCacheReport {
    /// The file.
    pub path: PathBuf,
    /// `frame cache`, `skeleton cache (KIND)`, `plausibility reference`
    /// or `content-hash memo`.
    pub cache: String,
    /// What it holds and who writes it.
    pub what: String,
    /// The database whose cache folder holds it (`None`: a copy elsewhere,
    /// checked against its own header only).
    pub database: Option<PathBuf>,
    /// The key it was written under (16 hex digits; `None`: the memo).
    pub key: Option<String>,
    /// The key the next load of the database wants (`None`: no database,
    /// or it cannot be computed: see `state`).
    pub wanted_key: Option<String>,
    /// The fingerprint of this build's code the key covers (the skeleton
    /// code's for a skeleton cache; `None` where the key names a format
    /// version instead).
    pub code: Option<String>,
    /// Frames it holds.
    pub frames: Option<u64>,
    /// Vertices per frame (frame cache).
    pub vertices: Option<u64>,
    /// Its length in bytes.
    pub bytes: u64,
    /// Further facts (the floor, the figures' source, the memo's entries).
    pub details: Vec<String>,
    /// Whether the next load reads it as it is.
    pub up_to_date: bool,
    /// `up to date`, or why not.
    pub state: String,
}

/// Which load cache `path` is: by its name in a database's cache folder,
/// else (a copy elsewhere) by the magic of a `.bin` file.
pub(crate) fn kind_of(path: &Path) -> Option<LoadCache> {
    if !path.is_file() {
        return None;
    }
    if let Some(db) = database_of(path) {
        return kind_in(path, &db);
    }
    let bin = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bin"));
    if !bin {
        return None;
    }
    match super::other::head(path, 8).ok()?.as_slice() {
        b"SMFRM001" => Some(LoadCache::Frames),
        b"SMPOS001" => Some(LoadCache::Poses(
            poses_kind_of(path).unwrap_or(SkeletonKind::Regressor),
        )),
        _ => None,
    }
}

/// Which load cache `file` of the database `db`'s cache folder is.
pub(crate) fn kind_in(file: &Path, db: &Path) -> Option<LoadCache> {
    if file == frames_path(db) {
        return Some(LoadCache::Frames);
    }
    if file == crate::tools::eval::plausibility::reference_path(db) {
        return Some(LoadCache::Reference);
    }
    if file == crate::db::cache::memo_path(db) {
        return Some(LoadCache::Memo);
    }
    if file == crate::db::examples::examples_path(db) {
        return Some(LoadCache::Examples);
    }
    poses_kind_of(file)
        .filter(|&k| poses_path(db, k) == file)
        .map(LoadCache::Poses)
}

/// The database whose cache folder holds `path`.
fn database_of(path: &Path) -> Option<PathBuf> {
    super::place::database_of_cache(path.parent()?)
}

/// Metres per file unit of a manifest (as a load reads it).
fn metres(m: &Manifest) -> f64 {
    crate::mocap::units::parse_unit(&m.units)
        .map(|u| u.metres_per_unit)
        .unwrap_or(1.0)
}

/// The frame and skeleton keys a load of `db` wants for skeletons of `kind`.
fn wanted(db: &Path, m: &Manifest, kind: SkeletonKind) -> Result<(u64, u64), String> {
    keys(db, m, metres(m), kind).map_err(|e| e.to_string())
}

/// The judgement of a cache file: up to date, the state, the key wanted.
pub(crate) struct Judged {
    pub up_to_date: bool,
    pub state: String,
    pub wanted: Option<u64>,
}

impl Judged {
    fn cannot(why: impl std::fmt::Display) -> Judged {
        Judged {
            up_to_date: false,
            state: format!("cannot tell: {why}"),
            wanted: None,
        }
    }
}

const AGAIN: &str = "the next load (`retarget`, `play`, ...) writes it again";

/// A frame cache's header `head` against the database `db`: its key and
/// vertex count.
fn judge_frames(db: &Path, m: &Manifest, head: &CacheHead) -> Judged {
    let (fk, _) = match wanted(db, m, SkeletonKind::Regressor) {
        Ok(k) => k,
        Err(why) => return Judged::cannot(why),
    };
    let n = m.load_topology(db).map(|t| t.vertex_count() as u64);
    let state = match n {
        Err(e) => return Judged::cannot(e),
        Ok(_) if head.key != fk => format!(
            "stale: the sequences, their units or axes changed since it was written: {AGAIN}"
        ),
        Ok(n) if n != head.per_frame => format!(
            "stale: frames of {} vertices, the topology has {n}: {AGAIN}",
            head.per_frame
        ),
        Ok(_) => "up to date".into(),
    };
    Judged {
        up_to_date: state == "up to date",
        state,
        wanted: Some(fk),
    }
}

/// A skeleton cache's header `head` of `kind` against the database `db`.
fn judge_poses(db: &Path, m: &Manifest, kind: SkeletonKind, head: &CacheHead) -> Judged {
    let (_, pk) = match wanted(db, m, kind) {
        Ok(k) => k,
        Err(why) => return Judged::cannot(why),
    };
    let state = if head.key == pk {
        "up to date".to_string()
    } else {
        format!(
            "stale: the sequences, the rig's inputs or the skeleton code changed since it was written (the key covers this build's skeleton code, fingerprint {}): {AGAIN}",
            crate::db::skeletons::SKELETON_SOURCE
        )
    };
    Judged {
        up_to_date: head.key == pk,
        state,
        wanted: Some(pk),
    }
}

/// An example memo of key `found` over `frames` frames against the
/// database `db`: its key follows from the default skeleton cache's key
/// and this build's choosing code.
fn judge_examples(db: &Path, m: &Manifest, found: u64, frames: usize) -> Judged {
    let kind = crate::db::CharacterOptions::default().skeleton;
    let (_, pk) = match wanted(db, m, kind) {
        Ok(k) => k,
        Err(why) => return Judged::cannot(why),
    };
    let want = crate::db::examples::examples_key(pk);
    let state = if found != want {
        format!(
            "stale: the database's skeletons or the choosing code changed since it was written (this build's code {}): the next `retarget` chooses again",
            crate::db::examples::EXAMPLES_SOURCE
        )
    } else {
        match read_poses_head(&poses_path(db, kind)) {
            Ok(h) if h.frames != frames as u64 => format!(
                "stale: chosen over {frames} frames, the database has {}: the next `retarget` chooses again",
                h.frames
            ),
            _ => "up to date".into(),
        }
    };
    Judged {
        up_to_date: state == "up to date",
        state,
        wanted: Some(want),
    }
}

/// Whether a load of `db` would read every cache it needs as it is (the
/// similarity and graph of the default measure, the rig, the frames and
/// the default skeletons) — so that loading it to judge the plausibility
/// reference writes nothing — or the first that it would make again.
fn load_reads_current(db: &Path, m: &Manifest) -> Result<(), String> {
    let measure = default_measure(m);
    let key = similarity_key(db, m, measure).map_err(|e| e.to_string())?;
    let skey = sparse_key(key, &scan_options(m, cached_frames(db, measure)).0);
    let gpath = graph_path(db, measure);
    let (gk, _) = read_graph_cache(&gpath).map_err(|_| name_of(&gpath, "missing or unreadable"))?;
    let (spath, want, magic) = if gk == graph_key(m, skey) {
        (sparse_path(db, measure), skey, b"SMSPA001")
    } else if gk == graph_key(m, key) {
        (similarity_path(db, measure), key, b"SMSIM001")
    } else {
        return Err(name_of(&gpath, "stale"));
    };
    match super::place::header_key(&spath, magic) {
        Ok(k) if k == want => {}
        _ => return Err(name_of(&spath, "missing, stale or unreadable")),
    }
    let (up, _) = super::rig_cache::entry_state(&crate::db::rig_cache::rig_path(db), db, m);
    if !up {
        return Err(name_of(
            &crate::db::rig_cache::rig_path(db),
            "missing or not up to date",
        ));
    }
    let kind = crate::db::CharacterOptions::default().skeleton;
    let (fk, pk) = wanted(db, m, kind)?;
    let fpath = frames_path(db);
    match read_frames_head(&fpath) {
        Ok(h) if h.key == fk => {}
        _ => return Err(name_of(&fpath, "missing, stale or damaged")),
    }
    let ppath = poses_path(db, kind);
    match read_poses_head(&ppath) {
        Ok(h) if h.key == pk => {}
        _ => return Err(name_of(&ppath, "missing, stale or damaged")),
    }
    Ok(())
}

fn name_of(path: &Path, why: &str) -> String {
    format!(
        "{} is {why}",
        path.file_name().unwrap_or_default().to_string_lossy()
    )
}

/// A plausibility reference of key `found` against the database `db`: the
/// key a retarget's checker computes, from the character loaded (only
/// when every cache a load reads is current, so nothing is written).
fn judge_reference(db: &Path, m: &Manifest, found: u64) -> Judged {
    if let Err(why) = load_reads_current(db, m) {
        return Judged::cannot(format!(
            "{why}, so the next load makes it again first; it then measures the reference again if the key changed"
        ));
    }
    let ch = match crate::db::Character::load(db, &crate::db::Quiet) {
        Ok(ch) => ch,
        Err(e) => return Judged::cannot(e),
    };
    let want = match crate::tools::eval::plausibility::reference_key_for(&ch) {
        Ok(k) => k,
        Err(e) => return Judged::cannot(e),
    };
    let state = if found == want {
        "up to date".to_string()
    } else {
        "stale: the frames, the rig, the skeletons, the checks' options or their code changed since it was measured: the next `retarget` measures it again (reads every frame)".into()
    };
    Judged {
        up_to_date: found == want,
        state,
        wanted: Some(want),
    }
}

/// The listing's state of the load cache `file` (`kind`) of `db`: (up to
/// date, state), damaged when its header or bytes are not its kind's. The
/// frames are not read (`inspect` of the file reads them).
pub(crate) fn entry_state(file: &Path, kind: LoadCache, db: &Path, m: &Manifest) -> (bool, String) {
    match judge_file(file, kind, Some((db, m)), false) {
        Ok((_, j)) => (j.up_to_date, j.state),
        Err(why) => (false, format!("damaged ({why}): {AGAIN}")),
    }
}

/// What was read of a cache file to judge it.
struct Read {
    key: Option<u64>,
    frames: Option<u64>,
    vertices: Option<u64>,
    bytes: u64,
    details: Vec<String>,
}

/// Reads the load cache `path` (`kind`) and judges it against `db` when
/// given; `verify`: every frame of a frame cache read too. `Err`: why the
/// file is damaged (naming it).
fn judge_file(
    path: &Path,
    kind: LoadCache,
    db: Option<(&Path, &Manifest)>,
    verify: bool,
) -> Result<(Read, Judged), String> {
    let fe = |e: FrameCacheError| e.to_string();
    let elsewhere = || Judged {
        up_to_date: false,
        state: "not in a database's cache folder: its key cannot be checked".into(),
        wanted: None,
    };
    match kind {
        LoadCache::Frames => {
            let head = read_frames_head(path).map_err(fe)?;
            if verify {
                verify_frames(path, &head).map_err(fe)?;
            }
            let read = Read {
                key: Some(head.key),
                frames: Some(head.frames),
                vertices: Some(head.per_frame),
                bytes: head.bytes,
                details: if verify {
                    vec![format!(
                        "checked: every coordinate finite and every frame's lowest point the one stored ({} frames read)",
                        head.frames
                    )]
                } else {
                    Vec::new()
                },
            };
            let j = db.map_or_else(elsewhere, |(d, m)| judge_frames(d, m, &head));
            Ok((read, j))
        }
        LoadCache::Poses(k) => {
            let head = read_poses_head(path).map_err(fe)?;
            let poses = read_poses(path, head.key, head.frames as usize).map_err(fe)?;
            if let Some(i) = poses.iter().position(|p| !p.iter().all(|j| j.is_finite())) {
                return Err(format!(
                    "{}: pose {i}: a joint that is not a finite number (changed after it was written)",
                    path.display()
                ));
            }
            let read = Read {
                key: Some(head.key),
                frames: Some(head.frames),
                vertices: None,
                bytes: head.bytes,
                details: vec![format!("{} joints a pose", head.per_frame)],
            };
            let mut j = db.map_or_else(elsewhere, |(d, m)| judge_poses(d, m, k, &head));
            // Its frames against the frame cache's, when that one is current.
            if let Some((d, _)) = db
                && j.up_to_date
                && let Ok(f) = read_frames_head(&frames_path(d))
                && f.frames != head.frames
            {
                j.up_to_date = false;
                j.state = format!(
                    "stale: {} poses, the frame cache has {} frames: {AGAIN}",
                    head.frames, f.frames
                );
            }
            Ok((read, j))
        }
        LoadCache::Reference => {
            let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
            let (key, floor, r) = crate::tools::eval::plausibility::read_reference_file(path)?;
            let read = Read {
                key: Some(key),
                frames: Some(r.frames as u64),
                vertices: None,
                bytes,
                details: vec![
                    format!("measured on {}", r.source),
                    format!("floor {floor:.4} m"),
                ],
            };
            let j = db.map_or_else(elsewhere, |(d, m)| judge_reference(d, m, key));
            Ok((read, j))
        }
        LoadCache::Examples => {
            let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
            let (key, frames, entries) = crate::db::examples::read_examples(path)?;
            let read = Read {
                key: Some(key),
                frames: Some(frames as u64),
                vertices: None,
                bytes,
                details: vec![format!(
                    "{entries} example sets (one for each region's joints and count)"
                )],
            };
            let j = db.map_or_else(elsewhere, |(d, m)| judge_examples(d, m, key, frames));
            Ok((read, j))
        }
        LoadCache::Memo => {
            let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
            let entries = crate::db::content::memo_entries(path)?;
            let read = Read {
                key: None,
                frames: None,
                vertices: None,
                bytes,
                details: vec![format!(
                    "{} remembered",
                    crate::batch::summary::count(entries, "file hash")
                )],
            };
            let j = Judged {
                up_to_date: true,
                state: "up to date (a memo: an entry whose file changed is hashed again, never trusted)".into(),
                wanted: None,
            };
            Ok((read, j))
        }
    }
}

/// `inspect` of a load cache file: `Err` naming the file when it is cut,
/// changed or not its kind (one line; the next load would write it
/// again); else what it is and whether the next load reads it. A frame
/// cache's frames are read whole.
pub(crate) fn inspect_load_cache(
    path: &Path,
    kind: LoadCache,
) -> Result<LoadCacheReport, InspectError> {
    let db = database_of(path);
    let m = match &db {
        Some(db) => Some(Manifest::read(db).map_err(|e| InspectError::Json(e.to_string()))?),
        None => None,
    };
    let pair = db.as_deref().zip(m.as_ref());
    let (read, j) = judge_file(path, kind, pair, true).map_err(|why| {
        let named = if why.contains(&path.display().to_string()) {
            why
        } else {
            format!("{}: {why}", path.display())
        };
        InspectError::Json(format!(
            "{named} (a damaged {}: the next load writes it again)",
            kind.name()
        ))
    })?;
    let code = match kind {
        LoadCache::Poses(_) => Some(crate::db::skeletons::SKELETON_SOURCE.to_string()),
        LoadCache::Examples => Some(crate::db::examples::EXAMPLES_SOURCE.to_string()),
        _ => None,
    };
    Ok(LoadCacheReport {
        path: path.to_path_buf(),
        cache: kind.name(),
        what: kind.what(),
        database: db,
        key: read.key.map(|k| format!("{k:016x}")),
        wanted_key: j.wanted.map(|k| format!("{k:016x}")),
        code,
        frames: read.frames,
        vertices: read.vertices,
        bytes: read.bytes,
        details: read.details,
        up_to_date: j.up_to_date,
        state: j.state,
    })
}

impl LoadCacheReport {
    /// A human-readable summary.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "{} ({})", self.path.display(), self.cache);
        let _ = writeln!(s, "  what        {}", self.what);
        match &self.database {
            Some(db) => {
                let _ = writeln!(s, "  database    {}", db.display());
            }
            None => {
                let _ = writeln!(s, "  database    none (not in a database's cache folder)");
            }
        }
        if let Some(f) = self.frames {
            let v = self
                .vertices
                .map(|v| format!(" of {v} vertices"))
                .unwrap_or_default();
            let _ = writeln!(s, "  frames      {f}{v}");
        }
        let _ = writeln!(s, "  bytes       {}", self.bytes);
        if let Some(k) = &self.key {
            let _ = writeln!(
                s,
                "  key         {k}{}",
                match &self.wanted_key {
                    Some(w) if w == k => " (the database's now)".to_string(),
                    Some(w) => format!(" (the database's now: {w})"),
                    None => String::new(),
                }
            );
        }
        if let Some(c) = &self.code {
            let _ = writeln!(s, "  code        {c} (this build's, in the key)");
        }
        for d in &self.details {
            let _ = writeln!(s, "  note        {d}");
        }
        let _ = writeln!(s, "  state       {}", self.state);
        s
    }
}
