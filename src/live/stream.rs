//! The body streams over UDP (VMC, Rokoko Studio Live): a receiver thread
//! reads datagrams, the [`Protocol`] reads each into the stream's
//! [`BodyState`], and every completed frame becomes a canonical pose
//! through the same rig detection as a file (the first frame decides; a
//! given `--rig-map` overrides) and is handed to the session through a
//! [`Mailbox`] at the database's rate.
//!
//! Timing is the sender's clock (VMC `/VMC/Ext/T`, Rokoko
//! `scene.timestamp`; the arrival time when a sender gives none): an
//! output frame takes the source frame nearest its time. A frame with the
//! time of the last is counted as duplicated, an older one as late (both
//! ignored); a clock that goes back or jumps ahead by more than
//! [`RESYNC_SECONDS`] is a sender that started again (counted as a
//! reconnect; the output numbering goes on). A datagram that does not read
//! is counted as malformed and changes nothing.

use super::humanoid::{BodyState, BoneTable, clip_offsets};
use super::mailbox::{Fed, Mailbox};
use super::source::{Incoming, SourceError};
use crate::pose::Pose;
use crate::pose::retarget::{ClipNeutral, JointRotations, choose_reference};
use crate::rig::{Canonical, LoadOptions, RigMap, detect_clip};
use glam::DVec3;
use std::collections::HashMap;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

/// A sender clock that goes back, or jumps ahead, by more than this many
/// seconds is a sender that started again.
pub(crate) const RESYNC_SECONDS: f64 = 2.0;

/// What one datagram did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Read {
    /// Bones updated (or nothing the receiver uses); the frame is not
    /// complete yet.
    Partial,
    /// The frame is complete, at this sender time (seconds) if it gave one.
    Frame(Option<f64>),
}

/// A datagram that does not read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("malformed datagram: {0}")]
pub struct Malformed(pub String);

/// A body-stream protocol over UDP.
pub trait Protocol: Send + 'static {
    /// Its name in messages.
    const NAME: &'static str;
    /// Its bones.
    const TABLE: BoneTable;
    /// The bone each canonical joint is sent as.
    const CANONICAL: [&'static str; Canonical::COUNT];
    /// True when bone transforms are local to the parent (else world).
    const LOCAL: bool;
    /// Reads one datagram into `state`. A malformed datagram leaves
    /// `state` as it was.
    fn read(&mut self, datagram: &[u8], state: &mut BodyState) -> Result<Read, Malformed>;
}

/// Listens on `addr` for datagrams of protocol `P`: a [`Fed`] source;
/// frames are taken at `fps` (the database's rate).
pub fn listen<P: Protocol>(
    addr: SocketAddr,
    protocol: P,
    fps: f64,
    load: LoadOptions,
    lossless: bool,
) -> Result<Fed, SourceError> {
    let io = |source| SourceError::Io {
        what: format!("listening for {} on {addr}", P::NAME),
        source,
    };
    let socket = UdpSocket::bind(addr).map_err(io)?;
    socket
        .set_read_timeout(Some(Duration::from_millis(50)))
        .map_err(io)?;
    let addr = socket.local_addr().unwrap_or(addr);
    Ok(Fed::spawn(addr, lossless, move |mb| {
        receive(socket, protocol, Decoder::new(fps, load), mb)
    }))
}

/// Reads datagrams until the mailbox is closed.
fn receive<P: Protocol>(socket: UdpSocket, mut protocol: P, mut dec: Decoder, mb: &Mailbox) {
    let mut buf = vec![0u8; 65_536];
    let mut state = BodyState::default();
    let clock = Instant::now();
    while !mb.closed() {
        let Ok(n) = socket.recv(&mut buf) else {
            continue;
        };
        let arrived = Instant::now();
        match protocol.read(&buf[..n], &mut state) {
            Err(_) => mb.count(|c| c.malformed += 1),
            Ok(Read::Partial) => {}
            Ok(Read::Frame(t)) => {
                let t = t.unwrap_or_else(|| clock.elapsed().as_secs_f64());
                dec.frame::<P>(&state, t, arrived, mb);
            }
        }
    }
}

/// The stream's decisions (rig map, rest offsets) and its clock.
pub struct Decoder {
    fps: f64,
    load: LoadOptions,
    map: Option<RigMap>,
    offsets: Option<HashMap<String, DVec3>>,
    pacer: Pacer,
}

impl Decoder {
    /// A stream taken at `fps`, read as `load` says (its rig map).
    pub fn new(fps: f64, load: LoadOptions) -> Decoder {
        Decoder {
            fps,
            load,
            map: None,
            offsets: None,
            pacer: Pacer::default(),
        }
    }

    /// A completed frame of `state` at sender time `t`: put in `mb` as the
    /// output frames it is nearest to.
    pub fn frame<P: Protocol>(
        &mut self,
        state: &BodyState,
        t: f64,
        arrived: Instant,
        mb: &Mailbox,
    ) {
        if !t.is_finite() {
            return mb.count(|c| c.malformed += 1);
        }
        let due = match self.pacer.due(t, self.fps) {
            Pace::Due(r) => r,
            Pace::Duplicate => return mb.count(|c| c.duplicated += 1),
            Pace::Late => return mb.count(|c| c.late += 1),
            Pace::Restarted(r) => {
                mb.count(|c| c.reconnects += 1);
                r
            }
        };
        if due.is_empty() {
            return;
        }
        let Some((pose, rot, reference)) = self.pose::<P>(state) else {
            return mb.count(|c| c.malformed += 1);
        };
        if mb.reference().is_none() {
            if let Some(r) = reference {
                mb.set_reference(r);
            }
        }
        for seq in due {
            mb.put(Incoming {
                seq,
                pose,
                rotations: Some(rot),
                arrived,
            });
        }
    }

    /// The canonical pose and rotations of `state`, and on the first frame
    /// the stream's reference.
    fn pose<P: Protocol>(
        &mut self,
        state: &BodyState,
    ) -> Option<(Pose, JointRotations, Option<ClipNeutral>)> {
        let first = self.map.is_none();
        if first {
            let clip = state.to_clip(P::TABLE, P::LOCAL, None)?;
            let offsets = clip_offsets(&clip, &P::CANONICAL, state.reference.as_ref());
            let clip = state.to_clip(P::TABLE, P::LOCAL, Some(&offsets))?;
            let map = match &self.load.rig_map {
                Some(m) => m.clone(),
                None => {
                    protocol_map::<P>(&clip).or_else(|| detect_clip(&clip).ok().map(|d| d.map))?
                }
            };
            // Checked before it is kept: a first frame that does not map
            // leaves the decision to the next.
            map.poses_and_rotations(&clip).ok()?;
            self.map = Some(map);
            self.offsets = Some(offsets);
        }
        let (map, offsets) = (self.map.as_ref()?, self.offsets.as_ref()?);
        let clip = state.to_clip(P::TABLE, P::LOCAL, Some(offsets))?;
        let (poses, rots) = map.poses_and_rotations(&clip).ok()?;
        let (pose, rot) = (*poses.first()?, *rots.first()?);
        if !pose.iter().all(|p| p.is_finite()) {
            return None;
        }
        let reference = if first {
            let rest = map.rest_pose(&clip).ok();
            choose_reference(rest.as_ref(), &[pose]).ok()
        } else {
            None
        };
        Some((pose, rot, reference))
    }
}

/// The protocol's own names for the canonical joints, when the stream
/// carries all of them (the names are the protocol's, so nothing is left
/// to guess; a stream that lacks some goes through the detection).
fn protocol_map<P: Protocol>(clip: &crate::mocap::Clip) -> Option<RigMap> {
    Canonical::ALL
        .iter()
        .all(|c| clip.joint(P::CANONICAL[c.index()]).is_some())
        .then(|| RigMap {
            convention: P::NAME.to_string(),
            joints: Canonical::ALL
                .iter()
                .map(|c| (*c, P::CANONICAL[c.index()].to_string()))
                .collect(),
            derived: Default::default(),
            file: None,
        })
}

/// Where a source frame falls among the output frames.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Pace {
    /// The output frames (numbers) it is nearest to (maybe none).
    Due(std::ops::Range<u64>),
    /// The same time as the last frame.
    Duplicate,
    /// Older than the last frame.
    Late,
    /// The sender's clock started again: the numbering goes on from the
    /// range's start.
    Restarted(std::ops::Range<u64>),
}

/// The sender's clock against the output frames.
#[derive(Debug, Clone, Default)]
pub(crate) struct Pacer {
    /// The sender time of output frame `base`.
    t0: f64,
    base: u64,
    next: u64,
    last: Option<f64>,
    /// The sender's frame period, once two frames came.
    period: Option<f64>,
}

impl Pacer {
    /// The output frames (at `fps`) a source frame at sender time `t` is
    /// the nearest to. Output frames before them that no source frame was
    /// nearest to (packets lost) are skipped: the gap in the numbering
    /// counts them as dropped.
    pub(crate) fn due(&mut self, t: f64, fps: f64) -> Pace {
        let mut restarted = false;
        match self.last {
            None => self.restart(t),
            Some(last) if t == last => return Pace::Duplicate,
            Some(last) if !(t - last).abs().le(&RESYNC_SECONDS) => {
                self.restart(t);
                restarted = true;
            }
            Some(last) if t < last => return Pace::Late,
            // A step much longer than the period is a gap, not a new rate.
            Some(last) => match self.period {
                Some(p) if t - last > 1.5 * p => {}
                _ => self.period = Some(t - last),
            },
        }
        self.last = Some(t);
        let half = 0.5 * self.period.unwrap_or(1.0 / fps);
        let rel = t - self.t0;
        let time = |next: u64| (next - self.base) as f64 / fps;
        while time(self.next) < rel - half - 1e-9 {
            self.next += 1;
        }
        let start = self.next;
        while time(self.next) < rel + half - 1e-9 {
            self.next += 1;
        }
        if restarted {
            Pace::Restarted(start..self.next)
        } else {
            Pace::Due(start..self.next)
        }
    }

    fn restart(&mut self, t: f64) {
        self.t0 = t;
        self.base = self.next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pacer_takes_the_nearest_source_frame_and_counts_the_odd_ones() {
        let mut p = Pacer::default();
        let fps = 30.0;
        // A sender at 60 fps: every other frame is due.
        let got: Vec<_> = (0..6).map(|k| p.due(k as f64 / 60.0, fps)).collect();
        assert_eq!(got[0], Pace::Due(0..1));
        assert_eq!(got[1], Pace::Due(1..1));
        assert_eq!(got[2], Pace::Due(1..2));
        assert_eq!(got[4], Pace::Due(2..3));
        assert_eq!(p.due(5.0 / 60.0, fps), Pace::Duplicate);
        assert_eq!(p.due(4.0 / 60.0, fps), Pace::Late);
        // Packets lost: the output frames in the gap are skipped.
        assert_eq!(p.due(20.0 / 60.0, fps), Pace::Due(10..11));
        // Started again: the numbering goes on.
        assert_eq!(p.due(-5.0, fps), Pace::Restarted(11..12));
        assert_eq!(p.due(1e300, fps), Pace::Restarted(12..13));
        assert_eq!(p.due(f64::NAN, fps), Pace::Restarted(13..13));
    }
}
