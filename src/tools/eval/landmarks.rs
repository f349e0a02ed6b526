//! The evaluation of the automatic landmarks of a static scan
//! ([`crate::embed::scan_landmarks`], issue 41) against a hand-made
//! landmark file: each landmark's distance in % of the height, its
//! confidence and how it was found, the mean, and the time the search took.
//! A refused scan is evaluated on what the search found before refusing
//! ([`crate::embed::scan_landmarks::estimate`]), with the refusal shown.

use crate::embed::landmarks::{LandmarkError, Landmarks};
use crate::embed::scan_landmarks::{AutoLandmarks, ScanLandmarkError, ScanOptions, estimate, find};
use crate::mesh::io::{LoadOptions, load_sequence};
use crate::mesh::{Mesh, MeshError, TopologyError};
use std::fmt;
use std::path::Path;
use std::time::Instant;

/// Why a landmark evaluation could not run.
#[derive(Debug, thiserror::Error)]
pub enum LandmarkEvalError {
    /// The mesh could not be read.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The mesh has no group of that name.
    #[error("{mesh}: no group named '{group}'")]
    Group {
        /// The mesh as given.
        mesh: String,
        /// The group asked for.
        group: String,
    },
    /// The group's mesh does not take the frame's positions.
    #[error(transparent)]
    Topology(#[from] TopologyError),
    /// The landmark file could not be read.
    #[error(transparent)]
    Landmarks(#[from] LandmarkError),
    /// The scan cannot be measured at all.
    #[error(transparent)]
    Scan(#[from] ScanLandmarkError),
}

/// One landmark of the file against the automatic one.
#[derive(Debug, Clone)]
pub struct LandmarkRow {
    /// Its file name (`chin`, `l_wrist`, ...).
    pub name: &'static str,
    /// Distance between the two, % of the automatic height.
    pub percent: f64,
    /// The automatic landmark's confidence.
    pub confidence: f64,
    /// The automatic point.
    pub auto: [f64; 3],
    /// The file's point.
    pub file: [f64; 3],
    /// How the automatic one was found.
    pub how: String,
}

/// The evaluation of one scan.
#[derive(Debug, Clone)]
pub struct LandmarkEvaluation {
    /// The mesh as given.
    pub mesh: String,
    /// Its vertex count.
    pub vertices: usize,
    /// CPU-clock seconds of the search ([`find`]).
    pub seconds: f64,
    /// The refusal, when the search refused the scan.
    pub refusal: Option<String>,
    /// What was found (after a refusal: what the search had found), if anything.
    pub found: Option<AutoLandmarks>,
    /// The file's landmarks the search also found, in the file's order.
    pub rows: Vec<LandmarkRow>,
}

impl LandmarkEvaluation {
    /// Mean of the rows' distances, % of the height (0 with no rows).
    pub fn mean_percent(&self) -> f64 {
        self.rows.iter().map(|r| r.percent).sum::<f64>() / self.rows.len().max(1) as f64
    }
}

/// Evaluates the automatic landmarks of frame 0 of `spec` (any mesh or
/// sequence the tool reads; `group` selects one named group, as MakeHuman's
/// `body`) against the landmark file `landmarks`.
pub fn evaluate_landmarks(
    spec: &str,
    group: Option<&str>,
    landmarks: &Path,
) -> Result<LandmarkEvaluation, LandmarkEvalError> {
    let seq = load_sequence(spec, &LoadOptions::default())?;
    let mut mesh = seq.frame_mesh(0);
    if let Some(g) = group {
        let mut m =
            seq.mesh()
                .select_groups(&[g.to_string()])
                .ok_or_else(|| LandmarkEvalError::Group {
                    mesh: spec.into(),
                    group: g.into(),
                })?;
        m.set_positions(mesh.positions())?;
        mesh = m;
    }
    let file = Landmarks::load(landmarks, mesh.vertex_count())?;
    evaluate(spec, &mesh, &file)
}

/// [`evaluate_landmarks`] of a mesh in memory (`name` names it).
pub fn evaluate(
    name: &str,
    mesh: &Mesh,
    file: &Landmarks,
) -> Result<LandmarkEvaluation, LandmarkEvalError> {
    let (p, t) = (mesh.positions(), mesh.triangles());
    let start = Instant::now();
    let searched = find(p, t, &ScanOptions::default());
    let seconds = start.elapsed().as_secs_f64();
    let (found, refusal) = match searched {
        Ok(f) => (Some(f), None),
        Err(e @ ScanLandmarkError::Refused { .. }) => (estimate(p, t)?.0, Some(e.to_string())),
        Err(e) => return Err(e.into()),
    };
    let rows = found.as_ref().map_or_else(Vec::new, |a| rows(a, file, p));
    Ok(LandmarkEvaluation {
        mesh: name.into(),
        vertices: mesh.vertex_count(),
        seconds,
        refusal,
        found,
        rows,
    })
}

/// The file's landmarks against the automatic ones found too.
fn rows(auto: &AutoLandmarks, file: &Landmarks, p: &[[f64; 3]]) -> Vec<LandmarkRow> {
    file.marks
        .keys()
        .filter_map(|&l| {
            let m = auto.marks.get(l.name())?;
            let q = file.point(l, p)?;
            let d = (0..3)
                .map(|i| (q[i] - m.point[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            Some(LandmarkRow {
                name: l.name(),
                percent: 100.0 * d / auto.height,
                confidence: m.confidence,
                auto: m.point,
                file: q,
                how: m.how.clone(),
            })
        })
        .collect()
}

impl fmt::Display for LandmarkEvaluation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(r) = &self.refusal {
            writeln!(f, "{r}")?;
        }
        let Some(a) = &self.found else {
            return Ok(());
        };
        let r2 = |v: [f64; 3]| v.map(|x| (x * 100.0).round() / 100.0);
        writeln!(
            f,
            "{} ({} vertices): {:.3} s, confidence {:.2}, height {:.4}, symmetry {:.2}%, up {:?}, facing {:?}, {} extremities",
            self.mesh,
            self.vertices,
            self.seconds,
            a.confidence,
            a.height,
            a.symmetry_percent,
            r2(a.up),
            r2(a.facing),
            a.extremities.len()
        )?;
        for r in &self.rows {
            let (m, q) = (r.auto, r.file);
            writeln!(
                f,
                "  {:10} {:5.2}%  conf {:.2}  auto [{:.3}, {:.3}, {:.3}]  file [{:.3}, {:.3}, {:.3}]  {}",
                r.name, r.percent, r.confidence, m[0], m[1], m[2], q[0], q[1], q[2], r.how
            )?;
        }
        writeln!(
            f,
            "  mean {:.2}% of the height over {} landmarks",
            self.mean_percent(),
            self.rows.len()
        )?;
        for d in &a.doubts {
            writeln!(f, "  doubt: {d}")?;
        }
        Ok(())
    }
}
