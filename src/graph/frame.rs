//! A database frame, named two ways (Huang et al. 2015, Sec. 4.3: the
//! Surface Motion Graph's frame-level adjacency numbers every frame of
//! every sequence).
//!
//! - [`FlatFrame`]: the flat id, the frames of all sequences numbered in
//!   graph order (sequence 0's frames first). What the adjacency, the
//!   trellis, the timeline, the key-frame search and the deformation's
//!   example frames hold, and what indexes the character's per-frame
//!   slices ([`crate::db::Character::poses`]).
//! - [`FrameId`]: a sequence (graph order) and a frame in it.
//!
//! One direction per name: [`crate::graph::SurfaceMotionGraph::flat_id`]
//! (`(sequence, frame) → FlatFrame`, and `checked_flat_id` for a
//! [`FrameId`] that may be out of range) and
//! [`crate::graph::SurfaceMotionGraph::frame_at`] / `frame_of`
//! (`FlatFrame → (sequence, frame)`).

use serde::{Deserialize, Serialize};
use std::fmt;

/// A database frame by its flat id (frames of all sequences numbered in
/// graph order). Serialised as the bare number (`serde(transparent)`), so
/// caches and reports read and write the same bytes as a `u32`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default, Serialize, Deserialize,
)]
#[serde(transparent)]
pub struct FlatFrame(u32);

impl FlatFrame {
    /// The frame with flat id `id`.
    pub const fn new(id: u32) -> FlatFrame {
        FlatFrame(id)
    }

    /// The frame at position `i` of a per-frame slice. Flat ids are `u32`
    /// (a database of more than 2³² frames cannot be loaded); `i` is
    /// truncated as `i as u32` was.
    pub const fn from_index(i: usize) -> FlatFrame {
        FlatFrame(i as u32)
    }

    /// The flat id as a number.
    pub const fn get(self) -> u32 {
        self.0
    }

    /// The position of this frame in a per-frame slice (poses, steps,
    /// centroids, adjacency rows).
    pub const fn index(self) -> usize {
        self.0 as usize
    }

    /// The frame after this one in flat order (the natural successor
    /// when both are in one sequence; callers check the sequence).
    pub const fn next(self) -> FlatFrame {
        FlatFrame(self.0 + 1)
    }

    /// The frame before this one in flat order (`None` for frame 0).
    pub const fn prev(self) -> Option<FlatFrame> {
        match self.0.checked_sub(1) {
            Some(p) => Some(FlatFrame(p)),
            None => None,
        }
    }

    /// The frame `k` after this one in flat order (negative: before),
    /// `None` outside `0..=u32::MAX`.
    pub fn offset(self, k: i64) -> Option<FlatFrame> {
        u32::try_from(i64::from(self.0) + k).ok().map(FlatFrame)
    }

    /// Every frame of a database of `count` frames, in flat order.
    pub fn all(count: usize) -> impl DoubleEndedIterator<Item = FlatFrame> + ExactSizeIterator {
        (0..count as u32).map(FlatFrame)
    }
}

impl fmt::Display for FlatFrame {
    /// The bare number, as a `u32` prints (messages and text reports are
    /// unchanged by the type).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0, f)
    }
}

impl From<FlatFrame> for u32 {
    fn from(f: FlatFrame) -> u32 {
        f.0
    }
}

/// A database frame: a sequence (in graph order) and a frame in it. The
/// frame-level adjacency and the searches use the [`FlatFrame`] instead
/// ([`crate::graph::SurfaceMotionGraph::checked_flat_id`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
pub struct FrameId {
    /// Sequence index.
    pub seq: u32,
    /// Frame within the sequence.
    pub frame: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_flat_frame_serialises_and_prints_as_its_number() {
        for id in [0u32, 1, 7, 4_096, u32::MAX] {
            let f = FlatFrame::new(id);
            assert_eq!(serde_json::to_string(&f).unwrap(), id.to_string());
            assert_eq!(
                serde_json::from_str::<FlatFrame>(&id.to_string()).unwrap(),
                f
            );
            assert_eq!(format!("{f}"), format!("{id}"));
            assert_eq!(format!("{f:>12}"), format!("{id:>12}"));
            assert_eq!(f.index(), id as usize);
            assert_eq!(u32::from(f), id);
        }
        let pairs = [(FlatFrame::new(3), 0.5f64), (FlatFrame::new(9), 0.25)];
        let plain = [(3u32, 0.5f64), (9, 0.25)];
        assert_eq!(
            serde_json::to_string(&pairs).unwrap(),
            serde_json::to_string(&plain).unwrap()
        );
    }

    #[test]
    fn steps_stay_in_range() {
        assert_eq!(FlatFrame::new(0).prev(), None);
        assert_eq!(FlatFrame::new(5).prev(), Some(FlatFrame::new(4)));
        assert_eq!(FlatFrame::new(5).next(), FlatFrame::new(6));
        assert_eq!(FlatFrame::new(5).offset(-5), Some(FlatFrame::new(0)));
        assert_eq!(FlatFrame::new(5).offset(-6), None);
        assert_eq!(FlatFrame::new(u32::MAX).offset(1), None);
        let all: Vec<u32> = FlatFrame::all(4).map(FlatFrame::get).collect();
        assert_eq!(all, [0, 1, 2, 3]);
        assert_eq!(FlatFrame::from_index(12), FlatFrame::new(12));
    }
}
