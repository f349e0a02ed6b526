//! The web viewer (issue 22): the exported geometry decodes within the
//! error bound and the page's transition table is the graph's; the server
//! keeps to the site folder; and in a real headless Chromium the page gets
//! a WebGL2 context, draws the character, follows a motion key, logs no
//! error, and shows a message (not a blank page) for corrupt data.

mod common;

use base64::Engine as _;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use surfmotion::web::{self, ExportOptions, SiteManifest, SiteServer, codec};

/// The procedural demo database (no files needed), made once.
fn demo_db() -> PathBuf {
    use std::sync::OnceLock;
    static DB: OnceLock<(PathBuf, PathBuf)> = OnceLock::new();
    DB.get_or_init(|| {
        let tmp = common::fixture_dir("web-demo");
        let out = Command::new(common::bin())
            .arg("demo")
            .arg("-o")
            .arg(tmp.join("demo"))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
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
    assert_eq!(d.sequences.len(), g.sequences.len());
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
    let m = manifest(site);
    let page: Vec<_> = m
        .transitions
        .iter()
        .map(|t| (t.from, t.to, t.m, t.n, t.window))
        .collect();
    let graph: Vec<_> = graph
        .transitions
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
        assert!((worst - r.geometry.max_error).abs() < 1e-7);
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
    assert_eq!(r.geometry.frames, 175);
    assert!(r.geometry.bytes <= 2_000_000, "{} bytes", r.geometry.bytes);
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
fn chromium() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("SURFMOTION_CHROMIUM") {
        return Some(p.into());
    }
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .flat_map(|d| ["chromium", "chromium-browser"].map(|n| d.join(n)))
        .find(|p| p.is_file())
}

/// Loads `url` in headless Chromium and waits for the page's self-test
/// report (POSTed to the server), at most `limit`.
fn run_page(
    browser: &Path,
    url: &str,
    reports: &std::sync::Mutex<Vec<String>>,
) -> serde_json::Value {
    let profile = tempfile::tempdir().unwrap();
    let mut child = Command::new(browser)
        .args([
            "--headless",
            "--no-sandbox",
            "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader",
            "--no-first-run",
            "--disable-extensions",
            "--window-size=800,600",
        ])
        .arg(format!("--user-data-dir={}", profile.path().display()))
        .arg(url)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let got = loop {
        if let Some(r) = reports.lock().unwrap().pop() {
            break Some(r);
        }
        if t0.elapsed() > Duration::from_secs(40) {
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let _ = child.kill();
    let _ = child.wait();
    let got = got.expect("the page sent no self-test report within 40 s");
    serde_json::from_str(&got).unwrap()
}

fn save_shots(r: &serde_json::Value, name: &str) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("web-shots");
    std::fs::create_dir_all(&dir).unwrap();
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

#[test]
fn browser_draws_the_character_follows_keys_and_reports_corrupt_data() {
    let Some(browser) = chromium() else {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true and no chromium installed (.ci/run installs it)"
        );
        eprintln!("SKIPPED: no chromium on the PATH (apt-get install chromium)");
        return;
    };
    let db = demo_db();
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    web::export_db(&db, &site, &ExportOptions::default()).unwrap();
    let bad = tmp.path().join("bad");
    web::export_db(&db, &bad, &ExportOptions::default()).unwrap();
    let geo = std::fs::read(bad.join("character.sm4d")).unwrap();
    std::fs::write(bad.join("character.sm4d"), &geo[..geo.len() / 2]).unwrap();
    let mut server = SiteServer::bind(tmp.path(), "127.0.0.1:0").unwrap();
    let reports = server.collect_reports();
    let url = server.url();
    server.spawn();

    let r = run_page(
        &browser,
        &format!("{url}site/index.html?selftest=1&shots=1"),
        &reports,
    );
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
        .transitions
        .iter()
        .map(|t| [t.from, t.to, t.m, t.n, t.window])
        .collect();
    assert_eq!(r["engineTransitions"], serde_json::json!(table));
    assert_eq!(r["webgl2"], true);
    assert_eq!(r["errors"], serde_json::json!([]), "console errors");
    let px = &r["characterPixels"];
    assert!(
        px[0].as_u64().unwrap() > 500 && px[1].as_u64().unwrap() > 500,
        "{px}"
    );
    assert!(
        r["diffPixels"].as_u64().unwrap() > 50,
        "frames identical: {r}"
    );
    // The key for the other motion: the engine moved into it by a graph
    // transition (it starts in the first sequence).
    let before = &r["before"];
    let after = &r["after"];
    assert_eq!(r["queued"].as_array().map(Vec::len), Some(1), "{r}");
    assert_ne!(after["sequence"], before["sequence"], "{after}");
    assert_eq!(after["lastTransition"]["kind"], "transition", "{after}");
    assert_eq!(after["lastTransition"]["to"], after["sequence"]);
    assert!(r["later"]["ticks"].as_u64().unwrap() > 300);
    let engine_ms = r["engineMsMean"].as_f64().unwrap();
    assert!(engine_ms < 4.0, "engine {engine_ms} ms per frame");

    // Pictures of other sites for a person to look at:
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
            &browser,
            &format!("{url}extra{i}/index.html?selftest=1&shots=1&skip=20&gap=40"),
            &reports,
        );
        let name = Path::new(extra).file_name().unwrap().to_string_lossy();
        eprintln!("{name}: {:?} {}", save_shots(&r, &name), r["stages"]);
    }

    let r = run_page(
        &browser,
        &format!("{url}bad/index.html?selftest=1"),
        &reports,
    );
    assert_eq!(r["ok"], false, "{r}");
    assert_eq!(r["errorVisible"], true, "{r}");
    let msg = r["error"].as_str().unwrap();
    assert!(
        msg.contains("corrupt 4D geometry") && msg.contains("truncated"),
        "{msg}"
    );
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
    let module = html.find("<script type=\"module\"").unwrap();
    assert!(boot < module && fetch < module);
    assert!(html.contains(&format!("'{}'", web::export::GEOMETRY_FILE)));
    let app = std::fs::read_to_string(site.join("app.js")).unwrap();
    assert!(app.contains("window.surfmotionBoot"));
}
