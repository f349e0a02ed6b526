//! Head-to-torso angle measured on the mesh: the check that sees a head
//! held pitched back (or forward) for a whole sequence, which the
//! joint-velocity error (a difference of velocities) cannot see.
//!
//! Three vertex sets are chosen once on the rest frame from the rig's part
//! labels: the crown (head-part vertices in the top `band` of the head's
//! extent along the body's up axis), the chin (head-part vertices in the
//! bottom `band` of the head: the chin and the neck below it) and the hips
//! (torso-part vertices in the bottom `band` of the torso's extent). Per
//! frame, with `c`, `k`, `h` the centroids of crown, chin and hips, the
//! measure is `∠(k→c, h→k) − ∠_rest(k→c, h→k)` in degrees: zero on the rest
//! frame and on any rigid motion (or uniform scaling) of the whole mesh; a
//! head turned by `α` about an axis normal to the plane of the two axes
//! reads `±α`. Its sign says whether the head leans further from (+) or
//! nearer to (−) the line of the trunk than at rest; summaries use `|·|`.

use super::EvalError;
use super::summary::Summary;
use crate::rig::embed::parts::Part;
use glam::DVec3;

/// Options of [`HeadTorso`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadOptions {
    /// Share of the head's (and torso's) extent along up that makes the
    /// crown, chin and hip bands. Default: 0.10.
    pub band: f64,
}

impl Default for HeadOptions {
    fn default() -> Self {
        HeadOptions { band: 0.10 }
    }
}

/// The vertex sets of the head-to-torso angle and its rest value.
#[derive(Debug, Clone, PartialEq)]
pub struct HeadTorso {
    /// Crown vertices.
    pub crown: Vec<u32>,
    /// Chin (bottom of the head part) vertices.
    pub chin: Vec<u32>,
    /// Hip (bottom of the torso part) vertices.
    pub hips: Vec<u32>,
    /// `∠(chin→crown, hips→chin)` on the rest frame (degrees).
    pub rest_deg: f64,
    /// Vertices of the mesh.
    pub vertex_count: usize,
}

/// Vertices of `part` whose height along `up` lies in `[lo, hi]` as a share
/// of the part's extent (0 = its lowest vertex, 1 = its highest).
/// The vertices of `part` whose height along `up` lies between the
/// fractions `lo` and `hi` of the part's extent (0 its lowest point, 1 its
/// highest), on the rest frame. Shared by the head and foot checks.
pub(crate) fn band(
    rest: &[[f64; 3]],
    labels: &[u8],
    part: Part,
    up: DVec3,
    lo: f64,
    hi: f64,
) -> Vec<u32> {
    let ids: Vec<u32> = (0..labels.len() as u32)
        .filter(|&v| labels[v as usize] == part.index() as u8)
        .collect();
    let h = |v: u32| DVec3::from_array(rest[v as usize]).dot(up);
    let (a, b) = ids
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(h(v)), b.max(h(v)))
        });
    let (from, to) = (a + lo * (b - a), a + hi * (b - a));
    ids.into_iter()
        .filter(|&v| (from..=to).contains(&h(v)))
        .collect()
}

fn centroid(p: &[[f64; 3]], ids: &[u32]) -> DVec3 {
    ids.iter()
        .map(|&v| DVec3::from_array(p[v as usize]))
        .sum::<DVec3>()
        / ids.len().max(1) as f64
}

impl HeadTorso {
    /// Chooses the vertex sets on the rest frame `rest` with per-vertex part
    /// labels `labels` ([`Part::ALL`] indices) and the body's `up` axis.
    /// Errors when the labels do not match the mesh or a set is empty.
    pub fn new(
        rest: &[[f64; 3]],
        labels: &[u8],
        up: DVec3,
        opts: &HeadOptions,
    ) -> Result<HeadTorso, EvalError> {
        if labels.len() != rest.len() {
            return Err(EvalError::Labels {
                have: labels.len(),
                want: rest.len(),
            });
        }
        let up = up.normalize_or(DVec3::Y);
        let b = opts.band.clamp(1e-3, 0.5);
        let crown = band(rest, labels, Part::Head, up, 1.0 - b, 1.0);
        let chin = band(rest, labels, Part::Head, up, 0.0, b);
        let hips = band(rest, labels, Part::Torso, up, 0.0, b);
        for (name, set) in [("head", &crown), ("head", &chin), ("torso", &hips)] {
            if set.is_empty() {
                return Err(EvalError::MissingPart { part: name });
            }
        }
        let mut h = HeadTorso {
            crown,
            chin,
            hips,
            rest_deg: 0.0,
            vertex_count: rest.len(),
        };
        h.rest_deg = h.raw_deg(rest);
        Ok(h)
    }

    /// `∠(chin→crown, hips→chin)` of one frame (degrees, 0..180).
    pub fn raw_deg(&self, positions: &[[f64; 3]]) -> f64 {
        let c = centroid(positions, &self.crown);
        let k = centroid(positions, &self.chin);
        let h = centroid(positions, &self.hips);
        (c - k).angle_between(k - h).to_degrees()
    }

    /// The head-to-torso angle of one frame relative to rest (degrees).
    pub fn angle_deg(&self, positions: &[[f64; 3]]) -> f64 {
        self.raw_deg(positions) - self.rest_deg
    }

    /// Vertices of the mesh the sets were chosen on.
    pub fn vertex_count(&self) -> usize {
        self.vertex_count
    }

    /// The angle of every frame of `frames` (frame-major, `n` vertices each).
    pub fn series(&self, frames: &[[f64; 3]], n: usize) -> Vec<f64> {
        frames
            .chunks_exact(n.max(1))
            .map(|f| self.angle_deg(f))
            .collect()
    }

    /// Median, p95 and max of `|angle|` over a series from [`HeadTorso::series`].
    pub fn summary(series: &[f64]) -> Summary {
        let abs: Vec<f64> = series.iter().map(|x| x.abs()).collect();
        Summary::of(&abs)
    }
}
