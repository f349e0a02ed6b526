//! The `--pick` page's server: [`super::serve`]'s static server serves
//! files and refuses bodies, so this one answers the page's API
//! ([`PickSession::handle`]) on 127.0.0.1. One thread per connection (at
//! most [`MAX_CONNECTIONS`]), one request per connection, a request head
//! within [`ServeOptions::head_timeout`] and [`MAX_HEAD_BYTES`], a body
//! within [`MAX_BODY_BYTES`], every write within
//! [`ServeOptions::write_timeout`].
//!
//! A web page on another site can send requests to 127.0.0.1 too: a `POST`
//! must carry `Content-Type: application/json` (which such a page cannot
//! send without the browser asking first, and this server never allows
//! it), and every request's `Host` must be this server's own address
//! (`127.0.0.1:PORT` or `localhost:PORT`, against DNS rebinding).

use super::session::{MAX_BODY_BYTES, PickSession, Response};
use crate::web::serve::{MAX_HEAD_BYTES, ServeError, ServeOptions};
use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Connections served at once; one past it is answered `503`.
pub(crate) const MAX_CONNECTIONS: usize = 16;

const POLL: Duration = Duration::from_millis(20);

struct Shared {
    session: Mutex<PickSession>,
    port: u16,
    opts: ServeOptions,
    active: AtomicUsize,
    stop: AtomicBool,
    requests: AtomicUsize,
}

/// A bound `--pick` server.
pub struct PickServer {
    listener: TcpListener,
    shared: Arc<Shared>,
}

impl PickServer {
    /// Listens on `addr` (`127.0.0.1:0` picks a free port) for `session`.
    pub fn bind(session: PickSession, addr: &str) -> Result<PickServer, ServeError> {
        let err = |msg: String| ServeError {
            addr: addr.into(),
            msg,
        };
        let listener = TcpListener::bind(addr).map_err(|e| err(e.to_string()))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| err(e.to_string()))?;
        let port = listener
            .local_addr()
            .map_err(|e| err(e.to_string()))?
            .port();
        Ok(PickServer {
            listener,
            shared: Arc::new(Shared {
                session: Mutex::new(session),
                port,
                opts: ServeOptions::DEFAULT,
                active: AtomicUsize::new(0),
                stop: AtomicBool::new(false),
                requests: AtomicUsize::new(0),
            }),
        })
    }

    /// The page's URL.
    pub fn url(&self) -> String {
        match self.listener.local_addr() {
            Ok(a) => format!("http://{a}/"),
            Err(_) => format!("http://127.0.0.1:{}/", self.shared.port),
        }
    }

    /// Requests answered so far.
    pub fn requests(&self) -> usize {
        self.shared.requests.load(Ordering::Relaxed)
    }

    /// Runs `f` on the session (waiting for a request being answered).
    pub(crate) fn with_session<T>(&self, f: impl FnOnce(&PickSession) -> T) -> T {
        f(&self
            .shared
            .session
            .lock()
            .unwrap_or_else(|e| e.into_inner()))
    }

    /// Serves until `stop` is set (looked at every 20 ms).
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
                    tracing::warn!("pick: accept failed: {e}");
                    std::thread::sleep(Duration::from_millis(100));
                }
            }
        }
    }

    /// Serves on a background thread until `stop` is set; the server
    /// comes back from the thread's `join`.
    pub fn spawn(self, stop: Arc<AtomicBool>) -> std::thread::JoinHandle<PickServer> {
        std::thread::spawn(move || {
            self.run_until(&stop);
            self
        })
    }

    fn admit(&self, s: TcpStream) {
        let sh = &self.shared;
        if sh.active.fetch_add(1, Ordering::SeqCst) >= MAX_CONNECTIONS {
            sh.active.fetch_sub(1, Ordering::SeqCst);
            let _ = s.set_nonblocking(true);
            let _ = (&s).write(
                b"HTTP/1.1 503 Service Unavailable\r\nContent-Length: 0\r\nConnection: close\r\n\r\n",
            );
            return;
        }
        let sh = Arc::clone(sh);
        let spawned = std::thread::Builder::new()
            .name("surfmotion-pick".into())
            .spawn(move || {
                serve_one(&sh, s);
                sh.active.fetch_sub(1, Ordering::SeqCst);
            });
        if let Err(e) = spawned {
            self.shared.active.fetch_sub(1, Ordering::SeqCst);
            tracing::warn!("pick: cannot start a connection thread: {e}");
        }
    }
}

/// A request as read off the socket.
struct Request {
    method: String,
    target: String,
    host: Option<String>,
    content_type: Option<String>,
    body: Vec<u8>,
}

/// Reads one request, answers it and closes the connection.
fn serve_one(sh: &Shared, mut s: TcpStream) {
    if s.set_nonblocking(false).is_err() || s.set_read_timeout(Some(POLL)).is_err() {
        return;
    }
    let _ = s.set_nodelay(true);
    let r = match read_request(sh, &mut s) {
        Ok(Some(r)) => answer(sh, &r),
        Ok(None) => return,
        Err(r) => r,
    };
    write_response(sh, &mut s, &r);
    let _ = s.shutdown(std::net::Shutdown::Both);
}

/// The answer to a well-formed request.
fn answer(sh: &Shared, r: &Request) -> Response {
    sh.requests.fetch_add(1, Ordering::Relaxed);
    let ours = [
        format!("127.0.0.1:{}", sh.port),
        format!("localhost:{}", sh.port),
        format!("[::1]:{}", sh.port),
    ];
    match &r.host {
        Some(h) if ours.iter().any(|o| o.eq_ignore_ascii_case(h)) => {}
        h => {
            return Response::error(
                403,
                format!(
                    "Host {h:?}: this page answers only on 127.0.0.1:{}",
                    sh.port
                ),
            );
        }
    }
    if r.method == "POST"
        && !r.content_type.as_deref().is_some_and(|c| {
            c.trim()
                .to_ascii_lowercase()
                .starts_with("application/json")
        })
    {
        return Response::error(415, "a POST must be Content-Type: application/json");
    }
    // A panic while embedding would leave the page without an answer; it
    // is a bug, answered 500 with what it said.
    let mut session = sh.session.lock().unwrap_or_else(|e| e.into_inner());
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        session.handle(&r.method, &r.target, &r.body)
    })) {
        Ok(resp) => resp,
        Err(p) => {
            let what = p
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            Response::error(500, format!("internal error: {what}"))
        }
    }
}

/// `Ok(None)`: the client went away or the server stops; `Err`: an answer
/// to a malformed request.
fn read_request(sh: &Shared, s: &mut TcpStream) -> Result<Option<Request>, Response> {
    let start = Instant::now();
    let mut buf = Vec::new();
    let mut chunk = [0u8; 8192];
    let end = loop {
        if let Some(e) = buf.windows(4).position(|w| w == b"\r\n\r\n") {
            break e;
        }
        if buf.len() > MAX_HEAD_BYTES {
            return Err(Response::error(431, "request head too large"));
        }
        if sh.stop.load(Ordering::Relaxed) {
            return Ok(None);
        }
        if start.elapsed() > sh.opts.head_timeout {
            return Err(Response::error(408, "no complete request in time"));
        }
        match s.read(&mut chunk) {
            Ok(0) => return Ok(None),
            Ok(n) => buf.extend_from_slice(&chunk[..n]),
            Err(e) if is_wait(&e) => {}
            Err(_) => return Ok(None),
        }
    };
    let head = String::from_utf8_lossy(&buf[..end]).into_owned();
    let mut body: Vec<u8> = buf[end + 4..].to_vec();
    let mut lines = head.split("\r\n");
    let mut first = lines.next().unwrap_or("").split(' ');
    let (Some(method), Some(target), Some(_), None) =
        (first.next(), first.next(), first.next(), first.next())
    else {
        return Err(Response::error(400, "malformed request line"));
    };
    let (mut host, mut content_type, mut length) = (None, None, 0usize);
    for line in lines {
        let Some((k, v)) = line.split_once(':') else {
            continue;
        };
        let (k, v) = (k.trim(), v.trim());
        if k.eq_ignore_ascii_case("host") {
            host = Some(v.to_string());
        } else if k.eq_ignore_ascii_case("content-type") {
            content_type = Some(v.to_string());
        } else if k.eq_ignore_ascii_case("transfer-encoding") {
            return Err(Response::error(411, "send the body with a Content-Length"));
        } else if k.eq_ignore_ascii_case("content-length") {
            length = v
                .parse()
                .map_err(|_| Response::error(400, format!("Content-Length {v:?}")))?;
        }
    }
    if length > MAX_BODY_BYTES {
        return Err(Response::error(
            413,
            format!("the body has {length} bytes; at most {MAX_BODY_BYTES}"),
        ));
    }
    while body.len() < length {
        if sh.stop.load(Ordering::Relaxed) {
            return Ok(None);
        }
        if start.elapsed() > sh.opts.head_timeout {
            return Err(Response::error(408, "the body did not arrive in time"));
        }
        match s.read(&mut chunk) {
            Ok(0) => return Err(Response::error(400, "the body ended early")),
            Ok(n) => body.extend_from_slice(&chunk[..n]),
            Err(e) if is_wait(&e) => {}
            Err(_) => return Ok(None),
        }
    }
    body.truncate(length);
    Ok(Some(Request {
        method: method.to_string(),
        target: target.to_string(),
        host,
        content_type,
        body,
    }))
}

fn is_wait(e: &std::io::Error) -> bool {
    matches!(
        e.kind(),
        std::io::ErrorKind::WouldBlock
            | std::io::ErrorKind::TimedOut
            | std::io::ErrorKind::Interrupted
    )
}

fn reason(status: u16) -> &'static str {
    match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        409 => "Conflict",
        411 => "Length Required",
        413 => "Content Too Large",
        415 => "Unsupported Media Type",
        422 => "Unprocessable Content",
        431 => "Request Header Fields Too Large",
        _ => "Internal Server Error",
    }
}

fn write_response(sh: &Shared, s: &mut TcpStream, r: &Response) {
    let head = format!(
        "HTTP/1.1 {} {}\r\nContent-Type: {}\r\nContent-Length: {}\r\nCache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\nConnection: close\r\n\r\n",
        r.status,
        reason(r.status),
        r.content_type,
        r.body.len()
    );
    let body_time = Duration::from_secs_f64(r.body.len() as f64 / sh.opts.min_rate as f64);
    let deadline = Instant::now() + sh.opts.write_timeout + body_time;
    for part in [head.as_bytes(), &r.body] {
        let mut bytes = part;
        while !bytes.is_empty() {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() || s.set_write_timeout(Some(left)).is_err() {
                return;
            }
            match s.write(bytes) {
                Ok(0) => return,
                Ok(n) => bytes = &bytes[n..],
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(_) => return,
            }
        }
    }
}
