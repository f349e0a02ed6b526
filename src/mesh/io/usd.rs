//! USD output of a mesh sequence: a `.usda` text layer (Pixar's Universal
//! Scene Description) with one `Mesh` prim whose `points` are time-sampled,
//! one sample per frame, and an `extent` per frame.
//!
//! The layer's metadata says what the numbers mean: `metersPerUnit = 1`
//! (the project's meshes are in metres), `upAxis = "Y"`,
//! `timeCodesPerSecond`/`framesPerSecond` the frame rate, and
//! `startTimeCode`/`endTimeCode` the first and last frame (time code =
//! frame index). Points are `point3f` (32-bit floats, as every other
//! writer stores them), each written as the shortest decimal that reads
//! back as the same `f32`.
//!
//! Written frame by frame ([`UsdaWriter`]): the header needs the frame
//! count, which a [`super::stream::SequenceWriter`] knows up front; each
//! frame's points are appended as they come, and the extents (six numbers
//! a frame) follow the last frame. Atomic: the file appears when the last
//! frame is in. Checked in `tests/it/mesh/io.rs` by Pixar's `usd-core`
//! (its validators pass; points read back equal ours).

use crate::mesh::{Mesh, MeshError, MeshSequence};
use crate::util::fsutil::AtomicFile;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A `.usda` sequence being written; see the module documentation.
pub struct UsdaWriter {
    out: PathBuf,
    file: AtomicFile,
    vertices: usize,
    frames: usize,
    written: usize,
    /// Per frame: min and max corner, as written (f32).
    extents: Vec<[f32; 6]>,
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
    /// Starts `out` for `frames` frames of `mesh`'s topology at `fps`:
    /// writes the layer header, the topology and the rest points.
    pub fn create(
        mesh: &Mesh,
        out: &Path,
        frames: usize,
        fps: f64,
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
        h.push_str("\n    point3f[] points.timeSamples = {\n");
        let mut file = AtomicFile::create(out)?;
        file.write_all(h.as_bytes())?;
        Ok(UsdaWriter {
            out: out.to_path_buf(),
            file,
            vertices: mesh.vertex_count(),
            frames,
            written: 0,
            extents: Vec::with_capacity(frames),
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
        self.written += 1;
        Ok(())
    }

    /// Frames written so far.
    pub fn written(&self) -> usize {
        self.written
    }

    /// Writes the extents and closes the layer, once every announced frame
    /// is in. Dropped before, it leaves no file.
    pub fn finish(mut self) -> Result<(), MeshError> {
        super::frame_check::check_complete(&self.out, self.written, self.frames)?;
        let mut t = String::from("    }\n    float3[] extent.timeSamples = {\n");
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
/// first).
pub(crate) fn write_usda(seq: &MeshSequence, fps: f64, out: &Path) -> Result<(), MeshError> {
    let fps = seq.fps.unwrap_or(fps);
    let mut w = UsdaWriter::create(seq.mesh(), out, seq.frame_count(), fps)?;
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
    }
}
