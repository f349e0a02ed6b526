//! The lock of a batch's output folder: `batch.lock` (or `batch-2of8.lock`
//! for a shard) holds the pid and host of the run writing there, so a
//! second run into the same folder is refused instead of interleaving its
//! outputs with the first. Shards of one split (`i/n`, same `n`) write
//! disjoint clips and may share a folder; anything else is refused while
//! another run's lock is held.
//!
//! A lock whose process is gone (same host, no such process or not this
//! program) is stale: it is removed with a note. A lock from another host
//! cannot be checked and is trusted; the message says which file to remove
//! if that run is gone. Once locked and alone in the folder, a run removes
//! the temporaries a killed run left ([`clean_temporaries`]).

use super::clips::{Shard, TEMP_PREFIX, is_temporary};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::{Path, PathBuf};

/// Error taking a folder's lock.
#[derive(Debug, thiserror::Error)]
pub enum LockError {
    /// Another run writes into the folder.
    #[error(
        "{dir}: in use by another batch (pid {pid} on {host}{shard}, lock file {lock}); wait for it to finish, or remove the lock file if that run is gone"
    )]
    InUse {
        /// The output folder.
        dir: PathBuf,
        /// The other run's lock file.
        lock: PathBuf,
        /// Its process id.
        pid: u32,
        /// Its host.
        host: String,
        /// `, shard i/n` when it is a shard.
        shard: String,
    },
    /// The lock file could not be written or read.
    #[error("{path}: {source}")]
    Io {
        /// The lock file.
        path: PathBuf,
        /// What the OS said.
        #[source]
        source: std::io::Error,
    },
}

/// What a lock file holds.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Holder {
    pid: u32,
    host: String,
    shard: Option<String>,
}

/// A held lock; removed when dropped.
#[derive(Debug)]
pub struct FolderLock {
    path: PathBuf,
    /// Stale locks of killed runs removed on the way.
    pub stale_removed: Vec<PathBuf>,
    /// No other run holds a lock in the folder (so its temporaries are
    /// leftovers).
    pub alone: bool,
}

impl Drop for FolderLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

impl FolderLock {
    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

fn host() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "this host".into())
}

/// Whether the holder's process may still be running. Checked on Linux
/// through /proc (the pid exists and runs this same program); elsewhere, and
/// for another host, assumed alive.
fn alive(h: &Holder, here: &str) -> bool {
    if h.host != here || !Path::new("/proc/self").exists() {
        return true;
    }
    let comm = |pid: &str| std::fs::read_to_string(format!("/proc/{pid}/comm")).ok();
    match (comm(&h.pid.to_string()), comm("self")) {
        (Some(theirs), Some(ours)) => theirs == ours,
        (None, _) => false,
        (Some(_), None) => true,
    }
}

/// Shards `i/n` and `j/n` of one split write disjoint clips.
fn compatible(a: &Option<String>, b: &Option<String>) -> bool {
    match (a, b) {
        (Some(a), Some(b)) => match (Shard::parse(a), Shard::parse(b)) {
            (Ok(a), Ok(b)) => a.count == b.count && a.index != b.index,
            _ => false,
        },
        _ => false,
    }
}

fn read_holder(p: &Path) -> Option<Holder> {
    serde_json::from_str(&crate::util::fsutil::read_small_text(p).ok()?).ok()
}

/// Takes the lock `dir/STEM.lock` for a run of `shard` (None: the whole
/// library). Refuses while another live run holds the same lock, or any
/// lock a shard of another split or an unsharded run holds.
pub fn lock_folder(dir: &Path, stem: &str, shard: Option<&str>) -> Result<FolderLock, LockError> {
    let here = host();
    let path = dir.join(format!("{stem}.lock"));
    let io = |source| LockError::Io {
        path: path.clone(),
        source,
    };
    let me = Holder {
        pid: std::process::id(),
        host: here.clone(),
        shard: shard.map(str::to_string),
    };
    let mut stale_removed = Vec::new();
    let in_use = |lock: &Path, h: Holder| LockError::InUse {
        dir: dir.to_path_buf(),
        lock: lock.to_path_buf(),
        pid: h.pid,
        host: h.host,
        shard: h.shard.map(|s| format!(", shard {s}")).unwrap_or_default(),
    };
    // The lock file appears whole or not at all: written to a temporary,
    // then linked to its name only if that name is free.
    let mut held = None;
    for _ in 0..3 {
        // Named by this process ([`owner_pid`]): another run's clean-up
        // leaves it alone while this run lives.
        let prefix = format!("{TEMP_PREFIX}pid{}lock", std::process::id());
        let mut tmp = tempfile::Builder::new()
            .prefix(&prefix)
            .suffix(".part")
            .tempfile_in(dir)
            .map_err(io)?;
        tmp.write_all(&serde_json::to_vec(&me).unwrap_or_default())
            .and_then(|_| tmp.flush())
            .map_err(io)?;
        match tmp.persist_noclobber(&path) {
            Ok(_) => {
                held = Some(FolderLock {
                    path: path.clone(),
                    stale_removed: Vec::new(),
                    alone: true,
                });
                break;
            }
            Err(e) if e.error.kind() == std::io::ErrorKind::AlreadyExists => {
                match read_holder(&path) {
                    Some(h) if alive(&h, &here) => return Err(in_use(&path, h)),
                    // A holder that is gone, or a file that is not a lock.
                    _ => {
                        let _ = std::fs::remove_file(&path);
                        stale_removed.push(path.clone());
                    }
                }
            }
            // The temporary removed under it (a run of an older version
            // cleaning the folder): write it again.
            Err(e) if e.error.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(io(e.error)),
        }
    }
    let Some(mut lock) = held else {
        return Err(io(std::io::Error::other(
            "could not take the lock (another run keeps taking it)",
        )));
    };
    // Other runs' locks in the folder.
    let rd = std::fs::read_dir(dir).map_err(io)?;
    for e in rd.flatten() {
        let p = e.path();
        let name = e.file_name().to_string_lossy().to_string();
        if p == path || !(name.starts_with("batch") && name.ends_with(".lock")) {
            continue;
        }
        match read_holder(&p) {
            Some(h) if alive(&h, &here) => {
                if !compatible(&h.shard, &me.shard) {
                    return Err(in_use(&p, h));
                }
                lock.alone = false;
            }
            _ => {
                let _ = std::fs::remove_file(&p);
                stale_removed.push(p);
            }
        }
    }
    lock.stale_removed = stale_removed;
    Ok(lock)
}

/// The process a temporary's name says wrote it (`.surfmotion-pid<PID>…`:
/// an atomic write's, a lock's, a batch's folder of OBJ frames).
fn owner_pid(name: &str) -> Option<u32> {
    let rest = name.strip_prefix(TEMP_PREFIX)?.strip_prefix("pid")?;
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    rest[..digits].parse().ok()
}

/// Whether the temporary named `name` belongs to a process that runs (or
/// may: it cannot be told): another run's write in progress, left alone.
/// Shards of one split start together, and one that found itself alone
/// removed the lock another was about to take (CI, session 49: "batch-3of4.lock:
/// No such file or directory").
fn being_written(name: &str) -> bool {
    owner_pid(name).is_some_and(|pid| {
        pid == std::process::id() || crate::util::fsutil::process_alive(pid) != Some(false)
    })
}

/// Removes, under `dir`, the temporaries of writes that never finished
/// (files `.surfmotion-XXXXXX.part`, folders `.surfmotion-XXXXXX-partial`)
/// but those whose name carries the id of a process that runs ([`being_written`]).
/// Call only while holding the folder's lock alone. Returns their paths and
/// total size in bytes.
pub fn clean_temporaries(dir: &Path) -> (Vec<PathBuf>, u64) {
    let mut removed = Vec::new();
    let mut bytes = 0;
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in rd.flatten() {
            // Links are not followed: only what is in the folder itself.
            let Ok(ft) = e.file_type() else { continue };
            let p = e.path();
            let name = e.file_name().to_string_lossy().to_string();
            let temp = is_temporary(&name) && !being_written(&name);
            if ft.is_dir() {
                if temp {
                    bytes += size_of_tree(&p);
                    if std::fs::remove_dir_all(&p).is_ok() {
                        removed.push(p);
                    }
                } else {
                    stack.push(p);
                }
            } else if temp && ft.is_file() {
                bytes += e.metadata().map(|m| m.len()).unwrap_or(0);
                if std::fs::remove_file(&p).is_ok() {
                    removed.push(p);
                }
            }
        }
    }
    removed.sort();
    (removed, bytes)
}

fn size_of_tree(d: &Path) -> u64 {
    let Ok(rd) = std::fs::read_dir(d) else {
        return 0;
    };
    rd.flatten()
        .map(|e| match e.file_type() {
            Ok(t) if t.is_dir() => size_of_tree(&e.path()),
            Ok(_) => e.metadata().map(|m| m.len()).unwrap_or(0),
            Err(_) => 0,
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_is_refused_and_a_dead_holders_is_taken_over() {
        let dir = tempfile::tempdir().unwrap();
        let a = lock_folder(dir.path(), "batch", None).unwrap();
        assert!(a.alone);
        let e = lock_folder(dir.path(), "batch", None).unwrap_err();
        assert!(e.to_string().contains("in use"), "{e}");
        // A shard of any split conflicts with the whole-library run.
        assert!(lock_folder(dir.path(), "batch-1of2", Some("1/2")).is_err());
        drop(a);
        assert!(!dir.path().join("batch.lock").exists());
        // Shards of one split share the folder; another split does not.
        let s1 = lock_folder(dir.path(), "batch-1of2", Some("1/2")).unwrap();
        let s2 = lock_folder(dir.path(), "batch-2of2", Some("2/2")).unwrap();
        assert!(!s2.alone);
        assert!(lock_folder(dir.path(), "batch-1of3", Some("1/3")).is_err());
        drop((s1, s2));
        // A holder that no longer runs.
        let dead = Holder {
            pid: u32::MAX,
            host: host(),
            shard: None,
        };
        let p = dir.path().join("batch.lock");
        std::fs::write(&p, serde_json::to_vec(&dead).unwrap()).unwrap();
        let l = lock_folder(dir.path(), "batch", None).unwrap();
        if Path::new("/proc/self").exists() {
            assert_eq!(l.stale_removed, vec![p]);
        }
        // No temporary of the lock's own write is left.
        let names: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .collect();
        assert_eq!(names, ["batch.lock"]);
    }

    #[test]
    fn only_our_temporaries_are_cleaned() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir_all(d.join("sub/.surfmotion-Ab12cd-partial")).unwrap();
        std::fs::write(
            d.join("sub/.surfmotion-Ab12cd-partial/frame_0000.obj"),
            b"v",
        )
        .unwrap();
        std::fs::write(d.join(".surfmotion-xY9876.part"), [0u8; 100]).unwrap();
        for keep in [
            "walk.glb",
            ".surfmotion-.part",
            ".surfmotion-a.b.part",
            "surfmotion-abc123.part",
            "foo-partial",
        ] {
            std::fs::write(d.join(keep), b"k").unwrap();
        }
        // Another run's, in progress (this process's id: alive), kept; a
        // killed one's (no such process) removed.
        let live = format!(".surfmotion-pid{}lockAb12cd.part", std::process::id());
        std::fs::write(d.join(&live), b"l").unwrap();
        std::fs::write(d.join(".surfmotion-pid2147483647oAb12cd.part"), b"").unwrap();
        let (removed, bytes) = clean_temporaries(d);
        assert_eq!(removed.len(), 3, "{removed:?}");
        assert!(d.join(&live).exists());
        assert_eq!(bytes, 101);
        assert!(d.join("walk.glb").exists() && d.join("foo-partial").exists());
        assert!(d.join(".surfmotion-a.b.part").exists());
    }
}
