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
    /// Seconds solving all frames (wall clock, writing excluded).
    pub solve_seconds: f64,
}

/// Frames solved together by [`transfer_each`] (in parallel) before they
/// are handed on: the memory of a streamed transfer is this many frames of
/// the scan, whatever the clip's length.
pub const CHUNK_FRAMES: usize = 64;

/// Poses the scan for every frame of `motion` (its rotations are re-signed
/// in place). Returns positions, frames × vertices, row-major. `progress`
/// is called with the number of frames finished so far (from any thread).
/// Holds every frame: [`transfer_each`] streams them.
pub fn transfer(
    c: &Confluent,
    motion: &mut MarkerMotion,
    opts: &TransferOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> (Vec<[f64; 3]>, TransferStats) {
    let n = c.vertex_count();
    let mut out = Vec::with_capacity(motion.frames() * n);
    let r: Result<TransferStats, std::convert::Infallible> =
        transfer_each(c, motion, opts, progress, |_, p| {
            out.extend_from_slice(p);
            Ok(())
        });
    let Ok(stats) = r;
    (out, stats)
}

/// [`transfer`] without holding the result: frames are solved
/// [`CHUNK_FRAMES`] at a time (in parallel) and handed to `each(frame,
/// positions)` in frame order, so a clip of any length needs the memory of
/// one chunk (issue 18, item 12). The first error of `each` stops the
/// transfer and is returned.
pub fn transfer_each<E>(
    c: &Confluent,
    motion: &mut MarkerMotion,
    opts: &TransferOptions,
    progress: &(dyn Fn(usize) + Sync),
    mut each: impl FnMut(usize, &[[f64; 3]]) -> Result<(), E>,
) -> Result<TransferStats, E> {
    let m = motion.markers;
    let singular = orient_frames(&mut motion.rotations, m, opts.signs);
    let n = c.vertex_count();
    let frames = motion.frames();
    let chunk = CHUNK_FRAMES.min(frames.max(1));
    let mut buf = vec![[0.0; 3]; chunk * n];
    let done = std::sync::atomic::AtomicUsize::new(0);
    let mut solve_seconds = 0.0;
    let motion = &*motion;
    let mut weak = 0;
    for first in (0..frames).step_by(chunk) {
        let count = chunk.min(frames - first);
        let t = Instant::now();
        let w = buf[..count * n]
            .par_chunks_mut(n.max(1))
            .enumerate()
            .map_init(
                || c.workspace(),
                |ws, (k, o)| {
                    let (r, tg) = motion.frame(first + k);
                    let s = c.frame(r, tg, ws, o);
                    progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);
                    s.weak_triangles
                },
            )
            .max()
            .unwrap_or(0);
        solve_seconds += t.elapsed().as_secs_f64();
        weak = weak.max(w);
        for k in 0..count {
            each(first + k, &buf[k * n..(k + 1) * n])?;
        }
    }
    let stats = TransferStats {
        frames,
        markers: m,
        singular_frames: singular,
        max_weak_triangles: weak,
        solve_seconds,
    };
    Ok(stats)
}
