//! A temporally consistent mesh sequence: one connectivity, positions per frame.

use super::error::TopologyError;
use super::mesh::{Bounds, Mesh, check_finite};

/// A mesh sequence (4D capture, a point cache, an animation): the topology
/// (with its rest positions) and `frames × vertices` positions, frame-major.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshSequence {
    mesh: Mesh,
    frames: Vec<[f64; 3]>,
    /// Frames per second, if the source says.
    pub fps: Option<f64>,
}

impl MeshSequence {
    /// Builds a sequence; `frames.len()` must be a multiple of the vertex count
    /// and every coordinate finite.
    pub fn new(
        mesh: Mesh,
        frames: Vec<[f64; 3]>,
        fps: Option<f64>,
    ) -> Result<MeshSequence, TopologyError> {
        let n = mesh.vertex_count();
        if n == 0 || frames.len() % n != 0 {
            return Err(TopologyError::FrameSize {
                frame: frames.len() / n.max(1),
                got: frames.len() % n.max(1),
                expected: n,
            });
        }
        if let Err(TopologyError::NonFinite { vertex }) = check_finite(&frames) {
            return Err(TopologyError::NonFinite { vertex: vertex % n });
        }
        Ok(MeshSequence { mesh, frames, fps })
    }

    /// A one-frame sequence of a mesh.
    pub fn single(mesh: Mesh) -> MeshSequence {
        let frames = mesh.positions().to_vec();
        MeshSequence {
            mesh,
            frames,
            fps: None,
        }
    }

    /// The topology and rest positions.
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }
    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.frames.len() / self.mesh.vertex_count().max(1)
    }
    /// Positions of frame `i`.
    pub fn frame(&self, i: usize) -> &[[f64; 3]] {
        let n = self.mesh.vertex_count();
        &self.frames[i * n..(i + 1) * n]
    }
    /// All positions, frame-major.
    pub fn all_positions(&self) -> &[[f64; 3]] {
        &self.frames
    }
    /// Frame `i` as a mesh.
    pub fn frame_mesh(&self, i: usize) -> Mesh {
        let mut m = self.mesh.clone();
        // Positions were validated on construction.
        let _ = m.set_positions(self.frame(i));
        m
    }
    /// Bounds over all frames.
    pub fn bounds(&self) -> Bounds {
        Bounds::of(&self.frames)
    }
    /// Keeps only frame `i`.
    pub fn select_frame(&self, i: usize) -> Option<MeshSequence> {
        (i < self.frame_count()).then(|| MeshSequence {
            mesh: self.frame_mesh(i),
            frames: self.frame(i).to_vec(),
            fps: self.fps,
        })
    }
}
