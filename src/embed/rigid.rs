//! A rigid articulated skeleton fitted to measured joints, frame by frame.
//!
//! Joints read off a captured surface by fixed vertex combinations (the
//! regressors, or the part centres of Huang et al. 2015, Sec. 3) are a
//! measurement: where cloth slides over the body (the samba skirt, the
//! crane's jacket) they drift, and the distance between two joints changes
//! from frame to frame by up to 10-25 %. An actor's bones do not. As a
//! motion-capture solver does with marker-derived joint centres, the
//! skeleton is therefore calibrated once per character and each frame is
//! explained by a pose of that one skeleton:
//!
//! - **calibration**: every bone keeps the direction it has in the rest
//!   frame's embedding and takes the median of its measured length over all
//!   frames of the database;
//! - **articulation**: each bone turns about its parent joint on its own,
//!   except the three bones leaving the pelvis (spine root and both hips),
//!   which are one rigid body, as the BVH `Hips` joint carries them (CMU's
//!   ASF skeletons likewise give `lhipjoint`/`rhipjoint` no degree of
//!   freedom while the clavicles have theirs: the shoulders shrug about
//!   the chest, the hips do not move in the pelvis);
//! - **fit**: the root position `t` and one global rotation `R_b` per
//!   body (a bone, or the pelvis) minimise `E = Σ_k ‖p_k − m_k‖²`, the
//!   squared distances from the posed joints `p_k` (forward kinematics:
//!   `p_c = p_j + R_b o_c` for the bone `c` of body `b` hanging from `j`,
//!   `o_c` its calibrated offset) to the measured ones `m_k`, by
//!   Levenberg-Marquardt over `t` and a rotation increment per body
//!   (`R_b ← exp(ω_b) R_b`), started from each bone's least rotation onto
//!   its measured direction. A step is taken only if it lowers `E`; the
//!   twist about a lone bone, which joints do not observe, is left where
//!   the damping keeps it. Iterations stop when one lowers `E` by less than
//!   a relative `tolerance` or the joints are met to 1e-9 of the skeleton.
//!
//! Cost per frame: an iteration assembles the 51 × 51 normal equations from
//! 19 joints (≤ 6 blocks each) and factors them (dense Cholesky on the
//! stack); no heap allocation.

use crate::mocap::{Channel, Clip, ClipError, Joint, JointId};
use crate::pose::{
    Pose,
    measure::{BVH_NAMES, extracted_clip},
    pose_rotations,
};
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

const N: usize = Canonical::COUNT;

/// Options of [`RigidSkeleton::fit`].
#[derive(Debug, Clone, Copy)]
pub struct FitOptions {
    /// Most Levenberg-Marquardt iterations per frame. Default value: 100.
    pub max_iterations: usize,
    /// Stop when an iteration lowers the energy by less than this fraction of
    /// it. Default value: 1e-10.
    pub tolerance: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            max_iterations: 100,
            tolerance: 1e-10,
        }
    }
}

/// One frame's fit.
#[derive(Debug, Clone, Copy)]
pub struct Fit {
    /// The posed rigid skeleton.
    pub pose: Pose,
    /// Root-mean-square distance of the posed joints from the measured
    /// ones (model units).
    pub rms: f64,
    /// Largest distance of a posed joint from its measured one.
    pub max: f64,
    /// Levenberg-Marquardt iterations used.
    pub iterations: usize,
    /// Global rotation of each bone from its rest direction, indexed by the
    /// child joint (bones of one body share it).
    pub rotations: [DQuat; N],
}

/// A character's calibrated skeleton: one offset per bone.
#[derive(Debug, Clone)]
pub struct RigidSkeleton {
    /// Offset of each joint from its parent in the rest pose, with the
    /// calibrated length (zero for the root).
    offsets: [DVec3; N],
    /// The rest pose with those offsets, rooted at the embedding's pelvis.
    rest: Pose,
    /// Sum of the bone lengths (the scale of "exact").
    size: f64,
}

/// The body each bone moves with, named by its leading bone: the bone
/// itself, or for the hips the spine (the pelvis is one rigid body).
const fn body_of(c: Canonical) -> Canonical {
    match c {
        Canonical::LHip | Canonical::RHip => Canonical::Spine,
        c => c,
    }
}

/// Whether bone `c` shares its body with another bone.
fn shares_body(c: Canonical) -> bool {
    Canonical::ALL
        .iter()
        .any(|&o| o != c && o.parent().is_some() && body_of(o) == body_of(c))
}

fn median(v: &mut Vec<f64>) -> Option<f64> {
    v.retain(|x| x.is_finite());
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    Some(v[v.len() / 2])
}

impl RigidSkeleton {
    /// Calibrates the skeleton: bone directions from `rest` (the rig's
    /// embedded joints), lengths the median of the bone's length over
    /// `measured` (the rest length when there are no usable frames).
    pub fn calibrate(rest: &Pose, measured: &[Pose]) -> Self {
        let mut offsets = [DVec3::ZERO; N];
        let mut lens = Vec::with_capacity(measured.len());
        for c in Canonical::ALL {
            let Some(p) = c.parent() else { continue };
            let o = rest[c.index()] - rest[p.index()];
            lens.clear();
            lens.extend(measured.iter().map(|m| m[c.index()].distance(m[p.index()])));
            let len = median(&mut lens).filter(|&l| l > 0.0);
            offsets[c.index()] = match (len, o.try_normalize()) {
                (Some(l), Some(d)) => d * l,
                _ => o,
            };
        }
        let mut rest_pose = [rest[0]; N];
        for c in Canonical::ALL {
            if let Some(p) = c.parent() {
                rest_pose[c.index()] = rest_pose[p.index()] + offsets[c.index()];
            }
        }
        RigidSkeleton {
            size: offsets.iter().map(|o| o.length()).sum(),
            offsets,
            rest: rest_pose,
        }
    }

    /// The calibrated rest pose (the rig's directions, calibrated lengths).
    pub fn rest(&self) -> &Pose {
        &self.rest
    }

    /// Calibrated length of each bone, indexed by its child joint.
    pub fn lengths(&self) -> [f64; N] {
        self.offsets.map(|o| o.length())
    }

    /// Forward kinematics: `r` holds each body's global rotation at its
    /// leading bone's index.
    fn forward(&self, t: DVec3, r: &[DQuat; N], out: &mut Pose) {
        out[0] = t;
        for c in Canonical::ALL.iter().skip(1) {
            if let Some(p) = c.parent() {
                out[c.index()] = out[p.index()] + r[body_of(*c).index()] * self.offsets[c.index()];
            }
        }
    }

    /// Fits the skeleton to one frame's measured joints (see the module
    /// docs). Non-finite measurements leave the rest pose moved to the
    /// measured root, or the rest pose itself.
    pub fn fit(&self, measured: &Pose, opts: &FitOptions) -> Fit {
        let energy = |p: &Pose| -> f64 {
            p.iter()
                .zip(measured)
                .map(|(a, b)| a.distance_squared(*b))
                .sum()
        };
        // Start from each bone's rotation of least angle onto the measured
        // bone (the pelvis body: its best-fitting rotation).
        let g = pose_rotations(&self.rest, measured);
        let mut r = [DQuat::IDENTITY; N];
        for c in Canonical::ALL.iter().skip(1) {
            let Some(p) = c.parent() else { continue };
            let from = self.offsets[c.index()].normalize_or_zero();
            let to = (measured[c.index()] - measured[p.index()]).normalize_or_zero();
            r[c.index()] = if shares_body(*c) {
                g[p.index()]
            } else if from != DVec3::ZERO && to != DVec3::ZERO {
                DQuat::from_rotation_arc(from, to)
            } else {
                g[p.index()]
            };
        }
        if r.iter().any(|q| !q.is_finite()) {
            r = [DQuat::IDENTITY; N];
        }
        let mut t = measured[0];
        if !t.is_finite() {
            t = self.rest[0];
        }
        let mut p = self.rest;
        self.forward(t, &r, &mut p);
        let mut e = energy(&p);
        let floor = (1e-9 * self.size).powi(2) * N as f64;
        let mut lambda = 1e-3;
        let mut iterations = 0;
        let (mut r1, mut p1) = (r, p);
        while iterations < opts.max_iterations && e.is_finite() && e > floor {
            iterations += 1;
            let (jtj, jtr) = self.normal_equations(&p, measured);
            let scale = (0..P).map(|i| jtj[(i, i)]).sum::<f64>() / P as f64;
            let mut improved = false;
            // Levenberg-Marquardt: raise the damping until a step lowers E.
            for _ in 0..30 {
                let mut a = jtj;
                for i in 0..P {
                    a[(i, i)] += lambda * (jtj[(i, i)] + 1e-9 * scale) + 1e-300;
                }
                let Some(ch) = nalgebra::Cholesky::new(a) else {
                    lambda *= 10.0;
                    continue;
                };
                let d = ch.solve(&(-jtr));
                let t1 = t + DVec3::new(d[0], d[1], d[2]);
                for (slot, &b) in BODIES.iter().enumerate() {
                    let o = 3 + 3 * slot;
                    let w = DVec3::new(d[o], d[o + 1], d[o + 2]);
                    r1[b] = (DQuat::from_scaled_axis(w) * r[b]).normalize();
                }
                self.forward(t1, &r1, &mut p1);
                let e1 = energy(&p1);
                if e1 < e {
                    improved = e - e1 > opts.tolerance * e && e1 > floor;
                    (t, r, p, e) = (t1, r1, p1, e1);
                    lambda = (lambda / 3.0).max(1e-12);
                    break;
                }
                lambda *= 4.0;
            }
            if !improved {
                break;
            }
        }
        let d: [f64; N] = std::array::from_fn(|k| p[k].distance(measured[k]));
        Fit {
            pose: p,
            rms: (d.iter().map(|x| x * x).sum::<f64>() / N as f64).sqrt(),
            max: d.iter().copied().fold(0.0, f64::max),
            iterations,
            rotations: std::array::from_fn(|c| r[body_of(Canonical::ALL[c]).index()]),
        }
    }

    /// A BVH-ready clip that plays `fits` back exactly: the canonical
    /// joints with [`BVH_NAMES`] and the calibrated offsets, each joint
    /// turning the body of its children; a bone that moves on its own
    /// beside its parent's body (the shoulders beside the neck) hangs from a
    /// zero-offset joint of its own (`LeftClavicle`, `RightClavicle`),
    /// which no rig convention reads as a canonical joint.
    pub fn clip(&self, fits: &[Fit], fps: f64) -> Result<Clip, ClipError> {
        // BVH joints: (name, parent BVH index, offset, canonical joint or
        // the bone it carries, is an inserted carrier).
        struct Node {
            name: String,
            parent: Option<usize>,
            offset: DVec3,
            carries: Option<Canonical>,
            leaf: bool,
        }
        let mut nodes: Vec<Node> = Vec::with_capacity(N + 2);
        let mut at = [0usize; N];
        for c in Canonical::ALL {
            let mut parent = c.parent().map(|p| at[p.index()]);
            if let Some(p) = c.parent() {
                let first = Canonical::ALL.iter().find(|k| k.parent() == Some(p));
                if first.is_some_and(|f| body_of(*f) != body_of(c)) {
                    nodes.push(Node {
                        name: match c {
                            Canonical::LShoulder => "LeftClavicle".into(),
                            Canonical::RShoulder => "RightClavicle".into(),
                            _ => format!("{}Carrier", BVH_NAMES[c.index()]),
                        },
                        parent,
                        offset: DVec3::ZERO,
                        carries: Some(c),
                        leaf: false,
                    });
                    parent = Some(nodes.len() - 1);
                }
            }
            let first_child = Canonical::ALL.iter().find(|k| k.parent() == Some(c));
            at[c.index()] = nodes.len();
            nodes.push(Node {
                name: BVH_NAMES[c.index()].into(),
                parent,
                offset: if c.parent().is_some() {
                    self.offsets[c.index()]
                } else {
                    self.rest[0]
                },
                carries: first_child.copied(),
                leaf: first_child.is_none(),
            });
        }
        let joints: Vec<Joint> = nodes
            .iter()
            .map(|n| Joint {
                name: n.name.clone(),
                parent: n.parent.map(|p| JointId(p as u32)),
                offset: n.offset,
                channels: if n.parent.is_none() {
                    Channel::ROOT6.to_vec()
                } else {
                    Channel::ROT_ZYX.to_vec()
                },
                tail: n.leaf.then_some(DVec3::ZERO),
            })
            .collect();
        let m = nodes.len();
        let mut rotations = Vec::with_capacity(fits.len() * m);
        let mut translations = Vec::with_capacity(fits.len() * m);
        let mut global = vec![DQuat::IDENTITY; m];
        for f in fits {
            for (i, n) in nodes.iter().enumerate() {
                let pg = n.parent.map_or(DQuat::IDENTITY, |p| global[p]);
                global[i] = n.carries.map_or(pg, |c| f.rotations[c.index()]);
                rotations.push((pg.inverse() * global[i]).normalize());
                translations.push(if n.parent.is_none() {
                    f.pose[0]
                } else {
                    n.offset
                });
            }
        }
        extracted_clip(joints, fps, rotations, translations)
    }

    /// `JᵀJ` and `Jᵀr` of the residuals `p_k − m_k` in the root
    /// translation and a rotation increment `ω_b` per body
    /// (`R_b ← exp(ω_b) R_b`): `∂p_k/∂t = I`, and for each bone `c` on the
    /// way from `k` to the root, `∂p_k/∂ω_b = −[p_c − p_parent(c)]×` for
    /// `c`'s body `b`.
    fn normal_equations(&self, p: &Pose, measured: &Pose) -> (Jtj, nalgebra::SVector<f64, P>) {
        let mut jtj = Jtj::zeros();
        let mut jtr = nalgebra::SVector::<f64, P>::zeros();
        let cross = |v: DVec3| {
            // −[v]×, so that (−[v]×) ω = ω × v.
            nalgebra::Matrix3::new(0.0, v.z, -v.y, -v.z, 0.0, v.x, v.y, -v.x, 0.0)
        };
        let mut blocks = [(0usize, nalgebra::Matrix3::<f64>::identity()); 8];
        for k in Canonical::ALL {
            let mut count = 1;
            blocks[0] = (0, nalgebra::Matrix3::identity());
            let mut c = k;
            while let Some(par) = c.parent() {
                let v = p[c.index()] - p[par.index()];
                blocks[count] = (3 + 3 * SLOT[body_of(c).index()], cross(v));
                count += 1;
                c = par;
            }
            let res = p[k.index()] - measured[k.index()];
            let res = nalgebra::Vector3::new(res.x, res.y, res.z);
            for i in 0..count {
                let (oi, ai) = blocks[i];
                let g = ai.transpose() * res;
                let mut seg = jtr.fixed_rows_mut::<3>(oi);
                seg += g;
                for &(oj, aj) in &blocks[..count] {
                    let m = ai.transpose() * aj;
                    let mut view = jtj.fixed_view_mut::<3, 3>(oi, oj);
                    view += m;
                }
            }
        }
        (jtj, jtr)
    }
}

/// Parameters of the fit: the root translation and a rotation per body.
const P: usize = 3 + 3 * BODIES.len();
type Jtj = nalgebra::SMatrix<f64, P, P>;

/// Number of bodies: the bones that lead their body.
const BODY_COUNT: usize = {
    let mut n = 0;
    let mut k = 1;
    while k < N {
        if body_of(Canonical::ALL[k]) as usize == k {
            n += 1;
        }
        k += 1;
    }
    n
};

/// The bodies' leading bones, by child joint index.
const BODIES: [usize; BODY_COUNT] = {
    let mut b = [0; BODY_COUNT];
    let mut i = 0;
    let mut k = 1;
    while k < N {
        if body_of(Canonical::ALL[k]) as usize == k {
            b[i] = k;
            i += 1;
        }
        k += 1;
    }
    b
};

/// Slot of each leading bone in [`BODIES`].
const SLOT: [usize; N] = {
    let mut s = [0; N];
    let mut i = 0;
    while i < BODIES.len() {
        s[BODIES[i]] = i;
        i += 1;
    }
    s
};
