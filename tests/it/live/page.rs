//! The live page in a real browser (headless Chromium driven over the
//! DevTools protocol, as `web::` does): `live --vmc --serve` streams a clip
//! sent by `live send` to the page; screenshots at two times differ where
//! the clip moves, and the page's draw rate is measured in the browser.

use crate::common;
use crate::web::{browser_or_skip, cdp, one_browser, shots_dir};
use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::time::Duration;

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_surfmotion")
}

/// Pixels (RGB) of a PNG.
fn pixels(path: &std::path::Path) -> (usize, usize, Vec<u8>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    let ch = info.color_type.samples();
    let (w, h) = (info.width as usize, info.height as usize);
    let rgb = buf[..w * h * ch]
        .chunks(ch)
        .flat_map(|p| [p[0], p[1], p[2]])
        .collect();
    (w, h, rgb)
}

/// Pixels that differ by more than 24 (any channel) between two shots, in
/// the left and the right half.
fn changed(a: &std::path::Path, b: &std::path::Path) -> (usize, usize) {
    let ((w, h, pa), (_, _, pb)) = (pixels(a), pixels(b));
    let (mut left, mut right) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let i = 3 * (y * w + x);
            if (0..3).any(|k| pa[i + k].abs_diff(pb[i + k]) > 24) {
                if x < w / 2 { left += 1 } else { right += 1 }
            }
        }
    }
    (left, right)
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_page_shows_the_character_moving_with_the_stream() {
    let Some(d) = common::data_dir() else { return };
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let _one = one_browser();
    let db = common::synthetic_db(&d);
    let clip = d.join("mocap/cmu-bvh-altered/05_06.bvh");
    let mut child = Command::new(bin())
        .args(["live", "--db"])
        .arg(&db)
        .args(["--vmc", "127.0.0.1:0", "--serve", "127.0.0.1:0"])
        // Every frame made (the stream's latency grows when the session is
        // slower than the clip, as on a loaded machine), so the page has
        // frames to draw for as long as the session runs.
        .args(["--until-idle", "4", "--lossless", "--json"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let (mut url, mut port) = (None, None);
    let mut line = String::new();
    while url.is_none() || port.is_none() {
        line.clear();
        assert!(err.read_line(&mut line).unwrap() > 0, "live exited early");
        if let Some(u) = line.trim().strip_prefix("live page at ") {
            url = Some(u.to_string());
        }
        if line.starts_with("listening for ") {
            port = line.trim().rsplit(':').next().map(String::from);
        }
    }
    std::thread::spawn(move || {
        let mut s = String::new();
        while err.read_line(&mut s).is_ok_and(|n| n > 0) {
            s.clear();
        }
    });
    let (url, port) = (url.unwrap(), port.unwrap());
    let mut b = cdp::Browser::launch(&browser);
    // A measurement knob: options for the page's address (e.g.
    // `antialias=1&scale=0.5`).
    let url = match std::env::var("SURFMOTION_LIVE_PAGE_QUERY") {
        Ok(q) if !q.is_empty() => format!("{url}?{q}"),
        _ => url,
    };
    b.navigate(&url);
    b.wait_for("window.live && live.meta", Duration::from_secs(60));
    let mut sender = Command::new(bin())
        .args(["live", "send"])
        .arg(&clip)
        .args(["--to", &format!("127.0.0.1:{port}"), "--protocol", "vmc"])
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let dir = shots_dir();
    let mut shots = Vec::new();
    let mut indices = Vec::new();
    // Under load the page may draw a frame a second: the second shot is
    // taken once the page has drawn 10 frames of the clip further on (or
    // the stream ended).
    let mut wait = "live.index >= 10 ? live.index : null".to_string();
    for k in 0..2 {
        b.wait_for(&wait, Duration::from_secs(90));
        let p = dir.join(format!("live-{k}.png"));
        b.screenshot(&p);
        // The frame drawn when the shot came back (a shot may take seconds
        // on a loaded machine).
        let idx = b.eval("live.index");
        wait = format!(
            "live.index >= {} || live.closed ? live.index : null",
            idx.as_u64().unwrap() + 10
        );
        indices.push(idx);
        shots.push(p);
    }
    // The draw rate apart from the screenshots' stalls: from after the
    // second shot to the stream's end.
    let after_shots = b.eval("({drawn: live.drawn, at: live.lastDrawAt})");
    assert!(sender.wait().unwrap().success());
    std::thread::sleep(Duration::from_millis(500));
    let clean = b.eval(&format!(
        "(live.drawn - {d}) / ((live.lastDrawAt - {t}) / 1000)",
        d = after_shots["drawn"].as_f64().unwrap_or(0.0),
        t = after_shots["at"].as_f64().unwrap_or(0.0)
    ));
    // The browser's animation-frame rate with nothing left to draw: the
    // most the page could draw at.
    let idle = b.eval(
        "new Promise(r => { let n = 0; const t0 = performance.now();
          const f = () => { n++; if (performance.now() - t0 < 1000) requestAnimationFrame(f);
            else r(n / ((performance.now() - t0) / 1000)); };
          requestAnimationFrame(f); })",
    );
    let st = b.eval(
        "({frames: live.frames, drawn: live.drawn, skipped: live.skipped, error: live.error,
          inRate: (live.frames - 1) / ((live.lastFrameAt - live.firstFrameAt) / 1000),
          drawRate: (live.drawn - 1) / ((live.lastDrawAt - live.firstDrawAt) / 1000),
          latencyMs: live.latencyMs, deliveryMs: live.deliveryMs, shownMs: live.shownMs,
          drawMs: live.drawMs, bytes: live.bytes, vertices: live.meta.vertices,
          outputFps: live.outputFps, antialias: live.antialias, renderer: live.renderer, together: live.together || 0})",
    );
    // The browser asks for a favicon the page does not have.
    let errors: Vec<String> = b
        .errors()
        .into_iter()
        .filter(|e| !e.contains("favicon.ico"))
        .collect();
    let (left, right) = changed(&shots[0], &shots[1]);
    eprintln!(
        "live page: {st}; drawn {clean} frames/s after the shots, animation frames {idle}/s idle; shots {shots:?} at frames {indices:?}: {left} character pixels and {right} skeleton pixels changed"
    );
    let out = child.wait_with_output().unwrap();
    assert!(out.status.success());
    assert!(errors.is_empty(), "console errors: {errors:?}");
    assert_eq!(st["error"], serde_json::Value::Null, "{st}");
    assert!(indices[1] != indices[0], "{indices:?}");
    // The character and the skeleton both moved between the shots.
    assert!(left > 500 && right > 200, "{left} / {right} pixels changed");
    // Positions quantised: 6 bytes a vertex after the header.
    let n = st["vertices"].as_u64().unwrap();
    assert_eq!(st["bytes"].as_u64(), Some(52 + 12 * 19 + 6 * n), "{st}");
    // Opened from disk, the page says it needs the server.
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/web/assets/live.html");
    b.navigate(&format!("file://{}", file.display()));
    let said = b.wait_for(
        "window.live && live.error ? document.getElementById('stats').textContent : null",
        Duration::from_secs(30),
    );
    b.screenshot(&dir.join("live-from-disk.png"));
    assert!(
        said.as_str()
            .is_some_and(|t| t.contains("needs the live server")),
        "{said}"
    );
}
