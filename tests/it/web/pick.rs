//! `rig embed --pick` (issue 41, "a page to look and correct"): the page's
//! HTTP API on the procedural humanoid (embed from posted landmarks,
//! refusals with a reason and never a panic, Save atomic and never over an
//! input), and the page itself in headless Chromium on samba: drawn, a
//! landmark moved by `?move=` and by a real pointer drag, the part
//! colouring changed where it moved, Save read back; without a landmark
//! file the page starts from the automatic landmarks (in Chromium on the
//! SMPL template).

use super::{browser_or_skip, cdp, one_browser, shots_dir};
use crate::common;
use serde_json::{Value, json};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;
use surfmotion::embed::landmarks::{Landmark, Landmarks};
use surfmotion::jobs::pick::{Pick, PickOptions, PickReport, finish, open};

/// A request to the page's server: `(status, JSON body)`.
fn request(
    addr: &str,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &[u8],
) -> (u16, Value) {
    let mut s = std::net::TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
    let mut head = format!("{method} {path} HTTP/1.1\r\nConnection: close\r\n");
    if !headers.iter().any(|(k, _)| *k == "Host") {
        head += &format!("Host: {addr}\r\n");
    }
    for (k, v) in headers {
        head += &format!("{k}: {v}\r\n");
    }
    head += &format!("Content-Length: {}\r\n\r\n", body.len());
    s.write_all(head.as_bytes()).unwrap();
    s.write_all(body).unwrap();
    let mut resp = Vec::new();
    let _ = s.read_to_end(&mut resp);
    let text = String::from_utf8_lossy(&resp).into_owned();
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let body = text.split_once("\r\n\r\n").map(|x| x.1).unwrap_or("");
    (status, serde_json::from_str(body).unwrap_or(Value::Null))
}

fn post(addr: &str, path: &str, body: &Value) -> (u16, Value) {
    request(
        addr,
        "POST",
        path,
        &[("Content-Type", "application/json")],
        body.to_string().as_bytes(),
    )
}

/// A running page: its address, stop flag and thread.
struct Served {
    addr: String,
    url: String,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<Pick>>,
}

impl Served {
    fn start(mesh: surfmotion::mesh::Mesh, o: &PickOptions) -> Served {
        let p = open(mesh, o).unwrap();
        let url = p.url();
        let addr = url
            .trim_start_matches("http://")
            .trim_end_matches('/')
            .to_string();
        let stop = Arc::new(AtomicBool::new(false));
        let thread = Some(p.spawn(Arc::clone(&stop)));
        Served {
            addr,
            url,
            stop,
            thread,
        }
    }

    fn stop(mut self) -> PickReport {
        self.stop.store(true, Ordering::Relaxed);
        finish(self.thread.take().unwrap().join().unwrap()).unwrap()
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

fn point(v: &Value) -> [f64; 3] {
    let a = v.as_array().unwrap();
    [0, 1, 2].map(|k| a[k].as_f64().unwrap())
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

fn surface_distance(mesh: &surfmotion::mesh::Mesh, p: [f64; 3]) -> f64 {
    surfmotion::embed::surface::distance_to_surface(
        mesh.positions(),
        mesh.triangles(),
        glam::DVec3::from_array(p),
    )
}

fn labels(v: &Value) -> Vec<u64> {
    v["labels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect()
}

#[test]
fn pick_api_embeds_posted_landmarks_refuses_bad_requests_and_saves_beside_the_input() {
    use surfmotion::synth::humanoid::{DEMO_GRID, humanoid_landmarks_json, humanoid_mesh};
    let tmp = tempfile::tempdir().unwrap();
    let mesh = humanoid_mesh(DEMO_GRID);
    let mesh_file = tmp.path().join("humanoid.obj");
    std::fs::write(&mesh_file, "not read: a protected input").unwrap();
    let input = tmp.path().join("humanoid.landmarks.json");
    std::fs::write(&input, humanoid_landmarks_json()).unwrap();
    let input_bytes = std::fs::read(&input).unwrap();
    // Another input (a part-label file, say): never written.
    let other = tmp.path().join("parts.json");
    std::fs::write(&other, "{}").unwrap();
    let o = PickOptions {
        mesh: mesh_file.display().to_string(),
        landmarks: Some(input.clone()),
        inputs: vec![mesh_file.clone(), other.clone()],
        ..Default::default()
    };
    let s = Served::start(mesh.clone(), &o);
    let a = s.addr.as_str();

    // The page and its script.
    let (st, _) = request(a, "GET", "/", &[], b"");
    assert_eq!(st, 200);
    let (st, m) = request(a, "GET", "/api/mesh", &[], b"");
    assert_eq!(st, 200);
    assert_eq!(
        m["positions"].as_array().unwrap().len(),
        3 * mesh.vertex_count()
    );
    let (st, s0) = request(a, "GET", "/api/state", &[], b"");
    assert_eq!(st, 200, "{s0}");
    assert_eq!(s0["embedded"], true, "{s0}");
    assert!(s0["error"].is_null());
    let l0 = labels(&s0);
    assert_eq!(l0.len(), mesh.vertex_count());

    // Move the left elbow halfway down its forearm, off the surface: the
    // server snaps it onto the surface and embeds again.
    let mut marks = s0["landmarks"].clone();
    let (e, w) = (point(&marks["l_elbow"]), point(&marks["l_wrist"]));
    let mid: [f64; 3] = std::array::from_fn(|k| 0.5 * (e[k] + w[k]));
    marks["l_elbow"] = json!(mid);
    let (st, s1) = post(
        a,
        "/api/embed",
        &json!({"landmarks": marks, "snap": ["l_elbow"]}),
    );
    assert_eq!(st, 200, "{s1}");
    assert!(s1["revision"].as_u64() > s0["revision"].as_u64());
    let moved = point(&s1["landmarks"]["l_elbow"]);
    assert!(
        surface_distance(&mesh, moved) < 1e-9,
        "not snapped: {moved:?}"
    );
    assert!(dist(moved, mid) < 0.1, "{moved:?} vs {mid:?}");
    let j0 = point(&s0["joints"]["l_elbow"]);
    let j1 = point(&s1["joints"]["l_elbow"]);
    assert!(
        dist(j0, j1) > 0.02,
        "elbow joint did not move: {j0:?} {j1:?}"
    );
    let changed = l0
        .iter()
        .zip(labels(&s1))
        .filter(|(x, y)| **x != *y)
        .count();
    assert!(changed > 20, "{changed} vertices changed part");
    // The same as the library embeds from those landmarks.
    let lm = Landmarks::parse(
        &s1["landmarks"].to_string(),
        Path::new("posted"),
        mesh.vertex_count(),
    )
    .unwrap();
    let direct = surfmotion::embed::Embedding::new(&mesh, &lm, None).unwrap();
    assert_eq!(
        labels(&s1),
        direct
            .labels()
            .iter()
            .map(|&l| l as u64)
            .collect::<Vec<_>>()
    );

    // Refusals, each with a reason; the state is untouched.
    let ct = [("Content-Type", "application/json")];
    for (body, status, words) in [
        (&b"{not json"[..], 400, "not JSON"),
        (b"[1, 2]", 400, "JSON object"),
        (b"\xff\xfe", 400, "UTF-8"),
        (b"{\"marks\": {}}", 400, "unknown field"),
        (b"{\"landmarks\": 3}", 400, "landmarks"),
        (b"{\"landmarks\": {\"nose\": 1}}", 400, "unknown landmark"),
        (b"{\"landmarks\": {\"chin\": 1}}", 400, "missing required"),
        (b"{\"landmarks\": {\"chin\": [1, \"a\", 2]}}", 400, "chin"),
    ] {
        let (st, v) = request(a, "POST", "/api/embed", &ct, body);
        assert_eq!(st, status, "{}: {v}", String::from_utf8_lossy(body));
        let e = v["error"].as_str().unwrap_or_default();
        assert!(e.contains(words), "{e}");
    }
    let mut snap = s1["landmarks"].clone();
    snap["l_wrist"] = json!(point(&snap["l_wrist"]));
    let (st, v) = post(
        a,
        "/api/embed",
        &json!({"landmarks": snap, "snap": ["l_hand"]}),
    );
    assert_eq!(st, 400, "{v}");
    // Landmarks no rig comes from (all at one point): 422 with the
    // reason, the earlier landmarks and rig kept.
    let one: serde_json::Map<String, Value> = Landmark::REQUIRED
        .iter()
        .map(|l| (l.name().to_string(), json!(mid)))
        .collect();
    let (st, v) = post(a, "/api/embed", &json!({ "landmarks": one }));
    assert_eq!(st, 422, "{v}");
    assert!(v["rejected"].as_str().unwrap().contains("span only"), "{v}");
    assert_eq!(v["landmarks"], s1["landmarks"]);
    assert_eq!(labels(&v), labels(&s1));
    // Not JSON content, another Host, a method, a path, a huge body.
    let (st, _) = request(a, "POST", "/api/embed", &[], b"{}");
    assert_eq!(st, 415);
    let (st, v) = request(a, "GET", "/api/state", &[("Host", "evil.example:80")], b"");
    assert_eq!(st, 403, "{v}");
    let (st, _) = request(a, "DELETE", "/api/state", &[], b"");
    assert_eq!(st, 405);
    let (st, _) = request(a, "GET", "/api/embed", &[], b"");
    assert_eq!(st, 405);
    let (st, _) = request(a, "GET", "/../secret", &[], b"");
    assert_eq!(st, 404);
    let (st, v) = request(
        a,
        "POST",
        "/api/embed",
        &[
            ("Content-Type", "application/json"),
            ("Content-Length", "99999999999"),
        ],
        b"",
    );
    assert!(st == 413 || st == 400, "{st} {v}");
    // Random bodies: answered, never a dropped connection.
    let mut x = 0x9e3779b97f4a7c15u64;
    for n in 0..40 {
        let body: Vec<u8> = (0..(n * 7) % 300)
            .map(|_| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                (x >> 24) as u8
            })
            .collect();
        let (st, _) = request(a, "POST", "/api/embed", &ct, &body);
        assert_eq!(st, 400, "body {body:?}");
    }
    let (st, v) = request(a, "GET", "/api/state", &[], b"");
    assert_eq!(st, 200);
    assert_eq!(v["landmarks"], s1["landmarks"]);

    // Save: by default beside the input, never over it; read back.
    let (st, v) = post(a, "/api/save", &json!({}));
    assert_eq!(st, 200, "{v}");
    let saved = PathBuf::from(v["saved"].as_str().unwrap());
    assert_eq!(saved, tmp.path().join("humanoid.picked.landmarks.json"));
    let back = Landmarks::load(&saved, mesh.vertex_count()).unwrap();
    assert_eq!(back, lm);
    assert_eq!(std::fs::read(&input).unwrap(), input_bytes);
    // Refused: an input, not .json, a missing folder; the input itself
    // only when named.
    for (path, status) in [
        (mesh_file.display().to_string(), 400),
        (other.display().to_string(), 409),
        (tmp.path().join("x.txt").display().to_string(), 400),
        (tmp.path().join("no/x.json").display().to_string(), 409),
        (tmp.path().display().to_string() + "/", 400),
    ] {
        let (st, v) = post(a, "/api/save", &json!({ "path": path }));
        assert_eq!(st, status, "{path}: {v}");
        assert!(v["error"].is_string(), "{v}");
    }
    assert_eq!(
        std::fs::read_to_string(&mesh_file).unwrap(),
        "not read: a protected input"
    );
    assert_eq!(std::fs::read_to_string(&other).unwrap(), "{}");
    let (st, v) = post(a, "/api/save", &json!({ "path": input }));
    assert_eq!(st, 200, "{v}");
    assert_eq!(Landmarks::load(&input, mesh.vertex_count()).unwrap(), lm);
    let r = s.stop();
    assert_eq!(r.saved, vec![saved, input.clone()]);
    assert!(r.embeds >= 3 && r.requests > 60, "{r:?}");
}

/// Without landmarks the page starts from the automatic ones (refused or
/// not: the page opens, the reason shown); a mesh too small to find any is
/// refused with advice.
#[test]
fn pick_without_landmarks_starts_from_the_automatic_ones() {
    use surfmotion::synth::humanoid::{DEMO_GRID, humanoid_mesh};
    let s = Served::start(
        humanoid_mesh(DEMO_GRID),
        &PickOptions {
            mesh: "body.obj".into(),
            ..Default::default()
        },
    );
    let (st, v) = request(&s.addr, "GET", "/api/state", &[], b"");
    assert_eq!(st, 200, "{v}");
    for l in Landmark::REQUIRED {
        assert!(v["landmarks"].get(l.name()).is_some(), "{}: {v}", l.name());
    }
    assert!(v["input"].is_null(), "{v}");
    assert!(
        v["defaultSave"]
            .as_str()
            .unwrap()
            .ends_with("body.picked.landmarks.json"),
        "{v}"
    );
    // Refused below the confidence: still opened, the reason shown.
    if let Some(n) = v["notice"].as_str() {
        assert!(n.contains("refused"), "{n}");
    }
    drop(s);
    // Every landmark required, so a confidence of 1 refuses: still opened.
    let s = Served::start(
        humanoid_mesh(DEMO_GRID),
        &PickOptions {
            mesh: "body.obj".into(),
            min_confidence: 1.0 + 1e-9,
            ..Default::default()
        },
    );
    let (_, v) = request(&s.addr, "GET", "/api/state", &[], b"");
    let n = v["notice"].as_str().unwrap_or_else(|| panic!("{v}"));
    assert!(n.contains("refused") && n.contains("confidence"), "{n}");
    drop(s);
    // Nothing to find on a tetrahedron: refused with advice.
    let tet = surfmotion::mesh::Mesh::new(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    )
    .unwrap();
    let e = open(
        tet,
        &PickOptions {
            mesh: "tet.obj".into(),
            ..Default::default()
        },
    )
    .err()
    .unwrap()
    .to_string();
    assert!(
        e.contains("tet.obj") && e.contains("too few") && e.contains("`PickOptions::landmarks`"),
        "{e}"
    );
    let tmp = tempfile::tempdir().unwrap();
    let out = std::process::Command::new(common::bin())
        .args(["rig", "embed"])
        .arg(tmp.path().join("none.obj"))
        .arg("--pick")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("none.obj"), "{err}");
}

/// The page opened without a landmark file on the SMPL template, in
/// headless Chromium: it starts from the automatic landmarks, says so,
/// and embeds a rig from them.
#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn browser_pick_page_opens_from_automatic_landmarks() {
    let Some(d) = common::data_dir() else { return };
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let _one = one_browser();
    let mesh_path = d.join("scans/smpl-template/human_man.obj");
    let mesh = surfmotion::mesh::io::obj::read_obj(&mesh_path).unwrap();
    let o = PickOptions {
        mesh: mesh_path.display().to_string(),
        inputs: vec![mesh_path.clone()],
        ..Default::default()
    };
    let s = Served::start(mesh, &o);
    let mut b = cdp::Browser::launch(&browser);
    b.navigate(&format!("{}?view=front", s.url));
    let ready =
        "window.pick && (pick.ready || pick.error) ? {ready: pick.ready, error: pick.error} : null";
    let r = b.wait_for(ready, Duration::from_secs(90));
    assert_eq!(r["ready"], true, "{r}");
    b.eval("pick.frame()");
    let st = b.eval("pick.state");
    assert_eq!(st["embedded"], true, "{st}");
    assert!(st["input"].is_null(), "{st}");
    assert!(st["notice"].is_null(), "{st}");
    let notice = b.eval("document.getElementById('notice').textContent");
    assert!(
        notice.as_str().unwrap().contains("automatic landmarks"),
        "{notice}"
    );
    let rows = b.eval("document.getElementById('landmarks').rows.length");
    assert!(rows.as_u64().unwrap() >= 8, "{rows}");
    b.screenshot(&shots_dir().join("pick-auto-smpl.png"));
    drop(b);
    let rep = s.stop();
    assert!(rep.saved.is_empty());
}

/// Pixels that differ between two screenshots in their first `width`
/// columns (the 3D view, not the panel), their centre, and the pixels
/// compared.
fn diff(a: &Path, b: &Path, width: usize) -> (usize, [f64; 2], usize) {
    let read = |p: &Path| {
        let d = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(p).unwrap()));
        let mut r = d.read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size().unwrap()];
        let info = r.next_frame(&mut buf).unwrap();
        buf.truncate(info.buffer_size());
        (info.width as usize, info.color_type.samples(), buf)
    };
    let (w, ca, pa) = read(a);
    let (_, cb, pb) = read(b);
    let n = pa.len() / ca;
    let (mut count, mut sx, mut sy) = (0usize, 0f64, 0f64);
    for i in (0..n).filter(|i| i % w < width) {
        let d: i32 = (0..3)
            .map(|k| (pa[i * ca + k] as i32 - pb[i * cb + k] as i32).abs())
            .sum();
        if d > 30 {
            count += 1;
            sx += (i % w) as f64;
            sy += (i / w) as f64;
        }
    }
    let c = if count > 0 {
        [sx / count as f64, sy / count as f64]
    } else {
        [0.0; 2]
    };
    (count, c, n / w * width.min(w))
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn browser_pick_page_moves_a_landmark_recolours_the_arm_and_saves() {
    let Some(d) = common::data_dir() else { return };
    let Some(browser) = browser_or_skip() else {
        return;
    };
    let _one = one_browser();
    let tmp = tempfile::tempdir().unwrap();
    let mesh_path = d.join("4d/samba/samba.obj");
    let mesh = surfmotion::mesh::io::obj::read_obj(&mesh_path).unwrap();
    // A copy of the fixture: Save writes beside it.
    let input = tmp.path().join("samba.landmarks.json");
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json");
    std::fs::copy(&fixture, &input).unwrap();
    let input_bytes = std::fs::read(&input).unwrap();
    let o = PickOptions {
        mesh: mesh_path.display().to_string(),
        landmarks: Some(input.clone()),
        inputs: vec![mesh_path.clone()],
        ..Default::default()
    };
    let s = Served::start(mesh.clone(), &o);
    let shots = shots_dir();
    let mut b = cdp::Browser::launch(&browser);
    let ready =
        "window.pick && (pick.ready || pick.error) ? {ready: pick.ready, error: pick.error} : null";
    let load = |b: &mut cdp::Browser, query: &str| {
        b.navigate(&format!("{}{query}", s.url));
        let r = b.wait_for(ready, Duration::from_secs(90));
        assert_eq!(r["ready"], true, "{r}");
        b.eval("pick.frame()");
    };

    // The page as it opens: coloured by part, skeleton and handles.
    load(&mut b, "?view=front");
    let st0 = b.eval("pick.state");
    assert_eq!(st0["embedded"], true, "{st0}");
    b.screenshot(&shots.join("pick-0-opened.png"));
    b.eval("pick.setOverlay(false), pick.frame()");
    let before = shots.join("pick-1-parts.png");
    b.screenshot(&before);

    // ?move=: the left elbow a third of the way down its forearm.
    let e = point(&st0["landmarks"]["l_elbow"]);
    let w = point(&st0["landmarks"]["l_wrist"]);
    let to: [f64; 3] = std::array::from_fn(|k| e[k] + (w[k] - e[k]) / 3.0);
    load(
        &mut b,
        &format!(
            "?view=front&overlay=0&move=l_elbow:{},{},{}",
            to[0], to[1], to[2]
        ),
    );
    let moved = b.eval("pick.moved");
    assert_eq!(moved["status"], 200, "{moved}");
    let st1 = b.eval("pick.state");
    let lm1 = point(&st1["landmarks"]["l_elbow"]);
    assert!(surface_distance(&mesh, lm1) < 1e-6, "{lm1:?}");
    let changed = labels(&st0)
        .iter()
        .zip(labels(&st1))
        .filter(|(x, y)| **x != *y)
        .count();
    let after = shots.join("pick-2-elbow-moved.png");
    b.screenshot(&after);
    // The colouring differs, and where the elbow moved: the differing
    // pixels centre on the left arm, between the old and new elbow.
    let dpr = b.eval("window.devicePixelRatio").as_f64().unwrap_or(1.0);
    let view = b
        .eval("document.getElementById('gl').clientWidth")
        .as_f64()
        .unwrap();
    let (n, centre, total) = diff(&before, &after, (view * dpr) as usize);
    let arm: Vec<f64> = [e, to]
        .iter()
        .flat_map(|p| {
            let q = b.eval(&format!("pick.project([{},{},{}])", p[0], p[1], p[2]));
            [q[0].as_f64().unwrap() * dpr, q[1].as_f64().unwrap() * dpr]
        })
        .collect();
    let mid = [(arm[0] + arm[2]) / 2.0, (arm[1] + arm[3]) / 2.0];
    let off = ((centre[0] - mid[0]).powi(2) + (centre[1] - mid[1]).powi(2)).sqrt();
    eprintln!(
        "pick: {changed} vertices changed part; {n} of {total} pixels differ, centred at {centre:?}, the elbow's move at {mid:?} ({off:.0} px away)"
    );
    assert!(changed > 50, "{changed}");
    assert!(n > 200 && n < total / 10, "{n} of {total} pixels differ");
    assert!(off < 60.0 * dpr, "the change is {off:.0} px from the elbow");

    // A real drag: the pointer presses on the right knee's handle and
    // lets go 25 px lower; the landmark follows onto the surface.
    b.eval("pick.setOverlay(true), pick.frame()");
    let k0 = point(&st1["landmarks"]["r_knee"]);
    let p = b.eval(&format!("pick.project([{},{},{}])", k0[0], k0[1], k0[2]));
    let (x0, y0) = (p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
    let rev = st1["revision"].as_u64().unwrap();
    let mouse = |b: &mut cdp::Browser, t: &str, x: f64, y: f64| {
        b.call(
            "Input.dispatchMouseEvent",
            json!({"type": t, "x": x, "y": y, "button": "left", "buttons": if t == "mouseReleased" { 0 } else { 1 }, "clickCount": 1}),
        );
    };
    mouse(&mut b, "mousePressed", x0, y0);
    for i in 1..=5 {
        mouse(&mut b, "mouseMoved", x0, y0 + 5.0 * i as f64);
    }
    mouse(&mut b, "mouseReleased", x0, y0 + 25.0);
    let st2 = b.wait_for(
        &format!("pick.state.revision > {rev} && pick.busy === 0 ? pick.state : null"),
        Duration::from_secs(60),
    );
    let k1 = point(&st2["landmarks"]["r_knee"]);
    assert!(surface_distance(&mesh, k1) < 1e-6, "{k1:?}");
    let up = point(&st2["up"]);
    let drop: f64 = (0..3).map(|i| (k0[i] - k1[i]) * up[i]).sum();
    assert!(drop > 0.01, "the knee moved {drop} down: {k0:?} → {k1:?}");
    b.eval("pick.frame()");
    b.screenshot(&shots.join("pick-3-knee-dragged.png"));

    // Save (the page's button's call): beside the input, read back.
    let r = b.eval("pick.save('').then((r) => r.body)");
    let saved = PathBuf::from(r["saved"].as_str().unwrap_or_else(|| panic!("{r}")));
    assert_eq!(saved, tmp.path().join("samba.picked.landmarks.json"));
    let back = Landmarks::load(&saved, mesh.vertex_count()).unwrap();
    let p_back = back.point(Landmark::LElbow, mesh.positions()).unwrap();
    assert!(dist(p_back, lm1) < 1e-12);
    let k_back = back.point(Landmark::RKnee, mesh.positions()).unwrap();
    assert!(dist(k_back, k1) < 1e-12);
    // The chin, given as a vertex id and not moved, stays one.
    assert!(
        std::fs::read_to_string(&saved)
            .unwrap()
            .contains("\"chin\": 8588")
    );
    assert_eq!(std::fs::read(&input).unwrap(), input_bytes);
    let errors = b.errors();
    assert!(errors.is_empty(), "console errors: {errors:?}");
    eprintln!("pick screenshots in {}", shots.display());
    let report = s.stop();
    assert_eq!(report.saved, vec![saved]);
}
