//! The stream inputs end to end through the binary: `live send` → `live
//! --bvh-tcp` over loopback gives the frames `live --replay` gives, and a
//! malformed line and a sender that disconnects and reconnects keep the
//! session alive and are reported.

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
#[allow(clippy::zombie_processes)]
fn listen(db: &Path, args: &[&str]) -> (Child, u16) {
    let mut child = Command::new(bin())
        .args(["live", "--db"])
        .arg(db)
        .args([
            "--bvh-tcp",
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
        if let Some(a) = line.trim().strip_prefix("listening for BVH over TCP on ") {
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

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn bvh_over_tcp_round_trips_to_the_replay_frames() {
    let Some(d) = common::data_dir() else { return };
    let db = common::synthetic_db(&d);
    let clip = d.join("mocap/cmu-bvh-altered/02_01.bvh");
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("replay.pc2"), tmp.path().join("tcp.pc2"));
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
    let (child, port) = listen(&db, &["--record", b.to_str().unwrap()]);
    common::run_ok(Command::new(bin()).args(["live", "send"]).arg(&clip).args([
        "--to",
        &format!("127.0.0.1:{port}"),
        "--fps",
        &fps,
    ]));
    let r = report(child);
    assert_eq!(r["input"]["malformed"], 0, "{r}");
    assert_eq!(r["input"]["dropped"], 0, "{r}");
    let sa = load_sequence(a.to_str().unwrap(), &Default::default()).unwrap();
    let sb = load_sequence(b.to_str().unwrap(), &Default::default()).unwrap();
    assert_eq!(sa.frame_count(), sb.frame_count());
    let worst = sa
        .all_positions()
        .iter()
        .zip(sb.all_positions())
        .map(|(p, q)| (0..3).map(|i| (p[i] - q[i]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    eprintln!(
        "{} frames over BVH/TCP and replayed: largest difference {worst:.2e} m",
        sa.frame_count()
    );
    assert!(worst < 1e-4, "largest difference {worst} m");
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
