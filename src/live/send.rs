//! `live send`: a clip file sent as a stream (BVH over TCP, VMC or Rokoko
//! Studio Live over UDP), so every input path can be tested without a suit.

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
    /// The clip's skeleton could not be mapped to the canonical joints.
    #[error(transparent)]
    Query(#[from] crate::drive::query::QueryError),
    /// A frame could not be encoded.
    #[error("encoding frame {frame}: {msg}")]
    Encode {
        /// The frame.
        frame: usize,
        /// Why.
        msg: String,
    },
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

/// The UDP protocols `live send` speaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UdpProtocol {
    /// VMC (OSC over UDP): local transforms as Unity humanoid bones.
    Vmc,
    /// Rokoko Studio Live (JSON over UDP): world transforms of the body
    /// joints.
    Rokoko,
}

/// Every how many frames the sender's reference is sent again (so a
/// receiver started late still gets it).
const REFERENCE_EVERY: usize = 30;

/// Sends the clip at `clip` to `to` over UDP in `protocol`: its canonical
/// joints (the same rig detection as a file) at `fps` (default: the
/// clip's rate), one datagram a frame at `speed` times the rate (0: as
/// fast as the socket takes them, which a receiver may not keep up with),
/// with the clip's neutral reference every [`REFERENCE_EVERY`] frames.
pub fn send_udp(
    clip: &Path,
    to: SocketAddr,
    protocol: UdpProtocol,
    load: &LoadOptions,
    fps: Option<f64>,
    speed: f64,
) -> Result<SendReport, SendError> {
    use super::humanoid::{local_bones, world_bones};
    let fps = match fps {
        Some(f) => f,
        None => load_clip(clip, load)?.fps(),
    };
    let m = crate::drive::query::load_mocap(clip, load, fps)?;
    let io = |source| SendError::Io { to, source };
    let any: SocketAddr = if to.is_ipv4() {
        ([0, 0, 0, 0], 0).into()
    } else {
        (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
    };
    let socket = std::net::UdpSocket::bind(any).map_err(io)?;
    let start = Instant::now();
    for (k, pose) in m.poses.iter().enumerate() {
        let t = k as f64 / fps;
        if speed > 0.0
            && let Some(w) = Duration::from_secs_f64(t / speed).checked_sub(start.elapsed())
        {
            std::thread::sleep(w);
        }
        let world = world_bones(pose, m.reference.rotations.get(k));
        let reference = (k % REFERENCE_EVERY == 0).then_some(&m.reference.pose);
        let bytes = match protocol {
            UdpProtocol::Vmc => super::vmc::encode_frame(&local_bones(&world), t, reference)
                .map_err(|e| e.to_string()),
            UdpProtocol::Rokoko => {
                super::rokoko::encode_frame(&world, t, fps, reference).map_err(|e| e.to_string())
            }
        }
        .map_err(|msg| SendError::Encode { frame: k, msg })?;
        socket.send_to(&bytes, to).map_err(io)?;
    }
    Ok(SendReport {
        frames: m.poses.len(),
        fps,
        seconds: start.elapsed().as_secs_f64(),
    })
}
