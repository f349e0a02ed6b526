//! Head-to-torso angle measured on the mesh: the check that sees a head
//! held pitched back (or forward) for a whole sequence, which the
//! joint-velocity error (a difference of velocities) cannot see.
//!
//! Three vertex sets are chosen once on the rest frame from the rig's part
//! labels: the crown (head-part vertices in the top `band` of the head's
//! extent along the body's up axis), the "chin" (head-part vertices in the
//! bottom `band` of the head; the head part starts at the rig's neck joint,
//! so on a rig embedded from landmarks this is the base of the neck, and
//! the head axis chin → crown pivots at the neck joint as a skeleton's
//! neck → head bone does) and the hips
//! (torso-part vertices in a slab `band` of the torso's extent thick,
//! centred at the height of the rig's pelvis joint; without a pelvis joint,
//! the bottom `band` of the torso's extent). Per
//! frame, with `c`, `k`, `h` the centroids of crown, chin and hips, the
//! measure is `∠(k→c, h→k) − ∠_rest(k→c, h→k)` in degrees (for a database
//! character whose rest frame is bent, `∠_rest` is its neutral frame's, see
//! `Checker::for_character`): zero on the rest
//! frame and on any rigid motion (or uniform scaling) of the whole mesh; a
//! head turned by `α` about an axis normal to the plane of the two axes
//! reads `±α`. Its sign says whether the head leans further from (+) or
//! nearer to (−) the line of the trunk than at rest; summaries use `|·|`.
//!
//! Why the hips are taken at the pelvis and not at the torso part's lowest
//! vertices: on a clothed capture the lowest band of the torso part is the
//! crotch and the top of a skirt, where the part meets the thighs. On the
//! samba dancer that band lies 5 cm below the pelvis joint and 4 cm to one
//! side of it (the skirt's fold), and it swings with the legs: in the deep
//! lunges of CMU 131_01 it read the head 10° further back than the
//! skeleton read off the same meshes (p95 28.1° against the pelvis-joint
//! line's 19.2°), and it read the capture's own frames p95 9.4° where the
//! slab at the pelvis reads 6.2°.

use super::EvalError;
use super::summary::EvalSummary;
use crate::embed::parts::Part;
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
    /// `∠(chin→crown, hips→chin)` of the pose the angle is measured from
    /// (degrees): the rest frame's, or for a database character whose rest
    /// frame is bent, its neutral frame's (`Checker::for_character`).
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

/// Lowest and highest height along `up` of `part`'s vertices.
fn extent(rest: &[[f64; 3]], labels: &[u8], part: Part, up: DVec3) -> (f64, f64) {
    (0..labels.len())
        .filter(|&v| labels[v] == part.index() as u8)
        .map(|v| DVec3::from_array(rest[v]).dot(up))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), h| {
            (a.min(h), b.max(h))
        })
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
        Self::with_pelvis(rest, labels, up, None, opts)
    }

    /// As [`HeadTorso::new`], the hips taken as the torso-part vertices in
    /// a slab `band` of the torso's extent thick centred at the height of
    /// `pelvis` (the rig's pelvis joint on the rest frame), when given.
    pub fn with_pelvis(
        rest: &[[f64; 3]],
        labels: &[u8],
        up: DVec3,
        pelvis: Option<DVec3>,
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
        let hips = match pelvis.filter(|p| p.is_finite()) {
            Some(p) => {
                // The pelvis height as a share of the torso part's extent.
                let (lo, hi) = extent(rest, labels, Part::Torso, up);
                let at = if hi > lo {
                    (p.dot(up) - lo) / (hi - lo)
                } else {
                    0.0
                };
                let at = at.clamp(0.5 * b, 1.0 - 0.5 * b);
                band(rest, labels, Part::Torso, up, at - 0.5 * b, at + 0.5 * b)
            }
            None => band(rest, labels, Part::Torso, up, 0.0, b),
        };
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

    /// No sets, for a character without a head: every angle reads 0.
    pub fn absent(vertex_count: usize) -> HeadTorso {
        HeadTorso {
            crown: Vec::new(),
            chin: Vec::new(),
            hips: Vec::new(),
            rest_deg: 0.0,
            vertex_count,
        }
    }

    /// `∠(chin→crown, hips→chin)` of one frame (degrees, 0..180); 0
    /// without a head ([`HeadTorso::absent`]).
    pub fn raw_deg(&self, positions: &[[f64; 3]]) -> f64 {
        if self.crown.is_empty() {
            return 0.0;
        }
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
    pub fn summary(series: &[f64]) -> EvalSummary {
        let abs: Vec<f64> = series.iter().map(|x| x.abs()).collect();
        EvalSummary::of(&abs)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A column of torso vertices (y 0.8..1.5) with a skirt flap of torso
    /// vertices below the pelvis on one side (y 0.8..0.85, x 0.1), and a
    /// head above (y 1.5..1.75); labels as [`Part::ALL`] indices.
    fn body() -> (Vec<[f64; 3]>, Vec<u8>) {
        let (mut p, mut l) = (Vec::new(), Vec::new());
        for i in 0..=70 {
            let y = 0.8 + 0.01 * i as f64;
            for x in [-0.1, 0.1] {
                p.push([x, y, 0.0]);
                l.push(Part::Torso.index() as u8);
            }
        }
        for i in 0..=5 {
            p.push([0.15, 0.8 + 0.01 * i as f64, 0.05]);
            l.push(Part::Torso.index() as u8);
        }
        for i in 0..=25 {
            p.push([0.0, 1.5 + 0.01 * i as f64, 0.0]);
            l.push(Part::Head.index() as u8);
        }
        (p, l)
    }

    #[test]
    fn the_hip_set_sits_at_the_pelvis_and_a_swinging_skirt_does_not_move_the_head_measure() {
        let (rest, labels) = body();
        let pelvis = DVec3::new(0.0, 0.9, 0.0);
        let opts = HeadOptions::default();
        let at = HeadTorso::with_pelvis(&rest, &labels, DVec3::Y, Some(pelvis), &opts).unwrap();
        let low = HeadTorso::new(&rest, &labels, DVec3::Y, &opts).unwrap();
        // Centred on the pelvis height, and none of the flap in it.
        let c = centroid(&rest, &at.hips);
        assert!((c.y - pelvis.y).abs() < 0.01 && c.x.abs() < 1e-9, "{c}");
        // The flap swings 20 cm forward and up (a lunge): the head and the
        // trunk have not moved, so the measure must still read 0.
        let mut swung = rest.clone();
        for q in swung.iter_mut().filter(|q| q[0] > 0.12) {
            *q = [q[0], q[1] + 0.1, q[2] + 0.2];
        }
        assert!(
            at.angle_deg(&swung).abs() < 1e-9,
            "{}",
            at.angle_deg(&swung)
        );
        // The lowest band of the torso part takes the flap in, and moves.
        assert!(
            low.angle_deg(&swung).abs() > 1.0,
            "{}",
            low.angle_deg(&swung)
        );
    }
}
