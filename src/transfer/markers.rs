//! Correspondence markers of Confluent Motion (de Aguiar et al. 2007,
//! Sec. 4.2): triangles of the scan, each tied to a source that says how it
//! turns per frame — a bone of the mocap skeleton or a triangle of a moving
//! template mesh.
//!
//! Markers are read from JSON or generated from the rig embedded from
//! landmarks. Generation follows the paper's rule for cylindrical parts:
//! along each bone, rings of rays in the plane across the bone are cast from
//! the bone outwards and the first triangle hit becomes a marker. Rings sit
//! away from the joints by a configurable fraction of the bone length: near
//! the joints gives sharp bends, far from them soft bends (Fig. 4). A
//! marker's name (`bone/ring/ray`) depends only on the rule, so markers made
//! with the same options on two characters pair up by name.

use crate::embed::Embedding;
use crate::embed::parts::Part;
use crate::mesh::Mesh;
use crate::rig::Canonical;
use crate::util::fsutil::{FsError, read_small_text, write_atomic};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One correspondence: a scan triangle and what drives it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Marker {
    /// A name unique in the set; pairs scan and template markers.
    pub name: String,
    /// The triangle on the mesh the set belongs to.
    pub triangle: u32,
    /// The joint whose rotation drives the marker (mocap sources).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bone: Option<Canonical>,
}

/// A marker file: `{"markers": [{"name", "triangle", "bone"?}, …]}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MarkerFile {
    /// Triangles of the mesh the markers were made for.
    #[serde(default)]
    pub triangle_count: Option<usize>,
    /// The markers.
    pub markers: Vec<Marker>,
}

/// Why markers cannot be read or made.
#[derive(Debug, thiserror::Error)]
pub enum MarkerError {
    /// Reading or writing failed.
    #[error(transparent)]
    Io(#[from] FsError),
    /// Options out of their range ([`MarkerOptions::new`]); says which.
    #[error("{0}")]
    Options(String),
    /// The file is not a marker file.
    #[error("{path}: {reason}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A marker names a triangle the mesh does not have.
    #[error(
        "{path}: marker {index} ({name}): triangle {triangle} is out of range (the mesh has {count})"
    )]
    Triangle {
        /// The file.
        path: PathBuf,
        /// Index of the marker in the file.
        index: usize,
        /// Its name.
        name: String,
        /// The triangle.
        triangle: u32,
        /// Triangles of the mesh.
        count: usize,
    },
    /// Too few markers to drive a mesh.
    #[error("{0}")]
    TooFew(String),
    /// More markers asked for than the mesh can hold (one per triangle).
    #[error(
        "{requested} markers asked for: the mesh has {triangles} triangles and a marker is a triangle, so at most {triangles} (the paper uses 140-220)"
    )]
    TooMany {
        /// The count asked for.
        requested: usize,
        /// Triangles of the mesh.
        triangles: usize,
    },
    /// Markers made for another mesh.
    #[error(
        "the markers were made for a mesh of {recorded} triangles; this one has {triangles}: markers of another mesh?"
    )]
    OtherMesh {
        /// The count the file records.
        recorded: usize,
        /// Triangles of the mesh they are used on.
        triangles: usize,
    },
}

impl MarkerOptions {
    /// Refuses a count the mesh cannot hold: none, or more than its
    /// triangles (generation casts one ray per marker against every
    /// triangle, so an absurd count ran for minutes; issue 18, item 15).
    pub fn validate(&self, triangles: usize) -> Result<(), MarkerError> {
        if self.count == 0 {
            return Err(MarkerError::TooFew(
                "0 markers asked for: at least one is needed (the paper uses 140-220)".into(),
            ));
        }
        if self.count > triangles {
            return Err(MarkerError::TooMany {
                requested: self.count,
                triangles,
            });
        }
        Ok(())
    }
}

/// Options for [`generate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarkerOptions {
    /// Markers wanted in total, spread evenly over the bones. Default: 180
    /// (the paper uses 140-220; 22 already give the pose, Fig. 3).
    pub count: usize,
    /// Distance of the outermost rings from the joints, as a fraction of the
    /// bone length, in [0, 0.5]. Small: sharp bends; large: soft bends
    /// (Fig. 4). Default: 0.25.
    pub margin: f64,
}

impl Default for MarkerOptions {
    fn default() -> Self {
        MarkerOptions {
            count: 180,
            margin: 0.25,
        }
    }
}

impl MarkerOptions {
    /// Checked options: `count` at least 1, `margin` a fraction in
    /// [0, 0.5] (the rings of one bone would cross past the middle).
    pub fn new(count: usize, margin: f64) -> Result<MarkerOptions, MarkerError> {
        if count == 0 {
            return Err(MarkerError::Options(
                "`MarkerOptions::count` 0: expected at least 1 marker".into(),
            ));
        }
        if !(0.0..=0.5).contains(&margin) {
            return Err(MarkerError::Options(format!(
                "`MarkerOptions::margin` {margin}: expected a fraction in [0, 0.5]"
            )));
        }
        Ok(MarkerOptions { count, margin })
    }
}

/// A bone segment markers are placed along.
struct Segment {
    name: &'static str,
    joint: Canonical,
    a: DVec3,
    b: DVec3,
    parts: [Part; 2],
}

/// The segments markers go on: every bone along a body part, plus the hand,
/// foot and head ends. The sideways pelvis→hip and chest→shoulder bones
/// are left out: they have no cross-section of their own.
fn segments(rig: &Embedding) -> Vec<Segment> {
    use Canonical as C;
    let j = |c: C| DVec3::from_array(rig.joints[c.index()]);
    let seg = |name, joint: C, a: DVec3, b: DVec3, end: C| Segment {
        name,
        joint,
        a,
        b,
        parts: [Part::of_joint(joint), Part::of_joint(end)],
    };
    let v = DVec3::from_array;
    vec![
        seg("pelvis", C::Pelvis, j(C::Pelvis), j(C::Spine), C::Spine),
        seg("spine", C::Spine, j(C::Spine), j(C::Chest), C::Chest),
        seg("chest", C::Chest, j(C::Chest), j(C::Neck), C::Chest),
        seg("neck", C::Neck, j(C::Neck), j(C::Head), C::Head),
        seg("head", C::Head, j(C::Head), v(rig.head_top), C::Head),
        seg(
            "l_upper_arm",
            C::LShoulder,
            j(C::LShoulder),
            j(C::LElbow),
            C::LShoulder,
        ),
        seg(
            "l_forearm",
            C::LElbow,
            j(C::LElbow),
            j(C::LWrist),
            C::LElbow,
        ),
        seg(
            "l_hand",
            C::LWrist,
            j(C::LWrist),
            v(rig.hand_tips[0]),
            C::LWrist,
        ),
        seg(
            "r_upper_arm",
            C::RShoulder,
            j(C::RShoulder),
            j(C::RElbow),
            C::RShoulder,
        ),
        seg(
            "r_forearm",
            C::RElbow,
            j(C::RElbow),
            j(C::RWrist),
            C::RElbow,
        ),
        seg(
            "r_hand",
            C::RWrist,
            j(C::RWrist),
            v(rig.hand_tips[1]),
            C::RWrist,
        ),
        seg("l_thigh", C::LHip, j(C::LHip), j(C::LKnee), C::LHip),
        seg("l_shin", C::LKnee, j(C::LKnee), j(C::LAnkle), C::LKnee),
        seg("l_foot", C::LAnkle, j(C::LAnkle), j(C::LToe), C::LAnkle),
        seg("l_toes", C::LToe, j(C::LToe), v(rig.toe_tips[0]), C::LToe),
        seg("r_thigh", C::RHip, j(C::RHip), j(C::RKnee), C::RHip),
        seg("r_shin", C::RKnee, j(C::RKnee), j(C::RAnkle), C::RKnee),
        seg("r_foot", C::RAnkle, j(C::RAnkle), j(C::RToe), C::RAnkle),
        seg("r_toes", C::RToe, j(C::RToe), v(rig.toe_tips[1]), C::RToe),
    ]
}

/// Rings per bone and rays per ring for about `per_bone` markers a bone.
fn layout(per_bone: usize) -> (usize, usize) {
    let per_bone = per_bone.max(1);
    let rings = per_bone.div_ceil(6);
    (rings, per_bone.div_ceil(rings))
}

/// Generates markers on `mesh` (the rest frame the rig was embedded in).
/// Rays that leave the body part (hit another limb, or nothing) give no
/// marker, so the count can fall short of `opts.count`.
///
/// Cost: one ray against every triangle per marker, O(markers × triangles);
/// check the count with [`MarkerOptions::validate`] first.
pub fn generate(mesh: &Mesh, rig: &Embedding, opts: &MarkerOptions) -> Vec<Marker> {
    let segs = segments(rig);
    let (rings, rays) = layout((opts.count as f64 / segs.len() as f64).round() as usize);
    let margin = opts.margin.clamp(0.0, 0.5);
    let p = mesh.positions();
    let t = mesh.triangles();
    let facing = DVec3::from_array(rig.facing).normalize_or(DVec3::Z);
    let up = DVec3::from_array(rig.up).normalize_or(DVec3::Y);
    let mut out: Vec<Marker> = Vec::new();
    let mut taken = std::collections::HashSet::new();
    for s in &segs {
        let axis = s.b - s.a;
        let Some(d) = axis.try_normalize() else {
            continue;
        };
        // ClipNeutral direction across the bone: the facing direction, or the
        // up direction for bones along the facing (feet).
        let mut u = facing - d * facing.dot(d);
        if u.length() < 0.3 {
            u = up - d * up.dot(d);
        }
        let u = u.normalize_or(d.any_orthonormal_vector());
        let v = d.cross(u);
        for r in 0..rings {
            let f = margin + (1.0 - 2.0 * margin) * (r as f64 + 0.5) / rings as f64;
            let origin = s.a + axis * f;
            for k in 0..rays {
                let th = std::f64::consts::TAU * k as f64 / rays as f64;
                let dir = u * th.cos() + v * th.sin();
                let Some(tri) = first_hit(p, t, origin, dir) else {
                    continue;
                };
                let on_part = t[tri as usize].iter().any(|&x| {
                    s.parts
                        .contains(&Part::ALL[rig.labels[x as usize] as usize])
                });
                if !on_part || !taken.insert(tri) {
                    continue;
                }
                out.push(Marker {
                    name: format!("{}/{r}/{k}", s.name),
                    triangle: tri,
                    bone: Some(s.joint),
                });
            }
        }
    }
    out
}

/// The first triangle hit by the ray `origin + s·dir`, s > 0 (Möller–Trumbore).
fn first_hit(p: &[[f64; 3]], t: &[[u32; 3]], origin: DVec3, dir: DVec3) -> Option<u32> {
    let mut best = (f64::INFINITY, None);
    for (i, tri) in t.iter().enumerate() {
        let [a, b, c] = tri.map(|v| DVec3::from_array(p[v as usize]));
        let (e1, e2) = (b - a, c - a);
        let h = dir.cross(e2);
        let det = e1.dot(h);
        if det.abs() < 1e-300 {
            continue;
        }
        let inv = 1.0 / det;
        let s = origin - a;
        let bu = s.dot(h) * inv;
        if !(0.0..=1.0).contains(&bu) {
            continue;
        }
        let q = s.cross(e1);
        let bv = dir.dot(q) * inv;
        if bv < 0.0 || bu + bv > 1.0 {
            continue;
        }
        let dist = e2.dot(q) * inv;
        if dist > 0.0 && dist < best.0 {
            best = (dist, Some(i as u32));
        }
    }
    best.1
}

impl MarkerFile {
    /// Parses marker JSON for a mesh with `triangle_count` triangles.
    pub fn parse(
        text: &str,
        path: &Path,
        triangle_count: usize,
    ) -> Result<MarkerFile, MarkerError> {
        let f: MarkerFile = serde_json::from_str(text).map_err(|e| MarkerError::Parse {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        for (index, m) in f.markers.iter().enumerate() {
            if m.triangle as usize >= triangle_count {
                return Err(MarkerError::Triangle {
                    path: path.to_path_buf(),
                    index,
                    name: m.name.clone(),
                    triangle: m.triangle,
                    count: triangle_count,
                });
            }
        }
        let mut names: Vec<&str> = f.markers.iter().map(|m| m.name.as_str()).collect();
        names.sort_unstable();
        if let Some(w) = names.windows(2).find(|w| w[0] == w[1]) {
            return Err(MarkerError::Parse {
                path: path.to_path_buf(),
                reason: format!("marker name {:?} is used twice", w[0]),
            });
        }
        Ok(f)
    }

    /// Reads a marker file.
    pub fn load(path: &Path, triangle_count: usize) -> Result<MarkerFile, MarkerError> {
        MarkerFile::parse(&read_small_text(path)?, path, triangle_count)
    }

    /// Writes the file atomically.
    pub fn save(&self, path: &Path) -> Result<(), MarkerError> {
        let s = serde_json::to_vec_pretty(self).map_err(|e| MarkerError::Parse {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        write_atomic(path, |w| w.write_all(&s))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_covers_the_count() {
        assert_eq!(layout(1), (1, 1));
        assert_eq!(layout(4), (1, 4));
        let (r, k) = layout(10);
        assert!(r * k >= 10 && r * k <= 12);
    }

    #[test]
    fn ray_hits_the_nearest_triangle() {
        let p = [
            [-1.0, -1.0, 1.0],
            [1.0, -1.0, 1.0],
            [0.0, 1.0, 1.0],
            [-1.0, -1.0, 2.0],
            [1.0, -1.0, 2.0],
            [0.0, 1.0, 2.0],
        ];
        let t = [[3, 4, 5], [0, 1, 2]];
        assert_eq!(first_hit(&p, &t, DVec3::ZERO, DVec3::Z), Some(1));
        assert_eq!(first_hit(&p, &t, DVec3::ZERO, -DVec3::Z), None);
    }

    #[test]
    fn bad_files_are_errors() {
        let p = Path::new("m.json");
        assert!(MarkerFile::parse("[]", p, 10).is_err());
        let two = r#"{"markers":[{"name":"a","triangle":1},{"name":"a","triangle":2}]}"#;
        assert!(MarkerFile::parse(two, p, 10).is_err());
        let far = r#"{"markers":[{"name":"a","triangle":10}]}"#;
        assert!(matches!(
            MarkerFile::parse(far, p, 10),
            Err(MarkerError::Triangle { .. })
        ));
        let ok = r#"{"markers":[{"name":"a","triangle":3,"bone":"l_elbow"}]}"#;
        // Regression (issue 18, item 15): a count the mesh cannot hold.
        let o = |count| MarkerOptions {
            count,
            margin: 0.25,
        };
        assert!(matches!(
            o(1_000_000).validate(100),
            Err(MarkerError::TooMany { .. })
        ));
        assert!(o(0).validate(100).is_err());
        assert!(o(100).validate(100).is_ok());
        let f = MarkerFile::parse(ok, p, 10).unwrap();
        assert_eq!(f.markers[0].bone, Some(Canonical::LElbow));
    }
}
