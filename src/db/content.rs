//! The content hashes of a database's large input files (over
//! [`WHOLE_FILE_BYTES`](super::cache::WHOLE_FILE_BYTES)), memoised in
//! `cache/content-hashes.json` (issue 43).
//!
//! A cache key takes a large file by the xxh3-64 hash of all its bytes, so a
//! copy without its times (`cp -r`) or a `touch` keeps every cache: the file
//! is hashed once more, its hash is the same, nothing is rebuilt. Hashing
//! 1.2 GB of sequences on every load would cost seconds, so each hash is
//! remembered with what identifies the file's state: its path (relative to
//! the database), length, modification time and status-change time. The
//! status-change time (`ctime`) is set by the system on every write, rename
//! into place or time change and cannot be set back by a program, so a file
//! rewritten in place with its length kept and its modification time put
//! back is hashed again, not trusted. A file changed less than
//! [`SETTLE_SECONDS`] before it was hashed is not remembered (a write in the
//! same clock tick would not move its times: "racy" entries, as git's index
//! has them); it is hashed again on the next load.
//!
//! Memo file (JSON): `{"version": 1, "files": [{"path", "len",
//! "modified_ns", "changed_ns", "xxh3"}]}`, written atomically. A memo that
//! cannot be read is never trusted: a warning naming it, and every large
//! file is hashed again.

use crate::util::fsutil::{FsError, write_atomic};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::Xxh3;

/// The memo's file name in the cache folder.
pub(crate) const MEMO_FILE: &str = "content-hashes.json";
/// Format of the memo file.
const MEMO_VERSION: u32 = 1;
/// A file changed this recently when hashed is not remembered.
pub const SETTLE_SECONDS: u64 = 2;

/// What identifies a file's state without reading it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
struct Stamp {
    len: u64,
    modified_ns: u128,
    changed_ns: u128,
}

impl Stamp {
    fn of(meta: &std::fs::Metadata) -> Stamp {
        let modified_ns = meta
            .modified()
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map_or(0, |d| d.as_nanos());
        Stamp {
            len: meta.len(),
            modified_ns,
            changed_ns: changed_ns(meta),
        }
    }

    /// True when both times are at least [`SETTLE_SECONDS`] before `now`.
    fn settled(&self, now: u128) -> bool {
        let settle = u128::from(SETTLE_SECONDS) * 1_000_000_000;
        self.modified_ns.saturating_add(settle) <= now
            && self.changed_ns.saturating_add(settle) <= now
    }
}

#[cfg(unix)]
fn changed_ns(meta: &std::fs::Metadata) -> u128 {
    use std::os::unix::fs::MetadataExt;
    u128::try_from(meta.ctime()).unwrap_or(0) * 1_000_000_000
        + u128::try_from(meta.ctime_nsec()).unwrap_or(0)
}

#[cfg(not(unix))]
fn changed_ns(_: &std::fs::Metadata) -> u128 {
    0
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Entry {
    path: String,
    len: u64,
    modified_ns: u128,
    changed_ns: u128,
    xxh3: String,
}

#[derive(Debug, Serialize, Deserialize)]
struct MemoFile {
    version: u32,
    files: Vec<Entry>,
}

/// The content hashes of one database's large files, read from and written
/// back to its cache folder.
#[derive(Debug)]
pub struct ContentMemo {
    dir: PathBuf,
    path: PathBuf,
    known: BTreeMap<String, (Stamp, u64)>,
    dirty: bool,
    /// Files hashed (not found in the memo) since it was opened.
    hashed: usize,
}

impl ContentMemo {
    /// The memo of the database `dir`, kept in the file `path`
    /// (`cache::memo_path`): empty when there is none; when it cannot be
    /// read, a warning naming it and empty (never trusted).
    pub fn open(dir: &Path, path: PathBuf) -> ContentMemo {
        let known = match read_memo(&path) {
            Ok(k) => k,
            Err(why) => {
                tracing::warn!(
                    "{}: {why}; hashing the database's large files again",
                    path.display()
                );
                BTreeMap::new()
            }
        };
        ContentMemo {
            dir: dir.to_path_buf(),
            path,
            known,
            dirty: false,
            hashed: 0,
        }
    }

    /// Files hashed whole since the memo was opened (not found in it).
    pub fn hashed(&self) -> usize {
        self.hashed
    }

    /// The xxh3-64 hash of all the bytes of `f` (opened at `p`, `meta` its
    /// metadata): remembered if its path, length and times are, else read.
    pub fn hash(
        &mut self,
        p: &Path,
        f: &mut std::fs::File,
        meta: &std::fs::Metadata,
    ) -> Result<u64, FsError> {
        let rel = p
            .strip_prefix(&self.dir)
            .unwrap_or(p)
            .to_string_lossy()
            .into_owned();
        let stamp = Stamp::of(meta);
        if let Some((s, h)) = self.known.get(&rel)
            && *s == stamp
        {
            return Ok(*h);
        }
        let h = hash_all(p, f)?;
        self.hashed += 1;
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos());
        if stamp.settled(now) {
            self.known.insert(rel, (stamp, h));
            self.dirty = true;
        } else if self.known.remove(&rel).is_some() {
            self.dirty = true;
        }
        Ok(h)
    }

    /// Writes the memo back (atomically) if it learnt anything. A database
    /// whose cache folder cannot be written keeps working: the failure is
    /// logged and the files are hashed again next time.
    pub fn save(&mut self) {
        if !self.dirty {
            return;
        }
        let path = self.path.clone();
        let file = MemoFile {
            version: MEMO_VERSION,
            files: self
                .known
                .iter()
                .map(|(p, (s, h))| Entry {
                    path: p.clone(),
                    len: s.len,
                    modified_ns: s.modified_ns,
                    changed_ns: s.changed_ns,
                    xxh3: format!("{h:016x}"),
                })
                .collect(),
        };
        let written = path
            .parent()
            .map_or(Ok(()), std::fs::create_dir_all)
            .map_err(|source| FsError {
                path: path.clone(),
                source,
            })
            .and_then(|()| {
                write_atomic(&path, |w| {
                    serde_json::to_writer_pretty(&mut *w, &file).map_err(std::io::Error::other)
                })
            });
        match written {
            Ok(()) => self.dirty = false,
            Err(e) => tracing::debug!("the content hashes are not remembered: {e}"),
        }
    }
}

/// The memo's entries: `Ok` empty without a file, `Err` saying why a file
/// that is there cannot be used.
/// The number of files the memo `path` remembers, or why it cannot be
/// read (`inspect`: a memo a load would not trust). A missing memo: 0.
pub(crate) fn memo_entries(path: &Path) -> Result<usize, String> {
    read_memo(path)
        .map(|k| k.len())
        .map_err(|why| format!("{}: {why}", path.display()))
}

fn read_memo(path: &Path) -> Result<BTreeMap<String, (Stamp, u64)>, String> {
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(BTreeMap::new()),
        _ => {}
    }
    let text = crate::util::fsutil::read_small_text(path).map_err(|e| e.source.to_string())?;
    let file: MemoFile = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    if file.version != MEMO_VERSION {
        return Err(format!(
            "format version {}, this build reads {MEMO_VERSION}",
            file.version
        ));
    }
    let mut known = BTreeMap::new();
    for (k, e) in file.files.into_iter().enumerate() {
        let h = u64::from_str_radix(&e.xxh3, 16)
            .ok()
            .filter(|_| e.xxh3.len() == 16)
            .ok_or_else(|| format!("file {k} ({}): '{}' is not a hash", e.path, e.xxh3))?;
        let stamp = Stamp {
            len: e.len,
            modified_ns: e.modified_ns,
            changed_ns: e.changed_ns,
        };
        if known.insert(e.path.clone(), (stamp, h)).is_some() {
            return Err(format!("file {k} ({}) is listed twice", e.path));
        }
    }
    Ok(known)
}

/// The xxh3-64 hash of every byte of `f` from its start.
pub(crate) fn hash_all(p: &Path, f: &mut std::fs::File) -> Result<u64, FsError> {
    use std::io::{Seek, SeekFrom};
    let err = |source| FsError {
        path: p.to_path_buf(),
        source,
    };
    f.seek(SeekFrom::Start(0)).map_err(err)?;
    let mut h = Xxh3::new();
    let mut buf = vec![0u8; 1 << 20];
    loop {
        let k = f.read(&mut buf).map_err(err)?;
        if k == 0 {
            break;
        }
        h.update(&buf[..k]);
    }
    Ok(h.digest())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn memo_path(dir: &Path) -> PathBuf {
        dir.join(MEMO_FILE)
    }

    fn stamp_back(f: &Path, secs: u64) {
        let t = std::time::UNIX_EPOCH + std::time::Duration::from_secs(secs);
        std::fs::File::options()
            .write(true)
            .open(f)
            .unwrap()
            .set_modified(t)
            .unwrap();
    }

    fn hash_of(memo: &mut ContentMemo, p: &Path) -> u64 {
        let mut f = std::fs::File::open(p).unwrap();
        let meta = f.metadata().unwrap();
        memo.hash(p, &mut f, &meta).unwrap()
    }

    /// A settled file is hashed once, then remembered across opens; a
    /// file changed just now is not remembered (racy); a corrupt memo is
    /// not trusted.
    #[test]
    fn remembered_once_settled_and_a_corrupt_memo_is_not_trusted() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("seq.pc2");
        std::fs::write(&f, vec![7u8; 4096]).unwrap();
        // Fresh: its ctime is now, so it is hashed but not remembered.
        let mut m = ContentMemo::open(dir.path(), memo_path(dir.path()));
        let h = hash_of(&mut m, &f);
        m.save();
        assert!(!memo_path(dir.path()).exists(), "a racy entry is not saved");
        std::thread::sleep(std::time::Duration::from_secs(SETTLE_SECONDS + 1));
        let mut m = ContentMemo::open(dir.path(), memo_path(dir.path()));
        assert_eq!(hash_of(&mut m, &f), h);
        assert_eq!(m.hashed(), 1);
        m.save();
        let mut m = ContentMemo::open(dir.path(), memo_path(dir.path()));
        assert_eq!(hash_of(&mut m, &f), h);
        assert_eq!(m.hashed(), 0, "remembered");
        // The memo claims another hash for the same stamp: corrupt memo
        // files are refused as a whole, a well-formed one is believed.
        let p = memo_path(dir.path());
        let text = std::fs::read_to_string(&p).unwrap();
        std::fs::write(&p, &text[..text.len() / 2]).unwrap();
        let mut m = ContentMemo::open(dir.path(), memo_path(dir.path()));
        assert_eq!(hash_of(&mut m, &f), h);
        assert_eq!(m.hashed(), 1, "a cut memo is not trusted");
        // Same length, the modification time set back: the ctime moved.
        stamp_back(&f, 1_700_000_000);
        std::thread::sleep(std::time::Duration::from_secs(SETTLE_SECONDS + 1));
        let mut m = ContentMemo::open(dir.path(), memo_path(dir.path()));
        hash_of(&mut m, &f);
        m.save();
        std::fs::write(&f, vec![8u8; 4096]).unwrap();
        stamp_back(&f, 1_700_000_000);
        let mut m = ContentMemo::open(dir.path(), memo_path(dir.path()));
        let h2 = hash_of(&mut m, &f);
        assert_ne!(h2, h, "an edit with the length and time put back is seen");
        assert_eq!(m.hashed(), 1);
    }
}
