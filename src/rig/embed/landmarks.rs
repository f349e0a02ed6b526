//! Landmarks a user marks on a character's rest frame, as Mixamo's
//! auto-rigger asks for them: chin, groin, wrists, elbows, knees (required);
//! shoulders, ankles, toes, head top (optional). A JSON object whose values
//! are either a 3D point `[x, y, z]` (on or near the surface) or a vertex
//! index. Left and right are the character's own.
//!
//! ```json
//! { "chin": 4512, "groin": [0.01, 0.93, 0.02], "l_wrist": 812, ... }
//! ```

use crate::fsutil::read_small_text;
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
    Io(#[from] crate::fsutil::FsError),
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
    /// A required landmark is absent.
    #[error("{path}: missing required landmark(s): {missing}")]
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

/// Where a landmark was given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Mark {
    /// A 3D point.
    Point([f64; 3]),
    /// A vertex of the rest mesh.
    Vertex(u32),
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
        for (key, val) in obj {
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
            } else {
                return Err(bad("expected a vertex index or [x, y, z]"));
            };
            marks.insert(l, mark);
        }
        let missing: Vec<&str> = Landmark::REQUIRED
            .iter()
            .filter(|l| !marks.contains_key(l))
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

    /// Refuses landmark sets no rig can be embedded from, naming the
    /// landmark: all within 20 % of the mesh's height of one another (all at
    /// one point, or in other units); a landmark outside the mesh (by its
    /// winding number) more than 10 % of the height from its surface; two
    /// landmarks of different joints (chin and groin, left and right
    /// knees, elbows, wrists, an elbow and its wrist, the groin and a knee)
    /// within 1 % of the height. `up` is the vertical the height is
    /// measured along.
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
        Ok(())
    }

    /// The position of a landmark on `positions`, if given.
    pub fn point(&self, l: Landmark, positions: &[[f64; 3]]) -> Option<[f64; 3]> {
        self.marks.get(&l).map(|m| match *m {
            Mark::Point(p) => p,
            Mark::Vertex(v) => positions[v as usize],
        })
    }
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
}
