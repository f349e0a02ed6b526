//! Transferring a whole clip: signs chosen in frame order, then the frames
//! solved in parallel (rayon across frames, one workspace per thread,
//! `Par::Seq` inside each solve).

use super::confluent::{Confluent, orient_frames};
use super::signs::SignMode;
use super::source::MarkerMotion;
use rayon::prelude::*;
use serde::Serialize;
use std::time::Instant;

/// Options for [`transfer`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TransferOptions {
    /// How marker quaternion signs are chosen. Default: consistent.
    pub signs: SignMode,
}

/// What a transfer did.
#[derive(Debug, Clone, Serialize, Default)]
pub struct TransferStats {
    /// Frames written.
    pub frames: usize,
    /// Markers used.
    pub markers: usize,
    /// Frames where some marker turned more than 160° from the reference
    /// pose (the paper's singular case, `|w|` small), handled by the sign
    /// choice.
    pub singular_frames: usize,
    /// The largest number of triangles in one frame whose interpolated
    /// quaternion nearly vanished (0 when no collapse threatens).
    pub max_weak_triangles: usize,
    /// Seconds solving all frames (wall clock).
    pub solve_seconds: f64,
}

/// Poses the scan for every frame of `motion` (its rotations are re-signed
/// in place). Returns positions, frames × vertices, row-major. `progress`
/// is called with the number of frames finished so far (from any thread).
pub fn transfer(
    c: &Confluent,
    motion: &mut MarkerMotion,
    opts: &TransferOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> (Vec<[f64; 3]>, TransferStats) {
    let m = motion.markers;
    let singular = orient_frames(&mut motion.rotations, m, opts.signs);
    let n = c.vertex_count();
    let frames = motion.frames();
    let mut out = vec![[0.0; 3]; frames * n];
    let done = std::sync::atomic::AtomicUsize::new(0);
    let t0 = Instant::now();
    let motion = &*motion;
    let weak = out
        .par_chunks_mut(n.max(1))
        .enumerate()
        .map_init(
            || c.workspace(),
            |ws, (f, o)| {
                let (r, tg) = motion.frame(f);
                let s = c.frame(r, tg, ws, o);
                progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                s.weak_triangles
            },
        )
        .max()
        .unwrap_or(0);
    let stats = TransferStats {
        frames,
        markers: m,
        singular_frames: singular,
        max_weak_triangles: weak,
        solve_seconds: t0.elapsed().as_secs_f64(),
    };
    (out, stats)
}
