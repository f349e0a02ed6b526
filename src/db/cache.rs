//! The database cache: similarity matrices and the graph, stored under
//! `DIR/cache/` and reused until their inputs change.
//!
//! Each entry carries a key: the xxh3-64 hash of everything it was computed
//! from (the bytes of the topology and sequence files, the manifest fields
//! that matter, the measure and its parameters, the cache format version).
//! A stale or unreadable entry is simply recomputed. Files are written
//! atomically, so an interrupted build leaves the old entry or none.
//!
//! Similarity file (`similarity-MEASURE.bin`, little-endian): magic
//! `SMSIM001`, key `u64`, span count `u32`, then per span a name length
//! `u32`, the UTF-8 name, start and length `u64`; then the upper triangle
//! with the diagonal, row by row, as `n (n + 1) / 2` f32.

use super::manifest::{DbError, Manifest};
use crate::fsutil::{FsError, write_atomic};
use crate::similarity::{SimilarityMatrix, Span};
use std::io::Read;
use std::path::{Path, PathBuf};
use xxhash_rust::xxh3::Xxh3;

/// Bump when a cached format or algorithm changes.
pub const CACHE_VERSION: u32 = 1;
const MAGIC: &[u8; 8] = b"SMSIM001";

/// The cache folder of a database.
pub fn cache_dir(dir: &Path) -> PathBuf {
    dir.join("cache")
}

/// A hasher of cache inputs.
pub struct KeyHasher(Xxh3);

impl Default for KeyHasher {
    fn default() -> Self {
        let mut h = Xxh3::new();
        h.update(&CACHE_VERSION.to_le_bytes());
        KeyHasher(h)
    }
}

impl KeyHasher {
    /// Adds a labelled string.
    pub fn text(&mut self, label: &str, value: &str) -> &mut Self {
        for s in [label, value] {
            self.0.update(&(s.len() as u64).to_le_bytes());
            self.0.update(s.as_bytes());
        }
        self
    }

    /// Adds the bytes of a file, or of every file under a folder (sorted by
    /// name). A missing path hashes as such (loading reports it).
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

    fn file(&mut self, p: &Path) -> Result<(), FsError> {
        let err = |e: std::io::Error| FsError {
            path: p.to_path_buf(),
            source: e,
        };
        let mut f = std::fs::File::open(p).map_err(err)?;
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
pub fn frames_key(dir: &Path, m: &Manifest) -> Result<KeyHasher, DbError> {
    let mut h = KeyHasher::default();
    h.text("up", &m.up.to_ascii_lowercase());
    h.text("fps", &m.fps.to_string());
    h.path(&Manifest::resolve(dir, &m.topology))?;
    for s in &m.sequences {
        h.text("sequence", &s.name);
        h.text("fps", &s.fps.unwrap_or(m.fps).to_string());
        h.text("path", &s.path.to_string_lossy());
        h.path(&Manifest::resolve(dir, &s.path))?;
    }
    Ok(h)
}

/// Adds the rig inputs (landmarks, parts) to a key.
pub fn add_rig(h: &mut KeyHasher, dir: &Path, m: &Manifest) -> Result<(), DbError> {
    for (label, p) in [("landmarks", &m.rig.landmarks), ("parts", &m.rig.parts)] {
        if let Some(p) = p {
            h.text("rig", label);
            h.path(&Manifest::resolve(dir, p))?;
        }
    }
    Ok(())
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

/// Reads a similarity matrix if the file exists, is well formed and has
/// `key`; `None` otherwise (the caller recomputes).
pub fn load_matrix(path: &Path, key: u64) -> Option<SimilarityMatrix> {
    parse_matrix(&std::fs::read(path).ok()?, key)
}

/// Parses a similarity file's bytes; `None` unless well formed with `key`.
/// Sizes in the header are checked against the bytes present before any
/// allocation follows them.
pub fn parse_matrix(bytes: &[u8], key: u64) -> Option<SimilarityMatrix> {
    let mut at = 0usize;
    let mut take = |k: usize| -> Option<&[u8]> {
        let s = bytes.get(at..at.checked_add(k)?)?;
        at += k;
        Some(s)
    };
    if take(8)? != MAGIC {
        return None;
    }
    let u64_of = |b: &[u8]| u64::from_le_bytes(b.try_into().unwrap_or([0; 8]));
    let u32_of = |b: &[u8]| u32::from_le_bytes(b.try_into().unwrap_or([0; 4]));
    if u64_of(take(8)?) != key {
        return None;
    }
    let count = u32_of(take(4)?) as usize;
    let mut spans = Vec::new();
    let mut n = 0usize;
    for _ in 0..count {
        let len = u32_of(take(4)?) as usize;
        let name = String::from_utf8(take(len)?.to_vec()).ok()?;
        let start = usize::try_from(u64_of(take(8)?)).ok()?;
        let len = usize::try_from(u64_of(take(8)?)).ok()?;
        n = n.checked_add(len)?;
        spans.push(Span { name, start, len });
    }
    let tri = n.checked_mul(n.checked_add(1)?)? / 2;
    let body = take(tri.checked_mul(4)?)?;
    let mut data = vec![0.0f32; n.checked_mul(n)?];
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
}
