//! The database cache: similarity matrices and the graph, stored under
//! `DIR/cache/` and reused until their inputs change.
//!
//! Each entry carries a key: the xxh3-64 hash of everything it was computed
//! from (the bytes of the topology and sequence files — of a file over
//! 1 MiB its length and the hash of all its bytes, remembered in
//! `cache/content-hashes.json` ([`super::content`]) —, the manifest fields
//! that matter, the measure and its parameters, the cache format version).
//! A stale or unreadable entry is simply recomputed. Files are written
//! atomically, so an interrupted build leaves the old entry or none.
//!
//! Similarity file (`similarity-MEASURE.bin`, little-endian): magic
//! `SMSIM001`, key `u64`, span count `u32`, then per span a name length
//! `u32`, the UTF-8 name, start and length `u64`; then the upper triangle
//! with the diagonal, row by row, as `n (n + 1) / 2` f32.

use super::content::ContentMemo;
use super::manifest::{DbError, Manifest};
use crate::similarity::{SimilarityMatrix, Span, SparseSimilarity};
use crate::util::fsutil::{FsError, write_atomic};
use std::io::Read;
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::Xxh3;

/// Bump when a cached format or algorithm changes.
pub(crate) const CACHE_VERSION: u32 = 1;
const MAGIC: &[u8; 8] = b"SMSIM001";
/// Files up to this length are hashed into a key byte by byte; longer
/// ones by their length and content hash, remembered between loads
/// ([`super::content::ContentMemo`]).
pub(crate) const WHOLE_FILE_BYTES: u64 = 1 << 20;

/// The cache folder of a database.
pub fn cache_dir(dir: &Path) -> PathBuf {
    dir.join("cache")
}

/// The content-hash memo of the database `dir` ([`ContentMemo`]).
pub fn memo_path(dir: &Path) -> PathBuf {
    cache_dir(dir).join(super::content::MEMO_FILE)
}

/// A hasher of cache inputs: with the memo of a database
/// ([`KeyHasher::for_db`]), a large file's content hash is read from it
/// when the file has not changed.
pub struct KeyHasher(Xxh3, Option<ContentMemo>);

impl Default for KeyHasher {
    fn default() -> Self {
        let mut h = Xxh3::new();
        h.update(&CACHE_VERSION.to_le_bytes());
        KeyHasher(h, None)
    }
}

impl KeyHasher {
    /// A hasher of the inputs of the database `dir`, remembering the content
    /// hashes of its large files in its cache folder ([`KeyHasher::save`]).
    pub(crate) fn for_db(dir: &Path) -> Self {
        let KeyHasher(h, _) = KeyHasher::default();
        KeyHasher(h, Some(ContentMemo::open(dir, memo_path(dir))))
    }

    /// Writes back the content hashes learnt ([`ContentMemo::save`]).
    pub fn save(&mut self) -> &mut Self {
        if let Some(m) = &mut self.1 {
            m.save();
        }
        self
    }

    /// Adds a labelled string.
    pub fn text(&mut self, label: &str, value: &str) -> &mut Self {
        for s in [label, value] {
            self.0.update(&(s.len() as u64).to_le_bytes());
            self.0.update(s.as_bytes());
        }
        self
    }

    /// Adds the bytes of a file, or of every file under a folder (sorted by
    /// name); of a file longer than [`WHOLE_FILE_BYTES`], its length and
    /// the hash of all its bytes. A missing path hashes as such (loading
    /// reports it).
    pub fn path(&mut self, p: &Path) -> Result<&mut Self, FsError> {
        let err = |e: std::io::Error| FsError {
            path: p.to_path_buf(),
            source: e,
        };
        if p.is_dir() {
            let mut entries: Vec<PathBuf> = std::fs::read_dir(p)
                .map_err(err)?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|e| e.is_file())
                .collect();
            entries.sort();
            for e in entries {
                let name = e.file_name().map(|n| n.to_string_lossy().into_owned());
                self.text("file", &name.unwrap_or_default());
                self.file(&e)?;
            }
        } else if p.is_file() {
            self.file(p)?;
        } else {
            self.text("missing", &p.to_string_lossy());
        }
        Ok(self)
    }

    /// A file's bytes when it is at most [`WHOLE_FILE_BYTES`] long; a
    /// larger one's length and the xxh3-64 hash of all its bytes, from the
    /// database's memo when the file's path, length and times are the ones
    /// remembered (issue 43: the 1.2 GB of sequences of a 10⁴-frame
    /// database are read once, not on every load; a copy or a `touch`
    /// costs one more reading of them, not a rebuild of every cache).
    fn file(&mut self, p: &Path) -> Result<(), FsError> {
        let err = |e: std::io::Error| FsError {
            path: p.to_path_buf(),
            source: e,
        };
        let mut f = crate::util::fsutil::open_input(p, crate::util::fsutil::MAX_INPUT_BYTES)?;
        let meta = f.metadata().map_err(err)?;
        let len = meta.len();
        if len > WHOLE_FILE_BYTES {
            let digest = match &mut self.1 {
                Some(memo) => memo.hash(p, &mut f, &meta)?,
                None => super::content::hash_all(p, &mut f)?,
            };
            self.text("hashed file", &format!("{len} bytes, xxh3 {digest:016x}"));
            self.0.update(&len.to_le_bytes());
            return Ok(());
        }
        let mut buf = vec![0u8; 1 << 20];
        let mut total = 0u64;
        loop {
            let k = f.read(&mut buf).map_err(err)?;
            if k == 0 {
                break;
            }
            total += k as u64;
            self.0.update(&buf[..k]);
        }
        self.0.update(&total.to_le_bytes());
        Ok(())
    }

    /// The key.
    pub fn finish(&self) -> u64 {
        self.0.digest()
    }
}

/// The key of everything the database's frames depend on: topology,
/// sequences (name, fps, file contents) and up axis.
pub(crate) fn frames_key(dir: &Path, m: &Manifest) -> Result<KeyHasher, DbError> {
    let mut h = KeyHasher::for_db(dir);
    h.text("up", &m.up.to_ascii_lowercase());
    h.text("fps", &m.fps.to_string());
    h.path(&Manifest::resolve(dir, &m.topology))?;
    for s in &m.sequences {
        h.text("sequence", &s.name);
        h.text("fps", &s.fps.unwrap_or(m.fps).to_string());
        h.text("path", &s.path.to_string_lossy());
        h.path(&Manifest::resolve(dir, &s.path))?;
    }
    h.save();
    Ok(h)
}

/// Adds the rig inputs (landmarks, parts) to a key.
pub(crate) fn add_rig(h: &mut KeyHasher, dir: &Path, m: &Manifest) -> Result<(), DbError> {
    for (label, p) in [("landmarks", &m.rig.landmarks), ("parts", &m.rig.parts)] {
        if let Some(p) = p {
            h.text("rig", label);
            h.path(&Manifest::resolve(dir, p))?;
        }
    }
    Ok(())
}

/// Header of a similarity build's checkpoint (`similarity-*.partial`).
const PARTIAL_MAGIC: &[u8; 8] = b"SMPART01";
const PARTIAL_HEADER: u64 = 24;

/// The checkpoint of a build of the similarity file `matrix`: the rows it
/// finished, so that a killed `db build` resumes from its last block.
pub(crate) fn partial_path(matrix: &Path) -> PathBuf {
    matrix.with_extension("partial")
}

/// Bytes of upper-triangle rows `0..rows` of an `n`-frame matrix.
fn partial_bytes(n: usize, rows: usize) -> u64 {
    (0..rows).map(|a| (n - a) as u64 * 4).sum()
}

/// Reads the finished rows of a checkpoint written for `key` and `n`
/// frames into `data` (`n × n`, upper triangle) and returns how many (a
/// multiple of `block`, or `n`): 0 without a checkpoint, for another key or
/// size, or one not even a block long. A torn last block is ignored.
pub(crate) fn resume_rows(
    path: &Path,
    key: u64,
    n: usize,
    block: usize,
    data: &mut [f32],
) -> usize {
    let Ok(mut f) = std::fs::File::open(path) else {
        return 0;
    };
    let mut head = [0u8; PARTIAL_HEADER as usize];
    if f.read_exact(&mut head).is_err()
        || &head[..8] != PARTIAL_MAGIC
        || head[8..16] != key.to_le_bytes()
        || head[16..24] != (n as u64).to_le_bytes()
        || data.len() != n * n
    {
        return 0;
    }
    let len = f.metadata().map(|m| m.len()).unwrap_or(0);
    let mut rows = 0;
    while rows < n && PARTIAL_HEADER + partial_bytes(n, (rows + block).min(n)) <= len {
        rows = (rows + block).min(n);
    }
    let mut buf = vec![0u8; n * 4];
    for a in 0..rows {
        let row = &mut buf[..(n - a) * 4];
        if f.read_exact(row).is_err() {
            return 0;
        }
        for (v, b) in data[a * n + a..(a + 1) * n]
            .iter_mut()
            .zip(row.chunks_exact(4))
        {
            *v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        }
    }
    rows
}

/// The checkpoint of a similarity build being written: finished rows are
/// appended (and synced) as they come.
#[derive(Debug)]
pub(crate) struct Checkpoint {
    path: PathBuf,
    file: std::fs::File,
    n: usize,
}

impl Checkpoint {
    /// Opens the checkpoint `path` for `key` and `n` frames, keeping its
    /// first `rows` rows (those [`resume_rows`] read) or starting it anew.
    pub fn open(path: &Path, key: u64, n: usize, rows: usize) -> Result<Checkpoint, FsError> {
        use std::io::{Seek, SeekFrom, Write};
        let fs = |source| FsError {
            path: path.to_path_buf(),
            source,
        };
        // The database's cache folder may not exist yet.
        if let Some(d) = path.parent() {
            std::fs::create_dir_all(d).map_err(fs)?;
        }
        let mut file = std::fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .read(true)
            .write(true)
            .open(path)
            .map_err(fs)?;
        let keep = if rows == 0 {
            0
        } else {
            PARTIAL_HEADER + partial_bytes(n, rows)
        };
        file.set_len(keep).map_err(fs)?;
        if rows == 0 {
            file.write_all(PARTIAL_MAGIC).map_err(fs)?;
            file.write_all(&key.to_le_bytes()).map_err(fs)?;
            file.write_all(&(n as u64).to_le_bytes()).map_err(fs)?;
        }
        file.seek(SeekFrom::End(0)).map_err(fs)?;
        Ok(Checkpoint {
            path: path.to_path_buf(),
            file,
            n,
        })
    }

    /// Appends the finished rows `first..` held in `rows` (whole rows of
    /// `n` values; the upper triangle of each is written) and syncs them.
    pub(crate) fn append(&mut self, first: usize, rows: &[f32]) -> Result<(), FsError> {
        use std::io::Write;
        let n = self.n;
        let mut bytes = Vec::with_capacity(rows.len() * 4);
        for (i, row) in rows.chunks_exact(n.max(1)).enumerate() {
            for v in &row[first + i..] {
                bytes.extend_from_slice(&v.to_le_bytes());
            }
        }
        self.file
            .write_all(&bytes)
            .and_then(|_| self.file.sync_data())
            .map_err(|source| FsError {
                path: self.path.clone(),
                source,
            })
    }

    /// Removes the checkpoint (the whole matrix is saved).
    pub fn remove(self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Writes a similarity matrix with its key, atomically (streamed: no copy
/// of the matrix is made).
pub fn save_matrix(path: &Path, key: u64, m: &SimilarityMatrix) -> Result<(), FsError> {
    write_atomic(path, |w| {
        w.write_all(MAGIC)?;
        w.write_all(&key.to_le_bytes())?;
        w.write_all(&(m.spans.len() as u32).to_le_bytes())?;
        for s in &m.spans {
            w.write_all(&(s.name.len() as u32).to_le_bytes())?;
            w.write_all(s.name.as_bytes())?;
            w.write_all(&(s.start as u64).to_le_bytes())?;
            w.write_all(&(s.len as u64).to_le_bytes())?;
        }
        for a in 0..m.len() {
            for v in &m.row(a)[a..] {
                w.write_all(&v.to_le_bytes())?;
            }
        }
        Ok(())
    })
}

/// Magic of a sparse similarity cache file.
const SPARSE_MAGIC: &[u8; 8] = b"SMSPA001";

/// Writes a sparse similarity with its key, atomically.
pub(crate) fn save_sparse(path: &Path, key: u64, s: &SparseSimilarity) -> Result<(), FsError> {
    write_atomic(path, |w| {
        w.write_all(SPARSE_MAGIC)?;
        w.write_all(&key.to_le_bytes())?;
        s.write_to(w)
    })
}

/// The frame count in a sparse similarity cache file's header (after its
/// magic and key), the rest not read; `None` without such a file.
pub(crate) fn sparse_frames(path: &Path) -> Option<usize> {
    let mut head = [0u8; 24];
    std::fs::File::open(path).ok()?.read_exact(&mut head).ok()?;
    let n: [u8; 8] = head[16..24].try_into().ok()?;
    (&head[..8] == SPARSE_MAGIC).then(|| u64::from_le_bytes(n) as usize)
}

/// Reads a sparse similarity, its pairs memory-mapped (read on demand,
/// issue 43): `Ok(None)` when there is no such file or it has another
/// key, `Err` saying why when it is there but cannot be used.
pub(crate) fn read_sparse(path: &Path, key: u64) -> Result<Option<SparseSimilarity>, String> {
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        _ => {}
    }
    let file = crate::util::fsutil::open_input(path, crate::util::fsutil::MAX_INPUT_BYTES)
        .map_err(|e| e.source.to_string())?;
    // SAFETY: the cache file is the database's own, written atomically (a
    // new file renamed over the old, never changed in place), so the
    // mapped bytes do not change under the map.
    let map = unsafe { memmap2::Mmap::map(&file) }.map_err(|e| e.to_string())?;
    if map.len() < 16 || &map[..8] != SPARSE_MAGIC {
        return Err("not a sparse similarity cache file (no SMSPA001 header)".into());
    }
    if u64::from_le_bytes(map[8..16].try_into().unwrap_or([0; 8])) != key {
        return Ok(None);
    }
    SparseSimilarity::from_mapped(std::sync::Arc::new(map), 16).map(Some)
}

/// Reads a similarity matrix if the file exists, is well formed and has
/// `key`; `None` otherwise (the caller recomputes).
#[cfg(test)]
pub(crate) fn load_matrix(path: &Path, key: u64) -> Option<SimilarityMatrix> {
    read_matrix(path, key).ok().flatten()
}

/// Reads a similarity matrix: `Ok(None)` when there is no such file or it
/// was computed from other inputs (another key: a normal change), `Err`
/// saying why when the file is there but cannot be used (unreadable,
/// truncated, not a similarity file). The caller recomputes either way,
/// but says so in the second case (a corrupt cache was rebuilt silently).
pub fn read_matrix(path: &Path, key: u64) -> Result<Option<SimilarityMatrix>, String> {
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        _ => {}
    }
    let bytes = crate::util::fsutil::read_bytes(path).map_err(|e| e.source.to_string())?;
    parse_matrix_checked(&bytes, key)
}

/// Parses a similarity file's bytes; `None` unless well formed with `key`.
/// Sizes in the header are checked against the bytes present before any
/// allocation follows them.
pub fn parse_matrix(bytes: &[u8], key: u64) -> Option<SimilarityMatrix> {
    parse_matrix_checked(bytes, key).ok().flatten()
}

/// [`parse_matrix`] saying why: `Ok(None)` for a well-formed header with
/// another key, `Err` for bytes that are not a whole similarity file.
pub(crate) fn parse_matrix_checked(
    bytes: &[u8],
    key: u64,
) -> Result<Option<SimilarityMatrix>, String> {
    let mut at = 0usize;
    let truncated = |at: usize| format!("truncated at byte {at} of {}", bytes.len());
    let mut take = |k: usize| -> Result<&[u8], String> {
        let s = at
            .checked_add(k)
            .and_then(|end| bytes.get(at..end))
            .ok_or_else(|| truncated(at))?;
        at += k;
        Ok(s)
    };
    if take(8).ok() != Some(MAGIC.as_slice()) {
        return Err("not a similarity cache file (no SMSIM001 header)".into());
    }
    let u64_of = |b: &[u8]| u64::from_le_bytes(b.try_into().unwrap_or([0; 8]));
    let u32_of = |b: &[u8]| u32::from_le_bytes(b.try_into().unwrap_or([0; 4]));
    if u64_of(take(8)?) != key {
        return Ok(None);
    }
    let count = u32_of(take(4)?) as usize;
    let mut spans = Vec::new();
    let mut n = 0usize;
    let too_big = || "a sequence length too large".to_string();
    for _ in 0..count {
        let len = u32_of(take(4)?) as usize;
        let name = String::from_utf8(take(len)?.to_vec())
            .map_err(|_| "a sequence name that is not UTF-8".to_string())?;
        let start = usize::try_from(u64_of(take(8)?)).map_err(|_| too_big())?;
        let len = usize::try_from(u64_of(take(8)?)).map_err(|_| too_big())?;
        n = n.checked_add(len).ok_or_else(too_big)?;
        spans.push(Span { name, start, len });
    }
    let tri = n
        .checked_mul(n.checked_add(1).ok_or_else(too_big)?)
        .ok_or_else(too_big)?
        / 2;
    let body = take(tri.checked_mul(4).ok_or_else(too_big)?)?;
    let mut data = vec![0.0f32; n.checked_mul(n).ok_or_else(too_big)?];
    let mut k = 0;
    for a in 0..n {
        for b in a..n {
            let v = f32::from_le_bytes([body[k], body[k + 1], body[k + 2], body[k + 3]]);
            k += 4;
            data[a * n + b] = v;
            data[b * n + a] = v;
        }
    }
    SimilarityMatrix::new(spans, data)
        .map(Some)
        .ok_or_else(|| "its sequences do not tile its frames".into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matrix_round_trip_and_stale_keys() {
        let spans = vec![
            Span {
                name: "a".into(),
                start: 0,
                len: 3,
            },
            Span {
                name: "bé".into(),
                start: 3,
                len: 2,
            },
        ];
        let n = 5;
        let data = (0..n * n)
            .map(|k| ((k / n) as f32 - (k % n) as f32).abs() * 0.5)
            .collect();
        let m = SimilarityMatrix::new(spans, data).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.bin");
        save_matrix(&p, 42, &m).unwrap();
        assert_eq!(load_matrix(&p, 42), Some(m));
        assert_eq!(load_matrix(&p, 43), None);
        // Truncated files are rejected, not trusted.
        let bytes = std::fs::read(&p).unwrap();
        for cut in [0, 7, 20, bytes.len() - 1] {
            std::fs::write(&p, &bytes[..cut]).unwrap();
            assert_eq!(load_matrix(&p, 42), None, "cut at {cut}");
        }
    }

    /// Regression (session 6 review): a corrupt cache was recomputed
    /// without a word. A missing file or another key is a normal miss
    /// (`Ok(None)`); garbage, a truncation or a folder say why.
    #[test]
    fn a_corrupt_matrix_says_why_and_a_stale_one_does_not() {
        let m = SimilarityMatrix::new(
            vec![Span {
                name: "a".into(),
                start: 0,
                len: 2,
            }],
            vec![0.0, 1.0, 1.0, 0.0],
        )
        .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("s.bin");
        assert_eq!(read_matrix(&p, 1), Ok(None));
        save_matrix(&p, 1, &m).unwrap();
        assert_eq!(read_matrix(&p, 1), Ok(Some(m)));
        assert_eq!(read_matrix(&p, 2), Ok(None));
        let bytes = std::fs::read(&p).unwrap();
        std::fs::write(&p, &bytes[..bytes.len() - 3]).unwrap();
        let e = read_matrix(&p, 1).unwrap_err();
        assert!(e.starts_with("truncated at byte"), "{e}");
        std::fs::write(&p, b"garbage").unwrap();
        let e = read_matrix(&p, 1).unwrap_err();
        assert!(e.contains("not a similarity cache file"), "{e}");
        std::fs::remove_file(&p).unwrap();
        std::fs::create_dir(&p).unwrap();
        assert!(read_matrix(&p, 1).unwrap_err().contains("directory"));
    }

    #[test]
    fn keys_follow_contents() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("x.obj");
        std::fs::write(&f, "v 0 0 0\n").unwrap();
        let k1 = KeyHasher::default().path(&f).unwrap().finish();
        std::fs::write(&f, "v 0 0 1\n").unwrap();
        let k2 = KeyHasher::default().path(&f).unwrap().finish();
        assert_ne!(k1, k2);
        let k3 = KeyHasher::default().path(dir.path()).unwrap().finish();
        assert_ne!(k3, k2);
        assert_eq!(k3, KeyHasher::default().path(dir.path()).unwrap().finish());
    }

    /// Issue 43: a file over [`WHOLE_FILE_BYTES`] is keyed by its length
    /// and the hash of all its bytes: touching it or copying it keeps the
    /// key; any changed byte changes it, also where the samples of the
    /// previous keys did not look (between them, the time set back).
    #[test]
    fn keys_of_a_long_file_follow_its_bytes_not_its_times() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("seq.pc2");
        let bytes: Vec<u8> = (0..3 << 20).map(|k: u32| (k % 251) as u8).collect();
        std::fs::write(&f, &bytes).unwrap();
        let key = || {
            let mut h = KeyHasher::for_db(dir.path());
            h.path(&f).unwrap();
            h.save();
            h.finish()
        };
        let set_time = |secs: u64| {
            let t = std::time::UNIX_EPOCH + std::time::Duration::from_secs(secs);
            std::fs::File::options()
                .write(true)
                .open(&f)
                .unwrap()
                .set_modified(t)
                .unwrap();
        };
        set_time(1_700_000_000);
        let k0 = key();
        assert_eq!(key(), k0, "the same file, the same key");
        assert_eq!(
            KeyHasher::default().path(&f).unwrap().finish(),
            k0,
            "with or without the memo"
        );
        set_time(1_700_000_001);
        assert_eq!(key(), k0, "a touched file keeps the key");
        // A copy elsewhere (new times) has the same key.
        let copy = tempfile::tempdir().unwrap();
        let g = copy.path().join("seq.pc2");
        std::fs::copy(&f, &g).unwrap();
        assert_eq!(
            KeyHasher::for_db(copy.path()).path(&g).unwrap().finish(),
            k0
        );
        // One byte between the former samples changed, the time set back.
        let mut changed = bytes.clone();
        changed[(3 << 20) / 2 + 100] ^= 1;
        std::fs::write(&f, &changed).unwrap();
        set_time(1_700_000_000);
        assert_ne!(key(), k0, "an edit anywhere changes the key");
        std::fs::write(&f, &bytes).unwrap();
        assert_eq!(key(), k0, "the same bytes again, the same key");
        let mut longer = bytes.clone();
        longer.push(0);
        std::fs::write(&f, &longer).unwrap();
        assert_ne!(key(), k0, "a longer file changes the key");
    }
}
