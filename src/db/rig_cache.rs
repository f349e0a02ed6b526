//! The rig of a loaded character, cached in its database (issue 43).
//!
//! A database's rig is embedded on its rest frame with skin weights fitted
//! to the sequences' motion ([`crate::embed::motion_weights::refine`], at
//! most 120 frames): embedding it reads the sequence files (1.2 GB of PC2
//! at 10⁴ frames) and was most of a 10⁴-frame load's CPU and all of its
//! peak memory. [`embed_rig_cached`] keeps the result in `cache/rig.json`
//! under a key of everything it was computed from, so a later load reads
//! no sequence file.
//!
//! The key ([`rig_key`]): the frames' key ([`super::cache::frames_key`]:
//! topology, each sequence's name, path, fps and bytes, the up axis), the
//! rig's inputs (landmarks, parts, glTF skin, rig map, `[rig] rest`), the
//! sequences' lengths the load passes, and `SURFMOTION_RIG_SOURCE`, a
//! fingerprint of the embedding's source code made by `build.rs` (a change
//! to the code embeds the rig again).
//!
//! File (`cache/rig.json`): one line of JSON, `{"format": "surfmotion rig
//! cache 1", "key": "16 hex digits", "bytes": N, "xxh3": "16 hex digits",
//! "source": "16 hex digits"}` (`source`: the writer's `SURFMOTION_RIG_SOURCE`,
//! since session 30; older files lack it and are read alike),
//! then the rig as [`crate::embed::Embedding::save`] writes it (`N` bytes
//! of JSON whose xxh3-64 is `xxh3`; f64 values written shortest and read
//! back bit for bit, serde_json's `float_roundtrip`). Written atomically;
//! only a rig that reads back equal to itself is written. A file of other
//! inputs, cut short, changed or not a rig cache is refused with a
//! [`RigCacheError`] naming it, logged, and the rig embedded and written
//! again.

use super::cache::{KeyHasher, add_rig, cache_dir, frames_key};
use super::manifest::{DbError, Manifest};
use super::skeletons::embed_rig_with;
use crate::embed::{EmbedError, Embedding};
use crate::mesh::Mesh;
use crate::util::fsutil::{FsError, write_atomic};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The file's format line; bump when the layout changes.
const FORMAT: &str = "surfmotion rig cache 1";

/// The fingerprint of the embedding's source code (`build.rs`).
pub(crate) const SOURCE: &str = env!("SURFMOTION_RIG_SOURCE");

/// Why a rig cache file cannot be used (the caller embeds the rig again).
#[derive(Debug, thiserror::Error)]
pub(crate) enum RigCacheError {
    /// The file cannot be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The cache file.
        path: PathBuf,
        /// The failure.
        source: std::io::Error,
    },
    /// Not a rig cache, made from other inputs, or its rig is not the one
    /// written (another length or checksum: cut or changed).
    #[error("{}: {what}", path.display())]
    Header {
        /// The cache file.
        path: PathBuf,
        /// What does not match.
        what: String,
    },
    /// The rig it holds is not a rig of this topology.
    #[error("{0}")]
    Rig(#[from] EmbedError),
}

/// Where the cache came from, for callers that report it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RigSource {
    /// Read from `cache/rig.json`.
    Cached,
    /// Embedded from the inputs (and written to the cache when it could be).
    Embedded,
}

/// The first line of the file.
#[derive(Debug, Serialize, Deserialize)]
struct Header {
    format: String,
    key: String,
    bytes: u64,
    xxh3: String,
    /// [`SOURCE`] of the build that wrote it (since session 30; it is in
    /// the key too: `inspect` tells other code from other inputs by it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    source: Option<String>,
}

/// What a rig cache file says of itself, checked against its own bytes
/// (format, length, checksum), not against a database: `inspect`'s view.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct RigCacheHead {
    /// The key it was written under (16 hex digits).
    pub key: String,
    /// [`SOURCE`] of the build that wrote it (`None`: written before
    /// session 30, which did not record it).
    pub source: Option<String>,
    /// Bytes of its rig.
    pub bytes: u64,
}

/// Reads the header of the rig cache `path` and checks its rig's length
/// and checksum; returns the header and the rig's bytes.
fn open(path: &Path) -> Result<(Header, Vec<u8>), RigCacheError> {
    let header = |what: &str| RigCacheError::Header {
        path: path.to_path_buf(),
        what: what.into(),
    };
    let mut bytes = crate::util::fsutil::read_bytes(path).map_err(|e| RigCacheError::Io {
        path: path.to_path_buf(),
        source: e.source,
    })?;
    let nl = bytes
        .iter()
        .position(|&b| b == b'\n')
        .ok_or_else(|| header("not a rig cache file (no header line)"))?;
    let head: Header = serde_json::from_slice(&bytes[..nl])
        .map_err(|_| header("not a rig cache file (no header line)"))?;
    if head.format != FORMAT {
        return Err(header(&format!(
            "not a rig cache of this version ({:?})",
            head.format
        )));
    }
    let body = bytes.split_off(nl + 1);
    Ok((head, body))
}

/// The rig's length and checksum against the header's.
fn check_body(path: &Path, head: &Header, body: &[u8]) -> Result<(), RigCacheError> {
    let header = |what: String| RigCacheError::Header {
        path: path.to_path_buf(),
        what,
    };
    if body.len() as u64 != head.bytes {
        return Err(header(format!(
            "cut or grown: its rig is {} bytes where {} were written",
            body.len(),
            head.bytes
        )));
    }
    if format!("{:016x}", xxhash_rust::xxh3::xxh3_64(body)) != head.xxh3 {
        return Err(header(
            "changed since it was written (its checksum differs)".into(),
        ));
    }
    Ok(())
}

/// The header of the rig cache `path`, its rig's length and checksum
/// checked (not its key: that needs the database, [`rig_key`]).
pub(crate) fn read_head(path: &Path) -> Result<RigCacheHead, RigCacheError> {
    let (head, body) = open(path)?;
    check_body(path, &head, &body)?;
    Ok(RigCacheHead {
        key: head.key,
        source: head.source,
        bytes: head.bytes,
    })
}

/// The rig cache file of the database `dir`.
pub fn rig_path(dir: &Path) -> PathBuf {
    cache_dir(dir).join("rig.json")
}

/// The key of the rig a load embeds from the database `dir` given each
/// sequence's frame count `lens` (see the module docs).
pub(crate) fn rig_key(dir: &Path, m: &Manifest, lens: Option<&[usize]>) -> Result<u64, DbError> {
    let mut h = frames_key(dir, m)?;
    h.text("rig cache", FORMAT);
    h.text("rig source", SOURCE);
    add_rig(&mut h, dir, m)?;
    add_rig_choice(&mut h, dir, m)?;
    h.text("lengths", &format!("{lens:?}"));
    h.save();
    Ok(h.finish())
}

/// The rig's inputs beside the landmarks and parts ([`add_rig`]): the
/// glTF skin and rig map files' bytes and the `[rig] rest` frame. The rig
/// key hashes them, and so does the skeleton cache's
/// ([`super::frames::keys`]): a rig embedded again on another rest frame
/// must not meet the skeletons of the old one.
pub(crate) fn add_rig_choice(h: &mut KeyHasher, dir: &Path, m: &Manifest) -> Result<(), DbError> {
    for (label, p) in [("gltf skin", &m.rig.gltf_skin), ("rig map", &m.rig.rig_map)] {
        if let Some(p) = p {
            h.text("rig", label);
            h.path(&Manifest::resolve(dir, p))?;
        }
    }
    match &m.rig.rest {
        Some(r) => h.text("rest", r),
        None => h.text("rest", "the topology's frame"),
    };
    Ok(())
}

/// The rig of the database `dir` ([`embed_rig_with`]): read from the
/// cache when it holds the rig of these inputs, else embedded and cached.
/// A cache that cannot be used is logged (a warning naming the file and
/// why) and replaced; a cache that cannot be written is logged and the
/// load goes on.
pub(crate) fn embed_rig_cached(
    dir: &Path,
    m: &Manifest,
    topology: &Mesh,
    lens: Option<&[usize]>,
) -> Result<(Embedding, RigSource), DbError> {
    let key = rig_key(dir, m, lens)?;
    let path = rig_path(dir);
    match read_rig(&path, key, topology.vertex_count()) {
        Ok(rig) => return Ok((rig, RigSource::Cached)),
        Err(RigCacheError::Io { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => tracing::warn!("{e}; embedding the rig again"),
    }
    let rig = embed_rig_with(dir, m, topology, lens)?;
    match save_rig(&path, key, &rig) {
        Ok(true) => {}
        Ok(false) => tracing::debug!(
            "{}: the rig does not read back as itself (a value not finite?); not cached",
            path.display()
        ),
        Err(e) => tracing::warn!("the rig is not cached: {e}"),
    }
    Ok((rig, RigSource::Embedded))
}

/// Reads the rig cache `path` written for `key` and a topology of `n`
/// vertices.
pub(crate) fn read_rig(path: &Path, key: u64, n: usize) -> Result<Embedding, RigCacheError> {
    let header = |what: &str| RigCacheError::Header {
        path: path.to_path_buf(),
        what: what.into(),
    };
    let (head, body) = open(path)?;
    if head.key != format!("{key:016x}") {
        return Err(header("made from other inputs (another key)"));
    }
    check_body(path, &head, &body)?;
    let text = std::str::from_utf8(&body).map_err(|_| header("the rig is not UTF-8"))?;
    Ok(Embedding::parse(text, path, n)?)
}

/// Writes `rig` to the cache `path` under `key`, atomically; `Ok(false)`
/// (nothing written) when the rig would not read back equal to itself.
pub(crate) fn save_rig(path: &Path, key: u64, rig: &Embedding) -> Result<bool, FsError> {
    let fs = |e: serde_json::Error| FsError {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    };
    let body = serde_json::to_vec(rig).map_err(fs)?;
    if serde_json::from_slice::<Embedding>(&body).ok().as_ref() != Some(rig) {
        return Ok(false);
    }
    let head = serde_json::to_vec(&Header {
        format: FORMAT.into(),
        key: format!("{key:016x}"),
        bytes: body.len() as u64,
        xxh3: format!("{:016x}", xxhash_rust::xxh3::xxh3_64(&body)),
        source: Some(SOURCE.into()),
    })
    .map_err(fs)?;
    if let Some(d) = path.parent() {
        std::fs::create_dir_all(d).map_err(|source| FsError {
            path: d.to_path_buf(),
            source,
        })?;
    }
    write_atomic(path, |w| {
        w.write_all(&head)?;
        w.write_all(b"\n")?;
        w.write_all(&body)
    })?;
    Ok(true)
}
