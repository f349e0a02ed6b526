//! The stream inputs end to end through the binary: `live send` → `live
//! --bvh-tcp` / `--vmc` / `--rokoko` over loopback gives the frames `live
//! --replay` gives, a malformed line and a sender that disconnects and
//! reconnects keep the session alive and are reported, and random
//! datagrams neither stop a session nor panic a reader.

use crate::common;

use std::io::{BufRead, BufReader, Write};
use std::net::TcpStream;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use surfmotion::mesh::io::load_sequence;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_surfmotion")
}

/// Starts `live --bvh-tcp 127.0.0.1:0 ARGS` and returns it with the port it
/// listens on (read from its standard error). The caller waits for it
/// ([`report`]); a child that exits before listening fails the test.
fn listen(db: &Path, args: &[&str]) -> (Child, u16) {
    listen_on(db, "--bvh-tcp", args)
}

/// [`listen`] with the input flag `flag` (`--vmc`, `--rokoko`...).
#[allow(clippy::zombie_processes)]
fn listen_on(db: &Path, flag: &str, args: &[&str]) -> (Child, u16) {
    let mut child = Command::new(bin())
        .args(["live", "--db"])
        .arg(db)
        .args([
            flag,
            "127.0.0.1:0",
            "--until-idle",
            "3",
            "--lossless",
            "--json",
        ])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    loop {
        line.clear();
        assert!(
            err.read_line(&mut line).unwrap() > 0,
            "live exited before listening"
        );
        if let Some(a) = line.trim().strip_prefix("listening for ") {
            let port = a.rsplit(':').next().unwrap().parse().unwrap();
            // Keep draining stderr so the child never blocks on it.
            std::thread::spawn(move || {
                let mut s = String::new();
                while err.read_line(&mut s).is_ok_and(|n| n > 0) {
                    s.clear();
                }
            });
            return (child, port);
        }
    }
}

fn report(child: Child) -> serde_json::Value {
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success(), "live failed");
    let text = String::from_utf8_lossy(&out.stdout);
    let json = &text[..text.rfind('}').unwrap() + 1];
    serde_json::from_str(json).unwrap()
}

/// `live send --protocol PROTOCOL` → `live FLAG` over loopback, recorded,
/// against `live --replay` of the same clip: the largest vertex difference
/// (metres) and the report.
fn round_trip(protocol: &str, flag: &str) -> (f64, serde_json::Value) {
    let d = common::data_dir().unwrap();
    let db = common::synthetic_db(&d);
    let clip = d.join("mocap/cmu-bvh-altered/02_01.bvh");
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("replay.pc2"), tmp.path().join("net.pc2"));
    let fps = surfmotion::db::Manifest::load(&db).unwrap().fps.to_string();
    common::run_ok(
        Command::new(bin())
            .args(["live", "--db"])
            .arg(&db)
            .arg("--replay")
            .arg(&clip)
            .args(["--speed", "0", "--record"])
            .arg(&a),
    );
    let (child, port) = listen_on(&db, flag, &["--record", b.to_str().unwrap()]);
    common::run_ok(Command::new(bin()).args(["live", "send"]).arg(&clip).args([
        "--to",
        &format!("127.0.0.1:{port}"),
        "--fps",
        &fps,
        "--protocol",
        protocol,
    ]));
    let r = report(child);
    assert_eq!(r["input"]["malformed"], 0, "{r}");
    assert_eq!(r["input"]["dropped"], 0, "{r}");
    let sa = load_sequence(a.to_str().unwrap(), &Default::default()).unwrap();
    let sb = load_sequence(b.to_str().unwrap(), &Default::default()).unwrap();
    assert_eq!(sa.frame_count(), sb.frame_count(), "{r}");
    let worst = sa
        .all_positions()
        .iter()
        .zip(sb.all_positions())
        .map(|(p, q)| (0..3).map(|i| (p[i] - q[i]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    eprintln!(
        "{} frames over {protocol} and replayed: largest difference {worst:.2e} m",
        sa.frame_count()
    );
    (worst, r)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn bvh_over_tcp_round_trips_to_the_replay_frames() {
    let Some(_) = common::data_dir() else { return };
    let (worst, _) = round_trip("bvh", "--bvh-tcp");
    assert!(worst < 1e-4, "largest difference {worst} m");
}

/// VMC carries 32-bit floats: 1 mm is far above their rounding (~1e-7 m
/// at 2 m) and far below a different retrieval's (centimetres).
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn vmc_round_trips_to_the_replay_frames() {
    let Some(_) = common::data_dir() else { return };
    let (worst, _) = round_trip("vmc", "--vmc");
    assert!(worst < 1e-3, "largest difference {worst} m");
}

/// Rokoko's JSON carries full doubles: the frames are the replay's to
/// rounding.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn rokoko_round_trips_to_the_replay_frames() {
    let Some(_) = common::data_dir() else { return };
    let (worst, _) = round_trip("rokoko", "--rokoko");
    assert!(worst < 1e-6, "largest difference {worst} m");
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_malformed_line_and_a_reconnect_keep_the_session_alive() {
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let text = std::fs::read_to_string(d.join("mocap/cmu-bvh-altered/02_01.bvh")).unwrap();
    let at = text.find("Frame Time").unwrap();
    let end = at + text[at..].find('\n').unwrap() + 1;
    let (header, body) = text.split_at(end);
    let frames: Vec<&str> = body.lines().filter(|l| !l.trim().is_empty()).collect();
    let (child, port) = listen(&db, &[]);
    let send = |lines: &[&str], garbage: bool| {
        let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
        s.write_all(header.as_bytes()).unwrap();
        for (i, l) in lines.iter().enumerate() {
            if garbage && i == 10 {
                s.write_all(b"this is not a frame\n").unwrap();
            }
            s.write_all(l.as_bytes()).unwrap();
            s.write_all(b"\n").unwrap();
            std::thread::sleep(std::time::Duration::from_millis(8));
        }
    };
    send(&frames[..120], true);
    std::thread::sleep(std::time::Duration::from_millis(300));
    send(&frames[120..240], false);
    let r = report(child);
    assert_eq!(r["input"]["malformed"], 1, "{r}");
    assert_eq!(r["input"]["reconnects"], 1, "{r}");
    // Both connections drove the character (120 + 120 frames at 120 fps
    // taken at the database's rate).
    let out = r["frames_out"].as_u64().unwrap();
    assert!(out >= 55, "{out} frames out: {r}");
    eprintln!("{out} frames out, input {}", r["input"]);
}

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// A datagram made from `valid`: random bytes, or `valid` truncated, with
/// bytes changed, cut out or repeated.
fn garble(rng: &mut Rng, valid: &[u8]) -> Vec<u8> {
    let mut d = valid.to_vec();
    match rng.below(5) {
        0 => (0..rng.below(3000)).map(|_| rng.next() as u8).collect(),
        1 => {
            d.truncate(rng.below(valid.len()));
            d
        }
        2 => {
            for _ in 0..1 + rng.below(8) {
                let i = rng.below(d.len());
                d[i] = rng.next() as u8;
            }
            d
        }
        3 => {
            let (i, j) = (rng.below(d.len()), rng.below(d.len()));
            d.drain(i.min(j)..i.max(j));
            d
        }
        _ => {
            let i = rng.below(d.len());
            let piece = d[i..].to_vec();
            d.extend_from_slice(&piece);
            d
        }
    }
}

/// A standing pose (metres, Y-up, left on +X).
fn standing() -> surfmotion::pose::Pose {
    std::array::from_fn(|c| {
        let side = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, -1.0, -1.0, -1.0][..]
            .get(c)
            .copied()
            .unwrap_or(if c < 15 { 0.5 } else { -0.5 });
        glam::DVec3::new(0.2 * side * (1 + c % 3) as f64, 1.7 - 0.09 * c as f64, 0.0)
    })
}

/// 20,000 garbled datagrams through each protocol's reader and the stream
/// decoder: none panics, each is read or refused as malformed, and a valid
/// frame after them still reads.
#[test]
fn random_datagrams_are_refused_without_a_panic() {
    use surfmotion::live::humanoid::{BodyState, local_bones, world_bones};
    use surfmotion::live::mailbox::Mailbox;
    use surfmotion::live::rokoko::{self, Rokoko};
    use surfmotion::live::stream::{Decoder, Protocol, Read};
    use surfmotion::live::vmc::{self, Vmc};
    fn run<P: Protocol>(mut p: P, valid: &[u8], rng: &mut Rng) -> (usize, usize) {
        let mb = Mailbox::lossless();
        let mut dec = Decoder::new(30.0, Default::default());
        let mut st = BodyState::default();
        let (mut ok, mut bad) = (0, 0);
        for k in 0..20_000 {
            let d = garble(rng, valid);
            match p.read(&d, &mut st) {
                Ok(Read::Frame(t)) => {
                    ok += 1;
                    let t = t.unwrap_or(k as f64 / 60.0);
                    dec.frame::<P>(&st, t, std::time::Instant::now(), &mb);
                }
                Ok(Read::Partial) => ok += 1,
                Err(_) => bad += 1,
            }
        }
        assert_eq!(
            p.read(valid, &mut st),
            Ok(Read::Frame(Some(0.5))),
            "{}",
            P::NAME
        );
        eprintln!(
            "{}: {ok} read, {bad} malformed; stream counters {:?}",
            P::NAME,
            mb.counters()
        );
        (ok, bad)
    }
    let pose = standing();
    let world = world_bones(&pose, None);
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let v = vmc::encode_frame(&local_bones(&world), 0.5, Some(&pose)).unwrap();
    // About a fifth are random bytes, nearly all refused; a garbled float
    // or name still reads.
    let (_, bad) = run(Vmc::default(), &v, &mut rng);
    assert!(bad > 3_000, "{bad}");
    let r = rokoko::encode_frame(&world, 0.5, 60.0, Some(&pose)).unwrap();
    let (_, bad) = run(Rokoko::default(), &r, &mut rng);
    assert!(bad > 3_000, "{bad}");
}

/// Random datagrams sprayed at `live --vmc` / `--rokoko` before and while
/// a clip is sent: the session lives, counts them as malformed and still
/// drives the character with the clip. (UDP may lose some of a burst on a
/// busy machine, so not all 600 need arrive.)
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn a_flood_of_garbage_datagrams_keeps_the_session_alive() {
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let clip = d.join("mocap/cmu-bvh-altered/02_01.bvh");
    let fps = surfmotion::db::Manifest::load(&db).unwrap().fps.to_string();
    for (protocol, flag) in [("vmc", "--vmc"), ("rokoko", "--rokoko")] {
        let (child, port) = listen_on(&db, flag, &[]);
        let to = format!("127.0.0.1:{port}");
        let sock = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        let mut rng = Rng(7);
        let spray = |rng: &mut Rng, n: usize| {
            for _ in 0..n {
                let len = rng.below(1500);
                let d: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
                sock.send_to(&d, &to).unwrap();
            }
        };
        spray(&mut rng, 300);
        let mut sender = Command::new(bin())
            .args(["live", "send"])
            .arg(&clip)
            .args(["--to", &to, "--fps", &fps, "--protocol", protocol])
            .stdout(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(500));
        spray(&mut rng, 300);
        assert!(sender.wait().unwrap().success());
        let r = report(child);
        let malformed = r["input"]["malformed"].as_u64().unwrap();
        let out = r["frames_out"].as_u64().unwrap();
        eprintln!("{protocol}: {malformed} malformed of 600 sprayed, {out} frames out");
        assert!(malformed >= 100, "{r}");
        // 02_01 is 86 frames at the database's 30 fps.
        assert!(out >= 80, "{r}");
    }
}
