//! USD output of a mesh sequence: a `.usda` text layer (Pixar's Universal
//! Scene Description) with one `Mesh` prim whose `points` and vertex
//! `normals` are time-sampled, one sample per frame, and an `extent` per
//! frame.
//!
//! The layer's metadata says what the numbers mean: `metersPerUnit = 1`
//! (the project's meshes are in metres), `upAxis = "Y"`,
//! `timeCodesPerSecond`/`framesPerSecond` the frame rate, and
//! `startTimeCode`/`endTimeCode` the first and last frame (time code =
//! frame index). Points are `point3f` (32-bit floats, as every other
//! writer stores them), each written as the shortest decimal that reads
//! back as the same `f32`.
//!
//! Normals (`normal3f[] normals`, `interpolation = "vertex"`, the
//! UsdGeomPointBased attribute) are the GLB writer's: area-weighted unit
//! vertex normals of each frame ([`crate::mesh::normals`]), a vertex on no
//! triangle of non-zero area taking its rest normal (the rest's: +Z), so
//! every normal is unit length. Viewers then shade the surface smoothly
//! as it deforms instead of recomputing normals per frame (or shading it
//! flat). [`UsdOptions::normals`] off leaves them out: the file is about
//! half the size and written in about half the time (README, "USD
//! output").
//!
//! Written frame by frame ([`UsdaWriter`]): the header needs the frame
//! count, which a [`super::stream::SequenceWriter`] knows up front; each
//! frame's points are appended as they come; its normals go to an
//! anonymous temporary file beside the output (a USD attribute's samples
//! are one block, so they cannot interleave with the points'), copied in
//! after the last frame, then the extents (six numbers a frame). Memory:
//! one frame of normals. Atomic: the file appears when the last frame is
//! in. Checked in `tests/it/mesh/io.rs` by Pixar's `usd-core` (its
//! validators pass; points and normals read back equal ours).

use super::glb::normals_or;
use crate::mesh::{Mesh, MeshError, MeshSequence};
use crate::util::fsutil::{AtomicFile, FsError};
use std::fmt::Write as _;
use std::io::{Read as _, Seek as _, Write as _};
use std::path::{Path, PathBuf};

/// Options of the `.usda` writer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct UsdOptions {
    /// Write each frame's vertex normals (see the module documentation).
    /// Default value: `true`.
    pub normals: bool,
}

impl UsdOptions {
    /// Normals on.
    pub const DEFAULT: UsdOptions = UsdOptions { normals: true };
}

impl Default for UsdOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A `.usda` sequence being written; see the module documentation.
pub struct UsdaWriter {
    out: PathBuf,
    file: AtomicFile,
    vertices: usize,
    frames: usize,
    written: usize,
    /// Per frame: min and max corner, as written (f32).
    extents: Vec<[f32; 6]>,
    /// The normals' samples so far, when written.
    normals: Option<NormalSpool>,
}

/// Each frame's normals as `.usda` sample lines, in an anonymous temporary
/// file (removed by the system however the process ends) until
/// [`UsdaWriter::finish`] copies them in after the points.
struct NormalSpool {
    file: std::io::BufWriter<std::fs::File>,
    triangles: Vec<[u32; 3]>,
    /// The rest normals: where a frame's normal is undefined.
    rest: Vec<[f64; 3]>,
    /// One frame's normals (reused).
    frame: Vec<[f64; 3]>,
    line: String,
}

impl NormalSpool {
    /// A spool beside `out` (else in the system's temporary folder: an
    /// output in `/dev`) for `mesh`'s topology; its rest normals.
    fn create(mesh: &Mesh, out: &Path) -> Result<NormalSpool, MeshError> {
        let dir = match out.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let file = tempfile::tempfile_in(dir)
            .or_else(|_| tempfile::tempfile())
            .map_err(|e| io_error(out, e))?;
        let triangles = mesh.triangles().to_vec();
        let mut rest = Vec::new();
        let up = vec![[0.0, 0.0, 1.0]; mesh.vertex_count()];
        normals_or(mesh.positions(), &triangles, &up, &mut rest);
        Ok(NormalSpool {
            file: std::io::BufWriter::with_capacity(1 << 20, file),
            triangles,
            rest,
            frame: Vec::new(),
            line: String::new(),
        })
    }

    /// Appends frame `k`'s normals (of `points`) as one sample line.
    fn push(&mut self, out: &Path, k: usize, points: &[[f64; 3]]) -> Result<(), MeshError> {
        normals_or(points, &self.triangles, &self.rest, &mut self.frame);
        self.line.clear();
        let _ = write!(self.line, "        {k}: ");
        push_points(&mut self.line, &self.frame);
        self.line.push_str(",\n");
        self.file
            .write_all(self.line.as_bytes())
            .map_err(|e| io_error(out, e))
    }

    /// Copies the samples into `dst` (the output, named `out`).
    fn copy_into(self, out: &Path, dst: &mut AtomicFile) -> Result<(), MeshError> {
        let mut f = self
            .file
            .into_inner()
            .map_err(|e| io_error(out, e.into_error()))?;
        f.rewind().map_err(|e| io_error(out, e))?;
        let mut buf = vec![0u8; 1 << 20];
        loop {
            let n = f.read(&mut buf).map_err(|e| io_error(out, e))?;
            if n == 0 {
                return Ok(());
            }
            dst.write_all(&buf[..n])?;
        }
    }
}

/// An I/O error on the normals' temporary, named by the output.
fn io_error(out: &Path, source: std::io::Error) -> MeshError {
    FsError {
        path: out.to_path_buf(),
        source,
    }
    .into()
}

/// The prim name: the file stem as a USD identifier (letters, digits,
/// `_`; not starting with a digit), else `Mesh`.
fn prim_name(out: &Path) -> String {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut s: String = stem
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if s.is_empty() || s.chars().all(|c| c == '_') {
        return "Mesh".into();
    }
    if s.starts_with(|c: char| c.is_ascii_digit()) {
        s.insert(0, '_');
    }
    s
}

/// Appends `[(x, y, z), ...]` of `points` as f32.
fn push_points(buf: &mut String, points: &[[f64; 3]]) {
    buf.push('[');
    for (i, p) in points.iter().enumerate() {
        if i > 0 {
            buf.push_str(", ");
        }
        let _ = write!(buf, "({}, {}, {})", p[0] as f32, p[1] as f32, p[2] as f32);
    }
    buf.push(']');
}

impl UsdaWriter {
    /// Starts `out` for `frames` frames of `mesh`'s topology at `fps`
    /// with the default options ([`UsdOptions::DEFAULT`]).
    pub fn create(
        mesh: &Mesh,
        out: &Path,
        frames: usize,
        fps: f64,
    ) -> Result<UsdaWriter, MeshError> {
        Self::create_with(mesh, out, frames, fps, UsdOptions::DEFAULT)
    }

    /// Starts `out` for `frames` frames of `mesh`'s topology at `fps`:
    /// writes the layer header, the topology, the rest points and (with
    /// `opts.normals`) the rest normals.
    pub(crate) fn create_with(
        mesh: &Mesh,
        out: &Path,
        frames: usize,
        fps: f64,
        opts: UsdOptions,
    ) -> Result<UsdaWriter, MeshError> {
        if frames == 0 {
            return Err(MeshError::invalid(out, "a USD sequence needs a frame"));
        }
        if !(fps.is_finite() && fps > 0.0) {
            return Err(MeshError::invalid(
                out,
                format!(
                    "frame rate {} is not a positive number",
                    crate::util::numfmt::Short(fps)
                ),
            ));
        }
        let name = prim_name(out);
        let mut h = String::new();
        let _ = write!(
            h,
            "#usda 1.0\n(\n    defaultPrim = \"{name}\"\n    doc = \"Written by surfmotion {}\"\n    metersPerUnit = 1\n    upAxis = \"Y\"\n    timeCodesPerSecond = {fps}\n    framesPerSecond = {fps}\n    startTimeCode = 0\n    endTimeCode = {}\n)\n\n",
            env!("CARGO_PKG_VERSION"),
            frames - 1
        );
        let _ = write!(h, "def Mesh \"{name}\"\n{{\n");
        h.push_str("    uniform bool doubleSided = 0\n");
        h.push_str("    int[] faceVertexCounts = [");
        for i in 0..mesh.triangle_count() {
            h.push_str(if i > 0 { ", 3" } else { "3" });
        }
        h.push_str("]\n    int[] faceVertexIndices = [");
        for (i, t) in mesh.triangles().iter().enumerate() {
            if i > 0 {
                h.push_str(", ");
            }
            let _ = write!(h, "{}, {}, {}", t[0], t[1], t[2]);
        }
        h.push_str("]\n    uniform token orientation = \"rightHanded\"\n");
        h.push_str("    uniform token subdivisionScheme = \"none\"\n");
        h.push_str("    point3f[] points = ");
        push_points(&mut h, mesh.positions());
        // The output first: it makes the folder the spool goes in.
        let mut file = AtomicFile::create(out)?;
        let normals = match opts.normals {
            true => Some(NormalSpool::create(mesh, out)?),
            false => None,
        };
        if let Some(n) = &normals {
            h.push_str("\n    normal3f[] normals = ");
            push_points(&mut h, &n.rest);
            h.push_str(" (\n        interpolation = \"vertex\"\n    )");
        }
        h.push_str("\n    point3f[] points.timeSamples = {\n");
        file.write_all(h.as_bytes())?;
        Ok(UsdaWriter {
            out: out.to_path_buf(),
            file,
            vertices: mesh.vertex_count(),
            frames,
            written: 0,
            extents: Vec::with_capacity(frames),
            normals,
        })
    }

    /// Appends the next frame's points (the mesh's vertex count, finite).
    pub fn push(&mut self, frame: &[[f64; 3]]) -> Result<(), MeshError> {
        super::frame_check::check_frame(
            &self.out,
            frame,
            self.vertices,
            self.written,
            self.frames,
        )?;
        let mut e = [
            f32::INFINITY,
            f32::INFINITY,
            f32::INFINITY,
            -f32::INFINITY,
            -f32::INFINITY,
            -f32::INFINITY,
        ];
        for p in frame {
            for (a, &c) in p.iter().enumerate() {
                let x = c as f32;
                e[a] = e[a].min(x);
                e[a + 3] = e[a + 3].max(x);
            }
        }
        if frame.is_empty() {
            e = [0.0; 6];
        }
        self.extents.push(e);
        let mut buf = String::with_capacity(32 * frame.len() + 16);
        let _ = write!(buf, "        {}: ", self.written);
        push_points(&mut buf, frame);
        buf.push_str(",\n");
        self.file.write_all(buf.as_bytes())?;
        if let Some(n) = &mut self.normals {
            n.push(&self.out, self.written, frame)?;
        }
        self.written += 1;
        Ok(())
    }

    /// Frames written so far.
    pub fn written(&self) -> usize {
        self.written
    }

    /// Writes the normals, the extents and closes the layer, once every
    /// announced frame is in. Dropped before, it leaves no file.
    pub fn finish(mut self) -> Result<(), MeshError> {
        super::frame_check::check_complete(&self.out, self.written, self.frames)?;
        self.file.write_all(b"    }\n")?;
        if let Some(n) = self.normals.take() {
            self.file
                .write_all(b"    normal3f[] normals.timeSamples = {\n")?;
            n.copy_into(&self.out, &mut self.file)?;
            self.file.write_all(b"    }\n")?;
        }
        let mut t = String::from("    float3[] extent.timeSamples = {\n");
        for (k, e) in self.extents.iter().enumerate() {
            let _ = writeln!(
                t,
                "        {k}: [({}, {}, {}), ({}, {}, {})],",
                e[0], e[1], e[2], e[3], e[4], e[5]
            );
        }
        t.push_str("    }\n}\n\n");
        self.file.write_all(t.as_bytes())?;
        self.file.commit()?;
        Ok(())
    }
}

/// Writes a whole sequence as `.usda` at `fps` (the sequence's own rate
/// first) with `opts` ([`UsdOptions::DEFAULT`]: normals on).
pub fn write_usda_with(
    seq: &MeshSequence,
    fps: f64,
    out: &Path,
    opts: UsdOptions,
) -> Result<(), MeshError> {
    let fps = seq.fps.unwrap_or(fps);
    let mut w = UsdaWriter::create_with(seq.mesh(), out, seq.frame_count(), fps, opts)?;
    for k in 0..seq.frame_count() {
        w.push(seq.frame(k))?;
    }
    w.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prim_names_are_identifiers() {
        assert_eq!(prim_name(Path::new("a/samba dance.usda")), "samba_dance");
        assert_eq!(prim_name(Path::new("01.usda")), "_01");
        assert_eq!(prim_name(Path::new("é.usda")), "Mesh");
    }

    #[test]
    fn a_two_frame_triangle_is_written_whole() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("tri.usda");
        let m = Mesh::new(
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            vec![[0, 1, 2]],
        )
        .unwrap();
        let mut w = UsdaWriter::create(&m, &out, 2, 30.0).unwrap();
        w.push(m.positions()).unwrap();
        assert!(!out.exists(), "nothing appears before the last frame");
        w.push(&[[0.0, 0.0, 0.1], [1.0, 0.0, 0.1], [0.0, 1.0, 0.1]])
            .unwrap();
        w.finish().unwrap();
        let s = std::fs::read_to_string(&out).unwrap();
        assert!(s.starts_with("#usda 1.0\n"));
        assert!(s.contains("endTimeCode = 1\n"));
        assert!(s.contains("        1: [(0, 0, 0.1), (1, 0, 0.1), (0, 1, 0.1)],\n"));
        assert!(s.contains("        1: [(0, 0, 0.1), (1, 1, 0.1)],\n"));
        assert!(s.contains(
            "    normal3f[] normals = [(0, 0, 1), (0, 0, 1), (0, 0, 1)] (\n        interpolation = \"vertex\"\n    )\n"
        ));
        let normals = s.split("normals.timeSamples = {\n").nth(1).unwrap();
        assert!(normals.starts_with(
            "        0: [(0, 0, 1), (0, 0, 1), (0, 0, 1)],\n        1: [(0, 0, 1), (0, 0, 1), (0, 0, 1)],\n    }\n    float3[] extent"
        ));
    }

    /// Frame 1 turns the triangle over (its normals flip); frame 2
    /// collapses it to a point (no normal: the rest's, unit length).
    #[test]
    fn normals_follow_each_frame_and_fall_back_to_the_rest() {
        let dir = tempfile::tempdir().unwrap();
        let m = Mesh::new(
            vec![[0.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 3.0]],
            vec![[0, 1, 2]],
        )
        .unwrap();
        let frames = [
            m.positions().to_vec(),
            vec![[0.0, 0.0, 0.0], [0.0, 0.0, 3.0], [0.0, 2.0, 0.0]],
            vec![[0.5; 3]; 3],
        ];
        let text = |opts: UsdOptions| {
            let out = dir.path().join("t.usda");
            let mut w = UsdaWriter::create_with(&m, &out, 3, 30.0, opts).unwrap();
            for f in &frames {
                w.push(f).unwrap();
            }
            w.finish().unwrap();
            std::fs::read_to_string(&out).unwrap()
        };
        let s = text(UsdOptions::DEFAULT);
        let block = s.split("normals.timeSamples = {\n").nth(1).unwrap();
        let want = "        0: [(1, 0, 0), (1, 0, 0), (1, 0, 0)],\n        1: [(-1, 0, 0), (-1, 0, 0), (-1, 0, 0)],\n        2: [(1, 0, 0), (1, 0, 0), (1, 0, 0)],\n    }\n";
        assert!(block.starts_with(want), "{block}");
        // Off: no normals anywhere, the points and extents as with them.
        let off = text(UsdOptions { normals: false });
        assert!(!off.contains("normal"), "{off}");
        let block_of = |t: &str, key: &str| {
            let after = t.split(key).nth(1).unwrap();
            after.split("\n    }").next().unwrap().to_string()
        };
        for key in ["points.timeSamples = {", "extent.timeSamples = {"] {
            assert_eq!(block_of(&s, key), block_of(&off, key), "{key}");
        }
    }
}
