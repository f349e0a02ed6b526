//! Landmarks a user marks on a character's rest frame, as Mixamo's
//! auto-rigger asks for them: chin, groin, wrists, elbows, knees (required);
//! shoulders, ankles, toes, head top (optional). A JSON object whose values
//! are either a 3D point `[x, y, z]` (on or near the surface), a vertex
//! index, or a point fixed to a triangle ([`Anchor`]: what the automatic
//! rig writes when it found the landmarks on a frame other than the
//! topology's). Left and right are the character's own.
//!
//! ```json
//! { "chin": 4512, "groin": [0.01, 0.93, 0.02], "l_wrist": 812, ... }
//! ```

use crate::util::fsutil::read_small_text;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A landmark name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[allow(missing_docs)]
pub enum Landmark {
    Chin,
    Groin,
    LWrist,
    RWrist,
    LElbow,
    RElbow,
    LKnee,
    RKnee,
    LShoulder,
    RShoulder,
    LAnkle,
    RAnkle,
    LToe,
    RToe,
    HeadTop,
}

impl Landmark {
    /// Every landmark, required ones first.
    pub const ALL: [Landmark; 15] = [
        Landmark::Chin,
        Landmark::Groin,
        Landmark::LWrist,
        Landmark::RWrist,
        Landmark::LElbow,
        Landmark::RElbow,
        Landmark::LKnee,
        Landmark::RKnee,
        Landmark::LShoulder,
        Landmark::RShoulder,
        Landmark::LAnkle,
        Landmark::RAnkle,
        Landmark::LToe,
        Landmark::RToe,
        Landmark::HeadTop,
    ];

    /// The landmarks without which no rig can be embedded: the first eight of [`Landmark::ALL`].
    pub const REQUIRED: &'static [Landmark] = Landmark::ALL.split_at(8).0;

    /// The JSON key.
    pub fn name(self) -> &'static str {
        match self {
            Landmark::Chin => "chin",
            Landmark::Groin => "groin",
            Landmark::LWrist => "l_wrist",
            Landmark::RWrist => "r_wrist",
            Landmark::LElbow => "l_elbow",
            Landmark::RElbow => "r_elbow",
            Landmark::LKnee => "l_knee",
            Landmark::RKnee => "r_knee",
            Landmark::LShoulder => "l_shoulder",
            Landmark::RShoulder => "r_shoulder",
            Landmark::LAnkle => "l_ankle",
            Landmark::RAnkle => "r_ankle",
            Landmark::LToe => "l_toe",
            Landmark::RToe => "r_toe",
            Landmark::HeadTop => "head_top",
        }
    }

    /// Parses a JSON key.
    pub fn from_name(s: &str) -> Option<Landmark> {
        Landmark::ALL.into_iter().find(|l| l.name() == s)
    }
}

/// Why a landmark file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum LandmarkError {
    /// The file could not be read.
    #[error(transparent)]
    Io(#[from] crate::util::fsutil::FsError),
    /// Not JSON, or not an object.
    #[error("{path}: {reason}")]
    Json {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A key is not a landmark name.
    #[error(
        "{path}: unknown landmark {key:?} (known: chin, groin, l_/r_wrist, l_/r_elbow, l_/r_knee, l_/r_shoulder, l_/r_ankle, l_/r_toe, head_top)"
    )]
    Unknown {
        /// The file.
        path: PathBuf,
        /// The key.
        key: String,
    },
    /// A value is neither a finite point nor a vertex index of the mesh.
    #[error("{path}: landmark {key}: {reason}")]
    BadValue {
        /// The file.
        path: PathBuf,
        /// The key.
        key: String,
        /// What is wrong.
        reason: String,
    },
    /// The file records the vertex count of the mesh it was made for, and
    /// this mesh has another: its vertex indices would mark other places.
    #[error(
        "{path}: made for a mesh of {recorded} vertices; this one has {actual}: landmarks of another mesh?"
    )]
    OtherMesh {
        /// The file.
        path: PathBuf,
        /// The count the file records.
        recorded: u64,
        /// The mesh's.
        actual: usize,
    },
    /// A required landmark is absent. The message says how to proceed
    /// (issue 39, item 7: a headless body's file without a chin was
    /// accepted by `db init` and refused only by `retarget`).
    #[error(
        "{path}: missing required landmark(s): {missing}; {}",
        missing_hint(missing)
    )]
    Missing {
        /// The file.
        path: PathBuf,
        /// Comma-separated names.
        missing: String,
    },
    /// The landmarks span a tiny part of the mesh: all at one point, or in
    /// other units than the mesh (metres on a millimetre mesh).
    #[error(
        "the landmarks span only {span:.4} (from {a} to {b}) on a mesh {height:.4} tall ({percent:.2}% of it): all at one point, or in other units than the mesh?"
    )]
    Span {
        /// The landmark at one end of the widest pair.
        a: &'static str,
        /// The landmark at the other end.
        b: &'static str,
        /// Their distance (mesh units).
        span: f64,
        /// The mesh's height along the vertical.
        height: f64,
        /// `span` as a percentage of `height`.
        percent: f64,
    },
    /// A landmark's point is not finite: a surface mark whose weights or
    /// offset, finite each, overflow (±1e308).
    #[error(
        "landmark {key}: its point ({x}, {y}, {z}) is not finite: the mark's weights or offset are too large (weights near 0-1 that sum to 1, an offset within the body's size)"
    )]
    NotFinite {
        /// The landmark.
        key: &'static str,
        /// The point's coordinates.
        x: f64,
        /// …
        y: f64,
        /// …
        z: f64,
    },
    /// A landmark lies outside the body, far from its surface.
    #[error(
        "landmark {key} is outside the mesh, {distance:.4} from its surface ({percent:.1}% of the height; the limit is {limit_percent:.0}%)"
    )]
    OffSurface {
        /// The landmark.
        key: &'static str,
        /// Distance to the nearest surface point (mesh units).
        distance: f64,
        /// As a percentage of the height.
        percent: f64,
        /// The limit, as a percentage of the height.
        limit_percent: f64,
    },
    /// A landmark is where no body has that joint: a knee above the
    /// groin, an arm below the knees, a left landmark on the right side
    /// (seen from the other pairs). Typically the vertex indices of
    /// another mesh, which land in range but on the wrong places.
    #[error(
        "landmark {key}: {reason}; landmarks of another mesh or character? (a file made for this mesh may record its \"vertex_count\")"
    )]
    Implausible {
        /// The landmark.
        key: &'static str,
        /// Where it is and where it should be.
        reason: String,
    },
    /// Two landmarks that mark different joints are at one place.
    #[error(
        "landmarks {a} and {b} are {distance:.4} apart ({percent:.2}% of the height): they mark different joints"
    )]
    Coincide {
        /// One landmark.
        a: &'static str,
        /// The other.
        b: &'static str,
        /// Their distance (mesh units).
        distance: f64,
        /// As a percentage of the height.
        percent: f64,
    },
}

/// What to do about the missing required landmarks `missing`
/// (comma-separated names).
fn missing_hint(missing: &str) -> String {
    let mut s = "a rig is embedded from all of chin, groin, l_wrist, r_wrist, l_elbow, r_elbow, l_knee and r_knee: \
                 mark each on the rest frame (a vertex index or [x, y, z])"
        .to_string();
    if missing.split(", ").any(|m| m == "chin") {
        s += "; the chin ends the neck: for a body without a head, place it at the top of the neck, or write \"absent\": [\"head\"]";
    }
    s
}

pub(crate) use super::stump::neck_top;

/// Where a landmark was given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mark {
    /// A 3D point.
    Point([f64; 3]),
    /// A vertex of the rest mesh.
    Vertex(u32),
    /// A point fixed to a triangle of the surface: on every frame where
    /// the triangle is found ([`Anchor::point`]). The automatic rig writes
    /// these when it found the landmarks on another frame than the
    /// topology's, so that they land on that frame exactly.
    Surface(Anchor),
}

/// A point fixed to a triangle of the surface: its foot on the triangle
/// (barycentric weights) and its offset from the foot in the triangle's
/// own frame (along the edge from the first vertex to the second, across
/// it in the plane, along the normal), so that a point inside the body
/// stays inside at the same depth on every frame. JSON:
/// `{"triangle": [a, b, c], "weights": [wa, wb, wc], "offset": [x, y, z]}`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anchor {
    /// The triangle's vertices.
    pub triangle: [u32; 3],
    /// Barycentric weights of the foot.
    pub weights: [f64; 3],
    /// The offset from the foot in the triangle's frame.
    pub offset: [f64; 3],
}

/// An orthonormal frame of a triangle (edge, in-plane, normal).
fn triangle_frame(
    a: glam::DVec3,
    b: glam::DVec3,
    c: glam::DVec3,
) -> (glam::DVec3, glam::DVec3, glam::DVec3) {
    let e1 = (b - a).normalize_or(glam::DVec3::X);
    let n = (b - a)
        .cross(c - a)
        .normalize_or(e1.any_orthonormal_vector());
    (e1, n.cross(e1), n)
}

impl Anchor {
    /// `q` anchored on triangle `t` of `positions`.
    pub fn on(q: [f64; 3], t: [u32; 3], positions: &[[f64; 3]]) -> Anchor {
        use glam::DVec3;
        let q = DVec3::from_array(q);
        let [a, b, c] = t.map(|i| DVec3::from_array(positions[i as usize]));
        let c0 = super::surface::closest_on_triangle(q, a, b, c);
        let weights = barycentric(c0, a, b, c);
        let (e1, e2, n) = triangle_frame(a, b, c);
        let o = q - c0;
        Anchor {
            triangle: t,
            weights,
            offset: [o.dot(e1), o.dot(e2), o.dot(n)],
        }
    }

    /// `q` anchored on its nearest triangle of `positions` among
    /// `triangles`; `None` when there is none.
    pub fn nearest<'a>(
        q: [f64; 3],
        positions: &[[f64; 3]],
        triangles: impl IntoIterator<Item = &'a [u32; 3]>,
    ) -> Option<Anchor> {
        use glam::DVec3;
        let p = DVec3::from_array(q);
        let v = |i: u32| DVec3::from_array(positions[i as usize]);
        triangles
            .into_iter()
            .map(|t| {
                let c0 = super::surface::closest_on_triangle(p, v(t[0]), v(t[1]), v(t[2]));
                (c0.distance_squared(p), t)
            })
            .min_by(|x, y| x.0.total_cmp(&y.0))
            .map(|(_, t)| Anchor::on(q, *t, positions))
    }

    /// The point on the frame `positions`.
    pub fn point(&self, positions: &[[f64; 3]]) -> [f64; 3] {
        let [a, b, c] = self
            .triangle
            .map(|i| glam::DVec3::from_array(positions[i as usize]));
        let (f1, f2, m) = triangle_frame(a, b, c);
        let (w, l) = (self.weights, self.offset);
        let on = a * w[0] + b * w[1] + c * w[2];
        (on + f1 * l[0] + f2 * l[1] + m * l[2]).to_array()
    }

    /// The anchor as the landmark file's JSON value.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "triangle": self.triangle,
            "weights": self.weights,
            "offset": self.offset,
        })
    }

    /// Parses [`Anchor::to_json`]'s object; the reason when it is not one
    /// (a vertex out of `vertex_count`, a number not finite).
    fn parse(v: &serde_json::Value, vertex_count: usize) -> Result<Anchor, String> {
        let three = |key: &str| -> Result<[f64; 3], String> {
            let a = v.get(key).and_then(|x| x.as_array());
            let p: Vec<f64> = a.map_or(Vec::new(), |a| {
                a.iter().filter_map(|x| x.as_f64()).collect()
            });
            match (a, p.as_slice()) {
                (Some(a), &[x, y, z]) if a.len() == 3 && p.iter().all(|x| x.is_finite()) => {
                    Ok([x, y, z])
                }
                _ => Err(format!("{key}: expected three finite numbers")),
            }
        };
        let t: Vec<u64> = v
            .get("triangle")
            .and_then(|x| x.as_array())
            .map_or(Vec::new(), |a| {
                a.iter().filter_map(|x| x.as_u64()).collect()
            });
        let &[a, b, c] = t.as_slice() else {
            return Err("triangle: expected three vertex indices".into());
        };
        if let Some(i) = [a, b, c].into_iter().find(|&i| i as usize >= vertex_count) {
            return Err(format!(
                "triangle: vertex {i} is out of range (the mesh has {vertex_count})"
            ));
        }
        if let Some(k) = v.as_object().and_then(|o| {
            o.keys()
                .find(|k| !matches!(k.as_str(), "triangle" | "weights" | "offset"))
        }) {
            return Err(format!(
                "unknown key {k:?} (expected triangle, weights, offset)"
            ));
        }
        Ok(Anchor {
            triangle: [a as u32, b as u32, c as u32],
            weights: three("weights")?,
            offset: three("offset")?,
        })
    }
}

/// A set of landmarks.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Landmarks {
    /// The marks by name.
    pub marks: BTreeMap<Landmark, Mark>,
}

impl Landmarks {
    /// Parses landmark JSON; `vertex_count` bounds vertex indices. `path`
    /// names the source in errors.
    pub fn parse(text: &str, path: &Path, vertex_count: usize) -> Result<Landmarks, LandmarkError> {
        let json = |reason: String| LandmarkError::Json {
            path: path.to_path_buf(),
            reason,
        };
        let v: serde_json::Value = serde_json::from_str(text).map_err(|e| json(e.to_string()))?;
        let obj = v
            .as_object()
            .ok_or_else(|| json("expected a JSON object of landmarks".into()))?;
        let mut marks = BTreeMap::new();
        let mut headless = false;
        for (key, val) in obj {
            // Optional: the body ends the file declares absent (a capture
            // cut at the neck or the wrists, issue 41): "head" lifts the
            // chin's requirement (the rig finds the top of the neck); the
            // hands are accepted and change nothing (no check needs them).
            if key == "absent" {
                let names: Option<Vec<&str>> = val
                    .as_array()
                    .and_then(|a| a.iter().map(|x| x.as_str()).collect());
                let Some(names) = names else {
                    return Err(json(
                        "absent: expected a list of names (head, hands, l_hand, r_hand)".into(),
                    ));
                };
                for n in names {
                    match n {
                        "head" => headless = true,
                        "hands" | "l_hand" | "r_hand" => {}
                        other => {
                            return Err(json(format!(
                                "absent: unknown body end {other:?} (known: head, hands, l_hand, r_hand)"
                            )));
                        }
                    }
                }
                continue;
            }
            // Optional: the vertex count of the mesh the file was made for
            // (vertex indices of another mesh are otherwise in range and
            // wrong; issue 18, item 16).
            if key == "vertex_count" {
                let Some(n) = val.as_u64() else {
                    return Err(json("vertex_count: expected a whole number".into()));
                };
                if n as usize != vertex_count {
                    return Err(LandmarkError::OtherMesh {
                        path: path.to_path_buf(),
                        recorded: n,
                        actual: vertex_count,
                    });
                }
                continue;
            }
            let Some(l) = Landmark::from_name(key) else {
                return Err(LandmarkError::Unknown {
                    path: path.to_path_buf(),
                    key: key.clone(),
                });
            };
            let bad = |reason: &str| LandmarkError::BadValue {
                path: path.to_path_buf(),
                key: key.clone(),
                reason: reason.to_string(),
            };
            let mark = if let Some(i) = val.as_u64() {
                if i as usize >= vertex_count {
                    return Err(bad(&format!(
                        "vertex {i} is out of range (the mesh has {vertex_count})"
                    )));
                }
                Mark::Vertex(i as u32)
            } else if let Some(a) = val.as_array() {
                let p: Vec<f64> = a.iter().filter_map(|x| x.as_f64()).collect();
                if p.len() != 3 || a.len() != 3 || p.iter().any(|x| !x.is_finite()) {
                    return Err(bad("expected [x, y, z] with three finite numbers"));
                }
                Mark::Point([p[0], p[1], p[2]])
            } else if val.is_object() {
                Mark::Surface(Anchor::parse(val, vertex_count).map_err(|r| bad(&r))?)
            } else {
                return Err(bad(
                    "expected a vertex index, [x, y, z] or {\"triangle\", \"weights\", \"offset\"}",
                ));
            };
            marks.insert(l, mark);
        }
        if headless
            && (marks.contains_key(&Landmark::Chin) || marks.contains_key(&Landmark::HeadTop))
        {
            return Err(json(
                "absent: \"head\" with a chin or head_top given: drop them (the top of the neck is found) or drop \"head\" from absent".into(),
            ));
        }
        let missing: Vec<&str> = Landmark::REQUIRED
            .iter()
            .filter(|l| !(marks.contains_key(l) || headless && **l == Landmark::Chin))
            .map(|l| l.name())
            .collect();
        if !missing.is_empty() {
            return Err(LandmarkError::Missing {
                path: path.to_path_buf(),
                missing: missing.join(", "),
            });
        }
        Ok(Landmarks { marks })
    }

    /// Reads a landmark file.
    pub fn load(path: &Path, vertex_count: usize) -> Result<Landmarks, LandmarkError> {
        Landmarks::parse(&read_small_text(path)?, path, vertex_count)
    }

    /// Reads a landmark file made for the rest frame `mesh` and checks it
    /// as the rig embedding does before using it ([`Landmarks::validate`],
    /// the vertical from the groin→chin direction): what `db init`, `db
    /// info` and `inspect` check, so that a file no rig can be embedded
    /// from is refused there and not first by `retarget`.
    pub(crate) fn load_checked(
        path: &Path,
        mesh: &crate::mesh::Mesh,
    ) -> Result<Landmarks, LandmarkError> {
        let lm = Landmarks::load(path, mesh.vertex_count())?;
        let p = mesh.positions();
        let full = lm.completed(p, mesh.triangles());
        let up = match (
            full.point(Landmark::Chin, p),
            full.point(Landmark::Groin, p),
        ) {
            (Some(c), Some(g)) => {
                super::axes::body_up(glam::DVec3::from_array(c) - glam::DVec3::from_array(g))
            }
            _ => glam::DVec3::Y,
        };
        full.validate(p, mesh.triangles(), up.to_array())?;
        Ok(lm)
    }

    /// Whether the body has no head: no chin (the file declares
    /// `"absent": ["head"]`; [`Landmarks::parse`] requires a chin
    /// otherwise).
    pub fn headless(&self) -> bool {
        !self.marks.contains_key(&Landmark::Chin)
    }

    /// The landmarks with, for a headless body ([`Landmarks::headless`]),
    /// the chin placed at the top of the neck on `positions`
    /// ([`neck_top`], the mesh's `triangles` for an open cut's rim); a
    /// copy otherwise.
    pub(crate) fn completed(&self, positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> Landmarks {
        let mut lm = self.clone();
        if self.headless()
            && let Some(q) = neck_top(self, positions, triangles)
        {
            lm.marks.insert(Landmark::Chin, Mark::Point(q));
        }
        lm
    }

    /// Refuses landmark sets no rig can be embedded from, naming the
    /// landmark: all within 20 % of the mesh's height of one another (all at
    /// one point, or in other units); a landmark outside the mesh (by its
    /// winding number) more than 10 % of the height from its surface; two
    /// landmarks of different joints (chin and groin, left and right
    /// knees, elbows, wrists, an elbow and its wrist, the groin and a knee)
    /// within 1 % of the height; then [`Landmarks::check_anatomy`]. `up` is
    /// the vertical the height is measured along.
    pub fn validate(
        &self,
        positions: &[[f64; 3]],
        triangles: &[[u32; 3]],
        up: [f64; 3],
    ) -> Result<(), LandmarkError> {
        use super::surface::{distance_to_surface, is_inside};
        use glam::DVec3;
        let up = DVec3::from_array(up).normalize_or(DVec3::Y);
        let (lo, hi) = positions
            .iter()
            .map(|q| DVec3::from_array(*q).dot(up))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        let height = hi - lo;
        if height.is_nan() || height <= 0.0 {
            return Ok(());
        }
        let pts: Vec<(Landmark, DVec3)> = self
            .marks
            .keys()
            .filter_map(|&l| self.point(l, positions).map(|p| (l, DVec3::from_array(p))))
            .collect();
        // Before any distance: an overflowing surface mark read "inf from
        // its surface (inf% of the height)".
        if let Some((l, p)) = pts.iter().find(|(_, p)| !p.is_finite()) {
            return Err(LandmarkError::NotFinite {
                key: l.name(),
                x: p.x,
                y: p.y,
                z: p.z,
            });
        }
        let mut widest = (0.0, Landmark::Chin, Landmark::Groin);
        for (i, (la, pa)) in pts.iter().enumerate() {
            for (lb, pb) in &pts[i + 1..] {
                let d = pa.distance(*pb);
                if d > widest.0 {
                    widest = (d, *la, *lb);
                }
            }
        }
        if widest.0 < 0.2 * height {
            return Err(LandmarkError::Span {
                a: widest.1.name(),
                b: widest.2.name(),
                span: widest.0,
                height,
                percent: 100.0 * widest.0 / height,
            });
        }
        for (l, p) in &pts {
            if matches!(self.marks.get(l), Some(Mark::Vertex(_))) {
                continue;
            }
            let d = distance_to_surface(positions, triangles, *p);
            if d > 0.1 * height && !is_inside(positions, triangles, *p) {
                return Err(LandmarkError::OffSurface {
                    key: l.name(),
                    distance: d,
                    percent: 100.0 * d / height,
                    limit_percent: 10.0,
                });
            }
        }
        use Landmark as L;
        for (a, b) in [
            (L::Chin, L::Groin),
            (L::LKnee, L::RKnee),
            (L::LElbow, L::RElbow),
            (L::LWrist, L::RWrist),
            (L::LElbow, L::LWrist),
            (L::RElbow, L::RWrist),
            (L::Groin, L::LKnee),
            (L::Groin, L::RKnee),
        ] {
            let (Some(pa), Some(pb)) = (self.point(a, positions), self.point(b, positions)) else {
                continue;
            };
            let d = DVec3::from_array(pa).distance(DVec3::from_array(pb));
            if d < 0.01 * height {
                return Err(LandmarkError::Coincide {
                    a: a.name(),
                    b: b.name(),
                    distance: d,
                    percent: 100.0 * d / height,
                });
            }
        }
        self.check_anatomy(positions)
    }

    /// Refuses landmarks no body could have, naming the landmark (issue
    /// 18, item 16: vertex indices of another mesh are in range and were
    /// accepted when the file records no `vertex_count`). Along the body
    /// axis `b` (groin to chin): the knees lie below the groin by at least
    /// 5 % of the groin-chin distance (the crouching armadillo's: 15 %),
    /// ankles and toes below the knees, elbows, wrists and shoulders above
    /// the knees, the head top above the chin. Across it: the lateral axis
    /// is the mean direction from right to left of the given pairs
    /// (wrists, elbows, knees, shoulders, ankles, toes; `b` removed); every
    /// left landmark lies on its positive side of the mid-plane through the
    /// groin and every right one on the negative side, within 5 % of the
    /// groin-chin distance. Tolerant of the A-, T- and I-pose and of a body
    /// lying down (nothing assumes +Y).
    pub(crate) fn check_anatomy(&self, positions: &[[f64; 3]]) -> Result<(), LandmarkError> {
        use Landmark as L;
        use glam::DVec3;
        let at = |l: Landmark| self.point(l, positions).map(DVec3::from_array);
        let (Some(c), Some(g)) = (at(L::Chin), at(L::Groin)) else {
            return Ok(());
        };
        let len = c.distance(g);
        if !(len.is_finite() && len > 0.0) {
            return Ok(());
        }
        let b = (c - g) / len;
        let h = |p: DVec3| (p - g).dot(b) / len;
        let bad = |key: Landmark, reason: String| LandmarkError::Implausible {
            key: key.name(),
            reason,
        };
        let mut knee_top = f64::NEG_INFINITY;
        for (knee, ankle, toe) in [
            (L::LKnee, L::LAnkle, L::LToe),
            (L::RKnee, L::RAnkle, L::RToe),
        ] {
            let Some(k) = at(knee) else { continue };
            let hk = h(k);
            if hk > -0.05 {
                return Err(bad(
                    knee,
                    format!(
                        "{:.0}% of the groin-chin distance {} the groin along the body (groin to chin); a knee is below it",
                        100.0 * hk.abs(),
                        if hk >= 0.0 { "above" } else { "below" }
                    ),
                ));
            }
            knee_top = knee_top.max(hk);
            let mut above = hk;
            for l in [ankle, toe] {
                let Some(p) = at(l) else { continue };
                if h(p) >= above {
                    return Err(bad(
                        l,
                        format!(
                            "not below the {} along the body (groin to chin)",
                            if l == ankle {
                                knee.name()
                            } else {
                                ankle.name()
                            }
                        ),
                    ));
                }
                above = h(p);
            }
        }
        for l in [
            L::LElbow,
            L::RElbow,
            L::LWrist,
            L::RWrist,
            L::LShoulder,
            L::RShoulder,
        ] {
            let Some(p) = at(l) else { continue };
            if h(p) <= knee_top {
                return Err(bad(
                    l,
                    format!(
                        "{:.0}% of the groin-chin distance below the groin, not above the knees along the body (groin to chin)",
                        -100.0 * h(p)
                    ),
                ));
            }
        }
        if let Some(t) = at(L::HeadTop)
            && h(t) <= 1.0
        {
            return Err(bad(L::HeadTop, "not above the chin along the body".into()));
        }
        let pairs = [
            (L::LWrist, L::RWrist),
            (L::LElbow, L::RElbow),
            (L::LKnee, L::RKnee),
            (L::LShoulder, L::RShoulder),
            (L::LAnkle, L::RAnkle),
            (L::LToe, L::RToe),
        ];
        let across = |p: DVec3| p - b * p.dot(b);
        let lat = pairs
            .iter()
            .filter_map(|&(l, r)| Some(across(at(l)? - at(r)?).normalize_or_zero()))
            .sum::<DVec3>();
        let Some(lat) = lat.try_normalize() else {
            return Ok(());
        };
        let tol = 0.05;
        for &(l, r) in &pairs {
            let (Some(pl), Some(pr)) = (at(l), at(r)) else {
                continue;
            };
            let (sl, sr) = ((pl - g).dot(lat) / len, (pr - g).dot(lat) / len);
            for (key, side, s, other) in [(l, "left", sl, "right"), (r, "right", sr, "left")] {
                let wrong = if side == "left" { s < -tol } else { s > tol };
                if wrong || sl <= sr {
                    return Err(bad(
                        key,
                        format!(
                            "{:.0}% of the groin-chin distance on the {other} side of the body's mid-plane (through the groin), where the other left/right pairs put the {side} ones",
                            100.0 * s.abs()
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// The position of a landmark on `positions`, if given.
    pub fn point(&self, l: Landmark, positions: &[[f64; 3]]) -> Option<[f64; 3]> {
        self.marks.get(&l).map(|m| match *m {
            Mark::Point(p) => p,
            Mark::Vertex(v) => positions[v as usize],
            Mark::Surface(a) => a.point(positions),
        })
    }

    /// The landmarks carried from the frame `from` to the frame `to` (one
    /// position per vertex each, one connectivity `triangles`): a vertex
    /// stays that vertex and a surface mark on its triangle ([`Anchor`]:
    /// found on the frame it names, it needs no carrying); a point keeps its barycentric coordinates on its
    /// nearest triangle of `from` and its offset from that triangle in the
    /// triangle's own frame (a point inside the body stays inside, at the
    /// same depth). Used to embed a rig on another frame than the one the
    /// landmarks were marked on ([`super::rest`]). A point stays where it
    /// is when the mesh has no triangle.
    pub fn moved(&self, from: &[[f64; 3]], to: &[[f64; 3]], triangles: &[[u32; 3]]) -> Landmarks {
        let marks = self
            .marks
            .iter()
            .map(|(&l, &m)| {
                let Mark::Point(p) = m else {
                    return (l, m);
                };
                match Anchor::nearest(p, from, triangles) {
                    Some(a) => (l, Mark::Point(a.point(to))),
                    None => (l, m),
                }
            })
            .collect();
        Landmarks { marks }
    }
}

/// Barycentric coordinates of `p` (in the plane of `a b c`); the centre's
/// for a degenerate triangle.
fn barycentric(p: glam::DVec3, a: glam::DVec3, b: glam::DVec3, c: glam::DVec3) -> [f64; 3] {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (v0.dot(v0), v0.dot(v1), v1.dot(v1));
    let (d20, d21) = (v2.dot(v0), v2.dot(v1));
    let den = d00 * d11 - d01 * d01;
    if den.abs() <= 1e-300 || !den.is_finite() {
        return [1.0 / 3.0; 3];
    }
    let y = (d11 * d20 - d01 * d21) / den;
    let z = (d00 * d21 - d01 * d20) / den;
    [1.0 - y - z, y, z]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_points_and_indices_and_names_what_is_wrong() {
        let p = Path::new("l.json");
        let ok = r#"{"chin": 1, "groin": [0,1,0], "l_wrist": 2, "r_wrist": 3,
            "l_elbow": 4, "r_elbow": 5, "l_knee": 6, "r_knee": [1, 0.5, 0]}"#;
        let l = Landmarks::parse(ok, p, 10).unwrap();
        assert_eq!(l.marks[&Landmark::Chin], Mark::Vertex(1));
        assert_eq!(l.marks[&Landmark::RKnee], Mark::Point([1.0, 0.5, 0.0]));
        let e = Landmarks::parse(ok, p, 5).unwrap_err().to_string();
        assert!(e.contains("l_knee") && e.contains("out of range"), "{e}");
        let e = Landmarks::parse(r#"{"chin": 1}"#, p, 5)
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing") && e.contains("groin"), "{e}");
        let e = Landmarks::parse(r#"{"nose": 1}"#, p, 5)
            .unwrap_err()
            .to_string();
        assert!(e.contains("nose"), "{e}");
        let e = Landmarks::parse(r#"{"chin": [1, 2]}"#, p, 5)
            .unwrap_err()
            .to_string();
        assert!(e.contains("chin"), "{e}");
        assert!(Landmarks::parse("[1]", p, 5).is_err());
    }

    #[test]
    fn landmarks_of_another_mesh_are_refused_when_the_file_says_its_mesh() {
        let p = Path::new("l.json");
        let ok = r#"{"vertex_count": 10, "chin": 1, "groin": [0,1,0], "l_wrist": 2,
            "r_wrist": 3, "l_elbow": 4, "r_elbow": 5, "l_knee": 6, "r_knee": 7}"#;
        assert!(Landmarks::parse(ok, p, 10).is_ok());
        let e = Landmarks::parse(ok, p, 12).unwrap_err().to_string();
        assert!(
            e.contains("another mesh") && e.contains("10") && e.contains("12"),
            "{e}"
        );
        let bad = ok.replace("\"vertex_count\": 10", "\"vertex_count\": \"ten\"");
        assert!(Landmarks::parse(&bad, p, 10).is_err());
    }

    /// A standing A-pose body (Y up, its left at +x), every landmark a
    /// vertex index, and the points as the mesh's vertices.
    fn body() -> (Vec<[f64; 3]>, Landmarks) {
        let named = [
            ("chin", [0.0, 1.55, 0.05]),
            ("groin", [0.0, 0.8, 0.0]),
            ("l_wrist", [0.35, 0.85, 0.0]),
            ("r_wrist", [-0.35, 0.85, 0.0]),
            ("l_elbow", [0.3, 1.12, -0.02]),
            ("r_elbow", [-0.3, 1.12, -0.02]),
            ("l_knee", [0.1, 0.45, 0.02]),
            ("r_knee", [-0.1, 0.45, 0.02]),
            ("l_ankle", [0.1, 0.08, 0.0]),
            ("r_ankle", [-0.1, 0.08, 0.0]),
            ("head_top", [0.0, 1.8, 0.0]),
        ];
        let mut positions: Vec<[f64; 3]> = named.iter().map(|n| n.1).collect();
        positions.push([0.0, 0.0, 0.0]);
        let json: String = named
            .iter()
            .enumerate()
            .map(|(i, (k, _))| format!("\"{k}\": {i}"))
            .collect::<Vec<_>>()
            .join(", ");
        let lm =
            Landmarks::parse(&format!("{{{json}}}"), Path::new("b.json"), positions.len()).unwrap();
        (positions, lm)
    }

    fn key_of(e: LandmarkError) -> &'static str {
        match e {
            LandmarkError::Implausible { key, .. } => key,
            e => panic!("not an anatomy error: {e}"),
        }
    }

    /// Regression (issue 18, item 16): vertex indices of
    /// another mesh were accepted when the file records no vertex count.
    /// The resolved points are checked against a body's layout.
    #[test]
    fn landmarks_of_another_mesh_are_refused_without_a_vertex_count() {
        let (p, lm) = body();
        lm.validate(&p, &[], [0.0, 1.0, 0.0]).unwrap();
        // The same file on a mesh whose vertices are in another order.
        for shift in 1..p.len() {
            let other: Vec<[f64; 3]> = (0..p.len()).map(|i| p[(i + shift) % p.len()]).collect();
            let e = lm.check_anatomy(&other);
            if let Err(e) = e {
                let s = e.to_string();
                assert!(s.contains("another mesh"), "{s}");
            } else {
                // Only an order that keeps chin and groin apart and every
                // joint on its side may pass; none of these does.
                panic!("shift {shift} accepted");
            }
        }
    }

    #[test]
    fn misplaced_landmarks_are_named() {
        let (p, lm) = body();
        let mut swapped = p.clone();
        swapped.swap(2, 3); // l_wrist <-> r_wrist
        let k = key_of(lm.check_anatomy(&swapped).unwrap_err());
        assert!(k == "l_wrist" || k == "r_wrist", "{k}");
        let mut knee_up = p.clone();
        knee_up[6] = [0.1, 0.9, 0.0];
        assert_eq!(key_of(lm.check_anatomy(&knee_up).unwrap_err()), "l_knee");
        let mut arm_down = p.clone();
        arm_down[5] = [-0.3, 0.3, 0.0];
        assert_eq!(key_of(lm.check_anatomy(&arm_down).unwrap_err()), "r_elbow");
        let mut ankle_up = p.clone();
        ankle_up[8] = [0.1, 0.6, 0.0];
        assert_eq!(key_of(lm.check_anatomy(&ankle_up).unwrap_err()), "l_ankle");
        let mut head_low = p.clone();
        head_low[10] = [0.0, 1.3, 0.0];
        let e = lm.check_anatomy(&head_low).unwrap_err().to_string();
        assert!(e.contains("head_top"), "{e}");
    }

    /// T-pose, I-pose and a body lying down pass.
    #[test]
    fn plausible_poses_pass_the_anatomy_check() {
        let (p, lm) = body();
        let mut t = p.clone();
        t[2] = [0.8, 1.4, 0.0];
        t[3] = [-0.8, 1.4, 0.0];
        t[4] = [0.5, 1.4, 0.0];
        t[5] = [-0.5, 1.4, 0.0];
        lm.check_anatomy(&t).unwrap();
        let mut i = p.clone();
        i[2] = [0.22, 0.75, 0.0];
        i[3] = [-0.22, 0.75, 0.0];
        lm.check_anatomy(&i).unwrap();
        // Lying on its back along +x (y becomes x, z becomes -y).
        let lying: Vec<[f64; 3]> = p.iter().map(|q| [q[1], -q[2], q[0]]).collect();
        lm.check_anatomy(&lying).unwrap();
        let mirrored: Vec<[f64; 3]> = p.iter().map(|q| [-q[0], q[1], q[2]]).collect();
        lm.check_anatomy(&mirrored).unwrap();
    }
}
