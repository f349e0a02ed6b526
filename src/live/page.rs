//! `live --serve`: the browser page. The local server ([`SiteServer`])
//! serves the page (`src/web/assets/live.html`, `live.js`) and streams the
//! frames over a WebSocket at `/live`: first the character's topology (a
//! text message, JSON), then every output frame (binary, newest wins: a
//! page that draws slower than the stream skips frames, counted per
//! client).
//!
//! A frame message is little-endian: `u32` kind (2), `u32` frame number,
//! `f32` arrival-to-mesh latency (ms), `f32` output rate (frames/s),
//! `f64` the time it was sent (ms since the Unix epoch, for the page's own
//! delivery latency), `f32` × 3 the quantisation origin (metres), `f32` the
//! step (metres per unit), `f32` × 3 the vertices' centroid (the camera
//! follows it), the incoming skeleton's 19 canonical joints (`f32` × 3 ×
//! 19, metres, Y-up), then the character's vertices quantised as the web
//! codec does (`u16` × 3 × n, `origin + step · q`: within half a step,
//! 15 µm for a body 2 m tall). The page dequantises them in its vertex
//! shader and lights each triangle by the derivatives of its position (no
//! normals are sent or computed per vertex), so it does no per-vertex work
//! in JavaScript.

use crate::rig::Canonical;
use crate::web::serve::{ServeError, SiteServer, WebSocketHandler, export_folder};
use serde::Serialize;
use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Duration;

/// The page.
pub(crate) const LIVE_HTML: &str = include_str!("../web/assets/live.html");
/// Its script.
pub(crate) const LIVE_JS: &str = include_str!("../web/assets/live.js");

/// The path of the frames' WebSocket.
pub(crate) const WS_PATH: &str = "/live";

/// What the page is told first.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct Meta {
    /// Vertices of the character.
    pub vertices: usize,
    /// Its triangles (vertex indices, three a triangle).
    pub triangles: Vec<u32>,
    /// The database's frame rate.
    pub fps: f64,
    /// The retrieval's lag (frames).
    pub lag: usize,
    /// Canonical joint names and parents (-1: the root).
    pub joints: Vec<&'static str>,
    /// Each joint's parent index (-1: the root).
    pub parents: Vec<i32>,
}

#[derive(Default)]
struct Slot {
    meta: Option<Arc<String>>,
    frame: Option<(u64, Arc<Vec<u8>>)>,
    /// A frame's buffer no page holds any more, reused by the next.
    spare: Option<Vec<u8>>,
    closed: bool,
}

/// The newest frame, shared by the session (which publishes) and every
/// page connected (each sends the newest it has not sent).
#[derive(Default)]
pub(crate) struct Hub {
    slot: Mutex<Slot>,
    ready: Condvar,
}

/// One output frame as the page gets it.
pub(crate) struct PageFrame<'a> {
    /// Output frame number.
    pub index: u64,
    /// Arrival to mesh ready (ms).
    pub latency_ms: f64,
    /// Output frames per second so far.
    pub output_fps: f64,
    /// The character's vertices (metres, Y-up).
    pub positions: &'a [[f64; 3]],
    /// The incoming skeleton (metres, Y-up).
    pub incoming: &'a crate::pose::Pose,
}

impl Hub {
    fn lock(&self) -> MutexGuard<'_, Slot> {
        self.slot.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Sets what a page is told first.
    pub(crate) fn set_meta(&self, meta: &Meta) {
        let text = serde_json::to_string(meta).unwrap_or_default();
        self.lock().meta = Some(Arc::new(text));
        self.ready.notify_all();
    }

    /// Publishes a frame (replacing one no page has taken yet). The
    /// frame's buffer is the previous one's when no page still holds it,
    /// so a session with the page open does not allocate per frame.
    pub(crate) fn publish(&self, f: &PageFrame<'_>) {
        let mut bytes = self.lock().spare.take().unwrap_or_default();
        encode(f, &mut bytes);
        let mut s = self.lock();
        let old = s.frame.replace((f.index, Arc::new(bytes)));
        if let Some((_, old)) = old
            && let Ok(v) = Arc::try_unwrap(old)
        {
            s.spare = Some(v);
        }
        drop(s);
        self.ready.notify_all();
    }

    /// Ends every page's stream.
    pub fn close(&self) {
        self.lock().closed = true;
        self.ready.notify_all();
    }

    /// Streams to one page until it goes away, the hub closes or `stop`
    /// is set.
    pub fn serve(&self, mut ws: tungstenite::WebSocket<TcpStream>, stop: &AtomicBool) {
        use tungstenite::Message;
        let mut sent_meta = false;
        let mut sent: Option<u64> = None;
        loop {
            let (meta, frame) = {
                let mut s = self.lock();
                let fresh = |s: &Slot| {
                    s.closed
                        || (!sent_meta && s.meta.is_some())
                        || s.frame.as_ref().is_some_and(|(i, _)| Some(*i) != sent)
                };
                if !fresh(&s) {
                    s = self
                        .ready
                        .wait_timeout(s, Duration::from_millis(50))
                        .map(|(g, _)| g)
                        .unwrap_or_else(|e| e.into_inner().0);
                }
                if s.closed || stop.load(Ordering::Relaxed) {
                    let _ = ws.close(None);
                    let _ = ws.flush();
                    return;
                }
                (
                    s.meta.clone().filter(|_| !sent_meta),
                    s.frame
                        .clone()
                        .filter(|(i, _)| sent_meta && Some(*i) != sent),
                )
            };
            let result = if let Some(m) = meta {
                sent_meta = true;
                ws.send(Message::text(m.as_str()))
            } else if let Some((i, bytes)) = frame {
                sent = Some(i);
                ws.send(Message::binary(bytes.to_vec()))
            } else {
                Ok(())
            };
            if result.is_err() {
                return;
            }
        }
    }
}

/// Bytes of a frame message before the positions.
pub(crate) const FRAME_HEADER: usize = 52 + 12 * Canonical::COUNT;

/// A frame as the page reads it (see the module doc), into `b` (cleared
/// first; its capacity is kept).
fn encode(f: &PageFrame<'_>, b: &mut Vec<u8>) {
    b.clear();
    let n = f.positions.len();
    b.reserve(FRAME_HEADER + 6 * n);
    b.extend_from_slice(&2u32.to_le_bytes());
    b.extend_from_slice(&(f.index as u32).to_le_bytes());
    b.extend_from_slice(&(f.latency_ms as f32).to_le_bytes());
    b.extend_from_slice(&(f.output_fps as f32).to_le_bytes());
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64() * 1e3);
    b.extend_from_slice(&now.to_le_bytes());
    let (lo, step, centre) = quantisation(f.positions);
    for x in lo.iter().chain([&step]).chain(&centre) {
        b.extend_from_slice(&(*x as f32).to_le_bytes());
    }
    for p in f.incoming {
        for x in p.to_array() {
            b.extend_from_slice(&(x as f32).to_le_bytes());
        }
    }
    for p in f.positions {
        for k in 0..3 {
            let q = ((p[k] - lo[k]) / step).round().clamp(0.0, 65535.0) as u16;
            b.extend_from_slice(&q.to_le_bytes());
        }
    }
}

/// The quantisation of one frame (the web codec's scheme): the bounding
/// box's lower corner, one step for all three axes (the longest side over
/// 65,535 units; non-finite coordinates are left out), and the centroid.
fn quantisation(positions: &[[f64; 3]]) -> ([f64; 3], f64, [f64; 3]) {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    let (mut sum, mut count) = ([0.0; 3], 0usize);
    for p in positions.iter().filter(|p| p.iter().all(|x| x.is_finite())) {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
            sum[k] += p[k];
        }
        count += 1;
    }
    if count == 0 {
        return ([0.0; 3], 1.0, [0.0; 3]);
    }
    let side = (0..3).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
    let step = (side / 65535.0).max(1e-9);
    (lo, step, sum.map(|s| s / count as f64))
}

/// The page's server, running until dropped.
pub(crate) struct PageServer {
    hub: Arc<Hub>,
    stop: Arc<AtomicBool>,
    url: String,
    _folder: tempfile::TempDir,
}

/// Why the page could not be served.
#[derive(Debug, thiserror::Error)]
pub enum PageError {
    /// The page's folder could not be written.
    #[error("writing the live page: {0}")]
    Io(#[from] std::io::Error),
    /// The address could not be listened on.
    #[error(transparent)]
    Serve(#[from] ServeError),
}

impl PageServer {
    /// Serves the page on `addr` (port 0 picks one), telling each page
    /// `meta` first.
    pub fn start(addr: std::net::SocketAddr, meta: &Meta) -> Result<PageServer, PageError> {
        let folder = export_folder(&std::env::temp_dir())?;
        std::fs::write(folder.path().join("index.html"), LIVE_HTML)?;
        std::fs::write(folder.path().join("live.js"), LIVE_JS)?;
        let hub = Arc::new(Hub::default());
        hub.set_meta(meta);
        let h = hub.clone();
        let handler: WebSocketHandler = Arc::new(move |ws, stop| h.serve(ws, stop));
        let server =
            SiteServer::bind(folder.path(), &addr.to_string())?.with_websocket(WS_PATH, handler);
        let url = server.url();
        let stop = Arc::new(AtomicBool::new(false));
        let st = stop.clone();
        std::thread::spawn(move || server.run_until(&st));
        Ok(PageServer {
            hub,
            stop,
            url,
            _folder: folder,
        })
    }

    /// The page's URL.
    pub fn url(&self) -> &str {
        &self.url
    }

    /// Publishes a frame to every page.
    pub(crate) fn publish(&self, f: &PageFrame<'_>) {
        self.hub.publish(f);
    }
}

impl Drop for PageServer {
    fn drop(&mut self) {
        self.hub.close();
        self.stop.store(true, Ordering::Relaxed);
    }
}

/// The canonical joints' names and parents, for the page.
pub fn skeleton() -> (Vec<&'static str>, Vec<i32>) {
    Canonical::ALL
        .iter()
        .map(|c| (c.name(), c.parent().map_or(-1, |p| p.index() as i32)))
        .unzip()
}
