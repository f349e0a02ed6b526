//! A small static server for an exported site (tiny_http), bound to
//! 127.0.0.1 by default. It serves files inside the site's folder only:
//! request paths are percent-decoded, and any `..`, `.`, empty, absolute or
//! backslash segment, or a file whose real path (symlinks resolved) leaves
//! the folder, is refused with 404.

use std::path::{Path, PathBuf};

/// The file a request path names inside `root`, or `None` when the path
/// leaves it or names nothing there. `/` is `index.html`; the query and
/// fragment are ignored.
pub fn resolve_path(root: &Path, url: &str) -> Option<PathBuf> {
    let path = url.split(['?', '#']).next().unwrap_or("");
    let path = crate::fsutil::percent_decode(path)?;
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

/// Threads answering requests ([`SiteServer::run`]).
pub const SERVE_THREADS: usize = 4;

/// A running server of one site folder.
pub struct SiteServer {
    server: tiny_http::Server,
    root: PathBuf,
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
    /// the site in `root`.
    pub fn bind(root: &Path, addr: &str) -> Result<SiteServer, ServeError> {
        let server = tiny_http::Server::http(addr).map_err(|e| ServeError {
            addr: addr.into(),
            msg: e.to_string(),
        })?;
        Ok(SiteServer {
            server,
            root: root.to_path_buf(),
        })
    }

    /// The URL of the site.
    pub fn url(&self) -> String {
        match self.server.server_addr().to_ip() {
            Some(a) => format!("http://{a}/"),
            None => "http://localhost/".into(),
        }
    }

    /// Serves requests until the process ends, on [`SERVE_THREADS`]
    /// threads: one response that blocks (a client that stops reading a
    /// large file) cannot hold up the page's other requests. With one
    /// thread the browser test saw, about once in six runs at load 10, a
    /// page whose `manifest.json` never arrived in 90 s.
    pub fn run(&self) {
        std::thread::scope(|s| {
            for _ in 0..SERVE_THREADS {
                s.spawn(|| {
                    for req in self.server.incoming_requests() {
                        self.handle(req);
                    }
                });
            }
        });
    }

    /// Serves requests on a background thread until the returned server
    /// handle is dropped... or the process ends.
    pub fn spawn(self) -> std::thread::JoinHandle<()> {
        std::thread::spawn(move || self.run())
    }

    fn handle(&self, req: tiny_http::Request) {
        let url = req.url().to_string();
        if !matches!(
            req.method(),
            tiny_http::Method::Get | tiny_http::Method::Head
        ) {
            let _ = req.respond(tiny_http::Response::empty(405));
            return;
        }
        let file = resolve_path(&self.root, &url).and_then(|p| {
            // A named pipe in the folder would block this thread.
            let f = crate::fsutil::open_input(&p, crate::fsutil::MAX_INPUT_BYTES).ok()?;
            Some((p, f))
        });
        let _ = match file {
            Some((p, f)) => {
                let mut resp = tiny_http::Response::from_file(f);
                for (k, v) in [
                    ("Content-Type", content_type(&p)),
                    ("Cache-Control", "no-cache"),
                    ("X-Content-Type-Options", "nosniff"),
                ] {
                    if let Ok(h) = tiny_http::Header::from_bytes(k, v) {
                        resp.add_header(h);
                    }
                }
                req.respond(resp)
            }
            None => {
                req.respond(tiny_http::Response::from_string("not found").with_status_code(404))
            }
        };
    }
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
