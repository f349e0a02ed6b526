//! Automatic landmarks on a static scan, from its geometry alone (issue 41):
//! the chin, groin, wrists, elbows and knees (and the head top) that
//! [`super::landmarks`] otherwise asks a person to mark.
//!
//! The method, in order:
//!
//! 1. **Frame.** The principal axes of the surface (area-weighted); the
//!    body's symmetry plane is the principal plane whose reflection fits the
//!    surface best, refined by reflect-and-fit (each reflected vertex paired
//!    with its nearest vertex, the plane refitted to the pairs' midpoints, as
//!    in the symmetry detection of Mitra et al. 2006 reduced to one plane).
//!    Up is the longest principal direction in that plane (snapped to an
//!    axis of the file within 20°); its sign puts the floor at the end with
//!    the larger flat area (the soles). Facing is the other in-plane
//!    direction, signed by the feet: the toes reach forward of the shins.
//! 2. **Extremities.** Geodesic distance (Dijkstra on the edge graph) from
//!    the body's centre; the extremities are its local maxima over a
//!    geodesic ball of 12 % of the height, as skeletal extremities are found
//!    by geodesics in Pinocchio (Baran & Popović 2007) and in Reeb-graph
//!    skeletons (Hilaga et al. 2001). The lowest on each side of the plane
//!    are the feet, the farthest to each side above the knees the hands,
//!    the highest near the plane the head top.
//! 3. **Limb sections.** Geodesic rings around each hand and foot (the set
//!    of vertices at one geodesic distance from the tip is a ring across the
//!    limb): their centroids are the limb's centre line, their radii its
//!    thickness. The wrist is the narrowest ring at the hand's base; the
//!    elbow lies one forearm (14.5 % of the height, Drillis & Contini 1966)
//!    along the centre line from the wrist; the knee 57 % of the way along
//!    the leg's centre line from the ankle to the crotch (knee height
//!    0.285 H, ankle 0.039 H, crotch 0.47 H in the same tables).
//! 4. **Torso.** The groin is where the legs split: the lowest horizontal
//!    section whose loop encloses the mid-plane point between the legs. The
//!    chin is at the front of the section a quarter of the way from the
//!    neck's narrowest section (below the head) to the head top.
//!
//! Every landmark carries a confidence in 0..1 from how well its twin on
//! the other side mirrors it (wrists, elbows, knees), how clearly its
//! feature was found (a narrowing, a split), and the whole from the
//! symmetry fit and the extremities found. Below
//! [`ScanOptions::min_confidence`] the landmarks are refused with the
//! reason (a prop on a hand, a missing limb, a shape that is not a
//! standing human), never guessed.

mod frame;
mod geometry;
mod limbs;
mod torso;

use super::landmarks::{Landmark, Landmarks, Mark};
use geometry::Graph;
use glam::DVec3;
use limbs::Arm;
use serde::Serialize;
use std::collections::BTreeMap;

/// Options of [`find`].
#[derive(Debug, Clone, Copy)]
pub struct ScanOptions {
    /// Below this overall confidence (0..1) the landmarks are refused.
    /// Default 0.5.
    pub min_confidence: f64,
}

impl Default for ScanOptions {
    fn default() -> Self {
        ScanOptions {
            min_confidence: 0.5,
        }
    }
}

/// One automatic landmark.
#[derive(Debug, Clone, Serialize)]
pub struct AutoMark {
    /// Where it is (mesh units).
    pub point: [f64; 3],
    /// Confidence 0..1.
    pub confidence: f64,
    /// How it was found, and what lowered its confidence.
    pub how: String,
}

/// Landmarks found on a scan.
#[derive(Debug, Clone, Serialize)]
pub struct AutoLandmarks {
    /// Each landmark by its file name (`chin`, `l_wrist`, ...).
    pub marks: BTreeMap<&'static str, AutoMark>,
    /// The whole set's confidence 0..1: the least of the landmarks' and
    /// of the frame's (symmetry fit, extremities).
    pub confidence: f64,
    /// Unit up (floor to head).
    pub up: [f64; 3],
    /// Unit facing direction.
    pub facing: [f64; 3],
    /// The character's left (the symmetry plane's normal).
    pub left: [f64; 3],
    /// Height along `up` (mesh units).
    pub height: f64,
    /// The reflect-and-fit residual: median distance of a reflected vertex
    /// from the surface's nearest vertex, % of the height.
    pub symmetry_percent: f64,
    /// The extremities found (geodesic local maxima), as points.
    pub extremities: Vec<[f64; 3]>,
    /// What lowered the confidence, in words.
    pub doubts: Vec<String>,
}

impl AutoLandmarks {
    /// The landmarks as [`Landmarks`] (points).
    pub fn landmarks(&self) -> Landmarks {
        Landmarks {
            marks: self
                .marks
                .iter()
                .filter_map(|(k, m)| Landmark::from_name(k).map(|l| (l, Mark::Point(m.point))))
                .collect(),
        }
    }

    /// A landmark file (JSON) a user can edit and give back with
    /// `--landmarks`.
    pub fn to_json(&self) -> String {
        let mut m = serde_json::Map::new();
        for (k, v) in &self.marks {
            let r = |x: f64| (x * 1e5).round() / 1e5;
            m.insert(
                (*k).to_string(),
                serde_json::json!([r(v.point[0]), r(v.point[1]), r(v.point[2])]),
            );
        }
        serde_json::to_string_pretty(&serde_json::Value::Object(m)).unwrap_or_default() + "\n"
    }
}

/// Why no landmarks were found.
#[derive(Debug, thiserror::Error)]
pub enum ScanLandmarkError {
    /// The mesh cannot be measured (too small, flat, not finite).
    #[error("automatic landmarks: {0}")]
    Mesh(String),
    /// The shape does not read as a human body clearly enough.
    #[error(
        "automatic landmarks refused (confidence {confidence:.2} < {threshold:.2}): {reason}; give `landmarks`"
    )]
    Refused {
        /// The confidence reached.
        confidence: f64,
        /// The threshold.
        threshold: f64,
        /// Why, in words.
        reason: String,
        /// What was found, for reports.
        found: Box<Option<AutoLandmarks>>,
    },
}

/// A landmark of a given file that disagrees with the automatic one.
#[derive(Debug, Clone, Serialize)]
pub struct Disagreement {
    /// The landmark.
    pub landmark: &'static str,
    /// Distance from the automatic one, % of the height.
    pub percent: f64,
    /// What it looks like (e.g. left and right swapped).
    pub reason: String,
}

/// Compares given landmarks with automatic ones: each given landmark
/// farther than `limit_percent` of the height from the automatic one is
/// listed, and a left landmark that lies at the automatic right one (and
/// the other way round) is called a left/right swap.
pub fn compare(
    auto: &AutoLandmarks,
    given: &Landmarks,
    positions: &[[f64; 3]],
    limit_percent: f64,
) -> Vec<Disagreement> {
    let h = auto.height.max(1e-12);
    let at = |name: &str| auto.marks.get(name).map(|m| DVec3::from_array(m.point));
    let mut out = Vec::new();
    for &l in given.marks.keys() {
        let (Some(p), Some(a)) = (given.point(l, positions), at(l.name())) else {
            continue;
        };
        let p = DVec3::from_array(p);
        let d = 100.0 * p.distance(a) / h;
        if d <= limit_percent {
            continue;
        }
        let twin = twin_name(l.name());
        let swapped = twin
            .and_then(at)
            .is_some_and(|t| 100.0 * p.distance(t) / h <= limit_percent);
        let reason = if swapped {
            format!(
                "it lies at the automatic {} ({d:.1}% of the height from the automatic {}): left and right swapped?",
                twin.unwrap_or(""),
                l.name()
            )
        } else {
            format!("{d:.1}% of the height from the automatic one (limit {limit_percent:.0}%)")
        };
        out.push(Disagreement {
            landmark: l.name(),
            percent: d,
            reason,
        });
    }
    out
}

fn twin_name(n: &str) -> Option<&'static str> {
    let t = if let Some(s) = n.strip_prefix("l_") {
        format!("r_{s}")
    } else if let Some(s) = n.strip_prefix("r_") {
        format!("l_{s}")
    } else {
        return None;
    };
    Landmark::from_name(&t).map(|l| l.name())
}

/// Finds the landmarks of the scan `(positions, triangles)`; refuses with
/// the reason below `o.min_confidence`.
pub fn find(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    o: &ScanOptions,
) -> Result<AutoLandmarks, ScanLandmarkError> {
    let (found, fatal) = estimate(positions, triangles)?;
    if let Some(reason) = fatal {
        return Err(ScanLandmarkError::Refused {
            confidence: found.as_ref().map_or(0.0, |f| f.confidence),
            threshold: o.min_confidence,
            reason,
            found: Box::new(found),
        });
    }
    let Some(f) = found else {
        return Err(ScanLandmarkError::Mesh("nothing found".into()));
    };
    if f.confidence < o.min_confidence {
        let reason = if f.doubts.is_empty() {
            "the shape does not read clearly as a standing human".to_string()
        } else {
            f.doubts.join("; ")
        };
        return Err(ScanLandmarkError::Refused {
            confidence: f.confidence,
            threshold: o.min_confidence,
            reason,
            found: Box::new(Some(f)),
        });
    }
    Ok(f)
}

/// Estimates the landmarks; `Ok((found, Some(reason)))` when the shape is
/// refused whatever the threshold (a missing limb).
#[allow(clippy::type_complexity)]
pub fn estimate(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
) -> Result<(Option<AutoLandmarks>, Option<String>), ScanLandmarkError> {
    let (kept, tris) = frame::referenced(positions, triangles).map_err(ScanLandmarkError::Mesh)?;
    let (positions, triangles) = (&kept[..], &tris[..]);
    let p: Vec<DVec3> = positions.iter().map(|q| DVec3::from_array(*q)).collect();
    if p.len() < 100 || triangles.len() < 100 {
        return Err(ScanLandmarkError::Mesh(format!(
            "{} vertices and {} triangles: too few to read a body from",
            p.len(),
            triangles.len()
        )));
    }
    if p.iter().any(|q| !q.is_finite()) {
        return Err(ScanLandmarkError::Mesh("a vertex is not finite".into()));
    }
    let g = Graph::new(&p, triangles);
    let mut f = frame::frame(&p, &g).map_err(ScanLandmarkError::Mesh)?;
    let h = f.h;
    let mut doubts = std::mem::take(&mut f.doubts);
    let ext = limbs::extremities(&g, &p, &f, &mut doubts);
    let ends = limbs::classify(ext, &p, &f);
    let mut base = AutoLandmarks {
        marks: BTreeMap::new(),
        confidence: 0.0,
        up: f.up.to_array(),
        facing: f.facing.to_array(),
        left: f.left.to_array(),
        height: h,
        symmetry_percent: f.sym_pct,
        extremities: ends.all.iter().map(|&v| positions[v]).collect(),
        doubts,
    };
    let (Some(lfoot), Some(rfoot), Some(lhand), Some(rhand)) =
        (ends.lfoot, ends.rfoot, ends.lhand, ends.rhand)
    else {
        return Ok((Some(base), Some(missing_reason(&ends))));
    };

    // 4. Arms: rings from each hand tip, at least 1.5 edges wide (a ring
    // narrower than an edge misses vertices on one side).
    let mut edges: Vec<f64> = g.to.iter().map(|x| x.1).collect();
    let med_edge = super::midplane::median(&mut edges);
    let step = (0.01 * h).max(1.5 * med_edge);
    let arms = [lhand, rhand].map(|tip| limbs::arm(&g, &p, &f, tip, step));
    // 5. The groin: the lowest section enclosing the point between the legs.
    let groin = torso::groin(positions, triangles, &p, &g, &f);
    // 6. Legs: rings from each foot tip.
    let groin_h = f.hgt(groin.0);
    let legs = [lfoot, rfoot].map(|tip| limbs::leg(&g, &p, &f, tip, step, groin_h));
    // 7. The chin: the front of the neck's narrowest section below the head.
    let head_pt = ends.head.map(|v| p[v]);
    let chin = torso::chin(positions, triangles, &p, &g, &f, head_pt);

    let marks = marks(&f, &arms, &legs, groin, chin, head_pt);
    for (name, m) in &marks {
        if m.confidence < 0.5 {
            base.doubts.push(format!(
                "{name}: {} (confidence {:.2})",
                m.how, m.confidence
            ));
        }
    }
    base.confidence = marks.values().map(|m| m.confidence).fold(f.conf, f64::min);
    base.marks = marks;
    Ok((Some(base), None))
}

/// Why the shape is refused when a hand or a foot is not among the
/// extremities.
fn missing_reason(ends: &limbs::Ends) -> String {
    let mut missing = Vec::new();
    for (x, what) in [
        (ends.lfoot, "left foot"),
        (ends.rfoot, "right foot"),
        (ends.lhand, "left hand"),
        (ends.rhand, "right hand"),
    ] {
        if x.is_none() {
            missing.push(what);
        }
    }
    format!(
        "no {} among the {} extremities found (geodesic local maxima): a missing limb, or not a standing human",
        missing.join(", no "),
        ends.all.len()
    )
}

/// Step 8: every landmark with its confidence (twins mirror each other;
/// none above the frame's).
fn marks(
    f: &frame::Frame,
    arms: &[Arm; 2],
    legs: &[(DVec3, f64, String); 2],
    groin: (DVec3, f64, String),
    chin: (DVec3, f64, String),
    head_pt: Option<DVec3>,
) -> BTreeMap<&'static str, AutoMark> {
    let h = f.h;
    let mut marks: BTreeMap<&'static str, AutoMark> = BTreeMap::new();
    let twin_conf =
        |a: DVec3, b: DVec3| geometry::clamp01(1.0 - (a.distance(f.mirror(b)) / h - 0.05) / 0.1);
    let c_w = twin_conf(arms[0].wrist, arms[1].wrist);
    let c_e = twin_conf(arms[0].elbow, arms[1].elbow);
    let c_k = twin_conf(legs[0].0, legs[1].0);
    let mut put = |name: &'static str, q: DVec3, c: f64, how: String| {
        marks.insert(
            name,
            AutoMark {
                point: q.to_array(),
                confidence: c.min(f.conf),
                how,
            },
        );
    };
    let twin_note = |c: f64, what: &str| {
        if c < 1.0 {
            format!("; the {what}s do not mirror each other")
        } else {
            String::new()
        }
    };
    for (k, pre) in [(0, "l"), (1, "r")] {
        let wn = Landmark::from_name(&format!("{pre}_wrist")).map_or("?", |l| l.name());
        let en = Landmark::from_name(&format!("{pre}_elbow")).map_or("?", |l| l.name());
        let kn = Landmark::from_name(&format!("{pre}_knee")).map_or("?", |l| l.name());
        let ah = if arms[k].how.is_empty() {
            "the narrowest ring at the hand's base".to_string()
        } else {
            arms[k].how.clone()
        };
        put(
            wn,
            arms[k].wrist,
            arms[k].conf.min(c_w),
            format!("{ah}{}", twin_note(c_w, "wrist")),
        );
        put(
            en,
            arms[k].elbow,
            arms[k].conf.min(c_e),
            format!("{}{}", arms[k].elbow_how, twin_note(c_e, "elbow")),
        );
        let kh = if legs[k].2.is_empty() {
            "halfway up the leg's centre line from the ankle to the hip".to_string()
        } else {
            legs[k].2.clone()
        };
        put(
            kn,
            legs[k].0,
            legs[k].1.min(c_k),
            format!("{kh}{}", twin_note(c_k, "knee")),
        );
    }
    put("groin", groin.0, groin.1, groin.2);
    put("chin", chin.0, chin.1, chin.2);
    if let Some(t) = head_pt {
        put(
            "head_top",
            t,
            1.0,
            "the highest extremity near the mid-plane".into(),
        );
    }
    marks
}
