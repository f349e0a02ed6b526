//! Writing a mesh sequence frame by frame, so an output longer than memory
//! can still be written (issue 18, item 12: a 100,000-frame clip asked for
//! 35 GB when every frame was held before writing).
//!
//! Point caches stream: PC2 (a 32-byte header with the frame count, then
//! f32 xyz per vertex per frame) and MDD (frame count, point count and
//! frame times, then big-endian frames) know their frame count up front and
//! append each frame to an [`AtomicFile`], renamed over the output when the
//! last frame is in. A folder of OBJ frames writes each frame's file
//! (atomically) as it comes. GLB needs every frame at once (its JSON header
//! holds every target's bounds, and quantisation one grid for all frames),
//! as do `.obj`/`.ply` (one frame): those frames are held, after the memory
//! they need is checked against [`crate::util::budget`], and a GLB over its 4 GiB
//! format limit is refused before the first frame is computed.
//!
//! The bytes written are those of [`super::save_sequence_with`] for the same
//! frames.

use super::frame_check::{check_complete, check_frame};
use super::{MeshFormat, SaveOptions, glb, obj, pc2};
use crate::mesh::{Mesh, MeshError, MeshSequence};
use crate::util::fsutil::AtomicFile;
use std::path::{Path, PathBuf};

/// Bytes per vertex and frame a held GLB needs at its peak: the positions
/// (`[f64; 3]`), the binary buffer and its copy in the file's bytes.
fn glb_peak_bytes(opts: &glb::GlbOptions) -> u128 {
    let per = glb_file_bytes(opts);
    crate::util::budget::VERTEX_BYTES + 2 * per
}

/// Bytes per vertex and frame in a GLB file (position and normal
/// displacements).
fn glb_file_bytes(opts: &glb::GlbOptions) -> u128 {
    match (opts.quantize, opts.normals) {
        (false, true) => 24,
        (false, false) => 12,
        (true, true) => 12,
        (true, false) => 8,
    }
}

/// How frames reach the output.
enum Sink {
    /// A point cache appended frame by frame (big-endian for MDD).
    Cache { file: AtomicFile, big_endian: bool },
    /// One OBJ per frame in a folder.
    Folder { width: usize, files: Vec<PathBuf> },
    /// Held, written by [`super::save_sequence_with`] at the end.
    Hold(Vec<[f64; 3]>),
    /// A USD layer appended frame by frame.
    Usd(super::usd::UsdaWriter),
}

/// A sequence output written one frame at a time; see the module docs.
pub struct SequenceWriter {
    out: PathBuf,
    mesh: Mesh,
    frames: usize,
    written: usize,
    opts: SaveOptions,
    sink: Sink,
}

impl SequenceWriter {
    /// Starts writing `frames` frames of `mesh` (by `out`'s extension, as
    /// [`super::save_sequence_with`]). Outputs that must hold every frame
    /// are refused here, before any frame is computed, when they cannot fit
    /// the memory budget (or the GLB format).
    pub fn create(
        mesh: &Mesh,
        out: &Path,
        frames: usize,
        opts: &SaveOptions,
    ) -> Result<SequenceWriter, MeshError> {
        super::refuse_folder_as_file(out)?;
        let fmt = MeshFormat::of(out).ok_or_else(|| {
            MeshError::invalid(
                out,
                "unknown output format (use .glb .pc2 .mdd .obj .ply .usda or a folder)",
            )
        })?;
        let n = mesh.vertex_count();
        let fps = opts.fps.unwrap_or(30.0);
        let sink = match fmt {
            MeshFormat::Pc2 | MeshFormat::Mdd => {
                let too_many = |what: &str| {
                    MeshError::invalid(
                        out,
                        format!(
                            "{frames} frames × {n} vertices do not fit a {what} header (at most {} of each)",
                            i32::MAX
                        ),
                    )
                };
                let (fr, pts) = (
                    i32::try_from(frames).map_err(|_| too_many("point cache"))?,
                    i32::try_from(n).map_err(|_| too_many("point cache"))?,
                );
                let mut file = AtomicFile::create(out)?;
                if fmt == MeshFormat::Pc2 {
                    file.write_all(&pc2::header(pts, fr))?;
                } else {
                    file.write_all(&fr.to_be_bytes())?;
                    file.write_all(&pts.to_be_bytes())?;
                    let mut times = Vec::with_capacity(4 * frames);
                    for k in 0..frames {
                        times.extend_from_slice(&((k as f64 / fps) as f32).to_be_bytes());
                    }
                    file.write_all(&times)?;
                }
                Sink::Cache {
                    file,
                    big_endian: fmt == MeshFormat::Mdd,
                }
            }
            MeshFormat::Usda => Sink::Usd(super::usd::UsdaWriter::create_with(
                mesh, out, frames, fps, opts.usd,
            )?),
            MeshFormat::ObjFolder => Sink::Folder {
                width: frames.saturating_sub(1).to_string().len().max(4),
                files: Vec::new(),
            },
            MeshFormat::Gltf | MeshFormat::Fbx => return Err(super::format::not_written(out, fmt)),
            MeshFormat::Obj | MeshFormat::Ply => {
                if frames != 1 {
                    return Err(MeshError::invalid(
                        out,
                        format!(
                            "{frames} frames do not fit one {fmt:?} file; write a folder, .pc2, .mdd or .glb"
                        ),
                    ));
                }
                Sink::Hold(Vec::with_capacity(n))
            }
            MeshFormat::Glb => {
                if frames > glb::MAX_FRAMES {
                    return Err(MeshError::invalid(
                        out,
                        format!(
                            "{frames} frames: a GLB holds at most {} (one morph target each); write .pc2, .mdd or a folder, which stream any length",
                            glb::MAX_FRAMES
                        ),
                    ));
                }
                let file = (frames as u128) * (n as u128) * glb_file_bytes(&opts.glb);
                if file > u32::MAX as u128 {
                    return Err(MeshError::invalid(
                        out,
                        format!(
                            "{frames} frames × {n} vertices make a GLB of about {}, over the format's 4 GiB; quantise (`GlbOptions::quantize`), leave out normals (`GlbOptions::normals` false), or write .pc2, .mdd or a folder, which stream any length",
                            crate::util::budget::Bytes(file)
                        ),
                    ));
                }
                crate::util::budget::check(
                    || {
                        format!(
                            "a GLB of {} frames × {} vertices (a GLB is written whole; .pc2, .mdd and folders stream)",
                            crate::util::budget::thousands(frames as u128),
                            crate::util::budget::thousands(n as u128)
                        )
                    },
                    (frames as u128) * (n as u128) * glb_peak_bytes(&opts.glb),
                )
                .map_err(|e| MeshError::invalid(out, e.to_string()))?;
                Sink::Hold(Vec::with_capacity(frames * n))
            }
        };
        Ok(SequenceWriter {
            out: out.to_path_buf(),
            mesh: mesh.clone(),
            frames,
            written: 0,
            opts: SaveOptions {
                fps: Some(fps),
                ..*opts
            },
            sink,
        })
    }

    /// True when frames go to the output as they come (not held).
    pub fn streams(&self) -> bool {
        !matches!(self.sink, Sink::Hold(_))
    }

    /// Frames written so far.
    pub fn written(&self) -> usize {
        self.written
    }

    /// Appends the next frame (the mesh's vertex count of positions).
    pub fn push(&mut self, frame: &[[f64; 3]]) -> Result<(), MeshError> {
        let n = self.mesh.vertex_count();
        check_frame(&self.out, frame, n, self.written, self.frames)?;
        match &mut self.sink {
            Sink::Cache { file, big_endian } => {
                let mut bytes = Vec::with_capacity(12 * n);
                pc2::encode_points(&mut bytes, frame, *big_endian);
                file.write_all(&bytes)?;
            }
            Sink::Folder { width, files } => {
                let w = *width;
                let p = self.out.join(format!("frame_{:0w$}.obj", self.written));
                obj::write_obj(&self.mesh, Some(frame), &p)?;
                files.push(p);
            }
            Sink::Hold(all) => all.extend_from_slice(frame),
            Sink::Usd(w) => w.push(frame)?,
        }
        self.written += 1;
        Ok(())
    }

    /// Completes the output once every announced frame is in; returns the
    /// files written (a point cache's topology `.obj` beside it). Dropped
    /// before, a point cache leaves no file.
    pub fn finish(self) -> Result<Vec<PathBuf>, MeshError> {
        check_complete(&self.out, self.written, self.frames)?;
        match self.sink {
            Sink::Cache { file, .. } => {
                file.commit()?;
                let topo = self.out.with_extension("obj");
                obj::write_obj(&self.mesh, None, &topo)?;
                Ok(vec![self.out, topo])
            }
            Sink::Folder { files, .. } => Ok(files),
            Sink::Usd(w) => {
                w.finish()?;
                Ok(vec![self.out])
            }
            Sink::Hold(all) => {
                let seq = MeshSequence::new(self.mesh, all, self.opts.fps)
                    .map_err(|e| MeshError::from(e).in_file(&self.out))?;
                super::save_sequence_with(&seq, &self.out, &self.opts)
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A closed tetrahedron, outward-facing (shared by the writers' tests).
    pub(crate) fn tetra() -> Mesh {
        Mesh::new(
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap()
    }

    fn frames(m: &Mesh, count: usize) -> Vec<[f64; 3]> {
        (0..count)
            .flat_map(|f| {
                m.positions()
                    .iter()
                    .map(move |p| [p[0] + f as f64 * 0.1, p[1], p[2] - f as f64 * 0.05])
            })
            .collect()
    }

    /// The streamed bytes are those of the whole-sequence writer, for every
    /// format (issue 18, item 12).
    #[test]
    fn streamed_outputs_equal_whole_outputs() {
        let dir = tempfile::tempdir().unwrap();
        let m = tetra();
        let all = frames(&m, 5);
        let seq = MeshSequence::new(m.clone(), all.clone(), Some(24.0)).unwrap();
        let opts = SaveOptions {
            fps: Some(24.0),
            ..Default::default()
        };
        for name in ["a.pc2", "a.mdd", "a.glb", "folder"] {
            let whole = dir.path().join("whole").join(name);
            let streamed = dir.path().join("streamed").join(name);
            let w = super::super::save_sequence_with(&seq, &whole, &opts).unwrap();
            let mut s = SequenceWriter::create(&m, &streamed, 5, &opts).unwrap();
            assert_eq!(s.streams(), name != "a.glb", "{name}");
            for f in all.chunks(4) {
                s.push(f).unwrap();
            }
            let files = s.finish().unwrap();
            assert_eq!(files.len(), w.len(), "{name}");
            for (a, b) in w.iter().zip(&files) {
                assert_eq!(
                    std::fs::read(a).unwrap(),
                    std::fs::read(b).unwrap(),
                    "{a:?}"
                );
            }
        }
    }

    /// An unfinished point cache leaves no output and no temporary.
    #[test]
    fn an_unfinished_stream_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let m = tetra();
        let out = dir.path().join("a.pc2");
        let mut s = SequenceWriter::create(&m, &out, 3, &SaveOptions::default()).unwrap();
        s.push(m.positions()).unwrap();
        let e = s.finish().unwrap_err().to_string();
        assert!(e.contains("1 of the 3 frames"), "{e}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    /// A GLB too large for its format is refused before any frame, naming
    /// the numbers.
    #[test]
    fn a_glb_over_its_format_limit_is_refused_up_front() {
        let dir = tempfile::tempdir().unwrap();
        let m = tetra();
        let out = dir.path().join("a.glb");
        let e = SequenceWriter::create(&m, &out, 70_000, &SaveOptions::default())
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("70000 frames") && e.contains("65535"), "{e}");
    }
}
