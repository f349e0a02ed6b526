//! `live send`: a clip file sent as a stream (BVH over TCP), so every
//! input path can be tested without a suit.

use crate::mocap::bvh::format_bvh;
use crate::rig::{LoadOptions, load_clip};
use serde::Serialize;
use std::io::Write;
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::time::{Duration, Instant};

/// Why a clip could not be sent.
#[derive(Debug, thiserror::Error)]
pub enum SendError {
    /// The clip could not be read.
    #[error(transparent)]
    Mocap(#[from] crate::mocap::MocapError),
    /// The clip at the requested rate would not fit in memory.
    #[error(transparent)]
    Budget(#[from] crate::util::budget::OverBudget),
    /// The receiver could not be reached or went away.
    #[error("{to}: {source}")]
    Io {
        /// The receiver.
        to: SocketAddr,
        /// The error.
        source: std::io::Error,
    },
}

/// What was sent.
#[derive(Debug, Clone, Serialize)]
pub struct SendReport {
    /// Frames sent.
    pub frames: usize,
    /// The rate sent at (frames per second of clip time).
    pub fps: f64,
    /// Seconds sending.
    pub seconds: f64,
}

/// Sends the clip at `clip` (any format the tool reads, read as `load`
/// says) to `to` as BVH over TCP: its header, then one frame line per
/// frame at `speed` times the clip's rate (0: as fast as the socket takes
/// them), resampled to `fps` first when given.
pub fn send_bvh(
    clip: &Path,
    to: SocketAddr,
    load: &LoadOptions,
    fps: Option<f64>,
    speed: f64,
) -> Result<SendReport, SendError> {
    let mut c = load_clip(clip, load)?;
    if let Some(f) = fps {
        c = c.try_resampled(f)?;
    }
    let text = format_bvh(&c);
    let io = |source| SendError::Io { to, source };
    let mut s = TcpStream::connect(to).map_err(io)?;
    s.set_nodelay(true).map_err(io)?;
    let mut lines = text.lines();
    let mut header = String::new();
    for l in lines.by_ref() {
        header.push_str(l);
        header.push('\n');
        if l.starts_with("Frame Time:") {
            break;
        }
    }
    s.write_all(header.as_bytes()).map_err(io)?;
    let start = Instant::now();
    let mut frames = 0;
    for (i, l) in lines.enumerate() {
        if speed > 0.0 {
            let due = Duration::from_secs_f64(i as f64 * c.frame_time / speed);
            if let Some(w) = due.checked_sub(start.elapsed()) {
                std::thread::sleep(w);
            }
        }
        s.write_all(l.as_bytes()).map_err(io)?;
        s.write_all(b"\n").map_err(io)?;
        frames += 1;
    }
    s.flush().map_err(io)?;
    Ok(SendReport {
        frames,
        fps: 1.0 / c.frame_time,
        seconds: start.elapsed().as_secs_f64(),
    })
}
