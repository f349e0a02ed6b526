//! BVH over TCP (as Axis Studio / Perception Neuron broadcast): a BVH
//! header (`HIERARCHY` … `MOTION`, `Frames:`, `Frame Time:`), then one
//! frame line per sample.
//!
//! A listener thread accepts one sender at a time; a sender that
//! disconnects and connects again (with its header) resumes the session
//! (counted as a reconnect). Each frame line is read with the header as a
//! one-frame clip; the first frame decides the clip's units and up axis and
//! the rig map (the same detection as a file, [`crate::rig::load_clip`], or
//! the given `--rig-map`) and the neutral reference (the header's rest
//! skeleton when it stands upright, else the first frame). Frames arrive at
//! the sender's rate and are taken at the database's: the source frame
//! nearest each output time. A line that does not read is counted as
//! malformed and skipped, as is a line longer than [`MAX_LINE`] (read past
//! without being kept); a header longer than [`MAX_HEADER`] is malformed
//! and its sender dropped. When the session is busy the newest frame wins
//! (the ones it replaced are counted as dropped).

use super::mailbox::{Fed, Mailbox};
use super::source::{Incoming, SourceError};
use crate::mocap::Clip;
use crate::mocap::bvh::{BvhOptions, parse_bvh};
use crate::pose::retarget::{JointRotations, choose_reference};
use crate::rig::{LoadOptions, RigMap, detect_clip, load_clip};
use std::io::{BufRead, BufReader, Read};
use std::net::{SocketAddr, TcpListener};
use std::path::Path;
use std::time::Instant;

/// Listens on `addr` for BVH senders: a [`Fed`] source; frames are
/// taken at `fps` (the database's rate).
pub fn listen(
    addr: SocketAddr,
    fps: f64,
    load: LoadOptions,
    lossless: bool,
) -> Result<Fed, SourceError> {
    let listener = TcpListener::bind(addr).map_err(|source| SourceError::Io {
        what: format!("listening on {addr}"),
        source,
    })?;
    let addr = listener.local_addr().unwrap_or(addr);
    Ok(Fed::spawn(addr, lossless, move |mb| {
        serve(listener, fps, load, mb)
    }))
}

/// The longest frame time a sender's header may give (seconds). Each
/// source frame is put as every output frame nearest its time, about
/// `frame_time × fps` of them, so a header's `Frame Time: 1e12` (or
/// `inf`) from the network made one frame a list of 10¹³ numbers (the
/// receiver's memory without bound, session 44); a longer frame time is
/// refused as malformed, as a non-positive one is.
const MAX_FRAME_TIME: f64 = 10.0;

/// The longest line a sender may send, in bytes. A frame line is one
/// number a channel (a 100-joint, 6-channel skeleton writes about 7 KB), a
/// header line a joint's name or offset; without a bound one line without
/// a newline held the receiver's memory without limit (session 45). A
/// longer line is read past, not kept, and counted as malformed.
pub const MAX_LINE: usize = 1 << 20;

/// The longest header (`HIERARCHY` to `Frame Time:`) a sender may send, in
/// bytes: a longer one is malformed and its sender is dropped.
pub const MAX_HEADER: usize = 8 << 20;

/// What one bounded line read gave.
#[derive(Debug, PartialEq)]
enum LineRead {
    /// A line (with its newline, unless the stream ended before one).
    Line,
    /// A line longer than [`MAX_LINE`]: read past up to its newline.
    TooLong,
    /// The sender closed, or the bytes were not text.
    End,
}

/// Reads one line of at most `max` bytes into `line` (cleared first); a
/// longer line is consumed up to and including its newline without being
/// kept.
fn read_line_bounded(reader: &mut impl BufRead, line: &mut String, max: usize) -> LineRead {
    line.clear();
    match reader.by_ref().take(max as u64).read_line(line) {
        Ok(0) | Err(_) => LineRead::End,
        Ok(n) if n < max || line.ends_with('\n') => LineRead::Line,
        Ok(_) => {
            line.clear();
            skip_past_newline(reader);
            LineRead::TooLong
        }
    }
}

/// Consumes bytes up to and including the next newline (or the end).
fn skip_past_newline(reader: &mut impl BufRead) {
    loop {
        let (used, done) = match reader.fill_buf() {
            Ok([]) | Err(_) => return,
            Ok(buf) => match buf.iter().position(|&b| b == b'\n') {
                Some(i) => (i + 1, true),
                None => (buf.len(), false),
            },
        };
        reader.consume(used);
        if done {
            return;
        }
    }
}

/// What the first frame of the stream decided.
struct Decided {
    map: RigMap,
    units: crate::mocap::Units,
    up: crate::mocap::UpAxis,
}

/// Accepts senders one after the other until the mailbox is closed.
fn serve(listener: TcpListener, fps: f64, load: LoadOptions, mb: &Mailbox) {
    let mut decided: Option<Decided> = None;
    let mut out_index = 0u64;
    let mut connections = 0u64;
    for stream in listener.incoming() {
        if mb.closed() {
            break;
        }
        let Ok(stream) = stream else { continue };
        connections += 1;
        if connections > 1 {
            mb.count(|c| c.reconnects += 1);
        }
        let mut reader = BufReader::new(stream);
        let mut header = String::new();
        let mut frame_time: f64 = 0.0;
        let mut line = String::new();
        // The header, up to and including `Frame Time:`.
        loop {
            if !next_line(&mut reader, &mut line, mb) {
                break;
            }
            if header.len() + line.len() > MAX_HEADER {
                break;
            }
            let t = line.trim();
            if let Some(v) = t.strip_prefix("Frame Time:") {
                frame_time = v.trim().parse().unwrap_or(0.0);
                break;
            }
            if t.starts_with("Frames:") {
                continue;
            }
            header.push_str(&line);
        }
        if !(frame_time > 0.0 && frame_time <= MAX_FRAME_TIME) {
            mb.count(|c| c.malformed += 1);
            continue;
        }
        let mut source_index = 0u64;
        // Output frames are numbered on from the last connection's.
        let base = out_index;
        loop {
            if !next_line(&mut reader, &mut line, mb) {
                break;
            }
            if line.trim().is_empty() {
                continue;
            }
            let arrived = Instant::now();
            let text = format!(
                "{header}Frames: 1\nFrame Time: {frame_time}\n{}\n",
                line.trim_end()
            );
            let Ok(clip) = parse_bvh(&text, Path::new("tcp"), &BvhOptions::default()) else {
                mb.count(|c| c.malformed += 1);
                continue;
            };
            let t = source_index as f64 * frame_time;
            source_index += 1;
            // The output frames whose time this source frame is nearest.
            let mut due = Vec::new();
            while ((out_index - base) as f64 / fps) < t + 0.5 * frame_time - 1e-9 {
                due.push(out_index);
                out_index += 1;
            }
            if due.is_empty() {
                continue;
            }
            let Some((pose, rot, rest)) = frame_pose(clip, &text, &load, &mut decided) else {
                mb.count(|c| c.malformed += 1);
                continue;
            };
            if mb.reference().is_none()
                && let Ok(r) = choose_reference(rest.as_ref(), &[pose])
            {
                mb.set_reference(r);
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
    }
}

/// Reads the next line of at most [`MAX_LINE`] bytes into `line`; a longer
/// one is read past and counted as malformed. False at the stream's end.
fn next_line(reader: &mut impl BufRead, line: &mut String, mb: &Mailbox) -> bool {
    loop {
        match read_line_bounded(reader, line, MAX_LINE) {
            LineRead::End => return false,
            LineRead::TooLong => mb.count(|c| c.malformed += 1),
            LineRead::Line => return true,
        }
    }
}

/// The canonical pose (metres, Y-up) and file-joint rotations of a
/// one-frame clip, the rest pose when first decided.
fn frame_pose(
    mut clip: Clip,
    text: &str,
    load: &LoadOptions,
    decided: &mut Option<Decided>,
) -> Option<(crate::pose::Pose, JointRotations, Option<crate::pose::Pose>)> {
    let mut first = false;
    if decided.is_none() {
        // The same decisions as a file: units, up axis, rig map.
        let dir = tempfile::tempdir().ok()?;
        let p = dir.path().join("stream.bvh");
        std::fs::write(&p, text).ok()?;
        let c = load_clip(&p, load).ok()?;
        let map = match &load.rig_map {
            Some(m) => m.clone(),
            None => detect_clip(&c).ok()?.map,
        };
        *decided = Some(Decided {
            map,
            units: c.units.clone(),
            up: c.up,
        });
        first = true;
    }
    let d = decided.as_ref()?;
    clip.units = d.units.clone();
    clip.up = d.up;
    clip.to_metres_y_up();
    let (poses, rots) = d.map.poses_and_rotations(&clip).ok()?;
    let rest = if first {
        d.map.rest_pose(&clip).ok()
    } else {
        None
    };
    Some((*poses.first()?, *rots.first()?, rest))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::live::report::Counters;
    use crate::live::source::Source;
    use crate::mocap::bvh::format_bvh;
    use crate::synth::{Gait, gait_clip};
    use std::io::Write;
    use std::time::Duration;

    /// A lossless listener on a free loopback port, at 30 frames a second.
    fn listener() -> Fed {
        listen(
            "127.0.0.1:0".parse().unwrap(),
            30.0,
            LoadOptions::default(),
            true,
        )
        .unwrap()
    }

    /// `fed`'s counters once `what` holds of them, or after 30 s.
    fn wait_until(fed: &Fed, what: &dyn Fn(&Counters) -> bool) -> Counters {
        let end = Instant::now() + Duration::from_secs(30);
        while !what(&fed.counters()) && Instant::now() < end {
            std::thread::sleep(Duration::from_millis(20));
        }
        fed.counters()
    }

    /// A header whose frame time is huge or infinite is refused as
    /// malformed (the session lives, no frame is put), and the next
    /// sender with a sane one is read: before, the second frame line of
    /// `Frame Time: 1e12` put 3·10¹³ output numbers in a list (run only
    /// under a memory limit to see it).
    #[test]
    fn a_huge_frame_time_is_malformed_not_a_flood() {
        let text = format_bvh(&gait_clip(Gait::Walk, 1.0, 30.0));
        let fed = listener();
        let to = fed.local_addr();
        let send = |frame_time: &str| {
            let mut s = std::net::TcpStream::connect(to).unwrap();
            for l in text.lines() {
                let l = match l.starts_with("Frame Time:") {
                    true => format!("Frame Time: {frame_time}"),
                    false => l.to_string(),
                };
                // The receiver may have closed a refused sender.
                if s.write_all(format!("{l}\n").as_bytes()).is_err() {
                    break;
                }
            }
        };
        let wait_for = |what: &dyn Fn(&Counters) -> bool| wait_until(&fed, what);
        send("1e12");
        send("inf");
        let c = wait_for(&|c| c.malformed >= 2);
        assert_eq!((c.malformed, c.received), (2, 0), "{c:?}");
        send("0.0333333");
        let c = wait_for(&|c| c.received >= 20);
        assert!(c.received >= 20, "{c:?}");
    }

    /// Lines are read up to the bound; a longer one is read past up to
    /// its newline and not kept, and the next line reads whole.
    #[test]
    fn a_line_longer_than_the_bound_is_read_past_not_kept() {
        let long = "9".repeat(5000);
        let text = format!("short\n{long}\nafter\nlast-without-newline");
        let mut r = BufReader::with_capacity(64, text.as_bytes());
        let mut line = String::new();
        let mut got = Vec::new();
        loop {
            let read = read_line_bounded(&mut r, &mut line, 100);
            got.push((format!("{read:?}"), line.clone()));
            if read == LineRead::End {
                break;
            }
        }
        let want: Vec<(String, String)> = [
            ("Line", "short\n"),
            ("TooLong", ""),
            ("Line", "after\n"),
            ("Line", "last-without-newline"),
            ("End", ""),
        ]
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
        assert_eq!(got, want);
        assert!(line.capacity() <= 200, "{}", line.capacity());
    }

    /// A sender's frame line of more than [`MAX_LINE`] bytes is counted as
    /// malformed and the frames after it are read; a header of more than
    /// [`MAX_HEADER`] bytes drops its sender as malformed, and the next
    /// sender is read.
    #[test]
    fn an_endless_line_or_header_is_malformed_not_held() {
        let text = format_bvh(&gait_clip(Gait::Walk, 1.0, 30.0));
        let fed = listener();
        let to = fed.local_addr();
        let wait_for = |what: &dyn Fn(&Counters) -> bool| wait_until(&fed, what);
        // A header that never ends: the sender is dropped.
        {
            let mut s = std::net::TcpStream::connect(to).unwrap();
            let chunk = format!("{}\n", "x".repeat(1000));
            let mut sent = 0;
            while sent <= MAX_HEADER + MAX_LINE {
                if s.write_all(chunk.as_bytes()).is_err() {
                    break;
                }
                sent += chunk.len();
            }
        }
        let c = wait_for(&|c| c.malformed >= 1);
        assert_eq!((c.malformed, c.received), (1, 0), "{c:?}");
        // A frame line longer than the bound between good frames.
        let mut s = std::net::TcpStream::connect(to).unwrap();
        let (head, frames) = text.split_at(text.find("Frame Time:").unwrap());
        let (ft, frames) = frames.split_at(frames.find('\n').unwrap() + 1);
        s.write_all(head.as_bytes()).unwrap();
        s.write_all(ft.as_bytes()).unwrap();
        let mut lines = frames.lines();
        for l in lines.by_ref().take(3) {
            s.write_all(format!("{l}\n").as_bytes()).unwrap();
        }
        s.write_all("1 ".repeat(MAX_LINE).as_bytes()).unwrap();
        s.write_all(b"\n").unwrap();
        for l in lines {
            s.write_all(format!("{l}\n").as_bytes()).unwrap();
        }
        let c = wait_for(&|c| c.received >= 20 && c.malformed >= 2);
        assert_eq!(c.malformed, 2, "{c:?}");
        assert!(c.received >= 20, "{c:?}");
    }
}
