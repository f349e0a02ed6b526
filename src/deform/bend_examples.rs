//! The knees' bend as the capture shows it ([`super::DeformOptions::bend_examples`],
//! issue 42): an example-based correction of the retrieved frame at the
//! back and front of each knee, learnt from the database's own frames, in
//! the manner of pose-space deformation (Lewis, Cordner & Fong, *Pose
//! Space Deformation*, SIGGRAPH 2000, Sec. 4: a correction stored in the
//! rest space, interpolated over the pose and skinned with the bones) and
//! of Huang et al. 2015's example-based deformation (Sec. 5.2.3: the
//! captured frames say how the surface may change).
//!
//! Session 37 found the creases and the folds behind the knees where the
//! target bends the knee further than the retrieved frame: the retrieved
//! frame's skin, held to its shape and skinned, buckles where the bend
//! compresses it. The capture shows what the skin does there at each bend.
//!
//! - **Learnt once per character.** Every database frame `f`: its joints
//!   by the rig's regressors (as the deformation reads a source's), its
//!   knee angles `θ_f` (between thigh and shin, 0 straight), and for each
//!   vertex of a knee's zone its residual against the skinned rest frame,
//!   `r_f(v) = T_f(v)⁻¹ (x_f(v) − LBS_f(v))`, with `T_f(v)` the vertex's
//!   bones' turns blended by skin weight. Per knee the residuals are
//!   averaged over the frames whose knee angle is nearest (a Gaussian
//!   kernel of [`SIGMA`] in the angle, Nadaraya-Watson) on a grid of
//!   [`STEP`] between the smallest and largest angle captured: `r̄(θ)`.
//! - **Per frame.** For a source frame `x_s` (knee angle `θ_s`) deformed
//!   to a target pose (`θ_t`), each zone vertex moves by
//!   `gain · w(v) · T_s(v) (r̄(θ_t) − r̄(θ_s))` (linear between grid
//!   points, angles clamped to the captured range), and the deformation
//!   goes on from that source: its skinned targets and its Laplacian
//!   coordinates both carry the capture's shape at the target's bend.
//!   A target bent as the source is leaves the source as it is.
//!
//! The zone is [`super::step_zone`]'s ball (weight 1 within `reach` ×
//! the shin's rest length of the knee, 0 from twice that), cloth
//! ([`super::soft::softness`]) weighted out: a skirt's hem near the knees
//! moves with the dance, not with the knee. Cost: once, O(F · Z) for `F`
//! frames and `Z` zone vertices (plus reading each frame); per frame,
//! O(Z) and a copy of the source, no allocation.

use crate::db::Character;
use crate::embed::Embedding;
use crate::graph::FlatFrame;
use crate::pose::{Pose, pose_rotations};
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

/// Grid step of the learnt residuals over the knee angle (1°).
pub const STEP: f64 = std::f64::consts::PI / 180.0;

/// Width of the kernel that averages the frames of nearby knee angles (4°).
pub const SIGMA: f64 = 4.0 * STEP;

/// One knee's learnt residuals.
#[derive(Debug, Clone)]
struct Knee {
    /// The hip, knee and ankle joints (indices of [`Canonical`]).
    joints: [usize; 3],
    /// The zone's vertices (global ids).
    vertices: Vec<u32>,
    /// Their weights in the zone, cloth weighted out.
    weights: Vec<f64>,
    /// The residual grid over the angle.
    table: AngleTable,
}

/// Per-vertex residuals `r̄(θ)` on a grid of knee angles: `lo + g · STEP`
/// for `g` in `0..count`, rows of one value per vertex.
#[derive(Debug, Clone, PartialEq)]
pub struct AngleTable {
    lo: f64,
    count: usize,
    rows: Vec<[f64; 3]>,
    width: usize,
}

impl AngleTable {
    /// The kernel regression (Gaussian of [`SIGMA`] in the angle) of
    /// `samples` — one knee angle (radians) and one residual per vertex
    /// each, all of `width` vertices — on the grid from the smallest to the
    /// largest angle. `None` without a finite sample.
    pub fn learn(samples: &[(f64, Vec<[f64; 3]>)], width: usize) -> Option<AngleTable> {
        let ok = |s: &&(f64, Vec<[f64; 3]>)| s.0.is_finite() && s.1.len() == width;
        let (lo, hi) = samples
            .iter()
            .filter(ok)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
                (a.min(s.0), b.max(s.0))
            });
        if lo > hi {
            return None;
        }
        let count = ((hi - lo) / STEP).ceil() as usize + 1;
        let mut rows = vec![[0.0; 3]; count * width];
        for (g, row) in rows.chunks_mut(width.max(1)).enumerate().take(count) {
            let at = lo + g as f64 * STEP;
            // Relative to the nearest sample's, so a grid point in a gap
            // of the captured angles takes its nearest frames.
            let near = samples
                .iter()
                .filter(ok)
                .map(|s| (s.0 - at).powi(2))
                .fold(f64::INFINITY, f64::min);
            let mut sum = 0.0;
            for (theta, r) in samples.iter().filter(ok) {
                let k = (-0.5 * ((theta - at).powi(2) - near) / (SIGMA * SIGMA)).exp();
                sum += k;
                for (o, x) in row.iter_mut().zip(r) {
                    for d in 0..3 {
                        o[d] += k * x[d];
                    }
                }
            }
            for o in row.iter_mut() {
                for x in o.iter_mut() {
                    *x /= sum;
                }
            }
        }
        Some(AngleTable {
            lo,
            count,
            rows,
            width,
        })
    }

    /// The grid row below `theta` and the share of the one above (the
    /// angle clamped to the grid).
    fn at(&self, theta: f64) -> (usize, f64) {
        let t = ((theta - self.lo) / STEP).clamp(0.0, (self.count - 1) as f64);
        let g = (t.floor() as usize).min(self.count.saturating_sub(2));
        (g, (t - g as f64).clamp(0.0, 1.0))
    }

    /// `r̄(to) − r̄(from)` at vertex `i` (linear between grid rows).
    pub fn change(&self, i: usize, from: f64, to: f64) -> DVec3 {
        self.value(i, to) - self.value(i, from)
    }

    /// `r̄(theta)` at vertex `i`.
    pub fn value(&self, i: usize, theta: f64) -> DVec3 {
        let (g, s) = self.at(theta);
        let a = DVec3::from_array(self.rows[g * self.width + i]);
        if self.count == 1 {
            return a;
        }
        let b = DVec3::from_array(self.rows[(g + 1) * self.width + i]);
        a + s * (b - a)
    }

    /// The smallest and largest angle of the grid (radians).
    pub fn range(&self) -> (f64, f64) {
        (self.lo, self.lo + (self.count - 1) as f64 * STEP)
    }
}

/// The angle between the thigh (`hip → knee`) and the shin (`knee →
/// ankle`) of `pose`: 0 for a straight leg; NaN for a bone of no length.
pub fn knee_angle(pose: &Pose, joints: [usize; 3]) -> f64 {
    let [h, k, a] = joints.map(|j| pose[j]);
    let (u, v) = (k - h, a - k);
    if u.length_squared() == 0.0 || v.length_squared() == 0.0 {
        return f64::NAN;
    }
    u.cross(v).length().atan2(u.dot(v))
}

/// A vertex's position skinned linearly (as [`super::lbs::skin_into`])
/// and its bones' turns blended by skin weight (as
/// [`super::unflip::skin_turns`]).
fn skin_one(
    p: DVec3,
    (js, ws): &([u8; 4], [f64; 4]),
    rest_pose: &Pose,
    pose: &Pose,
    g: &[DQuat; Canonical::COUNT],
) -> (DVec3, DQuat) {
    let q0 = g[js[0] as usize];
    let (mut x, mut q) = (DVec3::ZERO, DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0));
    for (&j, &w) in js.iter().zip(ws) {
        let j = j as usize;
        if w != 0.0 {
            x += (g[j] * (p - rest_pose[j]) + pose[j]) * w;
        }
        q += if g[j].dot(q0) < 0.0 { -g[j] } else { g[j] } * w;
    }
    let q = if q.length_squared() > 0.0 {
        q.normalize()
    } else {
        q0
    };
    (x, q)
}

/// The knees' learnt residuals of a character ([`BendExamples::bend`]).
#[derive(Debug, Clone)]
pub struct BendExamples {
    knees: Vec<Knee>,
    gain: f64,
}

impl BendExamples {
    /// Learns the knees' residuals of `ch` from all its frames, in zones
    /// of `reach` (as [`super::DeformOptions::step_reach`]); `gain` scales
    /// the correction. `None` when no vertex is in a zone or no frame has a
    /// knee angle.
    pub fn new(ch: &Character, reach: f64, gain: f64) -> Option<BendExamples> {
        Self::from_frames(ch, reach, gain, &|_| true)
    }

    /// [`BendExamples::new`] learnt from the frames (flat indices) that
    /// `keep` takes only (e.g. half of them, to test on the other half).
    pub fn from_frames(
        ch: &Character,
        reach: f64,
        gain: f64,
        keep: &dyn Fn(usize) -> bool,
    ) -> Option<BendExamples> {
        let rest_mesh = ch.topology_metres();
        let rest = rest_mesh.positions();
        let rest_pose = ch.rest_pose();
        let soft = super::soft::softness(ch.topology(), ch.rig());
        let sides = [
            [Canonical::LHip, Canonical::LKnee, Canonical::LAnkle],
            [Canonical::RHip, Canonical::RKnee, Canonical::RAnkle],
        ]
        .map(|s| s.map(Canonical::index));
        let balls = sides.map(|[_, k, a]| {
            let r = (reach * (rest_pose[a] - rest_pose[k]).length()).max(f64::MIN_POSITIVE);
            (rest_pose[k], r)
        });
        let mut zones: [(Vec<u32>, Vec<f64>); 2] = Default::default();
        for (v, p) in rest.iter().enumerate() {
            let p = DVec3::from_array(*p);
            let d = balls.map(|(c, r)| (p - c).length() / r);
            let side = usize::from(d[1] < d[0]);
            let w = (2.0 - d[side]).clamp(0.0, 1.0) * (1.0 - soft[v]).clamp(0.0, 1.0);
            if w > 0.0 {
                zones[side].0.push(v as u32);
                zones[side].1.push(w);
            }
        }
        let mut samples: [Vec<(f64, Vec<[f64; 3]>)>; 2] = Default::default();
        let mut buf = vec![[0.0; 3]; ch.n()];
        for f in (0..ch.frame_count()).filter(|&f| keep(f)) {
            ch.frame_metres(FlatFrame::from_index(f), &mut buf);
            let pose = ch.rig().frame_joints(&buf);
            let g = pose_rotations(rest_pose, &pose);
            for ((s, side), (verts, _)) in samples.iter_mut().zip(sides).zip(&zones) {
                let r = verts
                    .iter()
                    .map(|&v| {
                        let v = v as usize;
                        let (x, q) = skin_one(
                            DVec3::from_array(rest[v]),
                            &ch.rig().skin[v],
                            rest_pose,
                            &pose,
                            &g,
                        );
                        (q.inverse() * (DVec3::from_array(buf[v]) - x)).to_array()
                    })
                    .collect();
                s.push((knee_angle(&pose, side), r));
            }
        }
        let knees: Vec<Knee> = zones
            .into_iter()
            .zip(sides)
            .zip(&samples)
            .filter(|((z, _), _)| !z.0.is_empty())
            .filter_map(|(((vertices, weights), joints), s)| {
                Some(Knee {
                    joints,
                    table: AngleTable::learn(s, vertices.len())?,
                    vertices,
                    weights,
                })
            })
            .collect();
        (!knees.is_empty()).then_some(BendExamples { knees, gain })
    }

    /// The smallest and largest knee angle captured, per knee learnt
    /// (left first), radians.
    pub fn ranges(&self) -> Vec<(f64, f64)> {
        self.knees.iter().map(|k| k.table.range()).collect()
    }

    /// The knees' zones' vertices (global ids, left knee's first).
    pub fn zone(&self) -> Vec<u32> {
        self.knees.iter().flat_map(|k| k.vertices.clone()).collect()
    }

    /// `source` (joints `source_pose`) with each knee's zone moved to the
    /// capture's shape at the knee angle of `target`, into `out` (the rest
    /// copied); `rest_pose` and `rig` the character's. O(Z) after the
    /// copy, no allocation.
    pub fn bend(
        &self,
        source: &[[f64; 3]],
        source_pose: &Pose,
        target: &Pose,
        rest_pose: &Pose,
        rig: &Embedding,
        out: &mut [[f64; 3]],
    ) {
        out.copy_from_slice(source);
        let g = pose_rotations(rest_pose, source_pose);
        for k in &self.knees {
            let (from, to) = (
                knee_angle(source_pose, k.joints),
                knee_angle(target, k.joints),
            );
            if !(from.is_finite() && to.is_finite()) || from == to {
                continue;
            }
            for (i, (&v, &w)) in k.vertices.iter().zip(&k.weights).enumerate() {
                let v = v as usize;
                let p = DVec3::from_array(source[v]);
                let (_, q) = skin_one(p, &rig.skin[v], rest_pose, source_pose, &g);
                let d = q * (self.gain * w * k.table.change(i, from, to));
                if d.is_finite() {
                    out[v] = (p + d).to_array();
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Residuals linear in the angle (one vertex `(θ, 2θ, 0)`, another
    /// constant) at angles 0.1-0.9 rad: the table reproduces them in the
    /// middle of the range within the kernel's bias, the change between
    /// two angles is antisymmetric and zero for one angle, and angles
    /// outside the range are clamped to its ends.
    #[test]
    fn the_table_follows_the_angle_and_clamps() {
        let samples: Vec<(f64, Vec<[f64; 3]>)> = (0..=80)
            .map(|k| {
                let t = 0.1 + 0.01 * k as f64;
                (t, vec![[t, 2.0 * t, 0.0], [0.3, -0.1, 0.2]])
            })
            .collect();
        let t = AngleTable::learn(&samples, 2).unwrap();
        let (lo, hi) = t.range();
        assert!(
            (lo - 0.1).abs() < 1e-12 && (0.9..0.9 + STEP).contains(&hi),
            "{lo} {hi}"
        );
        for theta in [0.4, 0.5, 0.6] {
            let v = t.value(0, theta);
            assert!(
                (v - DVec3::new(theta, 2.0 * theta, 0.0)).length() < 1e-3,
                "{v}"
            );
            let c = t.value(1, theta);
            assert!((c - DVec3::new(0.3, -0.1, 0.2)).length() < 1e-12, "{c}");
        }
        let d = t.change(0, 0.4, 0.6);
        assert!((d - DVec3::new(0.2, 0.4, 0.0)).length() < 1e-3, "{d}");
        assert_eq!(t.change(0, 0.6, 0.4), -d);
        assert_eq!(t.change(0, 0.5, 0.5), DVec3::ZERO);
        assert!((t.value(0, -3.0) - t.value(0, lo)).length() < 1e-12);
        assert!((t.value(0, 3.0) - t.value(0, hi)).length() < 1e-12);
        assert!(t.change(1, -1.0, 5.0).length() < 1e-12);
    }

    /// Non-finite angles and residuals of the wrong width are left out;
    /// with none left there is no table; one angle alone gives a one-row
    /// table whose change is zero; a grid point in a wide gap between
    /// captured angles takes its nearest sample's residual.
    #[test]
    fn bad_samples_are_left_out() {
        assert!(AngleTable::learn(&[], 1).is_none());
        assert!(AngleTable::learn(&[(f64::NAN, vec![[1.0; 3]])], 1).is_none());
        let t = AngleTable::learn(
            &[
                (0.5, vec![[1.0, 0.0, 0.0]]),
                (f64::NAN, vec![[9.0; 3]]),
                (0.7, vec![]),
            ],
            1,
        )
        .unwrap();
        assert_eq!(t.range(), (0.5, 0.5));
        assert_eq!(t.value(0, 0.1), DVec3::X);
        assert_eq!(t.change(0, 0.1, 2.0), DVec3::ZERO);
        let gap = AngleTable::learn(&[(0.0, vec![[1.0; 3]]), (1.0, vec![[3.0; 3]])], 1).unwrap();
        assert!((gap.value(0, 0.2) - DVec3::ONE).length() < 1e-9);
        assert!((gap.value(0, 0.8) - 3.0 * DVec3::ONE).length() < 1e-9);
    }

    /// The knee angle: 0 straight, 90° bent, the same rescaled, mirrored
    /// and turned; NaN for a bone of no length.
    #[test]
    fn the_knee_angle_is_the_bend() {
        let j = [
            Canonical::LHip.index(),
            Canonical::LKnee.index(),
            Canonical::LAnkle.index(),
        ];
        let mut p: Pose = [DVec3::ZERO; Canonical::COUNT];
        p[j[0]] = DVec3::new(0.0, 1.0, 0.0);
        p[j[1]] = DVec3::new(0.0, 0.5, 0.0);
        p[j[2]] = DVec3::new(0.0, 0.0, 0.0);
        assert!(knee_angle(&p, j).abs() < 1e-12);
        p[j[2]] = DVec3::new(0.0, 0.5, -0.4);
        let right = std::f64::consts::FRAC_PI_2;
        assert!((knee_angle(&p, j) - right).abs() < 1e-12);
        let turn = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.9);
        let q: Pose = p.map(|x| turn * (-3.0 * x) + DVec3::ONE);
        assert!((knee_angle(&q, j) - right).abs() < 1e-12);
        let m: Pose = p.map(|x| DVec3::new(-x.x, x.y, x.z));
        assert!((knee_angle(&m, j) - right).abs() < 1e-12);
        p[j[2]] = p[j[1]];
        assert!(knee_angle(&p, j).is_nan());
    }
}
