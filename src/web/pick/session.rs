//! The state of one `--pick` page and its HTTP API, without sockets: the
//! rest mesh, the landmarks as they stand, the embedding made from them
//! ([`Embedding::new`], remade after each move), and the answers to the
//! page's requests ([`PickSession::handle`]).
//!
//! | request | answer |
//! |---|---|
//! | `GET /`, `GET /pick.js` | the page ([`super::PAGE`], [`super::SCRIPT`]) |
//! | `GET /api/mesh` | `{name, positions: [x, y, z, …], triangles: [a, b, c, …], parts}` |
//! | `GET /api/state` | the landmarks, the embedding's labels, joints and bones, its notes and self-check, or why no rig could be embedded |
//! | `POST /api/embed` | body `{"landmarks": {name: [x, y, z] or vertex}, "snap": [names]}`: the landmarks (the names in `snap` moved to the nearest surface point first) embedded; `200` and the state, `422` with the reason (the landmarks kept as they were), `400` for a body that is not such JSON |
//! | `POST /api/save` | body `{}` or `{"path": "FILE.json"}`: the landmarks written atomically; `200` `{saved}` or `409`/`400` with the reason |

use crate::embed::landmarks::{Landmark, Landmarks, Mark};
use crate::embed::parts::Part;
use crate::embed::surface::closest_on_triangle;
use crate::embed::{Embedding, bones_of, check};
use crate::mesh::Mesh;
use crate::rig::Canonical;
use glam::DVec3;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Largest request body accepted (a landmark set is well under 4 kB).
pub(crate) const MAX_BODY_BYTES: usize = 1 << 20;

/// An answer of the API.
#[derive(Clone, Debug, PartialEq)]
pub struct Response {
    /// HTTP status code.
    pub status: u16,
    /// Its `Content-Type`.
    pub content_type: &'static str,
    /// The body.
    pub body: Vec<u8>,
}

impl Response {
    fn json(status: u16, v: &Value) -> Response {
        Response {
            status,
            content_type: "application/json",
            body: v.to_string().into_bytes(),
        }
    }

    /// An error answer: `{"error": reason}`.
    pub fn error(status: u16, reason: impl Into<String>) -> Response {
        Response::json(status, &json!({ "error": reason.into() }))
    }

    fn asset(content_type: &'static str, body: &[u8]) -> Response {
        Response {
            status: 200,
            content_type,
            body: body.to_vec(),
        }
    }
}

/// Where the landmarks come from and where they go.
#[derive(Clone, Debug)]
pub struct SessionFiles {
    /// The landmark file the page started from (`None`: none given).
    pub input: Option<PathBuf>,
    /// Where Save writes when the page names no path.
    pub default_save: PathBuf,
    /// Files the page must never write (the mesh, the sequences, the
    /// other inputs); the landmark input may be written only when the
    /// page names it explicitly.
    pub protected: Vec<PathBuf>,
}

/// One page's state.
pub struct PickSession {
    mesh: Mesh,
    name: String,
    files: SessionFiles,
    landmarks: Landmarks,
    embedding: Option<Embedding>,
    /// Why the current landmarks give no rig.
    error: Option<String>,
    /// Where the starting landmarks came from when no file was given (the
    /// automatic landmarks' refusal, with its reason).
    notice: Option<String>,
    revision: u64,
    embeds: usize,
    saved: Vec<PathBuf>,
}

/// `(name, [x, y, z])` of each landmark given.
fn landmark_points(lm: &Landmarks, p: &[[f64; 3]]) -> Vec<(&'static str, [f64; 3])> {
    lm.marks
        .keys()
        .filter_map(|&l| lm.point(l, p).map(|q| (l.name(), q)))
        .collect()
}

impl PickSession {
    /// A session on the rest mesh `mesh` (named `name` on the page) from
    /// `landmarks`: the rig is embedded at once; landmarks no rig can be
    /// embedded from still open the page, with the reason shown, so that
    /// they can be corrected there.
    pub fn new(mesh: Mesh, name: &str, landmarks: Landmarks, files: SessionFiles) -> PickSession {
        let mut s = PickSession {
            mesh,
            name: name.to_string(),
            files,
            landmarks,
            embedding: None,
            error: None,
            notice: None,
            revision: 0,
            embeds: 0,
            saved: Vec::new(),
        };
        let lm = s.landmarks.clone();
        // Refused landmarks still open the page: the reason is in the state.
        let _ = s.embed(lm);
        s
    }

    /// Embeds `lm`; on success it becomes the session's landmarks and
    /// embedding, on failure the reason (the earlier embedding is kept).
    fn embed(&mut self, lm: Landmarks) -> Result<(), String> {
        self.embeds += 1;
        let r = Embedding::new(&self.mesh, &lm, None);
        self.revision += 1;
        match r {
            Ok(e) => {
                self.landmarks = lm;
                self.embedding = Some(e);
                self.error = None;
                Ok(())
            }
            Err(e) => {
                let reason = e.to_string();
                if self.embedding.is_none() {
                    // Nothing embedded yet: show these landmarks, wrong as
                    // they are, so that the page can move them.
                    self.landmarks = lm;
                }
                self.error = Some(reason.clone());
                Err(reason)
            }
        }
    }

    /// A note shown on the page above everything else (e.g. why the
    /// automatic landmarks it starts from were refused); `None` clears it.
    pub(crate) fn set_notice(&mut self, notice: Option<String>) {
        self.notice = notice;
    }

    /// The landmarks as they stand.
    pub fn landmarks(&self) -> &Landmarks {
        &self.landmarks
    }

    /// The embedding of the current landmarks, if one could be made.
    pub fn embedding(&self) -> Option<&Embedding> {
        self.embedding.as_ref()
    }

    /// Embeddings computed so far (the first included).
    pub fn embeds(&self) -> usize {
        self.embeds
    }

    /// Files written by Save, in order (one entry per save).
    pub fn saved(&self) -> &[PathBuf] {
        &self.saved
    }

    /// The landmark file's JSON: every landmark as a point (vertex ids
    /// kept as given), with the mesh's vertex count.
    pub(crate) fn landmark_json(&self) -> Value {
        let mut m = serde_json::Map::new();
        for (l, mark) in &self.landmarks.marks {
            let v = match *mark {
                Mark::Vertex(i) => json!(i),
                Mark::Point(p) => json!(p),
                Mark::Surface(a) => a.to_json(),
            };
            m.insert(l.name().to_string(), v);
        }
        m.insert("vertex_count".into(), json!(self.mesh.vertex_count()));
        Value::Object(m)
    }

    /// The page's view of the session.
    pub fn state(&self) -> Value {
        let p = self.mesh.positions();
        let landmarks: serde_json::Map<String, Value> = landmark_points(&self.landmarks, p)
            .into_iter()
            .map(|(n, q)| (n.to_string(), json!(q)))
            .collect();
        let vertex_ids: serde_json::Map<String, Value> = self
            .landmarks
            .marks
            .iter()
            .filter_map(|(l, m)| match m {
                Mark::Vertex(i) => Some((l.name().to_string(), json!(i))),
                Mark::Point(_) | Mark::Surface(_) => None,
            })
            .collect();
        let mut v = json!({
            "revision": self.revision,
            "name": self.name,
            "landmarks": landmarks,
            "required": Landmark::REQUIRED.iter().map(|l| l.name()).collect::<Vec<_>>(),
            "known": Landmark::ALL.iter().map(|l| l.name()).collect::<Vec<_>>(),
            "error": self.error,
            "notice": self.notice,
            "input": self.files.input,
            "defaultSave": self.files.default_save,
            "saved": self.saved,
            "embedded": self.embedding.is_some(),
            "vertexIds": vertex_ids,
        });
        if let Some(e) = &self.embedding {
            let joints: serde_json::Map<String, Value> = Canonical::ALL
                .iter()
                .map(|c| (c.name().to_string(), json!(e.joints[c.index()])))
                .collect();
            let bones: Vec<[[f64; 3]; 2]> = bones_of(e)
                .iter()
                .map(|b| [b.a.to_array(), b.b.to_array()])
                .collect();
            let mut sizes = [0usize; Part::COUNT];
            for &l in &e.labels {
                sizes[l as usize] += 1;
            }
            v["labels"] = json!(e.labels);
            v["joints"] = json!(joints);
            v["bones"] = json!(bones);
            v["partSizes"] = json!(sizes);
            v["up"] = json!(e.up);
            v["facing"] = json!(e.facing);
            v["height"] = json!(e.height);
            v["notes"] = json!(e.notes);
            v["check"] = serde_json::to_value(check(e, &self.mesh)).unwrap_or(Value::Null);
        }
        v
    }

    fn mesh_json(&self) -> Value {
        let positions: Vec<f64> = self.mesh.positions().iter().flatten().copied().collect();
        let triangles: Vec<u32> = self.mesh.triangles().iter().flatten().copied().collect();
        json!({
            "name": self.name,
            "positions": positions,
            "triangles": triangles,
            "parts": Part::ALL.iter().map(|p| p.name()).collect::<Vec<_>>(),
        })
    }

    /// The surface point nearest `q`.
    pub fn snap(&self, q: [f64; 3]) -> [f64; 3] {
        let (p, t) = (self.mesh.positions(), self.mesh.triangles());
        let q = DVec3::from_array(q);
        let mut best = (f64::INFINITY, q);
        for tri in t {
            let [a, b, c] = tri.map(|v| DVec3::from_array(p[v as usize]));
            let s = closest_on_triangle(q, a, b, c);
            let d = s.distance_squared(q);
            if d < best.0 {
                best = (d, s);
            }
        }
        best.1.to_array()
    }

    /// Answers one request: `method`, the request target (its query is
    /// ignored) and the body.
    pub fn handle(&mut self, method: &str, target: &str, body: &[u8]) -> Response {
        let path = target.split(['?', '#']).next().unwrap_or("");
        let get = method == "GET" || method == "HEAD";
        match (path, get, method == "POST") {
            ("/" | "/index.html" | "/pick.html", true, _) => {
                Response::asset("text/html; charset=utf-8", super::PAGE)
            }
            ("/pick.js", true, _) => {
                Response::asset("text/javascript; charset=utf-8", super::SCRIPT)
            }
            ("/api/mesh", true, _) => Response::json(200, &self.mesh_json()),
            ("/api/state", true, _) => Response::json(200, &self.state()),
            ("/api/embed", _, true) => self.post_embed(body),
            ("/api/save", _, true) => self.post_save(body),
            (
                "/" | "/index.html" | "/pick.html" | "/pick.js" | "/api/mesh" | "/api/state",
                _,
                _,
            ) => Response::error(405, format!("{method} {path}: use GET")),
            ("/api/embed" | "/api/save", _, _) => {
                Response::error(405, format!("{method} {path}: use POST"))
            }
            _ => Response::error(404, format!("{path}: not found")),
        }
    }

    fn body_json(body: &[u8]) -> Result<serde_json::Map<String, Value>, Response> {
        if body.len() > MAX_BODY_BYTES {
            return Err(Response::error(
                413,
                format!(
                    "the body has {} bytes; at most {MAX_BODY_BYTES}",
                    body.len()
                ),
            ));
        }
        let text = std::str::from_utf8(body)
            .map_err(|e| Response::error(400, format!("the body is not UTF-8: {e}")))?;
        let v: Value = serde_json::from_str(text)
            .map_err(|e| Response::error(400, format!("the body is not JSON: {e}")))?;
        match v {
            Value::Object(m) => Ok(m),
            _ => Err(Response::error(400, "the body must be a JSON object")),
        }
    }

    fn post_embed(&mut self, body: &[u8]) -> Response {
        let obj = match Self::body_json(body) {
            Ok(o) => o,
            Err(r) => return r,
        };
        if let Some(k) = obj.keys().find(|k| *k != "landmarks" && *k != "snap") {
            return Response::error(
                400,
                format!("unknown field {k:?} (expected \"landmarks\" and optionally \"snap\")"),
            );
        }
        let Some(lv @ Value::Object(_)) = obj.get("landmarks") else {
            return Response::error(
                400,
                "expected {\"landmarks\": {name: [x, y, z] or vertex id, …}}",
            );
        };
        let n = self.mesh.vertex_count();
        let mut lm = match Landmarks::parse(&lv.to_string(), Path::new("the posted landmarks"), n) {
            Ok(l) => l,
            Err(e) => return Response::error(400, e.to_string()),
        };
        match obj.get("snap") {
            None | Some(Value::Null) => {}
            Some(Value::Array(names)) => {
                for s in names {
                    let Some(l) = s.as_str().and_then(Landmark::from_name) else {
                        return Response::error(400, format!("snap: {s} is not a landmark name"));
                    };
                    let Some(q) = lm.point(l, self.mesh.positions()) else {
                        return Response::error(
                            400,
                            format!("snap: {} is not among the landmarks", l.name()),
                        );
                    };
                    let q = self.snap(q);
                    lm.marks.insert(l, Mark::Point(q));
                }
            }
            Some(_) => return Response::error(400, "snap: expected an array of landmark names"),
        }
        match self.embed(lm) {
            Ok(()) => Response::json(200, &self.state()),
            Err(reason) => {
                let mut v = self.state();
                v["rejected"] = json!(reason);
                Response::json(422, &v)
            }
        }
    }

    fn post_save(&mut self, body: &[u8]) -> Response {
        let obj = if body.iter().all(u8::is_ascii_whitespace) {
            serde_json::Map::new()
        } else {
            match Self::body_json(body) {
                Ok(o) => o,
                Err(r) => return r,
            }
        };
        if let Some(k) = obj.keys().find(|k| *k != "path") {
            return Response::error(400, format!("unknown field {k:?} (expected \"path\")"));
        }
        let explicit = match obj.get("path") {
            None | Some(Value::Null) => None,
            Some(Value::String(s)) if s.trim().is_empty() => None,
            Some(Value::String(s)) => Some(PathBuf::from(s.trim())),
            Some(_) => return Response::error(400, "path: expected a file name (a string)"),
        };
        let path = explicit
            .clone()
            .unwrap_or_else(|| self.files.default_save.clone());
        if let Err(r) = self.may_write(&path, explicit.is_some()) {
            return r;
        }
        if self.embedding.is_none() {
            return Response::error(
                409,
                format!(
                    "no rig could be embedded from these landmarks ({}): move them first",
                    self.error.as_deref().unwrap_or("unknown reason")
                ),
            );
        }
        let text = match serde_json::to_string_pretty(&self.landmark_json()) {
            Ok(t) => t + "\n",
            Err(e) => return Response::error(500, e.to_string()),
        };
        if let Err(e) = crate::util::fsutil::write_bytes_atomic(&path, text.as_bytes()) {
            return Response::error(409, e.to_string());
        }
        self.saved.push(path.clone());
        Response::json(200, &json!({ "saved": path, "state": self.state() }))
    }

    /// Refuses a save path: not `.json`, a protected input, the landmark
    /// input unless named explicitly, a folder, or in a missing folder.
    fn may_write(&self, path: &Path, explicit: bool) -> Result<(), Response> {
        let conflict =
            |why: String| Err(Response::error(409, format!("{}: {why}", path.display())));
        if path.extension().and_then(|e| e.to_str()) != Some("json") {
            return Err(Response::error(
                400,
                format!("{}: a landmark file ends in .json", path.display()),
            ));
        }
        let same = |a: &Path, b: &Path| {
            a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
        };
        if self.files.protected.iter().any(|p| same(p, path)) {
            return conflict("an input of this session; it is never written".into());
        }
        if !explicit && self.files.input.as_deref().is_some_and(|i| same(i, path)) {
            return conflict("the landmark input; name it explicitly to overwrite it".into());
        }
        if path.is_dir() {
            return conflict("is a folder".into());
        }
        let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
        if parent.is_some_and(|p| !p.is_dir()) {
            return conflict("its folder does not exist".into());
        }
        Ok(())
    }
}
