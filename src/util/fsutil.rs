//! File-system helpers shared by every writer: atomic writes and bounded reads.

use std::io::Write;
use std::path::{Path, PathBuf};

/// Largest input file any reader accepts (4 GiB). Readers never trust counts
/// in a header: they check them against the bytes actually present.
pub(crate) const MAX_INPUT_BYTES: u64 = 4 << 30;

/// Error of a file-system helper, carrying the path it concerns.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {source}")]
pub struct FsError {
    /// The file that could not be read or written.
    pub path: PathBuf,
    /// What the OS said.
    #[source]
    pub source: std::io::Error,
}

/// The error shape every file reader shares (meshes, mocap): the file could
/// not be read, a syntax or value error at a 1-based line of a text file, or
/// a problem with the file as a whole (or at a byte offset of a binary
/// file). Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The file could not be read or written.
    #[error(transparent)]
    Io(#[from] FsError),
    /// A syntax or value error at a line of a text file.
    #[error("{path}:{line}: {msg}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// A problem with the file as a whole (no frames, missing companion
    /// file, ...) or at a byte offset of a binary file.
    #[error("{path}: {msg}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        msg: String,
    },
}

impl FileError {
    /// A [`FileError::Parse`] at 1-based `line` of `path`.
    pub fn parse(path: &Path, line: usize, msg: impl Into<String>) -> Self {
        FileError::Parse {
            path: path.to_path_buf(),
            line,
            msg: msg.into(),
        }
    }
    /// A [`FileError::Invalid`] about `path` as a whole.
    pub fn invalid(path: &Path, msg: impl Into<String>) -> Self {
        FileError::Invalid {
            path: path.to_path_buf(),
            msg: msg.into(),
        }
    }
}

/// The `tracing` target of the library's collected warnings: those raised
/// while reading input files (a clip's frame count disagreeing with its
/// header, bytes after a point cache's last frame, ...) and the rig
/// embedding self-check. Every such warning is emitted once, where it is
/// raised, as a `WARN` event with this target (readers add a `file` field),
/// and also kept in the struct returned (`Clip::warnings`,
/// `PointCache::warnings`, `EmbedCheck::warnings`), so reports still carry
/// it.
pub const WARNING: &str = "surfmotion::warning";

/// Raise a reader warning about `path`: a `tracing` event with target
/// [`WARNING`], and `message` appended to `warnings`.
pub(crate) fn raise_warning(warnings: &mut Vec<String>, path: &Path, message: String) {
    tracing::warn!(target: WARNING, file = %path.display(), "{message}");
    warnings.push(message);
}

/// Largest settings file (landmarks, markers, rig maps, part labels,
/// manifests) any reader accepts (64 MiB): such files are a few kB.
pub(crate) const MAX_SMALL_FILE_BYTES: u64 = 64 << 20;

/// Reads a whole file into memory, refusing files over [`MAX_INPUT_BYTES`].
pub(crate) fn read_bytes(path: &Path) -> Result<Vec<u8>, FsError> {
    read_bytes_limited(path, MAX_INPUT_BYTES)
}

/// Opens an input file for reading, refusing anything that is not a
/// regular file (after following symbolic links) before it is opened: a
/// folder, a named pipe (opening one with no writer blocks forever: `inspect
/// FIFO.bvh` hung), a device (`/dev/zero` is endless: a symlink to it read
/// as a BVH was read to the 4 GiB limit before it was refused), a socket.
/// Files over `limit` bytes are refused too. Every reader opens its input
/// through this (directly or through [`read_bytes`] and friends).
pub(crate) fn open_input(path: &Path, limit: u64) -> Result<std::fs::File, FsError> {
    let wrap = |source| FsError {
        path: path.to_path_buf(),
        source,
    };
    let meta = std::fs::metadata(path).map_err(wrap)?;
    check_regular(path, &meta, limit)?;
    let file = std::fs::File::open(path).map_err(wrap)?;
    // The file checked may have been replaced between the check and the
    // open: check what was opened.
    let opened = file.metadata().map_err(wrap)?;
    check_regular(path, &opened, limit)?;
    Ok(file)
}

/// Refuses `meta` unless it is a regular file of at most `limit` bytes.
fn check_regular(path: &Path, meta: &std::fs::Metadata, limit: u64) -> Result<(), FsError> {
    let refuse = |what: String| {
        Err(FsError {
            path: path.to_path_buf(),
            source: std::io::Error::other(what),
        })
    };
    if meta.is_dir() {
        return refuse("is a directory, expected a file".into());
    }
    if !meta.is_file() {
        return refuse(format!(
            "is {}, not a regular file; refusing to read it (save the data to a file first)",
            file_kind(meta)
        ));
    }
    if meta.len() > limit {
        return refuse(format!(
            "file is {} bytes, larger than the {limit} byte limit",
            meta.len()
        ));
    }
    Ok(())
}

/// What a file that is not a regular file or a folder is, for messages.
fn file_kind(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_fifo() {
            return "a named pipe (FIFO)";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    let _ = meta;
    "a special file"
}

/// Reads a whole file into memory, refusing more than `limit` bytes and
/// anything but a regular file ([`open_input`]). At most `limit + 1` bytes
/// are read even if the file grows while it is read.
pub(crate) fn read_bytes_limited(path: &Path, limit: u64) -> Result<Vec<u8>, FsError> {
    use std::io::Read;
    let wrap = |source| FsError {
        path: path.to_path_buf(),
        source,
    };
    let file = open_input(path, limit)?;
    let len = file.metadata().map(|m| m.len()).unwrap_or(0);
    let mut out = Vec::with_capacity(len.min(limit) as usize);
    file.take(limit.saturating_add(1))
        .read_to_end(&mut out)
        .map_err(wrap)?;
    if out.len() as u64 > limit {
        return Err(wrap(std::io::Error::other(format!(
            "more than the {limit} byte limit could be read (the file grew while it was read?)"
        ))));
    }
    Ok(out)
}

/// Reads a text file; invalid UTF-8 is replaced rather than rejected (mocap
/// files from Windows tools carry Latin-1 comments).
pub fn read_text(path: &Path) -> Result<String, FsError> {
    read_text_limited(path, MAX_INPUT_BYTES)
}

/// [`read_text`] of a settings file, at most [`MAX_SMALL_FILE_BYTES`].
pub(crate) fn read_small_text(path: &Path) -> Result<String, FsError> {
    read_text_limited(path, MAX_SMALL_FILE_BYTES)
}

fn read_text_limited(path: &Path, limit: u64) -> Result<String, FsError> {
    Ok(decode_text(read_bytes_limited(path, limit)?))
}

/// The text of a file's bytes, as every text reader wants it: a UTF-8
/// byte-order mark dropped, UTF-16 (with its mark; Windows "Unicode" text)
/// decoded, invalid UTF-8 replaced, and lone carriage returns (classic Mac
/// line ends) turned into line feeds so that `str::lines` numbers lines as
/// an editor does. CRLF is left alone (`str::lines` handles it).
pub fn decode_text(mut bytes: Vec<u8>) -> String {
    let utf16 = |be: bool, b: &[u8]| {
        let units = b.chunks_exact(2).map(|c| {
            if be {
                u16::from_be_bytes([c[0], c[1]])
            } else {
                u16::from_le_bytes([c[0], c[1]])
            }
        });
        char::decode_utf16(units)
            .map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER))
            .collect::<String>()
            .into_bytes()
    };
    if bytes.starts_with(&[0xFF, 0xFE]) {
        bytes = utf16(false, &bytes[2..]);
    } else if bytes.starts_with(&[0xFE, 0xFF]) {
        bytes = utf16(true, &bytes[2..]);
    } else if bytes.starts_with(&[0xEF, 0xBB, 0xBF]) {
        bytes.drain(..3);
    }
    for i in 0..bytes.len() {
        if bytes[i] == b'\r' && bytes.get(i + 1) != Some(&b'\n') {
            bytes[i] = b'\n';
        }
    }
    match String::from_utf8(bytes) {
        Ok(s) => s,
        Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned(),
    }
}

/// Writes a file atomically: the bytes go to a temporary file in the same
/// folder, which is flushed and renamed over `path`. A killed run leaves
/// either the old file or the complete new one, never a truncated one.
pub(crate) fn write_atomic(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), FsError> {
    let mut f = AtomicFile::create(path)?;
    fill(&mut f.buf).map_err(|source| FsError {
        path: path.to_path_buf(),
        source,
    })?;
    f.commit()
}

/// A file written piece by piece and made visible at once: the bytes go to
/// a temporary file beside `path` (`.surfmotion-pid<PID>o<HASH><XXXXXX>.part`,
/// see [`temp_prefix`]), which [`AtomicFile::commit`] flushes and renames
/// over `path`. Temporaries of the same output left by a process that is
/// gone (a `kill -9`) are removed first, with a warning. Dropped without
/// a commit (an error, a panic), the temporary is removed and `path` keeps
/// its old content. For outputs too large to hold in memory (a point cache
/// streamed frame by frame; issue 18, item 12).
pub(crate) struct AtomicFile {
    /// The output as named (for messages).
    path: PathBuf,
    /// Where the temporary is renamed to: `path`, or the file a symbolic
    /// link at `path` names.
    target: PathBuf,
    buf: std::io::BufWriter<Sink>,
}

/// Where an [`AtomicFile`]'s bytes go: a temporary renamed into place, or,
/// for an output that exists and is not a regular file (`/dev/null`,
/// `/dev/stdout`, a named pipe), the file itself. Renaming a temporary
/// over a device would replace the device node (`-o /dev/full` turned
/// `/dev/full` into a PNG and exited 0).
enum Sink {
    Temp(tempfile::NamedTempFile),
    Direct(std::fs::File),
}

impl Write for Sink {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        match self {
            Sink::Temp(t) => t.write(buf),
            Sink::Direct(f) => f.write(buf),
        }
    }
    fn flush(&mut self) -> std::io::Result<()> {
        match self {
            Sink::Temp(t) => t.flush(),
            Sink::Direct(f) => f.flush(),
        }
    }
}

impl AtomicFile {
    /// Starts writing `path` (its folder is created). An existing folder
    /// is refused; an existing device or pipe (`/dev/null`, `/dev/stdout`)
    /// is written directly, since there is nothing to rename over; an
    /// existing symbolic link keeps pointing at the file it names, which
    /// is the one replaced.
    pub fn create(path: &Path) -> Result<AtomicFile, FsError> {
        let wrap = |source| FsError {
            path: path.to_path_buf(),
            source,
        };
        // An existing output: a folder is refused, a device or pipe is
        // written in place, and a symbolic link is followed (the file it
        // names is replaced, not the link).
        let mut target = path.to_path_buf();
        if let Ok(meta) = std::fs::metadata(path) {
            if meta.is_dir() {
                return Err(wrap(std::io::Error::other(
                    "is a folder, expected a file name",
                )));
            }
            if !meta.is_file() {
                let f = std::fs::OpenOptions::new()
                    .write(true)
                    .open(path)
                    .map_err(wrap)?;
                return Ok(AtomicFile {
                    path: path.to_path_buf(),
                    target,
                    buf: std::io::BufWriter::with_capacity(1 << 20, Sink::Direct(f)),
                });
            }
            if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
                target = std::fs::canonicalize(path).map_err(wrap)?;
            }
        }
        let dir = match target.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&dir).map_err(wrap)?;
        let name = target.file_name().unwrap_or_default();
        for stale in remove_stale_temporaries(&dir, name) {
            tracing::warn!(
                "removed {}: the temporary of an earlier write of {} whose process ({}) is gone",
                stale.path.display(),
                path.display(),
                stale.pid
            );
        }
        let tmp = tempfile::Builder::new()
            .prefix(&temp_prefix(std::process::id(), name))
            .suffix(".part")
            .tempfile_in(&dir)
            .map_err(wrap)?;
        Ok(AtomicFile {
            path: path.to_path_buf(),
            target,
            buf: std::io::BufWriter::with_capacity(1 << 20, Sink::Temp(tmp)),
        })
    }

    /// Appends bytes.
    pub fn write_all(&mut self, bytes: &[u8]) -> Result<(), FsError> {
        self.buf.write_all(bytes).map_err(|source| FsError {
            path: self.path.clone(),
            source,
        })
    }

    /// Flushes, syncs and renames the temporary over the path (with the
    /// permissions of the file it replaces, or 0644).
    pub fn commit(self) -> Result<(), FsError> {
        let (path, target) = (self.path, self.target);
        let wrap = |source| FsError {
            path: path.clone(),
            source,
        };
        let tmp = match self.buf.into_inner().map_err(|e| wrap(e.into_error()))? {
            Sink::Temp(t) => t,
            Sink::Direct(mut f) => return f.flush().map_err(wrap),
        };
        tmp.as_file().sync_all().map_err(wrap)?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(&target)
                .map(|m| m.permissions().mode())
                .unwrap_or(0o644);
            tmp.as_file()
                .set_permissions(std::fs::Permissions::from_mode(mode))
                .map_err(wrap)?;
        }
        tmp.persist(&target).map_err(|e| wrap(e.error))?;
        Ok(())
    }
}

/// The prefix of the temporaries [`AtomicFile`] writes for an output named
/// `name` by process `pid`: `.surfmotion-pid<PID>o<HASH>`, where `HASH` is
/// 8 hexadecimal digits of the name's xxh3 hash; 6 random letters and
/// `.part` follow. The process and the output it was for can be read back
/// from the name ([`stale_temporary_pid`]), so a temporary left by a killed
/// run is provably stale once its process is gone (issue 39, item 12: a
/// `kill -9` during a write left a 150 MB `.surfmotion-XXXXXX.part` beside
/// the output for good). Letters and digits only after the prefix, as
/// `batch`'s clean-up expects.
pub fn temp_prefix(pid: u32, name: &std::ffi::OsStr) -> String {
    let hash = xxhash_rust::xxh3::xxh3_64(name.as_encoded_bytes()) as u32;
    format!(".surfmotion-pid{pid}o{hash:08x}")
}

/// The process id in a temporary's file name `file`, when it is one that
/// [`AtomicFile`] writes for an output named `name`; `None` otherwise.
pub(crate) fn stale_temporary_pid(file: &str, name: &std::ffi::OsStr) -> Option<u32> {
    let rest = file.strip_prefix(".surfmotion-pid")?;
    let digits = rest.bytes().take_while(u8::is_ascii_digit).count();
    let pid: u32 = rest[..digits].parse().ok()?;
    let tail = file
        .strip_prefix(&temp_prefix(pid, name))?
        .strip_suffix(".part")?;
    (tail.len() == 6 && tail.bytes().all(|b| b.is_ascii_alphanumeric())).then_some(pid)
}

/// Whether process `pid` runs: `Some(false)` only when the system says
/// there is no such process, `None` when that cannot be told (not Unix).
pub(crate) fn process_alive(pid: u32) -> Option<bool> {
    #[cfg(unix)]
    {
        let p = i32::try_from(pid).ok().filter(|&p| p > 0)?;
        // SAFETY: signal 0 sends nothing; it only checks the process.
        if unsafe { libc::kill(p, 0) } == 0 {
            return Some(true);
        }
        match std::io::Error::last_os_error().raw_os_error() {
            Some(libc::ESRCH) => Some(false),
            Some(libc::EPERM) => Some(true),
            _ => None,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        None
    }
}

/// A stale temporary removed by [`remove_stale_temporaries`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct StaleTemporary {
    /// The file removed.
    pub path: PathBuf,
    /// The process that wrote it (gone).
    pub pid: u32,
}

/// Removes, in `dir`, the temporaries [`AtomicFile`] wrote for an output
/// named `name` whose process is gone: regular files of that naming, owned
/// by this user, written by another process that no longer runs. Anything
/// it cannot prove stale stays. Returns what it removed.
pub(crate) fn remove_stale_temporaries(dir: &Path, name: &std::ffi::OsStr) -> Vec<StaleTemporary> {
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir(dir) else {
        return out;
    };
    for e in rd.flatten() {
        let file = e.file_name();
        let Some(pid) = file.to_str().and_then(|f| stale_temporary_pid(f, name)) else {
            continue;
        };
        if pid == std::process::id() || process_alive(pid) != Some(false) {
            continue;
        }
        let Ok(meta) = std::fs::symlink_metadata(e.path()) else {
            continue;
        };
        if !meta.is_file() || !owned_by_me(&meta) {
            continue;
        }
        if std::fs::remove_file(e.path()).is_ok() {
            out.push(StaleTemporary {
                path: e.path(),
                pid,
            });
        }
    }
    out
}

/// Whether this process's user owns the file (always true off Unix).
pub(crate) fn owned_by_me(meta: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        // SAFETY: geteuid has no preconditions and cannot fail.
        meta.uid() == unsafe { libc::geteuid() }
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        true
    }
}

/// [`write_atomic`] for a byte slice.
pub fn write_bytes_atomic(path: &Path, bytes: &[u8]) -> Result<(), FsError> {
    write_atomic(path, |w| w.write_all(bytes))
}

/// `%XX` escapes decoded (RFC 3986, 2.1): the paths of glTF buffer URIs and
/// of the web viewer's requests. `None` for a bad escape or bytes that are
/// not UTF-8.
pub(crate) fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The messages of the shared file-error shape (tests/it/hostile/malformed.rs and
    /// tests/it/hostile/verbs.rs check them through every reader).
    #[test]
    fn file_error_messages_name_file_and_line() {
        let p = Path::new("dir/a.bvh");
        assert_eq!(
            FileError::parse(p, 7, "bad number").to_string(),
            "dir/a.bvh:7: bad number"
        );
        assert_eq!(
            FileError::invalid(p, "no frames").to_string(),
            "dir/a.bvh: no frames"
        );
        let io = FileError::from(FsError {
            path: p.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "gone"),
        });
        assert_eq!(io.to_string(), "dir/a.bvh: gone");
    }

    #[test]
    fn atomic_write_replaces_whole_file_and_leaves_no_temporaries() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a/b/out.txt");
        write_bytes_atomic(&p, b"first").unwrap();
        write_bytes_atomic(&p, b"second").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"second");
        let names: Vec<_> = std::fs::read_dir(p.parent().unwrap()).unwrap().collect();
        assert_eq!(names.len(), 1);
    }

    #[test]
    fn an_atomic_file_appears_only_when_committed() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.bin");
        write_bytes_atomic(&p, b"old").unwrap();
        let mut f = AtomicFile::create(&p).unwrap();
        f.write_all(b"new ").unwrap();
        f.write_all(b"content").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
        f.commit().unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"new content");
        // Dropped without a commit: the old file stays, no temporary.
        let mut f = AtomicFile::create(&p).unwrap();
        f.write_all(b"partial").unwrap();
        drop(f);
        assert_eq!(std::fs::read(&p).unwrap(), b"new content");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    /// Regression: `-o /dev/full` renamed the temporary over the device
    /// node (it became a regular file, exit 0). A device is written in
    /// place: /dev/null takes the bytes, /dev/full reports a full disk.
    #[cfg(target_os = "linux")]
    #[test]
    fn a_device_output_is_written_in_place_not_replaced() {
        use std::os::unix::fs::FileTypeExt;
        write_bytes_atomic(Path::new("/dev/null"), b"bytes").unwrap();
        assert!(
            std::fs::metadata("/dev/null")
                .unwrap()
                .file_type()
                .is_char_device()
        );
        if std::fs::metadata("/dev/full").is_ok_and(|m| m.file_type().is_char_device()) {
            let e = write_bytes_atomic(Path::new("/dev/full"), b"bytes").unwrap_err();
            assert!(e.to_string().starts_with("/dev/full: "), "{e}");
            assert!(
                std::fs::metadata("/dev/full")
                    .unwrap()
                    .file_type()
                    .is_char_device()
            );
        }
    }

    /// A symbolic link to an output keeps pointing at it: the file it names
    /// is replaced, not the link; a folder is refused.
    #[cfg(unix)]
    #[test]
    fn a_symlinked_output_replaces_its_target_and_a_folder_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let real = dir.path().join("real.txt");
        std::fs::write(&real, b"old").unwrap();
        let link = dir.path().join("link.txt");
        std::os::unix::fs::symlink(&real, &link).unwrap();
        write_bytes_atomic(&link, b"new").unwrap();
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        assert_eq!(std::fs::read(&real).unwrap(), b"new");
        let e = write_bytes_atomic(dir.path(), b"x").unwrap_err();
        assert!(e.to_string().contains("is a folder"), "{e}");
    }

    /// Regression: a byte-order mark hid an OBJ's first vertex and an
    /// AMC's header; classic-Mac line ends made a BVH one line; UTF-16 text
    /// was garbage.
    #[test]
    fn text_is_decoded_from_bom_utf16_and_lone_carriage_returns() {
        assert_eq!(
            decode_text(b"\xEF\xBB\xBFv 1\r\nv 2".to_vec()),
            "v 1\r\nv 2"
        );
        assert_eq!(decode_text(b"a\rb\r\rc\r".to_vec()).lines().count(), 4);
        let le: Vec<u8> = [0xFF, 0xFE]
            .into_iter()
            .chain("HIERARCHY\r\n".encode_utf16().flat_map(u16::to_le_bytes))
            .collect();
        assert_eq!(decode_text(le), "HIERARCHY\r\n");
        let be: Vec<u8> = [0xFE, 0xFF]
            .into_iter()
            .chain("é".encode_utf16().flat_map(u16::to_be_bytes))
            .collect();
        assert_eq!(decode_text(be), "é");
        assert_eq!(decode_text(b"caf\xe9".to_vec()), "caf\u{fffd}");
    }

    /// Regression (session 6 review): a symbolic link to `/dev/zero` read
    /// as input was read to the 4 GiB limit (seconds, gigabytes) before it
    /// was refused, and a named pipe with no writer blocked the reader
    /// forever. Both are refused before they are opened.
    #[cfg(unix)]
    #[test]
    fn devices_and_pipes_are_refused_before_they_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let link = dir.path().join("zero.bvh");
        std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
        let t = std::time::Instant::now();
        let e = read_bytes(&link).unwrap_err().to_string();
        assert!(t.elapsed() < std::time::Duration::from_secs(1), "{e}");
        assert!(
            e.starts_with(&format!("{}: ", link.display())) && e.contains("not a regular file"),
            "{e}"
        );
        assert!(e.contains("character device"), "{e}");
        let fifo = dir.path().join("pipe.bvh");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status();
        if made.is_ok_and(|s| s.success()) {
            // With no writer, opening it would block this test forever.
            let e = read_text(&fifo).unwrap_err().to_string();
            assert!(e.contains("named pipe") && e.contains("pipe.bvh"), "{e}");
            assert!(open_input(&fifo, MAX_INPUT_BYTES).is_err());
        }
        let e = read_small_text(dir.path()).unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
        // A regular file (and a link to one) reads as before.
        let f = dir.path().join("a.txt");
        std::fs::write(&f, b"abc").unwrap();
        let l = dir.path().join("l.txt");
        std::os::unix::fs::symlink(&f, &l).unwrap();
        assert_eq!(read_bytes(&l).unwrap(), b"abc");
        let e = read_bytes_limited(&f, 2).unwrap_err().to_string();
        assert!(e.contains("larger than the 2 byte limit"), "{e}");
    }

    /// The temporaries' naming names the process and the output: only
    /// those of the same output whose process is gone are removed.
    #[cfg(unix)]
    #[test]
    fn stale_temporaries_of_the_same_output_are_removed_others_stay() {
        let dir = tempfile::tempdir().unwrap();
        let name = std::ffi::OsStr::new("out.pc2");
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let dead = child.id();
        child.wait().unwrap();
        let me = std::process::id();
        let stale = format!("{}Ab12Cd.part", temp_prefix(dead, name));
        assert_eq!(stale_temporary_pid(&stale, name), Some(dead));
        assert_eq!(
            stale_temporary_pid(&stale, std::ffi::OsStr::new("other.pc2")),
            None
        );
        let keep = [
            format!("{}Ab12Cd.part", temp_prefix(me, name)),
            format!("{}Ab12Cd.part", temp_prefix(dead, "other.pc2".as_ref())),
            ".surfmotion-Ab12Cd.part".to_string(),
            format!("{}Ab12Cd.part.txt", temp_prefix(dead, name)),
        ];
        for f in keep.iter().chain([&stale]) {
            std::fs::write(dir.path().join(f), b"x").unwrap();
        }
        let removed = remove_stale_temporaries(dir.path(), name);
        assert_eq!(
            removed,
            vec![StaleTemporary {
                path: dir.path().join(&stale),
                pid: dead
            }]
        );
        for f in &keep {
            assert!(dir.path().join(f).exists(), "{f}");
        }
        // A write of the output removes it too.
        std::fs::write(dir.path().join(&stale), b"x").unwrap();
        write_bytes_atomic(&dir.path().join("out.pc2"), b"new").unwrap();
        assert!(!dir.path().join(&stale).exists());
        assert!(crate::batch::clips::is_temporary(&format!(
            "{}Ab12Cd.part",
            temp_prefix(me, name)
        )));
    }

    #[test]
    fn a_failing_writer_leaves_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("out.txt");
        write_bytes_atomic(&p, b"old").unwrap();
        let r = write_atomic(&p, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("killed"))
        });
        assert!(r.is_err());
        assert_eq!(std::fs::read(&p).unwrap(), b"old");
    }
}
