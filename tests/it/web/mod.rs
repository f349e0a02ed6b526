//! The web viewer (issue 22): the exported geometry decodes within the
//! error bound and the page's transition table is the graph's; the server
//! keeps to the site folder; and in a real headless Chromium the page gets
//! a WebGL2 context, draws the character, follows a motion key, logs no
//! error, and shows a message (not a blank page) for corrupt data.

use crate::common;

use base64::Engine as _;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;
use surfmotion::web::{self, ExportOptions, SiteManifest, SiteServer, codec};

mod pick;

/// The procedural demo database (no files needed), made once.
fn demo_db() -> PathBuf {
    use std::sync::OnceLock;
    static DB: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    DB.get_or_init(|| {
        let tmp = common::fixture_dir("web-demo");
        common::run_ok(
            Command::new(common::bin())
                .arg("demo")
                .arg("-o")
                .arg(tmp.join("demo")),
        );
        let db = tmp.join("demo/database");
        (tmp, db)
    })
    .1
    .clone()
}

fn manifest(site: &Path) -> SiteManifest {
    serde_json::from_str(&std::fs::read_to_string(site.join("manifest.json")).unwrap()).unwrap()
}

/// Decodes a site's geometry and checks it against the database: every
/// vertex within `bound` metres; returns the largest error.
fn check_round_trip(db: &Path, site: &Path, bound: f64) -> f64 {
    let (_, g, graph) = web::load_db_geometry(db).unwrap();
    let d = codec::decode(&std::fs::read(site.join("character.sm4d")).unwrap()).unwrap();
    assert_eq!(d.triangles, g.triangles);
    // The database's sequences first, then what the export adds (blended
    // transition windows, space references).
    let m = manifest(site);
    assert_eq!(d.sequences.len(), m.geometry_sequences);
    assert!(d.sequences.len() >= g.sequences.len());
    let mut worst = 0f64;
    for (a, b) in g.sequences.iter().zip(&d.sequences) {
        assert_eq!(a.len(), b.len());
        for (p, q) in a.iter().zip(b) {
            let r = d.position(*q);
            let e: f64 = (0..3).map(|c| ((r[c] - p[c]) as f64).powi(2)).sum();
            worst = worst.max(e.sqrt());
        }
    }
    assert!(worst <= bound, "max vertex error {worst} m > {bound} m");
    // The page's transition table is the graph's, in the graph's order.
    let page: Vec<_> = m
        .transitions
        .iter()
        .map(|t| (t.from, t.to, t.m, t.n, t.window))
        .collect();
    let graph: Vec<_> = graph
        .transitions()
        .iter()
        .map(|t| (t.from, t.to, t.m, t.n, t.window))
        .collect();
    assert_eq!(page, graph);
    assert!(
        !page.is_empty(),
        "a database without transitions tests nothing"
    );
    worst
}

#[test]
fn exported_demo_geometry_round_trips_within_the_bound_and_keeps_the_graph() {
    let db = demo_db();
    let tmp = tempfile::tempdir().unwrap();
    for mm in [1.0, 0.2] {
        let site = tmp.path().join(format!("site{mm}"));
        let mut opts = ExportOptions::default();
        opts.codec.max_error = mm * 1e-3;
        let r = web::export_db(&db, &site, &opts).unwrap();
        let worst = check_round_trip(&db, &site, mm * 1e-3);
        // The codec's figure also covers the blended transition windows.
        assert!(worst <= r.geometry.max_error + 1e-7);
        assert!(r.geometry.bytes * 4 < r.raw_bytes, "{r:?}");
    }
    // An export replaces an earlier one; a folder of other files is kept.
    let site = tmp.path().join("site1");
    web::export_db(&db, &site, &ExportOptions::default()).unwrap();
    let other = tmp.path().join("mine");
    std::fs::create_dir_all(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "keep").unwrap();
    assert!(web::export_db(&db, &other, &ExportOptions::default()).is_err());
    assert_eq!(
        std::fs::read_to_string(other.join("notes.txt")).unwrap(),
        "keep"
    );
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn samba_geometry_is_under_2mb_at_1mm() {
    let Some(d) = common::data_dir() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let db = tmp.path().join("samba");
    let st = Command::new(common::bin())
        .args(["db", "init"])
        .arg(&db)
        .arg("--mesh")
        .arg(d.join("4d/samba/samba.obj"))
        .arg("--sequence")
        .arg(format!("dance={}", d.join("4d/samba/samba.pc2").display()))
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let site = tmp.path().join("site");
    let r = web::export_db(&db, &site, &ExportOptions::default()).unwrap();
    assert_eq!(r.geometry.frames - r.transition_frames, 175);
    // The capture itself; the precomputed transition windows come on top.
    let capture = r.geometry.bytes - r.transition_bytes;
    assert!(capture <= 2_000_000, "{capture} bytes");
    check_round_trip(&db, &site, 1e-3);
}

fn http_status(addr: &str, path: &str) -> u16 {
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut resp = String::new();
    let _ = s.read_to_string(&mut resp);
    resp.split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0)
}

/// A client that stops reading a large response (its socket buffers full)
/// does not hold up the other requests: with one serving thread the page's
/// `manifest.json` once never arrived.
#[test]
fn server_answers_while_another_response_is_stalled() {
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    std::fs::create_dir_all(&site).unwrap();
    std::fs::write(site.join("index.html"), "x").unwrap();
    std::fs::write(site.join("big.bin"), vec![7u8; 48 << 20]).unwrap();
    let server = SiteServer::bind(&site, "127.0.0.1:0").unwrap();
    let addr = server
        .url()
        .trim_start_matches("http://")
        .trim_end_matches('/')
        .to_string();
    server.spawn();
    // Ask for the big file and never read it.
    let mut stalled = std::net::TcpStream::connect(&addr).unwrap();
    write!(stalled, "GET /big.bin HTTP/1.1\r\nHost: x\r\n\r\n").unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let (tx, rx) = std::sync::mpsc::channel();
    let a = addr.clone();
    std::thread::spawn(move || {
        let _ = tx.send(http_status(&a, "/index.html"));
    });
    assert_eq!(rx.recv_timeout(Duration::from_secs(20)), Ok(200));
    drop(stalled);
}

#[test]
fn server_refuses_paths_outside_the_site() {
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    std::fs::create_dir_all(&site).unwrap();
    std::fs::write(site.join("index.html"), "<p>hi</p>").unwrap();
    std::fs::write(tmp.path().join("secret.txt"), "no").unwrap();
    let server = SiteServer::bind(&site, "127.0.0.1:0").unwrap();
    let url = server.url();
    let addr = url
        .trim_start_matches("http://")
        .trim_end_matches('/')
        .to_string();
    server.spawn();
    assert_eq!(http_status(&addr, "/"), 200);
    assert_eq!(http_status(&addr, "/index.html"), 200);
    let abs = format!("{}", tmp.path().join("secret.txt").display());
    for bad in [
        "/../secret.txt",
        "/%2e%2e/secret.txt",
        "/%2E%2E%2fsecret.txt",
        "/..%2fsecret.txt",
        abs.as_str(),
        &format!("/{abs}"),
        &format!("/%2f{}", abs.trim_start_matches('/')),
    ] {
        assert_eq!(http_status(&addr, bad), 404, "{bad}");
    }
}

#[test]
fn serving_a_folder_that_is_no_site_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    for dir in [tmp.path().join("missing"), tmp.path().to_path_buf()] {
        // A server that starts would run forever: give it 10 s.
        let mut child = Command::new(common::bin())
            .args(["web", "serve", "--port", "0", "--site"])
            .arg(&dir)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let t = std::time::Instant::now();
        while child.try_wait().unwrap().is_none() {
            if t.elapsed().as_secs() > 10 {
                child.kill().unwrap();
                panic!("{}: served a folder that is no site", dir.display());
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        let o = child.wait_with_output().unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{e}");
        assert!(e.contains("not an exported site"), "{e}");
        assert_eq!(e.trim_end().lines().count(), 1, "{e}");
    }
}

/// The browser: `$SURFMOTION_CHROMIUM`, else `chromium` or
/// `chromium-browser` on the PATH.
pub(crate) fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("SURFMOTION_CHROMIUM") {
        return Some(p.into());
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|d| ["chromium", "chromium-browser"].map(|n| d.join(n)))
        .find(|p| p.is_file())
}

/// A database of the demo humanoid walking and running (procedural
/// clips, 3 s each, as tests/parametric.rs) with one parametric space
/// `locomotion = [walk, run]` steered by speed and turn; made once.
fn gaits_db() -> PathBuf {
    use std::sync::OnceLock;
    use surfmotion::jobs::SynthCharacter;
    use surfmotion::synth::Gait;
    static DB: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    DB.get_or_init(|| {
        let tmp = common::fixture_dir("web-gaits");
        let db = tmp.join("db");
        common::gaits::gaits_database(
            &db,
            &SynthCharacter::humanoid().unwrap(),
            &[Gait::Walk, Gait::Run],
            "gaits",
            &[("locomotion", &["walk", "run"], &["speed", "turn"])],
        );
        (tmp, db)
    })
    .1
    .clone()
}

fn max_dist(a: &[[f32; 3]], b: &[[f32; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            (0..3)
                .map(|c| ((p[c] - q[c]) as f64).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(0.0, f64::max)
}

/// The export carries what the page needs to play a parametric space
/// (Casas et al. 2013): every stored reference block of the hybrid blend,
/// decoded within the bound, the parameter map and its valid ranges.
#[test]
fn exported_space_carries_the_hybrid_references_and_parameter_map() {
    use surfmotion::parametric::{MotionOptions, store::load_or_build};
    let db = gaits_db();
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    let r = web::export_db(&db, &site, &ExportOptions::default()).unwrap();
    let (motion, _) = load_or_build(&db, &MotionOptions::default(), false).unwrap();
    let m = manifest(&site);
    assert_eq!(m.spaces.len(), 1);
    let (sp, model) = (&m.spaces[0], &motion.spaces[0]);
    assert_eq!(sp.name, "locomotion");
    assert_eq!(sp.parameters, ["speed", "turn"]);
    assert_eq!(sp.grid, model.grid());
    assert_eq!(sp.axis.as_ref(), model.axis());
    let range = sp.ranges[0];
    assert!(range[1] - range[0] > 0.5, "speed range {range:?}");
    assert_eq!(r.spaces, 1);
    assert_eq!(r.space_frames, model.blend().blocks.len() * model.grid());
    let d = codec::decode(&std::fs::read(site.join("character.sm4d")).unwrap()).unwrap();
    assert_eq!(d.sequences.len(), m.geometry_sequences);
    let n = d.vertices;
    let mut checked = 0;
    for (pair, mp) in sp.pairs.iter().zip(&model.blend().pairs) {
        assert_eq!(pair.weights, mp.weights);
        for (&g, &b) in pair.blocks.iter().zip(&mp.blocks) {
            let got: Vec<[f32; 3]> = d.sequences[g].iter().map(|q| d.position(*q)).collect();
            let want: Vec<[f32; 3]> = model.blend().blocks[b]
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect();
            assert_eq!(got.len(), sp.grid * n);
            let e = max_dist(&got, &want);
            assert!(e <= 1e-3 + 1e-6, "block {b}: {e} m");
            checked += 1;
        }
    }
    assert!(checked >= 3, "{checked} blocks");
}

/// Each transition's window is precomputed as the non-linear blend (Huang
/// et al. 2015, Sec. 4.4): it starts at the source's frame and ends at the
/// aligned target's (within the bound and the blender's reconstruction),
/// and differs from the linear blend in between.
#[test]
fn exported_transitions_carry_precomputed_nonlinear_windows() {
    let db = demo_db();
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    let r = web::export_db(&db, &site, &ExportOptions::default()).unwrap();
    let m = manifest(&site);
    let d = codec::decode(&std::fs::read(site.join("character.sm4d")).unwrap()).unwrap();
    let pos = |s: usize, f: usize| -> Vec<[f32; 3]> {
        d.sequences[s][f * d.vertices..(f + 1) * d.vertices]
            .iter()
            .map(|q| d.position(*q))
            .collect()
    };
    let aligned = |p: Vec<[f32; 3]>, a: [f64; 4]| -> Vec<[f32; 3]> {
        p.iter()
            .map(|q| {
                let (x, z) = (q[0] as f64, q[2] as f64);
                [
                    (a[0] * x + a[1] * z + a[2]) as f32,
                    q[1],
                    (-a[1] * x + a[0] * z + a[3]) as f32,
                ]
            })
            .collect()
    };
    let mut frames = 0;
    let mut largest_gap: f64 = 0.0;
    for t in &m.transitions {
        let w = t
            .blended
            .expect("every transition has its window precomputed");
        let l = t.window;
        assert_eq!(d.sequences[w].len(), (2 * l + 1) * d.vertices);
        frames += 2 * l + 1;
        let clamp = |s: usize, f: isize| f.clamp(0, m.sequences[s].frames as isize - 1) as usize;
        let a = pos(t.from, clamp(t.from, t.m as isize - l as isize));
        let b = aligned(pos(t.to, clamp(t.to, (t.n + l) as isize)), t.align);
        assert!(max_dist(&pos(w, 0), &a) < 3e-3, "{t:?}");
        assert!(max_dist(&pos(w, 2 * l), &b) < 3e-3, "{t:?}");
        if l > 0 {
            let ma = pos(t.from, clamp(t.from, t.m as isize));
            let mb = aligned(pos(t.to, t.n), t.align);
            let lin: Vec<[f32; 3]> = ma
                .iter()
                .zip(&mb)
                .map(|(p, q)| std::array::from_fn(|c| 0.5 * (p[c] + q[c])))
                .collect();
            largest_gap = largest_gap.max(max_dist(&pos(w, l), &lin));
        }
    }
    assert_eq!(r.transition_frames, frames);
    assert!(r.transition_bytes > 0);
    eprintln!(
        "{} transitions, {frames} blended frames, {} bytes ({:.1} % of {}), largest non-linear − linear gap {:.1} mm, {:.2} s",
        m.transitions.len(),
        r.transition_bytes,
        100.0 * r.transition_bytes as f64 / r.geometry.bytes as f64,
        r.geometry.bytes,
        largest_gap * 1e3,
        r.transition_seconds
    );
    assert!(
        largest_gap > 2e-3,
        "the window is the linear blend: {largest_gap} m"
    );
    // --linear-transitions leaves them to the page.
    let lin = tmp.path().join("linear");
    let opts = ExportOptions {
        linear_transitions: true,
        ..Default::default()
    };
    let r2 = web::export_db(&db, &lin, &opts).unwrap();
    assert!(
        manifest(&lin)
            .transitions
            .iter()
            .all(|t| t.blended.is_none())
    );
    assert!(r2.geometry.bytes < r.geometry.bytes);
}

/// The export's window blend (each database frame decomposed once, the
/// alignment applied to the decomposition) gives the frames the per-frame
/// [`web::windows::blend_windows_per_frame`] gives, with the default cache
/// budget (whole groups per batch) and with a budget of one window per
/// batch.
#[test]
fn fast_window_blend_matches_the_per_frame_blender() {
    let db = demo_db();
    let (_, g, graph) = web::load_db_geometry(&db).unwrap();
    let table = web::export::transition_table(&graph, &g);
    assert!(table.len() >= 2, "{} transitions", table.len());
    assert!(
        table.iter().any(|t| t.align[1].abs() > 1e-3),
        "no transition turns the target: the analytic alignment is untested"
    );
    let want = web::windows::blend_windows_per_frame(&g, &table).unwrap();
    for cache_bytes in [web::WindowOptions::default().cache_bytes, 1] {
        let got = web::blend_windows(&g, &table, &web::WindowOptions { cache_bytes }).unwrap();
        assert_eq!(got.len(), want.len());
        let mut worst: f64 = 0.0;
        for (a, b) in got.iter().zip(&want) {
            assert_eq!(a.len(), b.len());
            worst = worst.max(max_dist(a, b));
        }
        eprintln!("cache {cache_bytes} B: largest difference {:.2e} m", worst);
        assert!(worst < 1e-6, "cache {cache_bytes} B: {worst} m");
    }
}

/// In a real browser: pressing the space's key enters the parametric
/// space, and moving the speed slider changes the speed the engine
/// achieves (root path per second) to the one asked.
#[test]
fn browser_speed_slider_drives_the_achieved_speed() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let _one = one_browser();
    let db = gaits_db();
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    web::export_db(&db, &site, &ExportOptions::default()).unwrap();
    let range = manifest(&site).spaces[0].ranges[0];
    let server = SiteServer::bind(tmp.path(), "127.0.0.1:0").unwrap();
    let url = server.url();
    server.spawn();
    let mut b = cdp::Browser::launch(&browser);
    let r = run_page(&mut b, &format!("{url}site/index.html?selftest=1"));
    assert_eq!(r["ok"], true, "{r}");
    assert_eq!(
        b.eval("surfmotion.engine.state().space"),
        serde_json::Value::Null
    );
    b.key("q");
    let st = b.eval("surfmotion.engine.state()");
    assert_eq!(st["space"]["name"], "locomotion", "{st}");
    assert_eq!(b.eval("document.getElementById('sliders').hidden"), false);
    let mut achieved = Vec::new();
    for (i, f) in [0.1, 0.9].into_iter().enumerate() {
        let v = range[0] + f * (range[1] - range[0]);
        let st = b.eval(&format!(
            "(() => {{ const s = document.getElementById('speed'); s.value = {v}; s.dispatchEvent(new Event('input'));
               for (let i = 0; i < 90; i++) surfmotion.step(1, false);
               surfmotion.step(0, true); return surfmotion.engine.state(); }})()"
        ));
        let sp = &st["space"];
        let asked = sp["speedAsked"].as_f64().unwrap();
        let got = sp["achievedSpeed"].as_f64().unwrap();
        eprintln!(
            "slider at {f}: asked {asked:.3} m/s, achieved {got:.3} m/s, u {:.3}",
            sp["u"]
        );
        assert!((asked - v).abs() < 0.02 * v, "{st}");
        assert!((got - asked).abs() < 0.08 * asked, "{st}");
        achieved.push(got);
        let shot = shots_dir().join(format!("gaits-slider-{i}.png"));
        b.screenshot(&shot);
        eprintln!("screenshot {}", shot.display());
    }
    assert!(
        achieved[1] - achieved[0] > 0.5 * (range[1] - range[0]),
        "{achieved:?} over {range:?}"
    );
    // Leaving the space for a motion of the graph.
    b.key("1");
    let st = b.eval("surfmotion.engine.state()");
    assert_eq!(st["space"], serde_json::Value::Null, "{st}");
    assert_eq!(st["sequence"], "walk");
    let errors = b.errors();
    assert!(errors.is_empty(), "console errors: {errors:?}");
}

/// A headless Chromium driven from outside through the DevTools protocol
/// (a websocket to `--remote-debugging-port`): navigation, key presses
/// (`Input.dispatchKeyEvent`), evaluation, screenshots, and the console
/// errors and exceptions the page raised (`Runtime.consoleAPICalled`,
/// `Runtime.exceptionThrown`, `Log.entryAdded`).
pub(crate) mod cdp {
    use serde_json::{Value, json};
    use std::io::{Read, Write};
    use std::net::TcpStream;
    use std::path::Path;
    use std::process::{Child, Command, Stdio};
    use std::time::{Duration, Instant};
    use tungstenite::stream::MaybeTlsStream;

    pub struct Browser {
        child: Child,
        _profile: tempfile::TempDir,
        ws: tungstenite::WebSocket<MaybeTlsStream<TcpStream>>,
        next: u64,
        events: Vec<Value>,
    }

    fn http_get(port: u16, path: &str) -> String {
        let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
        write!(
            s,
            "GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nConnection: close\r\n\r\n"
        )
        .unwrap();
        // The DevTools server may keep the connection open: read the
        // headers, then Content-Length bytes.
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        let mut buf = Vec::new();
        let mut chunk = [0u8; 4096];
        loop {
            let text = String::from_utf8_lossy(&buf).into_owned();
            if let Some((head, body)) = text.split_once("\r\n\r\n") {
                let len = head
                    .lines()
                    .find_map(|l| {
                        let (k, v) = l.split_once(':')?;
                        k.eq_ignore_ascii_case("content-length")
                            .then(|| v.trim().parse::<usize>().ok())?
                    })
                    .unwrap_or(usize::MAX);
                if body.len() >= len {
                    return body[..len].to_string();
                }
            }
            match s.read(&mut chunk) {
                Ok(0) | Err(_) => {
                    return text
                        .split_once("\r\n\r\n")
                        .map(|x| x.1.to_string())
                        .unwrap_or(text);
                }
                Ok(k) => buf.extend_from_slice(&chunk[..k]),
            }
        }
    }

    impl Browser {
        pub fn launch(bin: &Path) -> Browser {
            let profile = tempfile::tempdir().unwrap();
            let child = Command::new(bin)
                .args([
                    "--headless",
                    "--no-sandbox",
                    "--use-angle=swiftshader",
                    "--enable-unsafe-swiftshader",
                    "--no-first-run",
                    "--disable-extensions",
                    "--window-size=800,600",
                    "--remote-debugging-port=0",
                ])
                .arg(format!("--user-data-dir={}", profile.path().display()))
                .arg("about:blank")
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .spawn()
                .unwrap();
            // Chromium writes the port it picked into the profile.
            let t0 = Instant::now();
            let port = loop {
                let f = profile.path().join("DevToolsActivePort");
                if let Some(p) = std::fs::read_to_string(&f)
                    .ok()
                    .and_then(|t| t.lines().next().and_then(|l| l.trim().parse::<u16>().ok()))
                {
                    break p;
                }
                assert!(
                    t0.elapsed() < Duration::from_secs(30),
                    "chromium opened no DevTools port within 30 s"
                );
                std::thread::sleep(Duration::from_millis(50));
            };
            let url = loop {
                let list: Value = serde_json::from_str(&http_get(port, "/json/list")).unwrap();
                if let Some(u) = list.as_array().and_then(|a| {
                    a.iter()
                        .find(|t| t["type"] == "page")
                        .and_then(|t| t["webSocketDebuggerUrl"].as_str().map(String::from))
                }) {
                    break u;
                }
                assert!(t0.elapsed() < Duration::from_secs(30), "no page target");
                std::thread::sleep(Duration::from_millis(50));
            };
            let (ws, _) = tungstenite::connect(url.as_str()).unwrap();
            if let MaybeTlsStream::Plain(s) = ws.get_ref() {
                s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
            }
            let mut b = Browser {
                child,
                _profile: profile,
                ws,
                next: 0,
                events: Vec::new(),
            };
            for m in ["Runtime.enable", "Log.enable", "Page.enable"] {
                b.call(m, json!({}));
            }
            b
        }

        /// Sends a command and waits for its answer; events that arrive
        /// meanwhile are kept.
        pub fn call(&mut self, method: &str, params: Value) -> Value {
            self.next += 1;
            let id = self.next;
            if std::env::var_os("SURFMOTION_CDP_TRACE").is_some() {
                eprintln!("cdp {id} {method} {params}");
            }
            let msg = json!({"id": id, "method": method, "params": params});
            self.ws
                .send(tungstenite::Message::text(msg.to_string()))
                .unwrap();
            loop {
                let m = self.ws.read().unwrap_or_else(|e| panic!("{method}: {e}"));
                let tungstenite::Message::Text(t) = m else {
                    continue;
                };
                let v: Value = serde_json::from_str(t.as_str()).unwrap();
                if v["id"] == id {
                    assert!(v["error"].is_null(), "{method}: {}", v["error"]);
                    return v["result"].clone();
                }
                if v["method"].is_string() {
                    self.events.push(v);
                }
            }
        }

        /// Evaluates an expression in the page (promises awaited) and
        /// returns its value.
        pub fn eval(&mut self, expr: &str) -> Value {
            let r = self.call(
                "Runtime.evaluate",
                json!({"expression": expr, "returnByValue": true, "awaitPromise": true}),
            );
            assert!(
                r["exceptionDetails"].is_null(),
                "{expr}: {}",
                r["exceptionDetails"]
            );
            r["result"]["value"].clone()
        }

        pub fn navigate(&mut self, url: &str) {
            self.call("Page.navigate", json!({ "url": url }));
        }

        /// Polls `expr` until it is neither null nor undefined, at most
        /// `limit` (`None` then).
        pub fn poll(&mut self, expr: &str, limit: Duration) -> Option<Value> {
            let t0 = Instant::now();
            loop {
                let v = self.eval(expr);
                if !v.is_null() {
                    return Some(v);
                }
                if t0.elapsed() > limit {
                    return None;
                }
                std::thread::sleep(Duration::from_millis(50));
            }
        }

        /// Polls `expr` until it is neither null nor undefined.
        pub fn wait_for(&mut self, expr: &str, limit: Duration) -> Value {
            let t0 = Instant::now();
            loop {
                let v = self.eval(expr);
                if !v.is_null() {
                    return v;
                }
                if t0.elapsed() > limit {
                    let page = self.eval(
                        "JSON.stringify({ready: window.surfmotion && surfmotion.ready, error: window.surfmotion && surfmotion.error, status: (document.getElementById('status') || {}).textContent})",
                    );
                    let errors = self.errors();
                    panic!("waited {limit:?} for {expr}; page {page}; errors {errors:?}");
                }
                std::thread::sleep(Duration::from_millis(50));
            }
        }

        /// Presses and releases a printable key as a user would.
        pub fn key(&mut self, key: &str) {
            let c = key.chars().next().unwrap();
            let (code, vk) = if c.is_ascii_digit() {
                (format!("Digit{c}"), c as u32)
            } else {
                (
                    format!("Key{}", c.to_ascii_uppercase()),
                    c.to_ascii_uppercase() as u32,
                )
            };
            for t in ["keyDown", "keyUp"] {
                let mut p =
                    json!({"type": t, "key": key, "code": code, "windowsVirtualKeyCode": vk});
                if t == "keyDown" {
                    p["text"] = json!(key);
                }
                self.call("Input.dispatchKeyEvent", p);
            }
        }

        /// A PNG of the whole page (canvas and controls).
        pub fn screenshot(&mut self, path: &Path) {
            use base64::Engine as _;
            let r = self.call("Page.captureScreenshot", json!({"format": "png"}));
            let png = base64::engine::general_purpose::STANDARD
                .decode(r["data"].as_str().unwrap())
                .unwrap();
            std::fs::write(path, png).unwrap();
        }

        /// Console errors, assertion failures, uncaught exceptions and
        /// error log entries so far.
        pub fn errors(&mut self) -> Vec<String> {
            self.eval("0");
            self.events
                .iter()
                .filter_map(|e| {
                    let p = &e["params"];
                    match e["method"].as_str()? {
                        "Runtime.consoleAPICalled"
                            if matches!(p["type"].as_str(), Some("error" | "assert")) =>
                        {
                            Some(format!("console.{}: {}", p["type"], p["args"]))
                        }
                        "Runtime.exceptionThrown" => {
                            Some(format!("exception: {}", p["exceptionDetails"]))
                        }
                        "Log.entryAdded" if p["entry"]["level"] == "error" => {
                            Some(format!("log: {}", p["entry"]))
                        }
                        _ => None,
                    }
                })
                .collect()
        }

        pub fn clear_events(&mut self) {
            self.eval("0");
            self.events.clear();
        }
    }

    impl Drop for Browser {
        fn drop(&mut self) {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// Loads a page with `?selftest=1` and waits for the page's self-test
/// (draw checks and timings), at most 90 s.
fn run_page(b: &mut cdp::Browser, url: &str) -> serde_json::Value {
    let done = "window.surfmotion && window.surfmotion.selftest || null";
    b.navigate(url);
    if let Some(v) = b.poll(done, Duration::from_secs(90)) {
        return v;
    }
    // Headless Chromium with software GL has, rarely, left a page without
    // its self-test (once in five full CI runs, never twice in a row; seen
    // again 2026-11-24 on the corrupt-data site, once in six runs at load
    // 10: document complete, inline start and app.js run, `surfmotion`
    // defined, so app.js's `main` was waiting on a promise that never
    // settled, not "no module run"). Load it once more before failing.
    // What the page got, for the next time it happens: which resources
    // arrived (status, bytes, when), whether the inline start and the
    // module ran.
    let state = b.eval(
        "JSON.stringify({ready: document.readyState, boot: !!window.surfmotionBoot, app: !!window.surfmotion,
           stages: window.surfmotion && surfmotion.stats.stages, error: window.surfmotion && surfmotion.error,
           scripts: [...document.scripts].map((s) => s.src || 'inline'),
           resources: performance.getEntriesByType('resource').map((e) => [e.name.split('/').pop(), e.responseStatus, e.transferSize, Math.round(e.startTime), Math.round(e.responseEnd)])})",
    );
    eprintln!("{url}: page not started after 90 s ({state}); loading it once more");
    b.navigate(url);
    b.wait_for(done, Duration::from_secs(90))
}

pub(crate) fn shots_dir() -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("web-shots");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn save_shots(r: &serde_json::Value, name: &str) -> Vec<PathBuf> {
    let dir = shots_dir();
    let mut out = Vec::new();
    for (i, s) in r["shots"].as_array().into_iter().flatten().enumerate() {
        let b64 = s.as_str().unwrap().split(',').nth(1).unwrap();
        let png = base64::engine::general_purpose::STANDARD
            .decode(b64)
            .unwrap();
        let p = dir.join(format!("{name}-{i}.png"));
        std::fs::write(&p, png).unwrap();
        out.push(p);
    }
    out
}

/// The browser tests run one at a time: three software-GL browsers at once
/// on 2 cores starve each other past the page's time limits.
static ONE_BROWSER: std::sync::Mutex<()> = std::sync::Mutex::new(());

pub(crate) fn one_browser() -> std::sync::MutexGuard<'static, ()> {
    ONE_BROWSER.lock().unwrap_or_else(|e| e.into_inner())
}

/// The browser, or `None` (skip) outside CI.
pub(crate) fn browser_or_skip() -> Option<PathBuf> {
    let b = chromium();
    if b.is_none() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true and no chromium installed (.ci/run installs it)"
        );
        eprintln!("SKIPPED: no chromium on the PATH (apt-get install chromium)");
    }
    b
}

#[test]
fn browser_draws_the_character_follows_keys_and_reports_corrupt_data() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let _one = one_browser();
    let db = demo_db();
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    web::export_db(&db, &site, &ExportOptions::default()).unwrap();
    let bad = tmp.path().join("bad");
    web::export_db(&db, &bad, &ExportOptions::default()).unwrap();
    let geo = std::fs::read(bad.join("character.sm4d")).unwrap();
    std::fs::write(bad.join("character.sm4d"), &geo[..geo.len() / 2]).unwrap();
    let server = SiteServer::bind(tmp.path(), "127.0.0.1:0").unwrap();
    let url = server.url();
    server.spawn();

    let mut b = cdp::Browser::launch(&browser);
    let r = run_page(&mut b, &format!("{url}site/index.html?selftest=1&shots=1"));
    let shots = save_shots(&r, "demo");
    eprintln!("page stages (ms since navigation): {}", r["stages"]);
    eprintln!(
        "page: load {:.0} ms (fetch {:.0}, decode {:.0}), engine {:.3} ms/frame (max {:.3}; tick alone {:.4}), GL {:.2} ms/frame (mean), shots {shots:?}",
        r["loadMs"].as_f64().unwrap_or(-1.0),
        r["fetchMs"].as_f64().unwrap_or(-1.0),
        r["decodeMs"].as_f64().unwrap_or(-1.0),
        r["engineMsMean"].as_f64().unwrap_or(-1.0),
        r["engineMsMax"].as_f64().unwrap_or(-1.0),
        r["engineTickMs"].as_f64().unwrap_or(-1.0),
        r["glMsMean"].as_f64().unwrap_or(-1.0),
    );
    assert_eq!(r["ok"], true, "{r}");
    // The engine in the page walks the graph's own transition table.
    let (_, _, graph) = web::load_db_geometry(&db).unwrap();
    let table: Vec<[usize; 5]> = graph
        .transitions()
        .iter()
        .map(|t| [t.from, t.to, t.m, t.n, t.window])
        .collect();
    assert_eq!(r["engineTransitions"], serde_json::json!(table));
    assert_eq!(r["webgl2"], true);
    let px = &r["characterPixels"];
    assert!(
        px[0].as_u64().unwrap() > 500 && px[1].as_u64().unwrap() > 500,
        "{px}"
    );
    assert!(
        r["diffPixels"].as_u64().unwrap() > 50,
        "frames identical: {r}"
    );
    // The key for the other motion, pressed through the DevTools protocol:
    // the engine queues it and moves into it by a graph transition (it
    // starts in the first sequence), playing the transition's precomputed
    // non-linear window.
    let before = b.eval("surfmotion.engine.state()");
    let names: Vec<String> = manifest(&site)
        .sequences
        .iter()
        .map(|s| s.name.clone())
        .collect();
    let target = names.iter().position(|n| *n != before["sequence"]).unwrap() + 1;
    b.key(&target.to_string());
    let queued = b.eval("surfmotion.engine.state().queue");
    assert_eq!(queued, serde_json::json!([names[target - 1]]), "{before}");
    let run = b.eval(
        "(() => { const e = surfmotion.engine, s0 = e.state().sequence, base = surfmotion.manifest.sequences.length;
           let n = 0, blended = 0, mid = null;
           while (n < 3000 && e.state().sequence === s0) {
             surfmotion.step(1, false); n++;
             const st = e.state();
             if (st.blending && st.shown.part >= base) { blended++; if (!mid && st.shown.frame >= 2) mid = n; }
           }
           const after = e.state();
           for (let i = 0; i < 300; i++) e.tick();
           return { n, blended, after, later: e.state() }; })()",
    );
    let after = &run["after"];
    assert_ne!(after["sequence"], before["sequence"], "{after}");
    assert_eq!(after["lastTransition"]["kind"], "transition", "{after}");
    assert_eq!(after["lastTransition"]["to"], after["sequence"]);
    assert!(
        run["blended"].as_u64().unwrap() > 0,
        "no precomputed blended frame was shown: {run}"
    );
    assert!(run["later"]["ticks"].as_u64().unwrap() > 300);
    // A picture during a transition: play on to the next one and stop in it.
    b.eval(
        "(() => { const e = surfmotion.engine; let n = 0;
           while (n < 3000 && !(e.blend && e.blend.i >= 2)) { surfmotion.step(1, false); n++; }
           surfmotion.step(0, true); return n; })()",
    );
    // The status line names the window it shows (it said "block 7").
    let status = b.eval("document.getElementById('status').textContent");
    let status = status.as_str().unwrap_or_default();
    assert!(
        status.starts_with("transition ") && status.contains(", window frame "),
        "{status}"
    );
    let shot = shots_dir().join("demo-transition.png");
    b.screenshot(&shot);
    eprintln!("transition screenshot {}", shot.display());
    let engine_ms = r["engineMsMean"].as_f64().unwrap();
    assert!(engine_ms < 4.0, "engine {engine_ms} ms per frame");
    let errors = b.errors();
    assert!(errors.is_empty(), "console errors: {errors:?}");

    // Pictures and load times of other sites for a person to look at:
    // SURFMOTION_WEB_SHOTS=/path/site1,/path/site2 (copied beside the test sites).
    for (i, extra) in std::env::var("SURFMOTION_WEB_SHOTS")
        .unwrap_or_default()
        .split(',')
        .filter(|s| !s.is_empty())
        .enumerate()
    {
        let dst = tmp.path().join(format!("extra{i}"));
        std::fs::create_dir_all(&dst).unwrap();
        for f in std::fs::read_dir(extra).unwrap() {
            let f = f.unwrap().path();
            std::fs::copy(&f, dst.join(f.file_name().unwrap())).unwrap();
        }
        let r = run_page(
            &mut b,
            &format!("{url}extra{i}/index.html?selftest=1&shots=1&skip=20&gap=40"),
        );
        let name = Path::new(extra).file_name().unwrap().to_string_lossy();
        eprintln!(
            "{name}: load {:.0} ms (fetch {:.0}, decode {:.0}), engine {:.3} ms/frame, GL {:.2} ms/frame, {:?} {}",
            r["loadMs"].as_f64().unwrap_or(-1.0),
            r["fetchMs"].as_f64().unwrap_or(-1.0),
            r["decodeMs"].as_f64().unwrap_or(-1.0),
            r["engineMsMean"].as_f64().unwrap_or(-1.0),
            r["glMsMean"].as_f64().unwrap_or(-1.0),
            save_shots(&r, &name),
            r["stages"]
        );
    }

    b.clear_events();
    let r = run_page(&mut b, &format!("{url}bad/index.html?selftest=1"));
    assert_eq!(r["ok"], false, "{r}");
    assert_eq!(r["errorVisible"], true, "{r}");
    let msg = r["error"].as_str().unwrap();
    assert!(
        msg.contains("corrupt 4D geometry") && msg.contains("truncated"),
        "{msg}"
    );
}

/// The console check listens from outside: an error the page logs, and an
/// uncaught exception, are both seen through the DevTools protocol.
#[test]
fn devtools_client_sees_console_errors_and_exceptions() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let _one = one_browser();
    let mut b = cdp::Browser::launch(&browser);
    assert!(b.errors().is_empty());
    b.eval("console.error('boom from the page'); setTimeout(() => { throw new Error('thrown later'); }, 0); 1");
    std::thread::sleep(Duration::from_millis(200));
    let e = b.errors();
    assert!(e.iter().any(|x| x.contains("boom from the page")), "{e:?}");
    assert!(e.iter().any(|x| x.contains("thrown later")), "{e:?}");
}

/// A small valid `.sm4d` file: a moving 5 × 5 grid, two sequences.
fn small_sm4d() -> Vec<u8> {
    let w = 5usize;
    let n = w * w;
    let mut triangles = Vec::new();
    for i in 0..w - 1 {
        for j in 0..w - 1 {
            let a = (i * w + j) as u32;
            triangles.push([a, a + 1, a + w as u32]);
            triangles.push([a + 1, a + w as u32 + 1, a + w as u32]);
        }
    }
    let seq = |speed: f32, frames: usize| -> Vec<[f32; 3]> {
        (0..frames * n)
            .map(|i| {
                let (t, v) = ((i / n) as f32, i % n);
                let (x, y) = ((v % w) as f32 * 0.1, (v / w) as f32 * 0.1);
                [x + 0.01 * t, y + (t * speed + x).sin() * 0.05, 0.02 * x * t]
            })
            .collect()
    };
    let g = codec::Geometry {
        vertices: n,
        triangles,
        sequences: vec![seq(0.3, 6), seq(0.7, 3)],
    };
    codec::encode(&g, &web::EncodeOptions::default()).unwrap().0
}

/// What the reader must do with any input: return geometry that is
/// consistent, or a typed `Corrupt` error naming a byte inside (or just
/// past the header of) the file. A panic fails the test by itself.
fn check_decode_is_total(data: &[u8]) {
    match codec::decode(data) {
        Ok(d) => {
            assert!(
                d.triangles
                    .iter()
                    .flatten()
                    .all(|&v| (v as usize) < d.vertices)
            );
            assert!(d.sequences.iter().all(|s| s.len() % d.vertices == 0));
        }
        Err(web::CodecError::Corrupt { offset, msg }) => {
            assert!(
                offset <= data.len().max(codec::HEADER_BYTES),
                "offset {offset} past a {}-byte file: {msg}",
                data.len()
            );
        }
        Err(e) => panic!("the reader returned a non-Corrupt error: {e}"),
    }
}

mod sm4d_reader_properties {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, .. ProptestConfig::default() })]

        /// Random bytes, with or without a valid magic and version in
        /// front, never panic the reader.
        #[test]
        fn sm4d_reader_never_panics_on_random_bytes(
            body in proptest::collection::vec(any::<u8>(), 0..400),
            prefix in 0usize..3,
        ) {
            let mut data = Vec::new();
            if prefix >= 1 { data.extend_from_slice(codec::MAGIC); }
            if prefix >= 2 { data.extend_from_slice(&codec::VERSION.to_le_bytes()); }
            data.extend_from_slice(&body);
            check_decode_is_total(&data);
        }

        /// A valid file with bytes overwritten, inserted, removed or the
        /// tail cut never panics the reader, and a changed header field
        /// that breaks the file gives a typed error.
        #[test]
        fn sm4d_reader_never_panics_on_mutated_valid_files(
            edits in proptest::collection::vec((any::<u16>(), any::<u8>(), 0u8..4), 1..6),
        ) {
            let mut data = small_sm4d();
            for (at, byte, kind) in edits {
                let len = data.len().max(1);
                let i = at as usize % len;
                match kind {
                    0 if !data.is_empty() => data[i] = byte,
                    1 => data.insert(i.min(data.len()), byte),
                    2 if !data.is_empty() => { data.remove(i); }
                    _ => data.truncate(i),
                }
            }
            check_decode_is_total(&data);
        }
    }
}

/// The hand-made file decodes: the mutation test starts from a valid file.
#[test]
fn small_sm4d_fixture_is_valid() {
    let d = codec::decode(&small_sm4d()).unwrap();
    assert_eq!(d.vertices, 25);
    assert_eq!(d.sequences.len(), 2);
}

/// The page starts the geometry's fetch and decode (a worker) and the
/// manifest's download from an inline script ahead of its modules, so they
/// overlap module loading and the WebGL2 context's creation.
#[test]
fn page_starts_geometry_download_before_its_modules() {
    let db = demo_db();
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    web::export_db(&db, &site, &ExportOptions::default()).unwrap();
    let html = std::fs::read_to_string(site.join("index.html")).unwrap();
    let boot = html
        .find("new Worker('worker.js'")
        .expect("index.html starts the decoder worker");
    let fetch = html
        .find("fetch('manifest.json')")
        .expect("and the manifest");
    let module = html.find("<script src=\"engine.js\"").unwrap();
    assert!(boot < module && fetch < module);
    assert!(html.contains(&format!("'{}'", web::export::GEOMETRY_FILE)));
    let app = std::fs::read_to_string(site.join("app.js")).unwrap();
    assert!(app.contains("window.surfmotionBoot"));
}

/// A small result to export: `dir/kf.obj` (a 6 × 6 grid standing up, 1.8 m
/// tall) and `dir/kf.pc2`, 12 frames swaying; returns the `.pc2`.
fn small_result(dir: &Path) -> PathBuf {
    use surfmotion::mesh::{Mesh, io};
    std::fs::create_dir_all(dir).unwrap();
    let k = 6;
    let rest: Vec<[f64; 3]> = (0..k * k)
        .map(|i| [0.1 * (i % k) as f64, 0.36 * (i / k) as f64, 0.0])
        .collect();
    let mut tris = Vec::new();
    for y in 0..k - 1 {
        for x in 0..k - 1 {
            let v = (y * k + x) as u32;
            let k = k as u32;
            tris.push([v, v + 1, v + k]);
            tris.push([v + 1, v + k + 1, v + k]);
        }
    }
    let mesh = Mesh::new(rest.clone(), tris).unwrap();
    io::obj::write_obj(&mesh, None, &dir.join("kf.obj")).unwrap();
    let frames: Vec<[f64; 3]> = (0..12)
        .flat_map(|f| {
            rest.iter()
                .map(move |p| [p[0] + 0.05 * p[1] * (f as f64 * 0.5).sin(), p[1], p[2]])
        })
        .collect();
    let pc2 = dir.join("kf.pc2");
    io::pc2::write_pc2(k * k, &frames, &pc2).unwrap();
    pc2
}

/// Every file under `dir` (relative path, contents).
fn tree(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    out.sort();
    out
}

/// Issue 46.1: `web export -o proj` where `proj/` holds the user's `main.rs`
/// and some `manifest.json` replaced the folder (main.rs deleted, exit 0);
/// re-exporting into an earlier export the user added `notes.txt` and
/// `mine/data.bin` to deleted both. The export refuses, naming the file, and
/// leaves the folder as it was; an untouched earlier export is replaced.
#[test]
fn web_export_keeps_the_users_files() {
    let tmp = tempfile::tempdir().unwrap();
    let pc2 = small_result(&tmp.path().join("in"));
    let opts = ExportOptions::default();
    // A project folder with a manifest.json that even says it is a site.
    let proj = tmp.path().join("proj");
    std::fs::create_dir_all(&proj).unwrap();
    std::fs::write(proj.join("main.rs"), "fn main() {}\n").unwrap();
    std::fs::write(
        proj.join("manifest.json"),
        r#"{"format": "surfmotion-web", "note": "mine"}"#,
    )
    .unwrap();
    let before = tree(&proj);
    let e = web::export_result(&pc2, None, &proj, &opts).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("main.rs"), "{msg}");
    assert_eq!(tree(&proj), before, "the folder changed");
    // Through the CLI: exit 1, one line naming the file.
    let out = Command::new(common::bin())
        .args(["web", "export", "--result"])
        .arg(&pc2)
        .arg("-o")
        .arg(&proj)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("main.rs"),
        "{out:?}"
    );
    assert_eq!(tree(&proj), before);

    // An earlier export the user added to.
    let site = tmp.path().join("site");
    web::export_result(&pc2, None, &site, &opts).unwrap();
    // Untouched, it is replaced (and the record lists what it wrote).
    web::export_result(&pc2, None, &site, &opts).unwrap();
    assert!(site.join(".surfmotion-export.json").is_file());
    std::fs::write(site.join("notes.txt"), "my notes").unwrap();
    std::fs::create_dir_all(site.join("mine")).unwrap();
    std::fs::write(site.join("mine/data.bin"), [1u8, 2, 3]).unwrap();
    let before = tree(&site);
    let msg = web::export_result(&pc2, None, &site, &opts)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("mine"), "{msg}");
    assert_eq!(tree(&site), before);
    std::fs::remove_dir_all(site.join("mine")).unwrap();
    let msg = web::export_result(&pc2, None, &site, &opts)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("notes.txt"), "{msg}");
    // A file of the export the user edited is theirs now.
    std::fs::remove_file(site.join("notes.txt")).unwrap();
    std::fs::write(site.join("index.html"), "<p>my page</p>").unwrap();
    let before = tree(&site);
    let msg = web::export_result(&pc2, None, &site, &opts)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("index.html") && msg.contains("changed"),
        "{msg}"
    );
    assert_eq!(tree(&site), before);
    // No stray temporary folders beside the outputs.
    let stray: Vec<_> = std::fs::read_dir(tmp.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with('.'))
        .collect();
    assert!(stray.is_empty(), "{stray:?}");
}

/// Issue 46.2: `web export --result site/kf.pc2 -o site` deleted its own
/// input (`site/kf.pc2`, `site/kf.obj`) and exited 0. An input inside the
/// output folder is refused with a one-line reason, the input kept; the
/// same for a database.
#[test]
fn web_export_never_deletes_its_input() {
    let tmp = tempfile::tempdir().unwrap();
    let opts = ExportOptions::default();
    let site = tmp.path().join("site");
    let src = small_result(&tmp.path().join("src"));
    web::export_result(&src, None, &site, &opts).unwrap();
    // The result put into the earlier export, as the issue did.
    let pc2 = site.join("kf.pc2");
    std::fs::copy(&src, &pc2).unwrap();
    std::fs::copy(src.with_extension("obj"), site.join("kf.obj")).unwrap();
    let before = tree(&site);
    let out = Command::new(common::bin())
        .args(["web", "export", "--result"])
        .arg(&pc2)
        .arg("-o")
        .arg(&site)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("kf.pc2") && err.contains("input"), "{err}");
    assert_eq!(tree(&site), before, "the folder changed");
    // Even if the folder held nothing but the record's files and the
    // input: an input never goes.
    let e = web::export_result(&pc2, None, &site.join("."), &opts).unwrap_err();
    assert!(e.to_string().contains("input"), "{e}");
    assert!(pc2.is_file() && site.join("kf.obj").is_file());
    // A database exported into its own folder, or into a folder above it.
    let db = tmp.path().join("up/db");
    small_result(&db);
    std::fs::write(
        db.join("character.toml"),
        "name = \"grid\"\ntopology = \"kf.obj\"\n[[sequence]]\nname = \"sway\"\npath = \"kf.pc2\"\n",
    )
    .unwrap();
    let before = tree(&tmp.path().join("up"));
    for out in [db.clone(), tmp.path().join("up")] {
        let e = web::export_db(&db, &out, &opts).unwrap_err();
        assert!(e.to_string().contains("input"), "{e}");
        assert_eq!(tree(&tmp.path().join("up")), before);
    }
}

/// Pixels of a page screenshot (PNG) in the character's warm colour
/// (red above blue by more than 40: the skin-tone material; the sky,
/// ground, grid, shadow and controls are grey or blue).
fn character_pixels(png_path: &Path) -> (usize, usize) {
    let mask = warm_mask(png_path);
    (mask.iter().filter(|w| **w).count(), mask.len())
}

/// Regression (issue 39, items 1 and 2): `web export --result` pages came
/// up blank on most loads (the first animation tick could be negative,
/// frame −1 was drawn and the camera target became NaN for good), and a
/// site opened from disk showed "loading…" forever (module scripts and
/// `fetch` are refused on `file://`). The old browser test never saw the
/// first because it drove the page with a scripted first step. Here every
/// kind of site (a database, a result, a parametric space) is loaded as a
/// person loads it — no `selftest`, nothing scripted — ten times in a row
/// served and three times from `file://`; after a second of playback the
/// screenshot's character pixels must cover a sensible area every time.
#[test]
fn browser_plays_every_kind_of_site_as_a_person_loads_it() {
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let _one = one_browser();
    let tmp = tempfile::tempdir().unwrap();
    export_every_kind(tmp.path());
    let server = SiteServer::bind(tmp.path(), "127.0.0.1:0").unwrap();
    let url = server.url();
    server.spawn();
    let mut b = cdp::Browser::launch(&browser);
    let shots = shots_dir();
    let ready = "window.surfmotion && (surfmotion.ready || surfmotion.error) ? true : null";
    for kind in ["result", "database", "parametric"] {
        let served = format!("{url}{kind}/index.html");
        let disk = format!("file://{}/{kind}/index.html", tmp.path().display());
        let loads = std::iter::repeat_n(("served", &served), 10)
            .chain(std::iter::repeat_n(("file", &disk), 3));
        for (i, (origin, page)) in loads.enumerate() {
            b.clear_events();
            b.navigate(page);
            b.wait_for(ready, Duration::from_secs(90));
            let error = b.eval("surfmotion.error");
            assert!(error.is_null(), "{kind} {origin} load {i}: {error}");
            std::thread::sleep(Duration::from_millis(1000));
            let shot = shots.join(format!("person-{kind}-{origin}-{i}.png"));
            b.screenshot(&shot);
            let (warm, all) = character_pixels(&shot);
            let state = b.eval(
                "JSON.stringify({status: (document.getElementById('status') || {}).textContent})",
            );
            assert!(
                warm > all / 1000 && warm < all / 3,
                "{kind} {origin} load {i}: {warm} character pixels of {all} ({state}); {}",
                shot.display()
            );
            let errors = b.errors();
            assert!(errors.is_empty(), "{kind} {origin} load {i}: {errors:?}");
        }
    }
}

/// One site of each kind under `dir`: `database` (the demo database),
/// `parametric` (the gaits space) and `result` (the demo's `turn.glb`
/// through the CLI, as the README does it).
fn export_every_kind(dir: &Path) {
    let demo = demo_db();
    web::export_db(&demo, &dir.join("database"), &ExportOptions::default()).unwrap();
    web::export_db(
        &gaits_db(),
        &dir.join("parametric"),
        &ExportOptions::default(),
    )
    .unwrap();
    common::run_ok(
        Command::new(common::bin())
            .args(["web", "export", "--result"])
            .arg(demo.parent().unwrap().join("turn.glb"))
            .arg("-o")
            .arg(dir.join("result")),
    );
}

/// A program on the PATH, or `None`.
fn on_path(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

/// Firefox, Xvfb and ImageMagick's `import` (the screenshot of the X
/// screen), or `None` (skip) outside CI. Headless Firefox has no WebGL2
/// here, so the test runs the real, windowed browser on a virtual screen.
fn firefox_or_skip() -> Option<(PathBuf, PathBuf, PathBuf)> {
    let firefox = on_path("firefox-esr").or_else(|| on_path("firefox"));
    let found = match (firefox, on_path("Xvfb"), on_path("import")) {
        (Some(f), Some(x), Some(i)) => Some((f, x, i)),
        _ => None,
    };
    if found.is_none() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true and no firefox-esr, Xvfb or ImageMagick (.ci/run installs them)"
        );
        eprintln!("SKIPPED: needs firefox-esr, xvfb and imagemagick (apt-get install)");
    }
    found
}

/// A process killed (and reaped) when dropped.
struct Killed(std::process::Child);

impl Drop for Killed {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A virtual X screen's server, asked to stop (SIGTERM, so that it removes
/// its lock and socket) when dropped, and killed if it has not stopped
/// within two seconds.
struct Screen(std::process::Child);

impl Drop for Screen {
    fn drop(&mut self) {
        let pid = self.0.id().to_string();
        let asked = Command::new("kill").args(["-TERM", &pid]).status();
        if asked.is_ok_and(|s| s.success()) {
            for _ in 0..20 {
                if matches!(self.0.try_wait(), Ok(Some(_))) {
                    return;
                }
                std::thread::sleep(Duration::from_millis(100));
            }
        }
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// A virtual X screen on the first free display from :91, and its name.
/// A display is taken while its lock names a live process; the lock and
/// socket an Xvfb killed by an earlier run left behind are removed (a
/// killed Xvfb cannot clean up, so on a reused machine stale locks filled
/// :91-:119 and the test failed with no display free). The screen's
/// server is stopped with SIGTERM ([`Screen`]), so it cleans up itself.
fn virtual_screen(xvfb: &Path) -> (Screen, String) {
    for n in 91..120 {
        let lock = format!("/tmp/.X{n}-lock");
        if let Ok(text) = std::fs::read_to_string(&lock) {
            let alive = text
                .trim()
                .parse::<u32>()
                .is_ok_and(|pid| Path::new(&format!("/proc/{pid}")).exists());
            if alive || std::fs::remove_file(&lock).is_err() {
                continue;
            }
            let _ = std::fs::remove_file(format!("/tmp/.X11-unix/X{n}"));
        } else if Path::new(&lock).exists() {
            continue;
        }
        let display = format!(":{n}");
        let mut child = Command::new(xvfb)
            .args([
                display.as_str(),
                "-screen",
                "0",
                "1280x900x24",
                "-nolisten",
                "tcp",
            ])
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        for _ in 0..50 {
            std::thread::sleep(Duration::from_millis(100));
            if Path::new(&format!("/tmp/.X11-unix/X{n}")).exists() {
                return (Screen(child), display);
            }
            if child.try_wait().unwrap().is_some() {
                break;
            }
        }
        let _ = child.kill();
    }
    panic!("no free X display in :91-:119 for Xvfb");
}

/// Regression (issue 39, item 2): an exported `index.html` opened from
/// disk (`file://`) showed "loading…" forever, as browsers refuse module
/// scripts and `fetch` there. Chromium is checked by
/// `browser_plays_every_kind_of_site_as_a_person_loads_it`; this is the
/// same in Firefox, with a new profile at its default settings (only the
/// first-run pages turned off), windowed on a virtual screen: every kind of
/// site opened from disk, and one served, must draw the character (the
/// screen's character pixels cover a sensible area) and play (two screens
/// a second apart differ in the character's pixels).
#[test]
fn firefox_plays_every_kind_of_site_from_disk() {
    let Some((firefox, xvfb, import)) = firefox_or_skip() else {
        return;
    };
    let _one = one_browser();
    let tmp = tempfile::tempdir().unwrap();
    let sites = tmp.path().join("sites");
    export_every_kind(&sites);
    let server = SiteServer::bind(&sites, "127.0.0.1:0").unwrap();
    let url = server.url();
    server.spawn();
    let (_screen, display) = virtual_screen(&xvfb);
    let shots = shots_dir();
    let pages = ["result", "database", "parametric"]
        .map(|k| {
            (
                k,
                "file",
                format!("file://{}/{k}/index.html", sites.display()),
            )
        })
        .into_iter()
        .chain([("result", "served", format!("{url}result/index.html"))]);
    for (i, (kind, origin, page)) in pages.enumerate() {
        let profile = tmp.path().join(format!("profile-{i}"));
        std::fs::create_dir_all(&profile).unwrap();
        std::fs::write(
            profile.join("user.js"),
            "user_pref(\"browser.shell.checkDefaultBrowser\", false);\n\
             user_pref(\"datareporting.policy.dataSubmissionEnabled\", false);\n\
             user_pref(\"toolkit.telemetry.reportingpolicy.firstRun\", false);\n\
             user_pref(\"browser.startup.homepage_override.mstone\", \"ignore\");\n\
             user_pref(\"app.update.auto\", false);\n",
        )
        .unwrap();
        let _browser = Killed(
            Command::new(&firefox)
                .args(["--no-remote", "--new-instance", "--profile"])
                .arg(&profile)
                .arg(&page)
                .env("DISPLAY", &display)
                .env("MOZ_CRASHREPORTER_DISABLE", "1")
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .spawn()
                .unwrap(),
        );
        let shoot = |name: &str| {
            let shot = shots.join(format!("firefox-{kind}-{origin}-{name}.png"));
            let ok = Command::new(&import)
                .args(["-window", "root"])
                .arg(&shot)
                .env("DISPLAY", &display)
                .status()
                .is_ok_and(|s| s.success());
            ok.then(|| {
                let (warm, all) = character_pixels(&shot);
                (shot, warm, all)
            })
        };
        // Firefox starts, decodes and draws within a minute even on a
        // loaded 2-core machine; poll the screen until the character shows.
        let start = std::time::Instant::now();
        let mut last = None;
        while start.elapsed() < Duration::from_secs(120) {
            std::thread::sleep(Duration::from_secs(2));
            last = shoot("a");
            if let Some((_, warm, all)) = &last
                && *warm > all / 1000
                && *warm < all / 3
            {
                break;
            }
        }
        let (a, warm, all) = last.expect("import took no screenshot");
        assert!(
            warm > all / 1000 && warm < all / 3,
            "Firefox, {kind} site {origin}: {warm} character pixels of {all} after 120 s; {}",
            a.display()
        );
        std::thread::sleep(Duration::from_millis(1000));
        let (b, ..) = shoot("b").expect("import took no second screenshot");
        let differ = warm_mask(&a)
            .iter()
            .zip(warm_mask(&b))
            .filter(|(x, y)| **x != *y)
            .count();
        assert!(
            differ > all / 20000,
            "Firefox, {kind} site {origin}: the character did not move in a second \
             ({differ} pixels changed); {} {}",
            a.display(),
            b.display()
        );
    }
}

/// Which pixels of a screenshot are the character's (as `character_pixels`).
fn warm_mask(png_path: &Path) -> Vec<bool> {
    let dec = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(png_path).unwrap(),
    ));
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    let step = info.color_type.samples();
    // A grey screen (before the browser's window opens, ImageMagick writes
    // one channel) has no warm pixel.
    buf[..info.buffer_size()]
        .chunks_exact(step)
        .map(|p| step >= 3 && p[0] as i32 > p[2] as i32 + 40)
        .collect()
}
