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
    // The shift given to the frame before this chunk, once some frame's
    // is known.
    let mut carried: Option<f64> = None;
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
        if let Some(feet) = &motion.feet {
            let known: Vec<Option<f64>> = (0..count)
                .map(|k| feet.shift(first + k, &buf[k * n..(k + 1) * n]))
                .collect();
            let shifts = chunk_shifts(&known, &mut carried);
            for (k, d) in shifts.iter().enumerate() {
                for p in &mut buf[k * n..(k + 1) * n] {
                    for (x, u) in p.iter_mut().zip(feet.up) {
                        *x += d * u;
                    }
                }
            }
        }
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

/// The vertical shift of each frame of a chunk ([`super::source::FootGround`]):
/// the `known` ones (frames where a foot touches); between two known
/// ones, linear; before the chunk's first, linear from `carried` (the
/// shift given to the frame before the chunk), or the first when there
/// is none; after the last, the last held (the next chunk's frames go
/// on from it). Frames are handed on chunk by chunk, so a shift is never
/// revised once given. Updates `carried`.
fn chunk_shifts(known: &[Option<f64>], carried: &mut Option<f64>) -> Vec<f64> {
    let count = known.len();
    let pts: Vec<(f64, f64)> = known
        .iter()
        .enumerate()
        .filter_map(|(k, d)| d.map(|d| (k as f64, d)))
        .collect();
    let before = carried.map(|d| (-1.0, d));
    let out: Vec<f64> = (0..count)
        .map(|k| {
            let x = k as f64;
            let prev = pts.iter().rev().find(|p| p.0 <= x).copied().or(before);
            let next = pts.iter().find(|p| p.0 >= x).copied();
            match (prev, next) {
                (Some(a), Some(b)) if b.0 > a.0 => a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0),
                (Some(a), _) => a.1,
                (None, Some(b)) => b.1,
                (None, None) => 0.0,
            }
        })
        .collect();
    if carried.is_some() || !pts.is_empty() {
        *carried = out.last().copied().or(*carried);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::chunk_shifts;

    #[test]
    fn shifts_interpolate_across_chunks_and_hold_at_the_ends() {
        let mut c = None;
        let a = chunk_shifts(&[None, Some(1.0), None, Some(3.0), None], &mut c);
        assert_eq!(a, vec![1.0, 1.0, 2.0, 3.0, 3.0]);
        assert_eq!(c, Some(3.0));
        // The gap over the boundary: held before it, then linear from the
        // frame before this chunk to the next known one.
        let b = chunk_shifts(&[None, None, None, Some(7.0)], &mut c);
        assert_eq!(b, vec![4.0, 5.0, 6.0, 7.0]);
        let mut none = None;
        assert_eq!(chunk_shifts(&[None, None], &mut none), vec![0.0, 0.0]);
        assert_eq!(none, None);
    }
}
