//! A small static server for an exported site, bound to 127.0.0.1 by
//! default. It serves files inside the site's folder only: request paths
//! are percent-decoded, and any `..`, `.`, empty, absolute or backslash
//! segment, or a file whose real path (symlinks resolved) leaves the
//! folder, is refused with 404.
//!
//! Slow or stalled clients cannot stall it (issue 46, item 8: six clients
//! that asked for a 64 MB file and stopped reading held all four threads of
//! the `tiny_http` server it used, and `GET /` got no answer in 5 s; that
//! server has no socket time-outs to set). Each connection gets its own
//! thread, up to [`ServeOptions::max_connections`]; a connection past the
//! cap is answered `503` at once by the accepting thread, which never
//! blocks. A response must be written within its deadline
//! ([`ServeOptions::write_timeout`] per write, and the whole body at
//! [`ServeOptions::min_rate`] at least); a request head must arrive within
//! [`ServeOptions::head_timeout`]; an idle keep-alive connection is closed
//! after [`ServeOptions::idle_timeout`], and at once when the server is
//! near its cap, so idle or half-open connections leave room for new ones.
//!
//! One path may be a WebSocket route ([`SiteServer::with_websocket`], as
//! `live --serve` streams its frames): a `GET` of it that asks to upgrade
//! is answered `101 Switching Protocols` and the connection handed to the
//! route's handler (with `tungstenite`) on its thread, counted against the
//! cap like any other.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// The file a request path names inside `root`, or `None` when the path
/// leaves it or names nothing there. `/` is `index.html`; the query and
/// fragment are ignored.
pub fn resolve_path(root: &Path, url: &str) -> Option<PathBuf> {
    let path = url.split(['?', '#']).next().unwrap_or("");
    let path = crate::util::fsutil::percent_decode(path)?;
    let rel = path.strip_prefix('/')?;
    let rel = if rel.is_empty() { "index.html" } else { rel };
    let mut out = root.to_path_buf();
    for seg in rel.split('/') {
        if seg.is_empty()
            || seg == "."
            || seg == ".."
            || seg.contains(['\\', '\0', ':'])
            || Path::new(seg).is_absolute()
        {
            return None;
        }
        out.push(seg);
    }
    let real = out.canonicalize().ok()?;
    let root = root.canonicalize().ok()?;
    (real.starts_with(&root) && real.is_file()).then_some(real)
}

fn content_type(p: &Path) -> &'static str {
    match p.extension().and_then(|e| e.to_str()).unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "json" => "application/json",
        "css" => "text/css",
        "png" => "image/png",
        "glsl" | "txt" => "text/plain; charset=utf-8",
        _ => "application/octet-stream",
    }
}

/// Limits of the server ([`ServeOptions::DEFAULT`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ServeOptions {
    /// Connections served at once, one thread each; a connection past the
    /// cap is answered `503 Service Unavailable` and closed. Default value:
    /// 64.
    pub max_connections: usize,
    /// Longest one write of a response may block (a client that stops
    /// reading). Default value: 10 s.
    pub write_timeout: Duration,
    /// Slowest rate, in bytes per second, at which a client may read a
    /// body: a response of `n` bytes must be written within
    /// `write_timeout + n / min_rate` (a client that reads a byte now and
    /// then). Default value: 256 kB/s (a 64 MB file: 4.4 minutes).
    pub min_rate: u64,
    /// Longest from the first byte of a request head to its end (a client
    /// that sends half a request and stops). Default value: 10 s.
    pub head_timeout: Duration,
    /// Longest a connection may wait for its next request (keep-alive).
    /// Near the cap (three quarters of `max_connections` in use) a
    /// connection that has waited for a request for `busy_idle_timeout`
    /// is closed at once, so that idle and half-open connections make room
    /// for new ones. Default value: 15 s.
    pub idle_timeout: Duration,
    /// The idle time-out near the cap. Default value: 1 s.
    pub busy_idle_timeout: Duration,
}

impl ServeOptions {
    /// The default limits.
    pub const DEFAULT: ServeOptions = ServeOptions {
        max_connections: 64,
        write_timeout: Duration::from_secs(10),
        min_rate: 256_000,
        head_timeout: Duration::from_secs(10),
        idle_timeout: Duration::from_secs(15),
        busy_idle_timeout: Duration::from_secs(1),
    };
}

impl Default for ServeOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Largest request head accepted (request line and headers); a larger one
/// is answered `431` and the connection closed.
pub(crate) const MAX_HEAD_BYTES: usize = 16 << 10;

/// How often a waiting connection and the accepting loop look at the stop
/// flag and the time-outs.
const POLL: Duration = Duration::from_millis(20);

/// A WebSocket route's handler: it gets the upgraded connection and the
/// server's stop flag, and returns when the client goes away or the flag is
/// set.
pub(crate) type WebSocketHandler =
    Arc<dyn Fn(tungstenite::WebSocket<TcpStream>, &AtomicBool) + Send + Sync>;

/// What the accepting loop and the connection threads share.
struct Shared {
    root: PathBuf,
    opts: ServeOptions,
    /// The WebSocket route: its path and handler.
    websocket: Option<(String, WebSocketHandler)>,
    /// Connections being served.
    active: AtomicUsize,
    /// Set to stop serving.
    stop: AtomicBool,
}

/// A running server of one site folder.
pub struct SiteServer {
    listener: TcpListener,
    shared: Arc<Shared>,
}

/// Errors of the server.
#[derive(Debug, thiserror::Error)]
#[error("cannot listen on {addr}: {msg}")]
pub struct ServeError {
    /// The address asked for.
    pub addr: String,
    /// Why.
    pub msg: String,
}

impl SiteServer {
    /// Listens on `addr` (`127.0.0.1:8080`; port 0 picks a free one) for
    /// the site in `root`, with the default limits.
    pub fn bind(root: &Path, addr: &str) -> Result<SiteServer, ServeError> {
        Self::bind_with(root, addr, ServeOptions::DEFAULT)
    }

    /// [`SiteServer::bind`] with other limits.
    pub fn bind_with(
        root: &Path,
        addr: &str,
        opts: ServeOptions,
    ) -> Result<SiteServer, ServeError> {
        let err = |msg: String| ServeError {
            addr: addr.into(),
            msg,
        };
        if opts.max_connections == 0 || opts.min_rate == 0 {
            return Err(err("max_connections and min_rate must be at least 1".into()));
        }
        let listener = TcpListener::bind(addr).map_err(|e| err(e.to_string()))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| err(e.to_string()))?;
        Ok(SiteServer {
            listener,
            shared: Arc::new(Shared {
                root: root.to_path_buf(),
                opts,
                websocket: None,
                active: AtomicUsize::new(0),
                stop: AtomicBool::new(false),
            }),
        })
    }

    /// Serves a WebSocket at `path` (e.g. `/live`): an upgrade request for it
    /// is handed to `handler`. Set before serving.
    pub(crate) fn with_websocket(mut self, path: &str, handler: WebSocketHandler) -> SiteServer {
        if let Some(sh) = Arc::get_mut(&mut self.shared) {
            sh.websocket = Some((path.to_string(), handler));
        }
        self
    }

    /// The URL of the site.
    pub fn url(&self) -> String {
        match self.listener.local_addr() {
            Ok(a) => format!("http://{a}/"),
            Err(_) => "http://localhost/".into(),
        }
    }

    /// Serves requests until the process ends.
    pub fn run(&self) {
        self.run_until(&AtomicBool::new(false))
    }

    /// Serves requests until `stop` is set (a signal handler's flag): it
    /// is looked at every 20 ms. Connections being served are told to
    /// stop too (a response being written ends at its deadline at the
    /// latest); they are not waited for.
    pub fn run_until(&self, stop: &AtomicBool) {
        loop {
            if stop.load(Ordering::Relaxed) || self.shared.stop.load(Ordering::Relaxed) {
                self.shared.stop.store(true, Ordering::Relaxed);
                return;
            }
            match self.listener.accept() {
                Ok((s, _)) => self.admit(s),
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => std::thread::sleep(POLL),
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => {
                    // Out of file descriptors and the like: wait, do not spin.
                    tracing::warn!("web serve: accept failed: {e}");
                    std::thread::sleep(Duration::from_millis(100));
                }
            }
        }
    }

    /// Serves requests on a background thread until the process ends.
    pub fn spawn(self) -> std::thread::JoinHandle<()> {
        std::thread::spawn(move || self.run())
    }

    /// Serves a new connection on a thread of its own, or answers 503 when
    /// the cap is reached. Never blocks.
    fn admit(&self, s: TcpStream) {
        let sh = &self.shared;
        if sh.active.fetch_add(1, Ordering::SeqCst) >= sh.opts.max_connections {
            sh.active.fetch_sub(1, Ordering::SeqCst);
            // The socket's buffer takes these few bytes at once; if it
            // does not, the client is not reading and loses nothing.
            let _ = s.set_nonblocking(true);
            let _ = (&s).write(
                b"HTTP/1.1 503 Service Unavailable\r\nContent-Length: 0\r\nRetry-After: 1\r\nConnection: close\r\n\r\n",
            );
            return;
        }
        let guard = Active(Arc::clone(sh));
        let spawned = std::thread::Builder::new()
            .name("surfmotion-serve".into())
            .spawn(move || {
                let sh = Arc::clone(&guard.0);
                serve_connection(&sh, s);
                drop(guard);
            });
        if let Err(e) = spawned {
            tracing::warn!("web serve: cannot start a connection thread: {e}");
        }
    }
}

/// One connection being served: counted in [`Shared::active`] while alive.
struct Active(Arc<Shared>);

impl Drop for Active {
    fn drop(&mut self) {
        self.0.active.fetch_sub(1, Ordering::SeqCst);
    }
}

/// A parsed request head.
struct Head {
    method: String,
    target: String,
    /// The connection may serve another request after this one.
    keep_alive: bool,
    /// `Sec-WebSocket-Key` of a request to upgrade to a WebSocket.
    websocket_key: Option<String>,
}

/// Serves requests on one connection until it closes, fails a time-out or
/// the server stops.
fn serve_connection(sh: &Shared, mut s: TcpStream) {
    if s.set_nonblocking(false).is_err() || s.set_read_timeout(Some(POLL)).is_err() {
        return;
    }
    let _ = s.set_nodelay(true);
    let mut buf = Vec::new();
    while let Some(head) = read_head(sh, &mut s, &mut buf) {
        if let Some(handler) = websocket_route(sh, &head) {
            upgrade(sh, s, &head, handler);
            return;
        }
        if !respond(sh, &mut s, &head) || !head.keep_alive {
            break;
        }
    }
    let _ = s.shutdown(std::net::Shutdown::Both);
}

/// The next request head on `s` (bytes after it stay in `buf`), or `None`
/// when the connection is to be closed: the client closed it, waited past
/// a time-out, sent a head too large or malformed (answered), or the server
/// stops.
fn read_head(sh: &Shared, s: &mut TcpStream, buf: &mut Vec<u8>) -> Option<Head> {
    let since = Instant::now();
    let mut first_byte = (!buf.is_empty()).then_some(since);
    let mut chunk = [0u8; 4096];
    loop {
        if let Some(end) = find_head_end(buf) {
            let head: Vec<u8> = buf.drain(..end + 4).collect();
            return parse_head(s, &head);
        }
        if buf.len() > MAX_HEAD_BYTES {
            let _ = reply(sh, s, "431 Request Header Fields Too Large", false);
            return None;
        }
        if sh.stop.load(Ordering::Relaxed) {
            return None;
        }
        let waited = since.elapsed();
        let busy = sh.active.load(Ordering::Relaxed) * 4 >= sh.opts.max_connections * 3;
        match first_byte {
            None if waited >= sh.opts.idle_timeout => return None,
            _ if busy && waited >= sh.opts.busy_idle_timeout => return None,
            Some(t) if t.elapsed() >= sh.opts.head_timeout => {
                let _ = reply(sh, s, "408 Request Timeout", false);
                return None;
            }
            _ => {}
        }
        match s.read(&mut chunk) {
            Ok(0) => return None,
            Ok(n) => {
                first_byte.get_or_insert_with(Instant::now);
                buf.extend_from_slice(&chunk[..n]);
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock
                        | std::io::ErrorKind::TimedOut
                        | std::io::ErrorKind::Interrupted
                ) => {}
            Err(_) => return None,
        }
    }
}

/// The handler of the WebSocket route when `head` asks to upgrade on it.
fn websocket_route(sh: &Shared, head: &Head) -> Option<WebSocketHandler> {
    let (path, handler) = sh.websocket.as_ref()?;
    let target = head.target.split(['?', '#']).next().unwrap_or("");
    (head.method == "GET" && head.websocket_key.is_some() && target == path)
        .then(|| Arc::clone(handler))
}

/// Answers `101 Switching Protocols` and hands the connection to `handler`.
fn upgrade(sh: &Shared, mut s: TcpStream, head: &Head, handler: WebSocketHandler) {
    let key = head.websocket_key.as_deref().unwrap_or("");
    let accept = tungstenite::handshake::derive_accept_key(key.as_bytes());
    let answer = format!(
        "HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Accept: {accept}\r\n\r\n"
    );
    if !write_all_by(
        &mut s,
        answer.as_bytes(),
        Instant::now() + sh.opts.write_timeout,
    ) {
        return;
    }
    // Writes block at most the write time-out (a client that stops reading
    // is dropped); reads wait a poll period.
    if s.set_write_timeout(Some(sh.opts.write_timeout)).is_err() {
        return;
    }
    let ws = tungstenite::WebSocket::from_raw_socket(s, tungstenite::protocol::Role::Server, None);
    handler(ws, &sh.stop);
}

fn find_head_end(b: &[u8]) -> Option<usize> {
    b.windows(4).position(|w| w == b"\r\n\r\n")
}

/// Parses a request head; a malformed one is answered `400` (`None`).
fn parse_head(s: &mut TcpStream, head: &[u8]) -> Option<Head> {
    let text = String::from_utf8_lossy(head);
    let mut lines = text.split("\r\n");
    let mut first = lines.next().unwrap_or("").split(' ');
    let (Some(method), Some(target), Some(version), None) =
        (first.next(), first.next(), first.next(), first.next())
    else {
        let _ = write_all_by(
            s,
            b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\nConnection: close\r\n\r\n",
            Instant::now() + Duration::from_secs(1),
        );
        return None;
    };
    let mut keep_alive = version == "HTTP/1.1";
    let (mut upgrade, mut websocket_key) = (false, None);
    for line in lines {
        let Some((k, v)) = line.split_once(':') else {
            continue;
        };
        let (k, v) = (k.trim(), v.trim());
        if k.eq_ignore_ascii_case("upgrade") && v.eq_ignore_ascii_case("websocket") {
            upgrade = true;
        }
        if k.eq_ignore_ascii_case("sec-websocket-key") {
            websocket_key = Some(v.to_string());
        }
        if k.eq_ignore_ascii_case("connection") {
            if v.eq_ignore_ascii_case("close") {
                keep_alive = false;
            } else if v.eq_ignore_ascii_case("keep-alive") {
                keep_alive = true;
            }
        }
        // A request body is not read: the connection ends after the answer.
        let body = (k.eq_ignore_ascii_case("content-length") && v != "0")
            || k.eq_ignore_ascii_case("transfer-encoding");
        if body {
            keep_alive = false;
        }
    }
    Some(Head {
        method: method.to_string(),
        target: target.to_string(),
        keep_alive,
        websocket_key: websocket_key.filter(|_| upgrade),
    })
}

/// An empty answer with `status`; `false` when it could not be written.
fn reply(sh: &Shared, s: &mut TcpStream, status: &str, keep_alive: bool) -> bool {
    let head = format!(
        "HTTP/1.1 {status}\r\nContent-Length: 0\r\n{}{}\r\n",
        if status.starts_with("405") {
            "Allow: GET, HEAD\r\n"
        } else {
            ""
        },
        connection(keep_alive)
    );
    write_all_by(s, head.as_bytes(), Instant::now() + sh.opts.write_timeout)
}

fn connection(keep_alive: bool) -> &'static str {
    if keep_alive {
        "Connection: keep-alive\r\n"
    } else {
        "Connection: close\r\n"
    }
}

/// Answers one request; `false` when the connection must close (a write
/// failed or missed its deadline, the file ended early).
fn respond(sh: &Shared, s: &mut TcpStream, head: &Head) -> bool {
    let get = head.method == "GET";
    if !get && head.method != "HEAD" {
        let _ = reply(sh, s, "405 Method Not Allowed", false);
        return false;
    }
    let file = resolve_path(&sh.root, &head.target).and_then(|p| {
        // A named pipe in the folder would block this thread.
        let f = crate::util::fsutil::open_input(&p, crate::util::fsutil::MAX_INPUT_BYTES).ok()?;
        let len = f.metadata().ok()?.len();
        Some((p, f, len))
    });
    let Some((p, f, len)) = file else {
        let body = b"not found";
        let h = format!(
            "HTTP/1.1 404 Not Found\r\nContent-Type: text/plain; charset=utf-8\r\nContent-Length: {}\r\n{}\r\n",
            body.len(),
            connection(head.keep_alive)
        );
        let deadline = Instant::now() + sh.opts.write_timeout;
        return write_all_by(s, h.as_bytes(), deadline)
            && (!get || write_all_by(s, body, deadline));
    };
    let h = format!(
        "HTTP/1.1 200 OK\r\nContent-Type: {}\r\nContent-Length: {len}\r\nCache-Control: no-cache\r\nX-Content-Type-Options: nosniff\r\n{}\r\n",
        content_type(&p),
        connection(head.keep_alive)
    );
    let body_time = Duration::from_secs_f64(len as f64 / sh.opts.min_rate as f64);
    let deadline = Instant::now() + sh.opts.write_timeout + body_time;
    if !write_all_by(s, h.as_bytes(), deadline) {
        return false;
    }
    if !get {
        return true;
    }
    let mut f = f.take(len);
    let mut chunk = vec![0u8; 64 << 10];
    let mut sent = 0u64;
    while sent < len {
        if sh.stop.load(Ordering::Relaxed) {
            return false;
        }
        let n = match f.read(&mut chunk) {
            Ok(0) | Err(_) => return false, // the file shrank: the length sent is wrong
            Ok(n) => n,
        };
        let step = deadline.min(Instant::now() + sh.opts.write_timeout);
        if !write_all_by(s, &chunk[..n], step) {
            return false;
        }
        sent += n as u64;
    }
    true
}

/// Writes all of `bytes` by `deadline`; `false` if the client did not take
/// them in time or the connection failed.
fn write_all_by(s: &mut TcpStream, mut bytes: &[u8], deadline: Instant) -> bool {
    while !bytes.is_empty() {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || s.set_write_timeout(Some(left)).is_err() {
            return false;
        }
        match s.write(bytes) {
            Ok(0) => return false,
            Ok(n) => bytes = &bytes[n..],
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(_) => return false,
        }
    }
    true
}

/// Prefix of the temporary folders `web serve --db/--result` exports into
/// (in the system's temporary folder): `surfmotion-serve-<PID>-XXXXXX`,
/// holding the file [`EXPORT_MARKER`] with the process id.
pub(crate) const EXPORT_DIR_PREFIX: &str = "surfmotion-serve-";

/// The file in a serve export folder that names the process that made it.
pub(crate) const EXPORT_MARKER: &str = "surfmotion-serve.pid";

/// A new temporary folder in `parent` for a served export, named and
/// marked with this process's id (removed when dropped).
pub fn export_folder(parent: &Path) -> std::io::Result<tempfile::TempDir> {
    let pid = std::process::id();
    let t = tempfile::Builder::new()
        .prefix(&format!("{EXPORT_DIR_PREFIX}{pid}-"))
        .tempdir_in(parent)?;
    std::fs::write(t.path().join(EXPORT_MARKER), pid.to_string())?;
    Ok(t)
}

/// Removes from `parent` the export folders of `web serve` runs that ended
/// without cleaning up (issue 46, item 13: one stopped by SIGTERM left its
/// 1.7 MB export behind): only folders it can prove are such — named
/// `surfmotion-serve-<PID>-XXXXXX`, a real folder owned by this user,
/// holding an [`EXPORT_MARKER`] with the same process id — whose process
/// is gone. Returns the folders removed.
pub fn remove_stale_exports(parent: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(rd) = std::fs::read_dir(parent) else {
        return out;
    };
    for e in rd.flatten() {
        let name = e.file_name();
        let Some(pid) = name
            .to_str()
            .and_then(|n| n.strip_prefix(EXPORT_DIR_PREFIX))
            .and_then(|r| r.split_once('-'))
            .filter(|(_, x)| x.len() == 6 && x.bytes().all(|b| b.is_ascii_alphanumeric()))
            .and_then(|(p, _)| p.parse::<u32>().ok())
        else {
            continue;
        };
        let dir = e.path();
        let own = std::fs::symlink_metadata(&dir)
            .is_ok_and(|m| m.is_dir() && crate::util::fsutil::owned_by_me(&m))
            && std::fs::read_to_string(dir.join(EXPORT_MARKER))
                .is_ok_and(|m| m.trim() == pid.to_string());
        if own
            && pid != std::process::id()
            && crate::util::fsutil::process_alive(pid) == Some(false)
            && std::fs::remove_dir_all(&dir).is_ok()
        {
            out.push(dir);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_outside_the_site_are_refused() {
        let d = tempfile::tempdir().unwrap();
        let site = d.path().join("site");
        std::fs::create_dir_all(site.join("sub")).unwrap();
        std::fs::write(site.join("index.html"), "x").unwrap();
        std::fs::write(site.join("sub/a.js"), "x").unwrap();
        std::fs::write(d.path().join("secret.txt"), "no").unwrap();
        assert!(resolve_path(&site, "/").is_some());
        assert!(resolve_path(&site, "/sub/a.js?v=1").is_some());
        assert!(resolve_path(&site, "/sub%2fa.js").is_some());
        for bad in [
            "/../secret.txt",
            "/sub/../../secret.txt",
            "/%2e%2e/secret.txt",
            "/%2E%2E%2Fsecret.txt",
            "/sub/%2e%2e/%2e%2e/secret.txt",
            "//etc/passwd",
            "/%2fetc%2fpasswd",
            "/..%5csecret.txt",
            "/%00",
            "/%zz",
            "secret.txt",
            "/missing.js",
        ] {
            assert!(resolve_path(&site, bad).is_none(), "{bad}");
        }
        let abs = format!("/{}", d.path().join("secret.txt").display());
        assert!(resolve_path(&site, &abs).is_none(), "{abs}");
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(d.path().join("secret.txt"), site.join("link.txt")).unwrap();
            assert!(resolve_path(&site, "/link.txt").is_none());
        }
    }
}
