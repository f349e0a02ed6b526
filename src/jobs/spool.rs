//! A live session's recording (`live --record OUT`), spooled frame by frame
//! to a temporary file beside `OUT` (each position's three f64, exact) and
//! written in `OUT`'s format when the stream ends, one frame at a time
//! through [`SequenceWriter`] (the bytes of
//! [`crate::mesh::io::save_sequence_with`] for the same frames). Until
//! session 45 the recording was held in memory: an hour at 30 frames a
//! second and 9,971 vertices is 26 GB of positions, more than this
//! project's 24 GB machine; now the session's memory does not grow with
//! the recording (issue 45: "no growth beyond the recording").
//!
//! The spool is made when the session starts, so an output folder that
//! cannot be made or written is said before the stream, not after it. A failed
//! write to the spool (a full disk) stops the spooling, not the session;
//! the recording then fails at the end with the spool's error.

use crate::mesh::io::SaveOptions;
use crate::mesh::io::stream::SequenceWriter;
use crate::mesh::{Mesh, MeshError};
use std::io::{BufReader, BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Bytes a vertex takes in the spool (three little-endian f64).
const VERTEX_BYTES: usize = 24;

/// A recording's frames on disk until the stream ends.
pub struct Spool {
    /// The spool's writer (`None` once a write failed).
    file: Option<BufWriter<std::fs::File>>,
    /// The spool file, removed when the spool is dropped.
    path: tempfile::TempPath,
    /// Vertices a frame.
    n: usize,
    /// Frames spooled.
    frames: usize,
    /// One frame's bytes, reused.
    bytes: Vec<u8>,
    /// The first failed write.
    error: Option<String>,
}

impl Spool {
    /// A spool for frames of `n` vertices in the folder `out` will be
    /// written to (its parent, made if missing, as the writers do; the
    /// current folder for a bare name).
    pub fn create(out: &Path, n: usize) -> Result<Spool, MeshError> {
        let dir = match out.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let cannot = |e: std::io::Error| {
            MeshError::invalid(
                out,
                format!("cannot record beside it in {}: {e}", dir.display()),
            )
        };
        // The writers make the output's folder as well (`AtomicFile`).
        std::fs::create_dir_all(&dir).map_err(cannot)?;
        let file = tempfile::Builder::new()
            .prefix(".surfmotion-record-")
            .suffix(".spool")
            .tempfile_in(&dir)
            .map_err(|e| {
                MeshError::invalid(
                    out,
                    format!("cannot record beside it in {}: {e}", dir.display()),
                )
            })?;
        let (file, path) = file.into_parts();
        Ok(Spool {
            file: Some(BufWriter::with_capacity(1 << 20, file)),
            path,
            n,
            frames: 0,
            bytes: vec![0; n * VERTEX_BYTES],
            error: None,
        })
    }

    /// Frames spooled so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Appends one frame (`n` positions; another length is refused at the
    /// end). Allocates nothing.
    pub fn push(&mut self, frame: &[[f64; 3]]) {
        let Some(file) = self.file.as_mut() else {
            return;
        };
        if frame.len() != self.n {
            self.error = Some(format!(
                "frame {} has {} positions, not {}",
                self.frames,
                frame.len(),
                self.n
            ));
            self.file = None;
            return;
        }
        for (b, v) in self.bytes.chunks_exact_mut(8).zip(frame.as_flattened()) {
            b.copy_from_slice(&v.to_le_bytes());
        }
        match file.write_all(&self.bytes) {
            Ok(()) => self.frames += 1,
            Err(e) => {
                self.error = Some(e.to_string());
                self.file = None;
            }
        }
    }

    /// Writes the spooled frames of `mesh` to `out` (by its extension, with
    /// `opts`) one at a time; returns the files written. The spool is
    /// removed either way.
    pub fn finish(
        self,
        mesh: &Mesh,
        out: &Path,
        opts: &SaveOptions,
    ) -> Result<Vec<PathBuf>, MeshError> {
        let spool_error = |e: String| {
            MeshError::invalid(
                out,
                format!("the recording's spool {}: {e}", self.path.display()),
            )
        };
        if let Some(e) = &self.error {
            return Err(spool_error(e.clone()));
        }
        let Some(file) = self.file else {
            return Err(spool_error("not written".into()));
        };
        let mut file = file
            .into_inner()
            .map_err(|e| spool_error(e.error().to_string()))?;
        file.seek(SeekFrom::Start(0))
            .map_err(|e| spool_error(e.to_string()))?;
        let mut read = BufReader::with_capacity(1 << 20, file);
        let mut writer = SequenceWriter::create(mesh, out, self.frames, opts)?;
        let (mut bytes, mut frame) = (vec![0u8; self.n * VERTEX_BYTES], vec![[0.0; 3]; self.n]);
        for _ in 0..self.frames {
            read.read_exact(&mut bytes)
                .map_err(|e| spool_error(e.to_string()))?;
            for (v, b) in frame
                .as_flattened_mut()
                .iter_mut()
                .zip(bytes.chunks_exact(8))
            {
                *v = f64::from_le_bytes(b.try_into().unwrap_or([0; 8]));
            }
            writer.push(&frame)?;
        }
        writer.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::io::stream::tests::tetra;

    /// Frames that are not round in decimal or binary: every bit must
    /// survive the spool.
    fn frame(m: &Mesh, f: usize) -> Vec<[f64; 3]> {
        m.positions()
            .iter()
            .map(|p| {
                let k = f as f64;
                [p[0] + k / 3.0, p[1] - k * 0.1, (p[2] + k).sqrt() * 1e-3]
            })
            .collect()
    }

    /// The spooled recording writes the bytes the whole-sequence writer
    /// writes, for the streamed and the held formats; the spool file is
    /// gone afterwards, and nothing else is left in the folder.
    #[test]
    fn a_spooled_recording_equals_the_whole_writer_and_leaves_no_spool() {
        let dir = tempfile::tempdir().unwrap();
        let m = tetra();
        let frames: Vec<Vec<[f64; 3]>> = (0..7).map(|f| frame(&m, f)).collect();
        let all: Vec<[f64; 3]> = frames.iter().flatten().copied().collect();
        let seq = crate::mesh::MeshSequence::new(m.clone(), all, Some(30.0)).unwrap();
        let opts = SaveOptions {
            fps: Some(30.0),
            ..SaveOptions::default()
        };
        let (a, b) = (dir.path().join("a"), dir.path().join("b"));
        std::fs::create_dir_all(&a).unwrap();
        std::fs::create_dir_all(&b).unwrap();
        for ext in ["pc2", "mdd", "glb", "usda"] {
            let whole = a.join(format!("rec.{ext}"));
            crate::mesh::io::save_sequence_with(&seq, &whole, &opts).unwrap();
            let out = b.join(format!("rec.{ext}"));
            let mut s = Spool::create(&out, m.vertex_count()).unwrap();
            let spool = s.path.to_path_buf();
            assert!(spool.exists());
            for f in &frames {
                s.push(f);
            }
            assert_eq!(s.frames(), 7);
            let files = s.finish(&m, &out, &opts).unwrap();
            assert!(files.contains(&out), "{files:?}");
            assert!(!spool.exists(), "{ext}: the spool is left");
            let (x, y) = (std::fs::read(&whole).unwrap(), std::fs::read(&out).unwrap());
            assert!(x == y, "{ext}: the spooled file differs");
        }
        let left: Vec<_> = std::fs::read_dir(&b)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().to_string())
            .filter(|n| n.contains("spool"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
    }

    /// A frame of another length stops the spooling and fails the
    /// recording at the end with a message naming the output; a folder
    /// that cannot be made fails at the start.
    #[test]
    fn a_wrong_frame_or_a_missing_folder_is_an_error_naming_the_output() {
        let dir = tempfile::tempdir().unwrap();
        let m = tetra();
        let out = dir.path().join("r.pc2");
        let mut s = Spool::create(&out, 4).unwrap();
        s.push(&frame(&m, 0));
        s.push(&frame(&m, 1)[..3]);
        s.push(&frame(&m, 2));
        assert_eq!(s.frames(), 1);
        let e = s.finish(&m, &out, &SaveOptions::default()).unwrap_err();
        assert!(e.to_string().contains("r.pc2"), "{e}");
        assert!(e.to_string().contains("frame 1 has 3 positions"), "{e}");
        assert!(!out.exists());
        // A missing folder is made; one under a file cannot be.
        let deep = dir.path().join("new/folder/r.pc2");
        let mut s = Spool::create(&deep, 4).unwrap();
        s.push(&frame(&m, 0));
        s.finish(&m, &deep, &SaveOptions::default()).unwrap();
        assert!(deep.exists());
        std::fs::write(dir.path().join("file"), b"x").unwrap();
        let under = dir.path().join("file/r.pc2");
        let e = Spool::create(&under, 4).err().unwrap();
        assert!(e.to_string().contains("r.pc2"), "{e}");
    }
}
