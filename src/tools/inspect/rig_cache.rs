//! `inspect DB/cache/rig.json`, and its line in `inspect DB`: the rig
//! cache a load writes (issue 43, [`crate::db::rig_cache`]) — which rig,
//! the key it was written under, and whether the next load would read it
//! (up to date), embed the rig again because the database, its rig inputs
//! or the embedding code changed (stale), or because the file is cut,
//! changed or not a rig cache (damaged). Before, the file was listed as
//! "not a file db build writes", and `inspect` of the file itself failed
//! on its header line ("trailing characters at line 2").

use super::error::InspectError;
use crate::db::build::{default_measure, graph_path, read_graph_cache};
use crate::db::rig_cache::{RigCacheHead, SOURCE, read_head, read_rig, rig_key, rig_path};
use crate::db::{DbError, Manifest};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// What a rig cache file is and whether a load would read it.
#[derive(Debug, Clone, Serialize)]
pub struct RigCacheReport {
    /// The file.
    pub path: PathBuf,
    /// The database whose cache folder holds it (`None`: a copy elsewhere,
    /// checked against its own bytes only).
    pub database: Option<PathBuf>,
    /// The rig's inputs the manifest names (`landmarks FILE`, `rest
    /// frame SEQ:FRAME`, ...).
    pub rig: Vec<String>,
    /// Its header: the key, the writer's code fingerprint, the rig's bytes.
    pub head: RigCacheHead,
    /// Vertices of the rig it holds.
    pub vertices: Option<usize>,
    /// The key a load of the database wants now (`None`: no database, or
    /// it cannot be computed: see `state`).
    pub wanted_key: Option<String>,
    /// This build's embedding code fingerprint (`SURFMOTION_RIG_SOURCE`).
    pub this_source: String,
    /// Whether the next load reads it as it is.
    pub up_to_date: bool,
    /// `up to date`, or why not.
    pub state: String,
}

/// What the cache listing says of a rig cache: up to date, and the state.
pub(crate) struct Judged {
    pub up_to_date: bool,
    pub state: String,
    pub wanted: Option<String>,
}

/// The rig cache `path` (its header `head`, read and self-consistent) of
/// the database `db` judged as a load would: its key against the one the
/// load computes, then, when equal, its rig read as the load reads it.
fn judge(path: &Path, db: &Path, m: &Manifest, head: &RigCacheHead) -> Judged {
    let want = wanted_key(db, m);
    let Ok(want) = want else {
        let why = want.err().unwrap_or_default();
        return Judged {
            up_to_date: false,
            state: format!("cannot tell: {why}"),
            wanted: None,
        };
    };
    let hex = format!("{want:016x}");
    let again = "the next load (`retarget`, `play`, ...) embeds the rig again";
    let state = if head.key == hex {
        // A key does not make the contents right: read it as a load does.
        let n = m.load_topology(db).map(|t| t.vertex_count());
        match n.map(|n| read_rig(path, want, n)) {
            Ok(Ok(_)) => {
                return Judged {
                    up_to_date: true,
                    state: "up to date".into(),
                    wanted: Some(hex),
                };
            }
            Ok(Err(e)) => format!("damaged ({e}): {again}"),
            Err(e) => format!("cannot tell: {e}"),
        }
    } else {
        match head.source.as_deref() {
            Some(s) if s != SOURCE => format!(
                "stale: written by other embedding code (its fingerprint {s}, this build's {SOURCE}): {again}"
            ),
            Some(_) => format!(
                "stale: the database or its rig inputs changed since it was written: {again}"
            ),
            None => format!(
                "stale: the database, its rig inputs or the embedding code changed since it was written (a file of before session 30: the code's fingerprint is not recorded): {again}"
            ),
        }
    };
    Judged {
        up_to_date: false,
        state,
        wanted: Some(hex),
    }
}

/// The key a load of `db` computes for its rig cache: a load passes the
/// sequences' lengths from the graph it built, so they are read from the
/// graph cache of the default measure (without one, the key of a load
/// that could not pass them).
fn wanted_key(db: &Path, m: &Manifest) -> Result<u64, String> {
    let lens: Option<Vec<usize>> = read_graph_cache(&graph_path(db, default_measure(m)))
        .ok()
        .map(|(_, g)| g.sequences().to_vec())
        .filter(|s| {
            s.len() == m.sequences.len()
                && s.iter().zip(&m.sequences).all(|(a, b)| a.name == b.name)
        })
        .map(|s| s.iter().map(|q| q.len).collect());
    rig_key(db, m, lens.as_deref()).map_err(|e: DbError| e.to_string())
}

/// The listing's line for the rig cache `path` of `db`: (up to date,
/// state), damaged when its header or bytes are not a rig cache's.
pub(crate) fn entry_state(path: &Path, db: &Path, m: &Manifest) -> (bool, String) {
    match read_head(path) {
        Err(e) => (
            false,
            format!("damaged ({e}): the next load embeds the rig again"),
        ),
        Ok(head) => {
            let j = judge(path, db, m, &head);
            (j.up_to_date, j.state)
        }
    }
}

/// What the listing calls the rig cache of a manifest's rig.
pub(crate) fn what(m: &Manifest) -> String {
    format!(
        "rig cache (written by loads: `retarget`, `play`, ...; rig from {})",
        rig_inputs(m).join(", ")
    )
}

/// The rig's inputs the manifest names: its files, then the rest frame.
fn rig_inputs(m: &Manifest) -> Vec<String> {
    let mut v = super::place::rig_files(m);
    v.push(match &m.rig.rest {
        Some(r) => format!("rest frame {r}"),
        None => "rest frame: the topology's".into(),
    });
    v
}

/// Whether `path` is a rig cache: the `rig.json` of a database's cache
/// folder (whatever it holds), or a file whose first line is a rig cache's
/// header (a copy elsewhere).
pub(crate) fn is_rig_cache(path: &Path) -> bool {
    if !path.is_file() {
        return false;
    }
    if database_of(path).is_some() {
        return true;
    }
    super::other::head(path, 48).is_ok_and(|b| b.starts_with(b"{\"format\":\"surfmotion rig cache"))
}

/// The database whose rig cache `path` is.
fn database_of(path: &Path) -> Option<PathBuf> {
    let db = super::place::database_of_cache(path.parent()?)?;
    (path.file_name() == rig_path(&db).file_name()).then_some(db)
}

/// `inspect` of a rig cache file: `Err` naming the file when it is cut,
/// changed or not a rig cache (one line; the next load would embed the rig
/// again); else what it is and whether the next load reads it.
pub(crate) fn inspect_rig_cache(path: &Path) -> Result<RigCacheReport, InspectError> {
    let damaged = |e: &dyn std::fmt::Display| {
        InspectError::Json(format!(
            "{e} (a damaged rig cache: the next load embeds the rig again)"
        ))
    };
    let head = read_head(path).map_err(|e| damaged(&e))?;
    let db = database_of(path);
    let m = match &db {
        Some(db) => Some(Manifest::read(db).map_err(|e| InspectError::Json(e.to_string()))?),
        None => None,
    };
    let vertices = crate::util::fsutil::read_bytes(path).ok().and_then(|b| {
        let nl = b.iter().position(|&c| c == b'\n')?;
        let v: serde_json::Value = serde_json::from_slice(&b[nl + 1..]).ok()?;
        v["vertex_count"].as_u64().map(|n| n as usize)
    });
    let (judged, rig) = match (&db, &m) {
        (Some(db), Some(m)) => (judge(path, db, m, &head), rig_inputs(m)),
        _ => (
            Judged {
                up_to_date: false,
                state: "not in a database's cache folder: its key cannot be checked".into(),
                wanted: None,
            },
            Vec::new(),
        ),
    };
    if judged.state.starts_with("damaged") {
        return Err(InspectError::Json(format!(
            "{}: {}",
            path.display(),
            judged.state
        )));
    }
    Ok(RigCacheReport {
        path: path.to_path_buf(),
        database: db,
        rig,
        head,
        vertices,
        wanted_key: judged.wanted,
        this_source: SOURCE.into(),
        up_to_date: judged.up_to_date,
        state: judged.state,
    })
}

impl RigCacheReport {
    /// A human-readable summary.
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "{} (rig cache)", self.path.display());
        match &self.database {
            Some(db) => {
                let _ = writeln!(
                    s,
                    "  database    {} (its loads write and read it)",
                    db.display()
                );
            }
            None => {
                let _ = writeln!(s, "  database    none (not in a database's cache folder)");
            }
        }
        if !self.rig.is_empty() {
            let _ = writeln!(s, "  rig         from {}", self.rig.join(", "));
        }
        if let Some(n) = self.vertices {
            let _ = writeln!(s, "  vertices    {n}");
        }
        let _ = writeln!(
            s,
            "  key         {}{}",
            self.head.key,
            match &self.wanted_key {
                Some(w) if *w == self.head.key => " (the database's now)".to_string(),
                Some(w) => format!(" (the database's now: {w})"),
                None => String::new(),
            }
        );
        let _ = writeln!(
            s,
            "  code        {} (this build's {})",
            self.head.source.as_deref().unwrap_or("not recorded"),
            self.this_source
        );
        let _ = writeln!(s, "  rig bytes   {}", self.head.bytes);
        let _ = writeln!(s, "  state       {}", self.state);
        s
    }
}
