//! Structural mapping of a humanoid clip onto the canonical joints, from the
//! hierarchy and the rest/motion geometry (names are hints only).
//!
//! Steps, all O(joints · sampled frames):
//! 1. Bone lengths and "reach" (longest path to an end point) per joint;
//!    joints joined by zero-length offsets form one node; helper bones are
//!    ignored with their helper-only subtrees: by name (twist, roll,
//!    fingers, ...; see [`super::names::is_helper`]) or by geometry (a side
//!    branch lying along the bone from its parent to a sibling in most
//!    poses: CC's ThighTwist01/02 beside Calf, ToeBaseShareBone).
//! 2. A branch of a node is *significant* when its reach is at least 12% of
//!    the body's size (the largest single-pose bounding-box diagonal; legs
//!    ≈ 35%, arms ≈ 30%, fingers and toes ≈ 7%, measured on CMU, CC and
//!    Bandai rigs).
//! 3. The pelvis is the first node where exactly three significant chains
//!    meet: two legs without further junctions and a spine that reaches a
//!    node where two arms branch off (the chest). Lone joints (no useful
//!    child: mesh attachments, sockets, pelvis controllers) beside the
//!    chains neither count as chains there nor make a junction. Legs must
//!    point away from the chest (the legs' mean direction at a cosine
//!    below −0.7 with the trunk's in the rest pose or the median sampled
//!    frame, [`legs_from_trunk`]): a quadruped's spine is near horizontal
//!    above its legs.
//!    A short bone (under 3% of the body's size) to a joint carrying both
//!    legs joins that joint to the junction (Daz Genesis `hip` → `pelvis`).
//! 4. Joints along a chain, where names do not fix them, by the body's
//!    proportions on arc lengths (rest offsets, so any pose works): knee and
//!    ankle make thigh ≈ shin and shin ≈ 2.5 × ankle-to-toe-tip; shoulder,
//!    elbow and wrist make upper arm ≈ 1.27 × forearm ≈ 1.27 · 1.35 × hand
//!    (Drillis & Contini 1966), a collar being the first arm joint when it
//!    sits under 0.6 of the next one's distance from the mid-plane; the
//!    spine is the joint nearest 40% of the pelvis→chest arc; the neck the
//!    first joint above the chest (a helper-named one when the chain has
//!    nothing else, CC's NeckTwist01), or the joint carrying it when that
//!    sits on the chest with a zero offset (the base of the neck, whose
//!    rotation turns the whole neck bone: CMU cgspeed's `Neck`, where the
//!    conversion dropped the thorax's length); the head the first joint
//!    above the first one off the chest whose node branches (jaw, eyes),
//!    else the chain's last joint; the toe
//!    the first joint after the ankle that is not a straight pass-through
//!    (Daz `lMetatarsals`). A joint whose name has the matching role wins
//!    inside its chain.
//! 5. Left/right from the body's own frame, not from names: up =
//!    pelvis→neck, forward = the feet's ankle→toe direction across the shin
//!    (else the knees'
//!    bend, else the root's travel), left = up × forward (Y-up, facing +Z:
//!    left is +X). Only when none of the three gives a forward direction
//!    (feet straight down, straight knees, no travel: the Biovision sample,
//!    mocapdata.com) do the sides the joints' names state decide.

use super::canonical::Canonical;
use super::derive::Derive;
use super::names::{Role, Side, is_helper, role, side};
use crate::mocap::Clip;
use glam::{DQuat, DVec3};

/// Where a canonical joint came from (its provenance: `Source` is the
/// name of a live input stream, [`crate::live::source::Source`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Provenance {
    /// A known convention's names.
    Convention,
    /// Name tokens (inside the chain structure found).
    Names,
    /// Hierarchy and geometry.
    Structure,
    /// Derived from other joints (no joint in the clip).
    Derived,
    /// Given by a rig map file.
    MapFile,
}

/// One canonical joint as found by [`analyse`].
#[derive(Debug, Clone)]
pub struct Pick {
    /// The clip joint (None when derived).
    pub joint: Option<usize>,
    /// How it was chosen.
    pub source: Provenance,
    /// Confidence in [0, 1].
    pub confidence: f64,
    /// The derivation rule when there is no joint.
    pub derive: Option<Derive>,
}

/// The structural analysis of a humanoid clip.
#[derive(Debug, Clone)]
pub struct Body {
    /// Per canonical joint, in [`Canonical::ALL`] order.
    pub picks: Vec<Pick>,
    /// Joints of the left and right leg subtrees (for checking a name map's sides).
    pub left_leg: Vec<usize>,
    /// Joints of the right leg subtree.
    pub right_leg: Vec<usize>,
    /// Joints of the left arm subtree.
    pub left_arm: Vec<usize>,
    /// Joints of the right arm subtree.
    pub right_arm: Vec<usize>,
    /// How forward was found (`feet`, `knees`, `travel` or `none`).
    pub forward_from: &'static str,
    /// Confidence of the left/right decision in [0, 1].
    pub side_confidence: f64,
    /// True when the joint names state sides opposite to the geometry.
    pub names_mirrored: bool,
    /// True when the geometry gave no forward direction and the names'
    /// sides decided left and right (`forward_from` is `none`).
    pub sides_from_names: bool,
    /// True when the rest skeleton is a standing body (its legs point away
    /// from its spine) and the structure was read on it.
    pub rest_stands: bool,
    /// The frame whose pose stood in for the rest skeleton (which is not a
    /// standing body), or `None` when the rest skeleton was used.
    pub reference_frame: Option<usize>,
    /// The joints' positions in the pose the structure was read on (the
    /// rest skeleton, or `reference_frame`), file units.
    pub reference: Vec<DVec3>,
    /// The first joints of chains off the chest that are neither arms nor
    /// the neck (wings, a cape), left out of the map.
    pub ignored: Vec<String>,
    /// Limbs mapped with fewer joints than usual, and how (a leg of two
    /// joints and an end marker).
    pub notes: Vec<String>,
}

/// The words a [`NotHumanoid`] reason contains when the clip has a
/// humanoid's chains (two legs, a spine with two limbs and a neck) on a
/// horizontal body: a quadruped or a bird, whatever its joint names.
pub(crate) const HORIZONTAL: &str = "a horizontal body";

/// The largest cosine between the legs' mean direction and the trunk's
/// ([`legs_from_trunk`]) of a standing body: −0.7 (134°). Humans walk and
/// run at −0.85 to −1; a fox standing with its chest above its hips is at
/// −0.53 (measured as the mean of the two legs' cosines).
pub(crate) const STANDING: f64 = -0.7;

/// The cosine between the legs' mean direction and the trunk's `up`:
/// `legs` are pelvis → foot vectors, each normalised, their sum's
/// direction taken (the bisector of a spread pair). A body standing with
/// its legs spread, as a depth sensor's rest can hold them (55° out from
/// the trunk's line each), has its feet below it all the same: the mean
/// of the legs' own cosines (−0.57) called it horizontal. A quadruped's
/// hind legs hang across its spine either way (near 0). 0 when the legs
/// cancel out.
pub(crate) fn legs_from_trunk(legs: &[DVec3], up: DVec3) -> f64 {
    legs.iter()
        .map(|l| l.normalize_or_zero())
        .sum::<DVec3>()
        .normalize_or_zero()
        .dot(up)
}

/// Why a clip is not a humanoid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct NotHumanoid(pub String);

const MAX_FRAMES: usize = 24;

struct Geo<'a> {
    clip: &'a Clip,
    names: Vec<String>,
    parent: Vec<Option<usize>>,
    children: Vec<Vec<usize>>,
    len: Vec<f64>,
    helper: Vec<bool>,
    useful: Vec<bool>,
    reach: Vec<f64>,
    rep: Vec<usize>,
    rest: Vec<DVec3>,
    tail_rest: Vec<Option<DVec3>>,
    eps: f64,
    thr: f64,
    /// Sampled poses: (positions, rotations); the reference pose (the rest
    /// pose, or the frame `from_frame`) first.
    poses: Vec<(Vec<DVec3>, Vec<DQuat>)>,
    /// The frame standing in for the rest pose (its world positions are
    /// `rest`, its local translations the bone lengths), when the rest
    /// pose is not a standing body.
    from_frame: Option<usize>,
}

/// Each joint's parent and children (children in index order).
fn hierarchy(clip: &Clip) -> (Vec<Option<usize>>, Vec<Vec<usize>>) {
    let parent: Vec<Option<usize>> = clip
        .joints
        .iter()
        .map(|j| j.parent.map(|p| p.idx()))
        .collect();
    let mut children = vec![Vec::new(); parent.len()];
    for (i, p) in parent.iter().enumerate() {
        if let Some(p) = p {
            children[*p].push(i);
        }
    }
    (parent, children)
}

/// Bone lengths, and the reference pose: the rest skeleton, or the frame
/// `from_frame` standing in for it (its world pose; its local
/// translations, which position channels may set, the bones). Returns
/// the lengths, world positions and world rotations.
fn reference_pose(clip: &Clip, from_frame: Option<usize>) -> (Vec<f64>, Vec<DVec3>, Vec<DQuat>) {
    let n = clip.joint_count();
    match from_frame {
        Some(f) if f < clip.frame_count() => {
            let mut p = vec![DVec3::ZERO; n];
            let mut r = vec![DQuat::IDENTITY; n];
            clip.world_into(f, &mut p, &mut r);
            let len = (0..n)
                .map(|i| clip.translations.get(f * n + i).map_or(0.0, |t| t.length()))
                .collect();
            (len, p, r)
        }
        _ => (
            clip.joints.iter().map(|j| j.offset.length()).collect(),
            clip.rest_positions().0,
            vec![DQuat::IDENTITY; n],
        ),
    }
}

/// The bounding-box diagonal of some points.
fn bbox_diag(pts: impl Iterator<Item = DVec3>) -> f64 {
    let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for p in pts {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    (hi - lo).length()
}

/// The reference pose (positions `rest`, rotations `rot0`) followed by
/// up to [`MAX_FRAMES`] frames spread over the clip.
fn sampled_poses(clip: &Clip, rest: &[DVec3], rot0: Vec<DQuat>) -> Vec<(Vec<DVec3>, Vec<DQuat>)> {
    let n = clip.joint_count();
    let mut poses = Vec::new();
    let mut rot = vec![DQuat::IDENTITY; n];
    poses.push((rest.to_vec(), rot0));
    let frames = clip.frame_count();
    let step = (frames / MAX_FRAMES).max(1);
    let mut pos = vec![DVec3::ZERO; n];
    let mut f = 0;
    while f < frames {
        clip.world_into(f, &mut pos, &mut rot);
        poses.push((pos.clone(), rot.clone()));
        f += step;
    }
    poses
}

/// The body's size: the largest single-pose extent (a rest skeleton in
/// bone-local frames, as CC exports, can be a folded stick; at least
/// `diag`, the reference pose's), over the joints from the first
/// branching joint down: a root chain above it is no part of the body
/// (Bandai's static `joint_Root` stays at the origin while the body walks
/// metres away from it).
fn body_size(
    parent: &[Option<usize>],
    children: &[Vec<usize>],
    poses: &[(Vec<DVec3>, Vec<DQuat>)],
    diag: f64,
) -> f64 {
    let n = parent.len();
    let mut top = parent.iter().position(Option::is_none).unwrap_or(0);
    for _ in 0..n {
        match children[top].as_slice() {
            [only] => top = *only,
            _ => break,
        }
    }
    let mut above = vec![false; n];
    let mut k = parent[top];
    while let Some(x) = k {
        if above[x] {
            break;
        }
        above[x] = true;
        k = parent[x];
    }
    poses
        .iter()
        .map(|(p, _)| {
            bbox_diag(
                p.iter()
                    .enumerate()
                    .filter(|&(i, _)| !above[i])
                    .map(|(_, q)| *q),
            )
        })
        .filter(|d| d.is_finite())
        .fold(diag, f64::max)
}

/// Twist and share bones by geometry: a side branch whose joints (and End
/// Sites) all lie on the bone from its parent to a sibling, in the rest
/// pose and most sampled poses (CC's ThighTwist01/02 beside Calf,
/// ToeBaseShareBone beside ToeBase), is a helper whatever its name.
fn helpers_along_bones(
    clip: &Clip,
    parent: &[Option<usize>],
    children: &[Vec<usize>],
    len: &[f64],
    poses: &[(Vec<DVec3>, Vec<DQuat>)],
    eps: f64,
    helper: &mut [bool],
) {
    let subtree_of = |j: usize| {
        let mut out = Vec::new();
        let mut stack = vec![j];
        while let Some(k) = stack.pop() {
            out.push(k);
            stack.extend(children[k].iter().copied());
            if out.len() > 64 {
                break; // a twist chain is short; a limb is not a helper
            }
        }
        out
    };
    for j in 0..parent.len() {
        let Some(p) = parent[j] else { continue };
        if helper[j] || children[p].len() < 2 {
            continue;
        }
        let sub = subtree_of(j);
        if sub.len() > 64 {
            continue;
        }
        let on_bone = |k: usize| {
            let seg_len = len[k];
            if k == j || seg_len < eps {
                return false;
            }
            let tol = 0.1 * seg_len;
            let hits = poses
                .iter()
                .filter(|(ps, rs)| {
                    let (a, mut b) = (ps[p], ps[k]);
                    // The bone runs on through pass-through joints in
                    // line with it (a split shin: Calf → x → Foot).
                    let mut e = k;
                    for _ in 0..8 {
                        let dir = (b - a).normalize_or_zero();
                        let next = children[e].iter().copied().find(|&q| {
                            let v = ps[q] - a;
                            len[q] >= eps
                                && v.dot(dir) > (b - a).length()
                                && (v - dir * v.dot(dir)).length() <= tol
                        });
                        match next {
                            Some(q) => {
                                e = q;
                                b = ps[q];
                            }
                            None => break,
                        }
                    }
                    let ab = b - a;
                    let d = |q: DVec3| {
                        let t = ((q - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
                        (a + ab * t).distance(q)
                    };
                    sub.iter().all(|&m| {
                        d(ps[m]) <= tol
                            && clip.joints[m]
                                .tail
                                .is_none_or(|t| d(ps[m] + rs[m] * t) <= tol)
                    })
                })
                .count();
            hits * 5 >= poses.len() * 4
        };
        if children[p].iter().any(|&k| on_bone(k)) {
            for m in sub {
                helper[m] = true;
            }
        }
    }
}

/// Per joint, whether its subtree holds a non-helper joint (`useful`),
/// and its reach: the longest path through useful children to an end
/// point (End Site included).
fn useful_and_reach(
    clip: &Clip,
    children: &[Vec<usize>],
    len: &[f64],
    helper: &[bool],
) -> (Vec<bool>, Vec<f64>) {
    let n = children.len();
    // Children lists are in index order and parents precede children, so
    // a reverse sweep sees every child before its parent.
    let mut useful = vec![false; n];
    let mut reach = vec![0.0f64; n];
    for i in (0..n).rev() {
        let mut r = clip.joints[i].tail.map_or(0.0, |t| t.length());
        let mut u = !helper[i];
        for &c in &children[i] {
            if useful[c] {
                u = true;
                r = r.max(len[c] + reach[c]);
            }
        }
        useful[i] = u;
        reach[i] = if r.is_finite() { r } else { 0.0 };
    }
    (useful, reach)
}

/// Joints joined to their parent by a bone under `eps` long form one node:
/// each joint's representative is the node's top joint.
fn zero_length_nodes(parent: &[Option<usize>], len: &[f64], eps: f64) -> Vec<usize> {
    let mut rep: Vec<usize> = (0..parent.len()).collect();
    for i in 0..parent.len() {
        if let Some(p) = parent[i]
            && len[i] < eps
        {
            rep[i] = rep[p];
        }
    }
    rep
}

impl<'a> Geo<'a> {
    /// Step 1 on the rest skeleton, or on the frame `from_frame` standing
    /// in for it: the hierarchy ([`hierarchy`]), bone lengths and the
    /// reference pose ([`reference_pose`]), the sampled poses
    /// ([`sampled_poses`]), the body's size ([`body_size`]), the helper
    /// bones (by name, then by geometry: [`helpers_along_bones`]), each
    /// joint's reach ([`useful_and_reach`]) and the zero-length nodes
    /// ([`zero_length_nodes`]).
    fn new(
        clip: &'a Clip,
        tokens: &[Vec<String>],
        from_frame: Option<usize>,
    ) -> Result<Geo<'a>, NotHumanoid> {
        let n = clip.joint_count();
        let (parent, children) = hierarchy(clip);
        let (len, rest, rot0) = reference_pose(clip, from_frame);
        let mut helper: Vec<bool> = (0..n)
            .map(|i| tokens.get(i).is_some_and(|t| is_helper(t)))
            .collect();
        let tail_rest: Vec<Option<DVec3>> = clip
            .joints
            .iter()
            .enumerate()
            .map(|(i, j)| j.tail.map(|t| rest[i] + rot0[i] * t))
            .collect();
        let diag = bbox_diag(rest.iter().chain(tail_rest.iter().flatten()).copied());
        if !(diag.is_finite() && diag > 0.0) {
            return Err(NotHumanoid(match from_frame {
                Some(f) => format!("the skeleton has no extent at frame {f}"),
                None => "the rest skeleton has no extent".into(),
            }));
        }
        let eps = 1e-3 * diag;
        let poses = sampled_poses(clip, &rest, rot0);
        let size = body_size(&parent, &children, &poses, diag);
        helpers_along_bones(clip, &parent, &children, &len, &poses, eps, &mut helper);
        let (useful, reach) = useful_and_reach(clip, &children, &len, &helper);
        let rep = zero_length_nodes(&parent, &len, eps);
        Ok(Geo {
            clip,
            names: clip.point_names(),
            parent,
            children,
            len,
            helper,
            useful,
            reach,
            rep,
            rest,
            tail_rest,
            eps,
            thr: 0.12 * size,
            poses,
            from_frame,
        })
    }

    /// Significant branches leaving the zero-length node of `r`.
    fn branches(&self, r: usize) -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = vec![r];
        while let Some(j) = stack.pop() {
            for &c in &self.children[j] {
                if self.rep[c] == self.rep[r] {
                    stack.push(c);
                } else if self.useful[c] && self.len[c] + self.reach[c] >= self.thr {
                    out.push(c);
                }
            }
        }
        out.sort_unstable();
        out
    }

    /// Significant branches of the node of `r`, a short bone to a node that
    /// itself splits into two or more significant branches counting as
    /// those branches: a pelvis split across two joints (Daz Genesis: `hip`
    /// carries the spine and, a centimetre or two away, `pelvis` carries
    /// the thighs; H-Anim: `humanoid_root` carries `vl5` and, 9 cm away,
    /// `sacroiliac` carries the hips; 3ds Max Biped: `Bip01 Spine` carries
    /// the thighs and `Bip01 Spine1` 9 cm above `Bip01 Pelvis`) is one
    /// junction. Short: under half the significance threshold (6% of the
    /// body's size).
    ///
    /// Lone joints below the short bone do not count ([`Geo::lone`]: a
    /// mesh attachment beside the knee made a CC thigh, 10 cm from the
    /// pelvis, such a junction, and the legs started at the knees).
    fn hip_branches(&self, r: usize) -> Vec<usize> {
        let mut out = Vec::new();
        for c in self.branches(r) {
            let sub: Vec<usize> = self
                .branches(self.rep[c])
                .into_iter()
                .filter(|&k| !self.lone(k))
                .collect();
            if self.len[c] < 0.5 * self.thr && sub.len() >= 2 {
                out.extend(sub);
            } else {
                out.push(c);
            }
        }
        out.sort_unstable();
        out
    }

    /// The two leg chains among five chains leaving one joint (two legs,
    /// two arms and a neck off a torso joint): the pair whose far ends lie
    /// farthest from the mean far end of the other three (the feet below
    /// the hands and the head, arms down or up). `None` when no pair stands
    /// out (its distance not the largest by 20%).
    fn hub_legs(&self, b: &[usize]) -> Option<[usize; 2]> {
        let end = |c: usize| {
            let path = self.path(c);
            let e = *path.last().unwrap_or(&c);
            self.tail_rest[e].unwrap_or(self.rest[e])
        };
        let ends: Vec<DVec3> = b.iter().map(|&c| end(c)).collect();
        let mut scores: Vec<(f64, usize, usize)> = Vec::new();
        for i in 0..b.len() {
            for j in i + 1..b.len() {
                let pair = 0.5 * (ends[i] + ends[j]);
                let others: DVec3 = (0..b.len())
                    .filter(|&k| k != i && k != j)
                    .map(|k| ends[k])
                    .sum::<DVec3>()
                    / (b.len() - 2) as f64;
                scores.push((pair.distance(others), i, j));
            }
        }
        scores.sort_by(|x, y| y.0.total_cmp(&x.0));
        let (best, i, j) = *scores.first()?;
        let second = scores.get(1).map_or(0.0, |s| s.0);
        (best > 1.2 * second).then_some([b[i], b[j]])
    }

    /// Spine, chest and legs among more than three significant chains
    /// leaving the pelvis node `p` (VRoid/anime rigs hang a tail, skirt and
    /// cloth chains off the hips; game rigs a holster): the spine is the
    /// only chain branching into limbs further on (its first junction the
    /// chest); the legs are the pair of the others whose far ends reach
    /// lowest below the pelvis (along pelvis→chest) and which mirror each
    /// other best (their far ends and their starts at the same heights and
    /// the same distances from the trunk's axis: a tail or a front skirt
    /// chain lies on the mid-plane, a side skirt is short). Each leg's end
    /// must lie below the pelvis; the pair's reaches within 1.6×. `None`
    /// when no chain or several reach a junction, or no pair qualifies.
    fn legs_among(&self, p: usize, b: &[usize]) -> Option<(usize, usize, [usize; 2])> {
        let with: Vec<(usize, usize)> = b
            .iter()
            .filter_map(|&c| self.junction_below(c).map(|j| (c, j)))
            .collect();
        let [(spine, chest)] = with[..] else {
            return None;
        };
        let origin = self.rest[p];
        let up = (self.rest[chest] - origin).normalize_or_zero();
        if up == DVec3::ZERO {
            return None;
        }
        // Height along `up` and distance from the trunk's axis.
        let split = |q: DVec3| {
            let d = q - origin;
            let h = d.dot(up);
            (h, (d - h * up).length())
        };
        // A candidate leg: its first joint, its far end's and its start's
        // (height, distance from the axis), its reach.
        struct Leg {
            c: usize,
            end: (f64, f64),
            start: (f64, f64),
            reach: f64,
        }
        let legs: Vec<Leg> = b
            .iter()
            .filter(|&&c| c != spine)
            .map(|&c| {
                let path = self.path(c);
                let e = *path.last().unwrap_or(&c);
                Leg {
                    c,
                    end: split(self.tail_rest[e].unwrap_or(self.rest[e])),
                    start: split(self.rest[c]),
                    reach: self.len[c] + self.reach[c],
                }
            })
            .filter(|l| l.end.0 < 0.0)
            .collect();
        let mut best: Option<(f64, [usize; 2])> = None;
        for (i, a) in legs.iter().enumerate() {
            for c in &legs[i + 1..] {
                if a.reach.max(c.reach) > 1.6 * a.reach.min(c.reach) {
                    continue;
                }
                let mismatch = (a.end.0 - c.end.0).abs()
                    + (a.end.1 - c.end.1).abs()
                    + (a.start.0 - c.start.0).abs()
                    + (a.start.1 - c.start.1).abs();
                let score = -(a.end.0 + c.end.0) - mismatch;
                if best.is_none_or(|(s, _)| score > s) {
                    best = Some((score, [a.c, c.c]));
                }
            }
        }
        best.map(|(_, legs)| (spine, chest, legs))
    }

    /// Useful (non-helper-only) children leaving the node of `r`, any length.
    fn node_children(&self, r: usize) -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = vec![r];
        while let Some(j) = stack.pop() {
            for &c in &self.children[j] {
                if self.rep[c] == self.rep[r] {
                    stack.push(c);
                } else if self.useful[c] {
                    out.push(c);
                }
            }
        }
        out.sort_unstable();
        out
    }

    /// The main path from `start`: at each joint the useful child of
    /// longest reach, a chain before a lone joint beside it (a mesh
    /// attachment as long as the neck's rest beside `NeckTwist02`: the
    /// path ran into it and missed the head), until an end.
    fn path(&self, start: usize) -> Vec<usize> {
        let mut out = vec![start];
        let mut j = start;
        while let Some(&c) =
            self.children[j]
                .iter()
                .filter(|&&c| self.useful[c])
                .max_by(|&&a, &&b| {
                    self.lone(b).cmp(&self.lone(a)).then(
                        (self.len[a] + self.reach[a]).total_cmp(&(self.len[b] + self.reach[b])),
                    )
                })
        {
            out.push(c);
            j = c;
            if out.len() > self.clip.joint_count() {
                break;
            }
        }
        out
    }

    /// The first junction (node with ≥ 2 significant branches) going down
    /// the single significant branch from `start`.
    ///
    /// A lone joint (no useful child: a mesh attachment, a socket, a twist
    /// leaf) beside the chain going on does not make a junction
    /// (`L_Humerus_RIGMESH` beside the forearm, a leaf as long as the spine
    /// bone beside `Spine1`: the chest was found at the first leaf).
    fn junction_below(&self, start: usize) -> Option<usize> {
        let mut j = self.rep[start];
        for _ in 0..=self.clip.joint_count() {
            let b = self.branches(j);
            let chains: Vec<usize> = b.iter().copied().filter(|&c| !self.lone(c)).collect();
            match (b.len(), chains.as_slice()) {
                (0, _) => return None,
                (1, _) => j = self.rep[b[0]],
                (_, [only]) => j = self.rep[*only],
                _ => return Some(j),
            }
        }
        None
    }

    /// True when the branch starting at `c` is a lone joint: no useful
    /// child leaves its zero-length node (an End Site at most).
    fn lone(&self, c: usize) -> bool {
        self.node_children(c).is_empty()
    }

    /// `b` without its lone joints ([`Geo::lone`]) when at least `keep`
    /// chains remain, else `b`.
    fn chains_of(&self, b: Vec<usize>, keep: usize) -> Vec<usize> {
        let chains: Vec<usize> = b.iter().copied().filter(|&c| !self.lone(c)).collect();
        if chains.len() >= keep && chains.len() < b.len() {
            chains
        } else {
            b
        }
    }

    /// Arc length (sum of bone lengths) along `path` from its first joint
    /// to each joint, and to the path's far end (the last joint's End Site
    /// included). Pose-independent: rest offsets only.
    fn arcs(&self, path: &[usize]) -> (Vec<f64>, f64) {
        let mut a = Vec::with_capacity(path.len());
        let mut acc = 0.0;
        for (k, &j) in path.iter().enumerate() {
            if k > 0 {
                acc += self.len[j];
            }
            a.push(acc);
        }
        let tail = path
            .last()
            .and_then(|&j| self.clip.joints[j].tail)
            .map_or(0.0, |t| t.length());
        (a, acc + tail)
    }

    fn subtree(&self, start: usize) -> Vec<usize> {
        let mut out = Vec::new();
        let mut stack = vec![start];
        while let Some(j) = stack.pop() {
            out.push(j);
            stack.extend(self.children[j].iter().copied());
        }
        out
    }

    /// Non-helper joints of `path` whose rest position differs from the
    /// previous kept one (starting from `from`), with pass-through joints
    /// (collinear with their neighbours in every sampled pose) removed.
    fn candidates(
        &self,
        tokens: &[Vec<String>],
        from: DVec3,
        path: &[usize],
        collinear: bool,
    ) -> Vec<usize> {
        let mut out: Vec<usize> = Vec::new();
        let mut last = from;
        for &j in path {
            if self.helper[j] || self.rest[j].distance(last) < self.eps {
                continue;
            }
            last = self.rest[j];
            out.push(j);
        }
        if collinear && self.poses.len() > 2 && out.len() > 2 {
            let mut keep = vec![true; out.len()];
            for k in 1..out.len() - 1 {
                let (a, b, c) = (out[k - 1], out[k], out[k + 1]);
                if tokens.get(b).is_some_and(|t| role(t).is_some()) {
                    continue; // a named body joint is never a pass-through
                }
                let bent = self.poses.iter().any(|(p, _)| {
                    let u = (p[b] - p[a]).normalize_or_zero();
                    let v = (p[c] - p[b]).normalize_or_zero();
                    u.dot(v) < 0.9994 // 2 degrees
                });
                keep[k] = bent;
            }
            let mut k = 0;
            out.retain(|_| {
                k += 1;
                keep[k - 1]
            });
        }
        out
    }
}

fn role_of(tokens: &[Vec<String>], j: usize) -> Option<Role> {
    tokens.get(j).and_then(|t| role(t))
}

fn first_role(tokens: &[Vec<String>], c: &[usize], f: impl Fn(Role) -> bool) -> Option<usize> {
    c.iter().position(|&j| role_of(tokens, j).is_some_and(&f))
}

struct Limb {
    /// (root joint, [upper, middle, lower, end]) as candidate picks.
    picks: [Option<(usize, bool)>; 4],
    derive_end: Option<Derive>,
    subtree: Vec<usize>,
    /// What the reader should know of a limb mapped with less than the
    /// usual joints ([`two_joint_leg`]).
    note: Option<String>,
}

/// Maps a clip's joints onto the canonical skeleton by structure, using
/// `tokens` (from [`super::names::all_tokens`]) as hints inside chains.
///
/// The hierarchy is read on the rest skeleton when it is a standing body
/// (legs pointing away from the spine). When it is not (LAFAN1's rest has
/// every bone along +X, legs and spine alike; some exporters write a zero
/// or collapsed rest and put the offsets in position channels), or no
/// humanoid is found on it, the analysis is done again on a representative
/// frame's pose (forward kinematics: [`representative_frame`]) standing in
/// for the rest; the body found there is kept when it is one (its legs
/// point away from its spine in the median sampled frame, as for any
/// clip), else the rest's answer stands.
pub fn analyse(clip: &Clip, tokens: &[Vec<String>]) -> Result<Body, NotHumanoid> {
    let at_rest = analyse_at(clip, tokens, None);
    if at_rest.as_ref().is_ok_and(|b| b.rest_stands) {
        return at_rest;
    }
    let Some(f) = representative_frame(clip) else {
        return at_rest;
    };
    match analyse_at(clip, tokens, Some(f)) {
        Ok(b) => Ok(b),
        Err(e) => match at_rest {
            Ok(b) => Ok(b),
            Err(r) if r.0.contains(HORIZONTAL) || !e.0.contains(HORIZONTAL) => Err(r),
            Err(_) => Err(e),
        },
    }
}

/// The frame whose pose stands in for a rest skeleton that is not a
/// standing body: of up to 24 sampled frames, the one of largest extent
/// (bounding-box diagonal of its joints), a pose with the limbs spread
/// rather than folded. `None` without frames.
pub(crate) fn representative_frame(clip: &Clip) -> Option<usize> {
    let n = clip.joint_count();
    let frames = clip.frame_count();
    let step = (frames / MAX_FRAMES).max(1);
    let (mut p, mut r) = (vec![DVec3::ZERO; n], vec![DQuat::IDENTITY; n]);
    let mut best: Option<(f64, usize)> = None;
    for f in (0..frames).step_by(step) {
        clip.world_into(f, &mut p, &mut r);
        let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        for q in &p {
            lo = lo.min(*q);
            hi = hi.max(*q);
        }
        let d = (hi - lo).length();
        if d.is_finite() && best.is_none_or(|(b, _)| d > b) {
            best = Some((d, f));
        }
    }
    best.map(|(_, f)| f)
}

fn analyse_at(
    clip: &Clip,
    tokens: &[Vec<String>],
    from_frame: Option<usize>,
) -> Result<Body, NotHumanoid> {
    let g = Geo::new(clip, tokens, from_frame)?;
    let n = clip.joint_count();
    let mut reasons: Vec<String> = Vec::new();
    for p in 0..n {
        if g.rep[p] != p || !g.useful[p] {
            continue;
        }
        // Lone joints beside the chains (pelvis controllers, mesh
        // attachments) are no legs or spine.
        let b = g.chains_of(g.hip_branches(p), 3);
        if b.len() < 3 {
            continue;
        }
        if b.len() == 5
            && let Some(legs) = g.hub_legs(&b)
        {
            // Legs, arms and neck off one joint (Kinect v1 / OpenNI's
            // `Torso`): pelvis and chest are that joint's node. When that
            // body is no humanoid, the five may be two legs, a spine and
            // two accessory chains (a Rigify export's torso controller and
            // tail): tried as such below.
            match body(&g, tokens, p, p, p, legs) {
                Ok(body) => return Ok(body),
                Err(e) => reasons.push(e.0),
            }
        }
        if b.len() > 3 {
            // Accessory chains beside the legs (a tail, skirt or cloth
            // chains, a holster): the spine is the one branch that reaches
            // the arms, the legs the pair the others cannot match.
            let Some((s, chest, legs)) = g.legs_among(p, &b) else {
                reasons.push(format!(
                    "{} chains meet at '{}' (two legs and a spine expected)",
                    b.len(),
                    g.names[p]
                ));
                continue;
            };
            match body(&g, tokens, p, s, chest, legs) {
                Ok(body) => return Ok(body),
                Err(e) => reasons.push(e.0),
            }
            continue;
        }
        let junctions: Vec<Option<usize>> = b.iter().map(|&s| g.junction_below(s)).collect();
        let with: Vec<usize> = (0..3).filter(|&k| junctions[k].is_some()).collect();
        if with.len() != 1 {
            reasons.push(if with.is_empty() {
                format!("no arms branch off the chains above '{}'", g.names[p])
            } else {
                format!(
                    "more than one chain below '{}' branches into limbs",
                    g.names[p]
                )
            });
            continue;
        }
        let s = with[0];
        let Some(chest) = junctions[s] else { continue };
        let legs: Vec<usize> = (0..3).filter(|&k| k != s).map(|k| b[k]).collect();
        match body(&g, tokens, p, b[s], chest, [legs[0], legs[1]]) {
            Ok(body) => return Ok(body),
            Err(e) => reasons.push(e.0),
        }
    }
    if reasons.is_empty() {
        reasons.push("no joint where two leg chains and a spine meet".into());
    }
    reasons.truncate(3);
    Err(NotHumanoid(reasons.join("; ")))
}

/// Step 3 and 4 on a candidate pelvis: the body whose pelvis is `pelvis`,
/// its spine starting at `spine_start` and reaching the chest `chest`, its
/// legs starting at `legs`: the trunk checked ([`trunk`]), then the
/// joints picked along each chain (pelvis, spine and chest:
/// [`spine_and_chest`]; neck and head: [`neck_and_head`]; the limbs:
/// [`leg_chain`], [`arm_chain`]), then step 5, left and right
/// ([`sides`]).
fn body(
    g: &Geo,
    tokens: &[Vec<String>],
    pelvis: usize,
    spine_start: usize,
    chest: usize,
    legs: [usize; 2],
) -> Result<Body, NotHumanoid> {
    let _ = spine_start;
    let trunk = trunk(g, tokens, pelvis, chest, legs)?;

    let mut picks: Vec<Pick> = (0..Canonical::COUNT)
        .map(|_| Pick {
            joint: None,
            source: Provenance::Structure,
            confidence: 0.0,
            derive: None,
        })
        .collect();
    let (neck_from_chest, chest_derived) =
        spine_and_chest(g, tokens, &mut picks, pelvis, chest, legs, trunk.hub);
    let neck_j = neck_and_head(
        g,
        tokens,
        &mut picks,
        chest,
        &trunk,
        neck_from_chest,
        chest_derived,
    )?;

    // Limbs.
    let leg = |start: usize| -> Result<Limb, NotHumanoid> { leg_chain(g, tokens, pelvis, start) };
    let arm =
        |start: usize| -> Result<Limb, NotHumanoid> { arm_chain(g, tokens, legs, chest, start) };
    let limbs = [
        leg(legs[0])?,
        leg(legs[1])?,
        arm(trunk.arms[0])?,
        arm(trunk.arms[1])?,
    ];
    let notes: Vec<String> = limbs.iter().filter_map(|l| l.note.clone()).collect();
    let s = sides(g, tokens, &mut picks, pelvis, neck_j, limbs);
    Ok(Body {
        picks,
        left_leg: s.left_leg,
        right_leg: s.right_leg,
        left_arm: s.left_arm,
        right_arm: s.right_arm,
        forward_from: s.forward_from,
        side_confidence: s.side_confidence,
        names_mirrored: s.names_mirrored,
        sides_from_names: s.sides_from_names,
        rest_stands: trunk.rest_stands,
        reference_frame: g.from_frame,
        reference: g.rest.clone(),
        ignored: trunk.ignored,
        notes,
    })
}

/// A pick of `j` for canonical joint `c`, by its name or by structure.
fn set_pick(picks: &mut [Pick], c: Canonical, j: usize, named: bool) {
    picks[c.index()] = Pick {
        joint: Some(j),
        source: if named {
            Provenance::Names
        } else {
            Provenance::Structure
        },
        confidence: if named { 0.95 } else { 0.8 },
        derive: None,
    };
}

/// Canonical joint `c` derived by the rule `d`.
fn derive_pick(picks: &mut [Pick], c: Canonical, d: Derive) {
    picks[c.index()] = Pick {
        joint: None,
        source: Provenance::Derived,
        confidence: 0.5,
        derive: Some(d),
    };
}

/// The trunk found by step 3: the arms and the neck off the chest, checked.
struct Trunk {
    /// Legs, arms and neck off one joint (pelvis and chest one node).
    hub: bool,
    /// Where the two arm chains start.
    arms: [usize; 2],
    /// Where the neck chain starts.
    neck_start: usize,
    /// The legs point away from the chest in the rest pose.
    rest_stands: bool,
    /// Chains off the chest that are neither arms nor the neck.
    ignored: Vec<String>,
}

/// A chain's reach: its first bone's length and the reach beyond it.
fn chain_reach(g: &Geo, j: usize) -> f64 {
    g.len[j] + g.reach[j]
}

/// The longer of two lengths over the shorter.
fn length_ratio(a: f64, b: f64) -> f64 {
    a.max(b) / a.min(b).max(1e-300)
}

/// Step 3's checks of a candidate trunk: legs and arms of like lengths,
/// the arms and the neck among the chest's chains, and the legs pointing
/// away from the chest (in the rest pose or the median sampled frame).
fn trunk(
    g: &Geo,
    tokens: &[Vec<String>],
    pelvis: usize,
    chest: usize,
    legs: [usize; 2],
) -> Result<Trunk, NotHumanoid> {
    let name = |j: usize| g.names[j].clone();
    // Leg/arm symmetry and the legs pointing away from the chest.
    let reach = |j: usize| chain_reach(g, j);
    if length_ratio(reach(legs[0]), reach(legs[1])) > 1.6 {
        return Err(NotHumanoid(format!(
            "the two chains below '{}' differ in length ({:.3} vs {:.3})",
            name(pelvis),
            reach(legs[0]),
            reach(legs[1])
        )));
    }
    // Legs, arms and neck off one joint: the chest's branches are the
    // others, and the trunk's up runs to the neck.
    let hub = g.rep[chest] == g.rep[pelvis];
    // Chains off the chest that are neither arms nor the neck (wings, a
    // cape, a holster: named in the report).
    let mut ignored: Vec<String> = Vec::new();
    let (arms, neck_start) = arms_and_neck(g, tokens, pelvis, chest, legs, hub, &mut ignored)?;
    if length_ratio(reach(arms[0]), reach(arms[1])) > 1.6 {
        return Err(NotHumanoid(format!(
            "the two chains off '{}' differ in length",
            name(chest)
        )));
    }
    let rest_stands = legs_stand(g, pelvis, chest, legs, hub, neck_start)?;
    let Some(neck_start) = neck_start else {
        return Err(NotHumanoid(format!("no neck above '{}'", name(chest))));
    };
    Ok(Trunk {
        hub,
        arms,
        neck_start,
        rest_stands,
        ignored,
    })
}

/// Step 3's arms and neck among the chest's chains (the legs left out
/// when pelvis and chest are one node, `hub`); chains that are neither
/// are pushed to `ignored` by name.
fn arms_and_neck(
    g: &Geo,
    tokens: &[Vec<String>],
    pelvis: usize,
    chest: usize,
    legs: [usize; 2],
    hub: bool,
    ignored: &mut Vec<String>,
) -> Result<([usize; 2], Option<usize>), NotHumanoid> {
    let name = |j: usize| g.names[j].clone();
    let cb: Vec<usize> = g
        .branches(chest)
        .into_iter()
        .filter(|c| !hub || !legs.contains(c))
        .collect();
    // Lone joints off the chest (a mesh attachment, a breast leaf) are no
    // arms; the neck may be one (OpenNI's `Head` on `Neck`).
    let cb = g.chains_of(cb, 2);
    Ok(match cb.len() {
        2 | 3 => {
            // The neck continues the spine: the child most aligned with pelvis→chest.
            let up = (g.rest[chest] - g.rest[pelvis]).normalize_or_zero();
            let far = |c: usize| {
                let path = g.path(c);
                let end = *path.last().unwrap_or(&c);
                (g.tail_rest[end].unwrap_or(g.rest[end]) - g.rest[chest]).normalize_or_zero()
            };
            if cb.len() == 3 {
                neck_among_three(g, tokens, &cb, up, far)
            } else {
                neck_beside_two(g, tokens, chest, &cb, up, far)
            }
        }
        k if k >= 4 => match arms_among(g, tokens, pelvis, chest, &cb, legs) {
            Some((arms, neck, rest)) => {
                ignored.extend(rest.iter().map(|&c| name(c)));
                (arms, Some(neck))
            }
            None => {
                return Err(NotHumanoid(format!(
                    "{k} limbs branch off '{}' and no two of them mirror each other as arms",
                    name(chest)
                )));
            }
        },
        k => {
            return Err(NotHumanoid(format!(
                "{k} limbs branch off '{}' (two arms expected)",
                name(chest)
            )));
        }
    })
}

/// Three chains off the chest, `cb`: the neck is the branch whose path
/// names a neck or head; else the odd one out of the three (the arms are
/// the most alike pair in reach), ties broken by pointing up (`far`: a
/// chain's direction from the chest, `up` the trunk's). The other two are
/// the arms.
fn neck_among_three(
    g: &Geo,
    tokens: &[Vec<String>],
    cb: &[usize],
    up: DVec3,
    far: impl Fn(usize) -> DVec3,
) -> ([usize; 2], Option<usize>) {
    let reach = |j: usize| chain_reach(g, j);
    let named = (0..3).find(|&k| {
        g.path(cb[k])
            .iter()
            .any(|&j| matches!(role_of(tokens, j), Some(Role::Neck) | Some(Role::Head)))
    });
    let odd = |k: usize| {
        let (a, b) = ((k + 1) % 3, (k + 2) % 3);
        -length_ratio(reach(cb[a]), reach(cb[b])) + 0.05 * far(cb[k]).dot(up)
    };
    let k = named.unwrap_or_else(|| {
        (0..3)
            .max_by(|&a, &b| odd(a).total_cmp(&odd(b)))
            .unwrap_or(0)
    });
    let arms: Vec<usize> = (0..3).filter(|&i| i != k).map(|i| cb[i]).collect();
    ([arms[0], arms[1]], Some(cb[k]))
}

/// Two chains off the chest, `cb`, the arms: the neck is among the chest's
/// other children (no collar), a chain before a lone joint beside it, then
/// the most upward (`far`, `up` as in [`neck_among_three`]).
fn neck_beside_two(
    g: &Geo,
    tokens: &[Vec<String>],
    chest: usize,
    cb: &[usize],
    up: DVec3,
    far: impl Fn(usize) -> DVec3,
) -> ([usize; 2], Option<usize>) {
    let others: Vec<usize> = g
        .node_children(chest)
        .into_iter()
        .filter(|c| !cb.contains(c) && role_of(tokens, *c) != Some(Role::Collar))
        .collect();
    // A chain before a lone joint beside it, then the most
    // upward.
    let neck = others.into_iter().max_by(|&a, &b| {
        (!g.lone(a))
            .cmp(&!g.lone(b))
            .then(far(a).dot(up).total_cmp(&far(b).dot(up)))
    });
    ([cb[0], cb[1]], neck)
}

/// Step 3's last check: the legs point away from the chest in the rest
/// pose or in the median sampled frame (not merely in one: a sitting
/// quadruped's hind legs do). Whether the rest pose stands.
fn legs_stand(
    g: &Geo,
    pelvis: usize,
    chest: usize,
    legs: [usize; 2],
    hub: bool,
    neck_start: Option<usize>,
) -> Result<bool, NotHumanoid> {
    let name = |j: usize| g.names[j].clone();
    let cosines: Vec<f64> = g
        .poses
        .iter()
        .map(|(p, _)| {
            let top = match neck_start {
                Some(n) if hub => p[n],
                _ => p[chest],
            };
            let up = (top - p[pelvis]).normalize_or_zero();
            let ends: Vec<DVec3> = legs
                .iter()
                .map(|&l| {
                    let path = g.path(l);
                    let end = *path.last().unwrap_or(&l);
                    p[end] - p[pelvis]
                })
                .collect();
            legs_from_trunk(&ends, up)
        })
        .collect();
    let mut frames: Vec<f64> = cosines.iter().skip(1).copied().collect();
    frames.sort_by(f64::total_cmp);
    let median = frames.get(frames.len() / 2).copied().unwrap_or(f64::MAX);
    // A frame standing in for the rest counts as one frame among the others.
    let first = cosines.first().copied().unwrap_or(f64::MAX);
    let rest_stands = g.from_frame.is_none() && first <= STANDING;
    let best_cos = if g.from_frame.is_some() {
        median
    } else {
        first.min(median)
    };
    if best_cos > STANDING {
        return Err(NotHumanoid(format!(
            "the chains below '{}' do not point away from the spine (cosine {best_cos:.2} in the {}median frame): {HORIZONTAL}",
            name(pelvis),
            if g.from_frame.is_some() {
                ""
            } else {
                "rest pose or the "
            }
        )));
    }
    Ok(rest_stands)
}

/// Step 4 on the trunk: the pelvis, spine and chest picks. Returns the
/// neck when the chest's joint is named as one (then the chest is the
/// spine chain's last joint), and whether the chest is left to derive.
fn spine_and_chest(
    g: &Geo,
    tokens: &[Vec<String>],
    picks: &mut [Pick],
    pelvis: usize,
    chest: usize,
    legs: [usize; 2],
    hub: bool,
) -> (Option<usize>, bool) {
    // Pelvis: a pelvis-named joint of the node, else of the node the legs
    // hang from, else the node.
    let node: Vec<usize> = (0..g.clip.joint_count())
        .filter(|&j| g.rep[j] == pelvis)
        .collect();
    let pj = node
        .iter()
        .copied()
        .find(|&j| {
            role_of(tokens, j) == Some(Role::Pelvis) && tokens[j].iter().any(|t| t == "pelvis")
        })
        .or_else(|| {
            node.iter()
                .copied()
                .find(|&j| role_of(tokens, j) == Some(Role::Pelvis))
        })
        .or_else(|| {
            // A pelvis-named joint where the legs hang, a short bone below
            // the junction (H-Anim's `sacroiliac` under `humanoid_root`).
            let carrier = g.parent[legs[0]]
                .map(|p| g.rep[p])
                .filter(|&p| p != pelvis)?;
            (0..g.clip.joint_count())
                .find(|&j| g.rep[j] == carrier && role_of(tokens, j) == Some(Role::Pelvis))
        });
    set_pick(picks, Canonical::Pelvis, pj.unwrap_or(pelvis), pj.is_some());

    // Spine chain between the pelvis and the chest.
    let mut between = Vec::new();
    let mut j = chest;
    while let Some(p) = g.parent[j].filter(|_| !hub) {
        if g.rep[p] == pelvis {
            break;
        }
        between.push(p);
        j = p;
    }
    between.reverse();
    let chest_named_neck = role_of(tokens, chest) == Some(Role::Neck);
    let spine_c: Vec<usize> = g
        .candidates(tokens, g.rest[pelvis], &between, false)
        .into_iter()
        .filter(|&j| g.rest[j].distance(g.rest[chest]) >= g.eps)
        .collect();
    let best_spine = spine_c
        .iter()
        .copied()
        .filter_map(|j| match role_of(tokens, j) {
            Some(Role::Spine(s)) => Some((s, j)),
            _ => None,
        })
        .max_by_key(|&(s, j)| (s, std::cmp::Reverse(j)));
    let (chest_j, neck_from_chest) = if chest_named_neck {
        (
            spine_c
                .last()
                .copied()
                .filter(|&l| Some(l) != spine_c.first().copied()),
            Some(chest),
        )
    } else {
        (Some(chest), None)
    };
    let spine_j = match best_spine {
        Some((_, j)) => {
            set_pick(picks, Canonical::Spine, j, true);
            j
        }
        None => {
            // The joint nearest 40% of the way (arc length) from the pelvis
            // to the chest: the canonical spine sits at the lumbar curve
            // (the procedural skeleton's spine is at 0.43 of pelvis→chest;
            // rigs with two lumbar joints put the name-chosen one at
            // 0.28-0.47: Mixamo Spine 0.28 vs Spine1 0.62, CC Spine01 0.47
            // vs Waist 0.29, SMPL Spine1 0.37 vs Spine2 0.81).
            let arc_to = |j: usize| {
                let (mut a, mut k) = (0.0, j);
                while g.rep[k] != pelvis {
                    a += g.len[k];
                    match g.parent[k] {
                        Some(p) => k = p,
                        None => break,
                    }
                }
                a
            };
            let total = arc_to(chest_j.unwrap_or(chest)).max(1e-300);
            let pick = spine_c
                .iter()
                .copied()
                .filter(|&j| Some(j) != chest_j)
                .min_by(|&a, &b| {
                    let f = |j: usize| (arc_to(j) / total - 0.4).abs();
                    f(a).total_cmp(&f(b))
                });
            match pick {
                Some(j) => {
                    set_pick(picks, Canonical::Spine, j, false);
                    j
                }
                None => {
                    set_pick(picks, Canonical::Spine, chest, false);
                    chest
                }
            }
        }
    };
    let chest_derived = match chest_j {
        Some(c) if c != spine_j => {
            set_pick(
                picks,
                Canonical::Chest,
                c,
                role_of(tokens, c) == Some(Role::Chest),
            );
            false
        }
        _ => true,
    };
    (neck_from_chest, chest_derived)
}

/// Step 4 above the chest: the neck and head picks (a hub body's spine
/// and chest, and a chest left to derive, on the pelvis → neck line).
/// Returns the neck's joint.
fn neck_and_head(
    g: &Geo,
    tokens: &[Vec<String>],
    picks: &mut [Pick],
    chest: usize,
    trunk: &Trunk,
    neck_from_chest: Option<usize>,
    chest_derived: bool,
) -> Result<usize, NotHumanoid> {
    let (hub, neck_start) = (trunk.hub, trunk.neck_start);
    // Neck and head.
    let neck_path = g.path(neck_start);
    let neck_c = neck_candidates(g, tokens, chest, &neck_path);
    let neck_base = neck_base(g, tokens, chest, neck_start);
    let (neck_j, head_c) = neck_joint(g, tokens, chest, &neck_c, neck_base, neck_from_chest)?;
    set_pick(
        picks,
        Canonical::Neck,
        neck_j,
        role_of(tokens, neck_j) == Some(Role::Neck),
    );
    spine_and_chest_on_neck_line(picks, hub, chest_derived);
    pick_head(g, tokens, picks, &head_c, &neck_path, neck_j);
    Ok(neck_j)
}

/// The neck chain's candidate joints above the chest (`neck_path` the
/// chain from the neck's start).
fn neck_candidates(
    g: &Geo,
    tokens: &[Vec<String>],
    chest: usize,
    neck_path: &[usize],
) -> Vec<usize> {
    let neck_c = g.candidates(tokens, g.rest[chest], neck_path, false);
    // A neck made only of helper-named bones (CC's NeckTwist01/02 under
    // Head): the first of them off the chest is the neck when the chain
    // has no other joint for it (helpers are ignored only as leaves or
    // pass-throughs).
    match neck_c.first() {
        Some(&first) if neck_c.len() < 2 || role_of(tokens, first) == Some(Role::Head) => {
            let mut out = neck_c.clone();
            if let Some(&h) = neck_path
                .iter()
                .take_while(|&&j| j != first)
                .find(|&&j| g.helper[j] && g.rest[j].distance(g.rest[chest]) >= g.eps)
            {
                out.insert(0, h);
            }
            out
        }
        _ => neck_c,
    }
}

/// The base of the neck chain starting at `neck_start`, when a joint of
/// the chest's node carries it (see the comment within).
fn neck_base(g: &Geo, tokens: &[Vec<String>], chest: usize, neck_start: usize) -> Option<usize> {
    // The base of the neck: a joint of the chest's zero-length node, not
    // the chest itself, that carries the neck chain and nothing else (no
    // helper, not named for another role). Its rotation turns the whole
    // neck bone, as an ASF `lowerneck`'s does: a conversion that drops the
    // thorax's length hangs that joint on the chest with a zero offset
    // (CMU cgspeed `Neck` under `Spine1`, the 3dsMax-friendly release's
    // `lowerneck` under `Chest2`), and the first joint above it is then the
    // top of the lower neck, not its base.
    g.parent[neck_start].filter(|&p| {
        p != chest
            && g.rep[p] == g.rep[chest]
            && !g.helper[p]
            // A spine-numbered name goes on up the spine (Rigify's neck is
            // `DEF-spine.004`).
            && matches!(
                role_of(tokens, p),
                None | Some(Role::Neck) | Some(Role::Chest) | Some(Role::Spine(_))
            )
            && g.children[p]
                .iter()
                .all(|&c| c == neck_start || !g.useful[c])
    })
}

/// The neck's joint and the candidates for the head above it: the
/// chest's named neck when there is one (`neck_from_chest`), else the
/// first neck-named candidate, or the neck's base, or the first
/// candidate.
fn neck_joint(
    g: &Geo,
    tokens: &[Vec<String>],
    chest: usize,
    neck_c: &[usize],
    neck_base: Option<usize>,
    neck_from_chest: Option<usize>,
) -> Result<(usize, Vec<usize>), NotHumanoid> {
    let name = |j: usize| g.names[j].clone();
    let (neck_j, head_c): (usize, Vec<usize>) = match neck_from_chest {
        Some(nj) => (nj, neck_c.to_vec()),
        None => {
            let k = first_role(tokens, neck_c, |r| r == Role::Neck).unwrap_or(0);
            let Some(&nj) = neck_c.get(k) else {
                return Err(NotHumanoid(format!("no neck above '{}'", name(chest))));
            };
            // The head is looked for above the first neck joint either way;
            // the base is the neck unless names put the neck further up.
            let nj = match neck_base {
                Some(b) if k == 0 => b,
                _ => nj,
            };
            (nj, neck_c[k + 1..].to_vec())
        }
    };
    Ok((neck_j, head_c))
}

/// A hub body's spine and chest on the pelvis → neck line, or a chest
/// left to derive between the spine and the neck.
fn spine_and_chest_on_neck_line(picks: &mut [Pick], hub: bool, chest_derived: bool) {
    if hub {
        // No spine joint: spine and chest on the pelvis→neck line where the
        // procedural skeleton has them (0.19 and 0.6 of the way).
        derive_pick(
            picks,
            Canonical::Spine,
            Derive::Between {
                from: Canonical::Pelvis,
                to: Canonical::Neck,
                t: 0.2,
            },
        );
        derive_pick(
            picks,
            Canonical::Chest,
            Derive::Between {
                from: Canonical::Pelvis,
                to: Canonical::Neck,
                t: 0.6,
            },
        );
    } else if chest_derived {
        derive_pick(
            picks,
            Canonical::Chest,
            Derive::Between {
                from: Canonical::Spine,
                to: Canonical::Neck,
                t: 0.5,
            },
        );
    }
}

/// The head's pick among `head_c` (see the comment within), else derived
/// from the neck chain's end (`neck_path`, `neck_j` the neck's joint).
fn pick_head(
    g: &Geo,
    tokens: &[Vec<String>],
    picks: &mut [Pick],
    head_c: &[usize],
    neck_path: &[usize],
    neck_j: usize,
) {
    let name = |j: usize| g.names[j].clone();
    // The head: by name, else the top of the neck: the first joint whose
    // node branches (into jaw, eyes, face bones), else the chain's last
    // joint (its End Site the crown), skipping a final leaf marker with no
    // End Site (`HeadTop_End` as a joint).
    let head_geo = || -> Option<usize> {
        if let Some(k) = head_c
            .iter()
            .position(|&j| g.node_children(g.rep[j]).len() >= 2)
        {
            return Some(k);
        }
        let last = head_c.len().checked_sub(1)?;
        let j = head_c[last];
        let marker = last >= 1
            && g.children[j].is_empty()
            && g.clip.joints[j].tail.is_none_or(|t| t.length() < g.eps);
        Some(if marker { last - 1 } else { last })
    };
    match first_role(tokens, head_c, |r| r == Role::Head).or_else(head_geo) {
        Some(k) => {
            let h = head_c[k];
            set_pick(
                picks,
                Canonical::Head,
                h,
                role_of(tokens, h) == Some(Role::Head),
            );
        }
        None => {
            // The End Site of the neck chain's last joint (the neck itself
            // or a helper after it), else a third of a neck above the neck.
            let mut last = *neck_path.last().unwrap_or(&neck_j);
            while let [only] = g.children[last].as_slice() {
                last = *only;
            }
            let tail = g.clip.joints[last].tail.filter(|t| t.length() > g.eps);
            let d = match tail {
                Some(_) => Derive::EndSite { joint: name(last) },
                None => Derive::Between {
                    from: Canonical::Chest,
                    to: Canonical::Neck,
                    t: 4.0 / 3.0,
                },
            };
            derive_pick(picks, Canonical::Head, d);
        }
    }
}

/// Step 5's answer: the limbs sorted into left and right, and how.
struct Sides {
    left_leg: Vec<usize>,
    right_leg: Vec<usize>,
    left_arm: Vec<usize>,
    right_arm: Vec<usize>,
    forward_from: &'static str,
    side_confidence: f64,
    names_mirrored: bool,
    sides_from_names: bool,
}

/// Step 5: left and right from the body's own frame (up = pelvis → neck
/// `neck_j`, forward from the feet, else the knees, else the travel),
/// else from the sides the names state; picks the limbs' joints
/// (`limbs`: two legs, then two arms) on their sides.
fn sides(
    g: &Geo,
    tokens: &[Vec<String>],
    picks: &mut [Pick],
    pelvis: usize,
    neck_j: usize,
    limbs: [Limb; 4],
) -> Sides {
    // Left/right from the body frame.
    let pj = picks[Canonical::Pelvis.index()].joint.unwrap_or(pelvis);
    let [votes, leg_s, arm_s] = side_votes(g, pj, neck_j, &limbs);
    let [l0, l1, a0, a1] = limbs;
    let m = (0..3).find(|&m| votes[m] > 0.0 && leg_s[m].abs() > 0.1 * votes[m]);
    let forward_from = match m {
        Some(0) => "feet",
        Some(1) => "knees",
        Some(2) => "travel",
        _ => "none",
    };
    // No forward direction (feet straight down or no toes, straight
    // knees, no travel: the Biovision sample, mocapdata.com, a one-frame
    // T-pose): the names' sides decide, each limb pair by the sides its
    // joints' names state.
    let named_sign = |a: &Limb, b: &Limb| -> Option<f64> {
        let s = |l: &Limb| -> i32 {
            l.picks
                .iter()
                .flatten()
                .map(|&(j, _)| match tokens.get(j).and_then(|t| side(t)) {
                    Some(Side::Left) => 1,
                    Some(Side::Right) => -1,
                    None => 0,
                })
                .sum()
        };
        match s(a).cmp(&s(b)) {
            std::cmp::Ordering::Less => Some(-1.0),
            std::cmp::Ordering::Greater => Some(1.0),
            std::cmp::Ordering::Equal => None,
        }
    };
    // Names that state no side (`joint_12`) leave the sides undecided
    // (confidence 0: a skin asks for a rig map).
    let (leg_named, arm_named) = (named_sign(&l0, &l1), named_sign(&a0, &a1));
    let sides_from_names = m.is_none() && (leg_named.is_some() || arm_named.is_some());
    let (leg_sign, arm_sign, conf) = match m {
        Some(m) => (
            leg_s[m],
            arm_s[m],
            (leg_s[m].abs().min(arm_s[m].abs()) / votes[m]).clamp(0.0, 1.0),
        ),
        None => (leg_named.unwrap_or(1.0), arm_named.unwrap_or(1.0), 0.0),
    };
    let (ll, rl) = if leg_sign >= 0.0 { (l0, l1) } else { (l1, l0) };
    let (la, ra) = if arm_sign >= 0.0 { (a0, a1) } else { (a1, a0) };
    let sc = if sides_from_names {
        0.9
    } else {
        0.5 + 0.5 * conf
    };
    let mut named_sides = [0i32; 2];
    let lim =
        |picks: &mut [Pick], l: &Limb, cs: [Canonical; 4], s: Side, named_sides: &mut [i32; 2]| {
            for (k, c) in cs.into_iter().enumerate() {
                match l.picks[k] {
                    Some((j, named)) => {
                        set_pick(picks, c, j, named);
                        picks[c.index()].confidence *= sc;
                        match tokens.get(j).and_then(|t| side(t)) {
                            Some(ns) if ns == s => named_sides[0] += 1,
                            Some(_) => named_sides[1] += 1,
                            None => {}
                        }
                    }
                    None => {
                        if let Some(d) = &l.derive_end {
                            derive_pick(picks, c, d.clone());
                            picks[c.index()].confidence *= sc;
                        }
                    }
                }
            }
        };
    use Canonical as C;
    lim(
        picks,
        &ll,
        [C::LHip, C::LKnee, C::LAnkle, C::LToe],
        Side::Left,
        &mut named_sides,
    );
    lim(
        picks,
        &rl,
        [C::RHip, C::RKnee, C::RAnkle, C::RToe],
        Side::Right,
        &mut named_sides,
    );
    lim(
        picks,
        &la,
        [C::LShoulder, C::LElbow, C::LWrist, C::LToe],
        Side::Left,
        &mut named_sides,
    );
    lim(
        picks,
        &ra,
        [C::RShoulder, C::RElbow, C::RWrist, C::RToe],
        Side::Right,
        &mut named_sides,
    );
    // Arms fill 3 joints; the 4th slot above is a placeholder never set for arms.
    // Toe derivation needs the side's canonical ankle.
    for (c, a) in [(C::LToe, C::LAnkle), (C::RToe, C::RAnkle)] {
        if let Some(Derive::ToeFromAnkle { ankle, .. }) = &mut picks[c.index()].derive {
            *ankle = a;
        }
    }
    Sides {
        left_leg: ll.subtree,
        right_leg: rl.subtree,
        left_arm: la.subtree,
        right_arm: ra.subtree,
        forward_from,
        side_confidence: conf,
        names_mirrored: named_sides[1] > named_sides[0],
        sides_from_names,
    }
}

/// Step 5's votes: per way of telling forward (the feet, the knees, the
/// travel), summed over the sampled poses, its weight and how far the
/// first leg and the first arm (of `limbs`: two legs, then two arms) lie
/// to the body's left of the second (up = pelvis `pj` → neck `neck_j`).
fn side_votes(g: &Geo, pj: usize, neck_j: usize, limbs: &[Limb; 4]) -> [[f64; 3]; 3] {
    let [l0, l1, a0, a1] = limbs;
    let toe_pt = |l: &Limb, p: &[DVec3], r: &[DQuat]| -> Option<DVec3> {
        match (l.picks[3], &l.derive_end) {
            (Some((t, _)), _) => Some(p[t]),
            (None, Some(Derive::EndSite { .. })) => {
                let a = l.picks[2]?.0;
                Some(p[a] + r[a] * g.clip.joints[a].tail?)
            }
            _ => None,
        }
    };
    let pt = |l: &Limb, k: usize, p: &[DVec3]| l.picks[k].map(|(j, _)| p[j]).unwrap_or(DVec3::ZERO);
    // Hips and shoulders: rigidly lateral to the trunk in every pose.
    let mean3 = |l: &Limb, p: &[DVec3]| pt(l, 0, p);
    let travel = {
        let f = g.clip.frame_count();
        if f >= 2 {
            let (mut a, mut b) = (
                vec![DVec3::ZERO; g.clip.joint_count()],
                vec![DQuat::IDENTITY; g.clip.joint_count()],
            );
            g.clip.world_into(0, &mut a, &mut b);
            let first = a[pj];
            g.clip.world_into(f - 1, &mut a, &mut b);
            a[pj] - first
        } else {
            DVec3::ZERO
        }
    };
    // A foot that lies along its shin (an ankle End Site straight down:
    // the Biovision sample, mocapdata.com) gives no forward: its part
    // across the shin is the ankle's flexion, whose sign turns it backward
    // when the toes lift (a walk on the Biovision skeleton came out
    // mirrored, 'forward from the feet, confidence 0.99'). Along: within
    // 15° in the median sampled pose (CesiumMan's toe, 3 cm ahead of and
    // 6 cm below its ankle, is 27° off its shin and counts; Bandai's rest
    // lays every bone along +X, so the rest alone cannot say).
    let foot_across = |l: &Limb| -> bool {
        let mut f: Vec<f64> = g
            .poses
            .iter()
            .filter_map(|(p, r)| {
                let t = toe_pt(l, p, r)?;
                let (k, a) = (pt(l, 1, p), pt(l, 2, p));
                let shin = (a - k).normalize_or_zero();
                let v = t - a;
                let len = v.length();
                (len > 0.0).then(|| (v - shin * v.dot(shin)).length() / len)
            })
            .collect();
        f.sort_by(f64::total_cmp);
        f.get(f.len() / 2)
            .is_some_and(|&m| m > 15f64.to_radians().sin())
    };
    let feet_point = foot_across(l0) && foot_across(l1);
    let mut votes = [0.0f64; 3]; // feet, knees, travel
    let mut leg_s = [0.0f64; 3];
    let mut arm_s = [0.0f64; 3];
    // A frame standing in for the rest is also among the sampled frames:
    // it votes once.
    let skip = usize::from(g.from_frame.is_some());
    for (p, r) in g.poses.iter().skip(skip) {
        let up = (p[neck_j] - p[pj]).normalize_or_zero();
        let flat = |v: DVec3| v - up * v.dot(up);
        let mut fw = [DVec3::ZERO; 3];
        if feet_point && let (Some(t0), Some(t1)) = (toe_pt(l0, p, r), toe_pt(l1, p, r)) {
            // The sole: ankle→toe across the shin (its part along the
            // knee→ankle axis removed). A foot stands at right angles to
            // its shin, so this points forward however the leg swings and
            // however low the rig puts its toe joint (CesiumMan's is 6 cm
            // below the ankle and 3 cm ahead: its plain ankle→toe
            // direction turns backward whenever the leg swings back).
            let sole = |l: &Limb, t: DVec3| {
                let (k, a) = (pt(l, 1, p), pt(l, 2, p));
                let shin = (a - k).normalize_or_zero();
                let v = t - a;
                v - shin * v.dot(shin)
            };
            let (a0, a1) = (pt(l0, 2, p), pt(l1, 2, p));
            let len = t0.distance(a0) + t1.distance(a1);
            if len > 0.0 {
                fw[0] = (flat(sole(l0, t0)) + flat(sole(l1, t1))) / len;
            }
        }
        for l in [l0, l1] {
            let (h, k, a) = (pt(l, 0, p), pt(l, 1, p), pt(l, 2, p));
            let axis = (a - h).normalize_or_zero();
            let off = (k - h) - axis * (k - h).dot(axis);
            let len = (a - h).length();
            if len > 0.0 && off.length() > 0.02 * len {
                fw[1] += flat(off) / len;
            }
        }
        let tl = travel.length();
        if tl > 0.0 {
            fw[2] = flat(travel) / tl;
        }
        for m in 0..3 {
            let w = fw[m].length();
            if w < 1e-9 {
                continue;
            }
            let left = up.cross(fw[m] / w);
            votes[m] += w;
            leg_s[m] += w * (mean3(l0, p) - mean3(l1, p)).normalize_or_zero().dot(left);
            arm_s[m] += w * (mean3(a0, p) - mean3(a1, p)).normalize_or_zero().dot(left);
        }
    }
    [votes, leg_s, arm_s]
}

/// The neck and the two arms among four or more significant chains off
/// the chest `chest` (wings, a cape, extra limb-like chains beside the
/// arms, none of them named as helpers), and the chains left over. The
/// neck is the chain whose path names a neck or head, else the one whose
/// far end points most along pelvis→chest. The arms are the pair of the
/// others that
/// - lie on opposite sides of the trunk's axis (their far ends' offsets
///   across it over 120° apart: a cape or a tail on the mid-plane pairs
///   with nothing),
/// - mirror each other (starts and far ends at the same heights along the
///   axis and the same distances from it, as [`Geo::legs_among`] pairs
///   legs), and
/// - are as long as arms are beside these legs: the chain's reach (collar
///   to fingertip end) about [`ARM_OF_LEG`] of the legs' (hip to toe tip),
///
/// scored by the mirror mismatch over the body's size plus the log ratio
/// of the pair's reach to that length, a pair whose both chains name an
/// arm joint (collar, shoulder, upper arm, elbow, wrist, hand) ahead by
/// one. `None` when no pair lies on opposite sides.
fn arms_among(
    g: &Geo,
    tokens: &[Vec<String>],
    pelvis: usize,
    chest: usize,
    cb: &[usize],
    legs: [usize; 2],
) -> Option<([usize; 2], usize, Vec<usize>)> {
    let origin = g.rest[chest];
    let up = (origin - g.rest[pelvis]).normalize_or_zero();
    if up == DVec3::ZERO {
        return None;
    }
    let far_end = |c: usize| {
        let path = g.path(c);
        let e = *path.last().unwrap_or(&c);
        g.tail_rest[e].unwrap_or(g.rest[e])
    };
    let named = |c: usize, f: &dyn Fn(Role) -> bool| {
        g.path(c).iter().any(|&j| role_of(tokens, j).is_some_and(f))
    };
    let neck = cb
        .iter()
        .copied()
        .find(|&c| named(c, &|r| matches!(r, Role::Neck | Role::Head)))
        .or_else(|| {
            cb.iter().copied().max_by(|&a, &b| {
                let d = |c: usize| (far_end(c) - origin).normalize_or_zero().dot(up);
                d(a).total_cmp(&d(b))
            })
        })?;
    let reach = |j: usize| g.len[j] + g.reach[j];
    let leg_reach = 0.5 * (reach(legs[0]) + reach(legs[1]));
    let size = g.thr / 0.12;
    // Height along the axis and the offset across it.
    let split = |q: DVec3| {
        let d = q - origin;
        let h = d.dot(up);
        (h, d - h * up)
    };
    let armish = |c: usize| {
        named(c, &|r| {
            matches!(
                r,
                Role::Collar
                    | Role::ShoulderWord
                    | Role::UpperArm
                    | Role::Elbow
                    | Role::Wrist
                    | Role::Hand
            )
        })
    };
    let others: Vec<usize> = cb.iter().copied().filter(|&c| c != neck).collect();
    let mut best: Option<(f64, [usize; 2])> = None;
    for (i, &a) in others.iter().enumerate() {
        for &b in &others[i + 1..] {
            let (ea, eb) = (split(far_end(a)), split(far_end(b)));
            let (sa, sb) = (split(g.rest[a]), split(g.rest[b]));
            if ea.1.dot(eb.1) > -0.5 * ea.1.length() * eb.1.length() {
                continue; // not on opposite sides (over 120 degrees apart)
            }
            let mismatch = (ea.0 - eb.0).abs()
                + (ea.1.length() - eb.1.length()).abs()
                + (sa.0 - sb.0).abs()
                + (sa.1.length() - sb.1.length()).abs();
            let length = (0.5 * (reach(a) + reach(b)) / (ARM_OF_LEG * leg_reach))
                .ln()
                .abs();
            let bonus = if armish(a) && armish(b) { 1.0 } else { 0.0 };
            let score = mismatch / size + length - bonus;
            if best.is_none_or(|(s, _)| score < s) {
                best = Some((score, [a, b]));
            }
        }
    }
    let (_, arms) = best?;
    let rest = others.into_iter().filter(|c| !arms.contains(c)).collect();
    Some((arms, neck, rest))
}

/// An arm chain's reach (collar to the fingertip end) over a leg chain's
/// (hip to the toe tip), both from the bone joining them to the trunk:
/// 0.67 on Bandai's rig, 0.65 and 0.61 on CMU 01 and 131 (cgspeed BVH),
/// 0.83 on CC's (its fingers reach further than its hand's end).
pub(crate) const ARM_OF_LEG: f64 = 0.7;

fn leg_chain(
    g: &Geo,
    tokens: &[Vec<String>],
    pelvis: usize,
    start: usize,
) -> Result<Limb, NotHumanoid> {
    let path = g.path(start);
    let c = g.candidates(tokens, g.rest[pelvis], &path, false);
    let short = || {
        NotHumanoid(format!(
            "the leg chain from '{}' has fewer than three joints",
            g.names[start]
        ))
    };
    if c.len() < 3 {
        return two_joint_leg(g, tokens, start, &c).ok_or_else(short);
    }
    // The hip: a thigh-named joint, else the first joint, unless a short
    // bone (under a quarter of the significance threshold, 3% of the
    // body's size) joins it to the next one with three more joints after:
    // a buttock offset bone above the hip joint (CMU Daz-friendly
    // `lButtock` → `lThigh`, 2.8 cm on a 1.75 m body).
    let hip_k = first_role(tokens, &c, |r| r == Role::Thigh).unwrap_or_else(|| {
        usize::from(c.len() >= 4 && g.rest[c[0]].distance(g.rest[c[1]]) < 0.25 * g.thr)
    });
    let after = &c[hip_k + 1..];
    let ankle_named = first_role(tokens, after, |r| r == Role::Ankle);
    let foot_named = first_role(tokens, after, |r| r == Role::Foot);
    let knee_named = first_role(tokens, after, |r| r == Role::Knee);
    // Knee and ankle: by name, else the joints whose segment lengths (arc
    // length along the chain, rest offsets: pose-independent) best match
    // the body's proportions: thigh / shin ≈ 1 and shin / foot (ankle to
    // the chain's far end) ≈ 2.5 (Drillis & Contini 1966: thigh 0.245 H,
    // shin 0.246 H; ankle to toe tip 0.10-0.13 H, 2.2-3.2 on CMU, CC and
    // Mixamo rigs), the foot term half-weighted.
    let (arc, far) = g.arcs(&path);
    let ac: Vec<f64> = after
        .iter()
        .map(|&j| path.iter().position(|&p| p == j).map_or(0.0, |k| arc[k]))
        .collect();
    let a_hip = path
        .iter()
        .position(|&p| p == c[hip_k])
        .map_or(0.0, |k| arc[k]);
    let ln_off = |x: f64, want: f64| {
        if x.is_finite() && x > 0.0 {
            (x / want).ln().abs()
        } else {
            f64::INFINITY
        }
    };
    let fixed_ankle = match ankle_named.or(foot_named) {
        Some(k) if k >= 1 => Some(k),
        _ => None,
    };
    let mut best: Option<(f64, usize, usize)> = None;
    for k in 0..after.len() {
        if knee_named.is_some_and(|x| x != k) {
            continue;
        }
        for an in k + 1..after.len() {
            if fixed_ankle.is_some_and(|x| x != an) {
                continue;
            }
            let (thigh, shin, foot) = (ac[k] - a_hip, ac[an] - ac[k], far - ac[an]);
            let f = if foot > 0.1 * shin {
                ln_off(shin / foot, 2.5)
            } else {
                0.6
            };
            let sc = ln_off(thigh / shin, 1.0) + 0.5 * f;
            if best.is_none_or(|b| sc < b.0) {
                best = Some((sc, k, an));
            }
        }
    }
    let Some((_, knee_k, ankle_k)) = best else {
        return Err(short());
    };
    let hip = c[hip_k];
    let ankle = after[ankle_k];
    let knee = after[knee_k];
    let toes = &after[ankle_k + 1..];
    let toe_k = if ankle_named.is_some() && foot_named.is_some_and(|f| f > ankle_k) {
        foot_named.map(|f| f - ankle_k - 1)
    } else {
        first_role(tokens, toes, |r| r == Role::Toe).or_else(|| first_bent(g, tokens, ankle, toes))
    };
    let named = |j: usize, r: Role| role_of(tokens, j) == Some(r);
    let toe = toe_k.and_then(|k| toes.get(k).copied());
    let derive_end = if toe.is_none() {
        Some(
            match g.clip.joints[ankle].tail.filter(|t| t.length() > g.eps) {
                Some(_) => Derive::EndSite {
                    joint: g.names[ankle].clone(),
                },
                None => Derive::ToeFromAnkle {
                    ankle: Canonical::LAnkle,
                    fraction: 0.35,
                },
            },
        )
    } else {
        None
    };
    Ok(Limb {
        picks: [
            Some((hip, named(hip, Role::Thigh))),
            Some((knee, named(knee, Role::Knee))),
            Some((ankle, named(ankle, Role::Ankle) || named(ankle, Role::Foot))),
            toe.map(|t| (t, named(t, Role::Toe) || named(t, Role::Foot))),
        ],
        derive_end,
        subtree: g.subtree(start),
        note: None,
    })
}

/// A leg of two joints and an end marker (a game character's or a
/// Blender export's: hip and knee bones, the knee bone's tail written as
/// a leaf joint, `pied gauche` → `pied gauche_end` on ufbx's barbarian,
/// no foot bone): the hip and the knee are the two joints, the ankle is
/// the end marker (the foot has no toes), and the toe is placed by
/// proportion ([`Derive::ToeFromAnkle`], 0.35 of the shin forward of the
/// ankle), with a note. Only when the structure is otherwise clear: the
/// marker is the second joint's one leaf child (the longest when
/// several), further from the pelvis than the knee in the reference
/// pose, and thigh and shin are of like lengths (0.5-2, a human's ≈ 1).
/// `None` otherwise (the leg is refused).
fn two_joint_leg(g: &Geo, tokens: &[Vec<String>], start: usize, c: &[usize]) -> Option<Limb> {
    let [hip, knee] = *c else {
        return None;
    };
    let end = g.children[knee]
        .iter()
        .copied()
        .filter(|&e| g.children[e].is_empty() && g.len[e] > g.eps)
        .max_by(|&a, &b| g.len[a].total_cmp(&g.len[b]))?;
    let (thigh, shin) = (
        g.rest[hip].distance(g.rest[knee]),
        g.rest[knee].distance(g.rest[end]),
    );
    let ratio = thigh / shin;
    if !(ratio.is_finite() && (0.5..=2.0).contains(&ratio))
        || g.rest[end].distance(g.rest[hip]) <= thigh
    {
        return None;
    }
    let named = |j: usize, r: Role| role_of(tokens, j) == Some(r);
    Some(Limb {
        picks: [
            Some((hip, named(hip, Role::Thigh))),
            Some((knee, named(knee, Role::Knee))),
            Some((end, false)),
            None,
        ],
        derive_end: Some(Derive::ToeFromAnkle {
            ankle: Canonical::LAnkle,
            fraction: 0.35,
        }),
        subtree: g.subtree(start),
        note: Some(format!(
            "the leg from '{}' has two joints and an end marker: '{}' is the ankle (thigh / shin {:.2}), the toe placed by proportion",
            g.names[start], g.names[end], ratio
        )),
    })
}

/// The first of `toes` (the joints after the ankle along the leg's main
/// path) that is not a straight pass-through: a joint in line with the one
/// before it and the one after it (within 2°) in every sampled pose, with
/// no body-part name, is skipped (Daz `lMetatarsals` between `lFoot` and
/// `lToe`), unless the joint after it is a bare leaf marker (a `Toe_End`
/// joint with no End Site), which is never the toe.
fn first_bent(g: &Geo, tokens: &[Vec<String>], ankle: usize, toes: &[usize]) -> Option<usize> {
    let marker = |j: usize| {
        g.children[j].is_empty() && g.clip.joints[j].tail.is_none_or(|t| t.length() < g.eps)
    };
    let straight = |a: usize, b: usize, c: usize| {
        g.poses.iter().all(|(p, _)| {
            let u = (p[b] - p[a]).normalize_or_zero();
            let v = (p[c] - p[b]).normalize_or_zero();
            u.dot(v) >= 0.9994
        })
    };
    if toes.is_empty() {
        return None;
    }
    let k = (0..toes.len()).find(|&k| {
        let prev = if k == 0 { ankle } else { toes[k - 1] };
        match toes.get(k + 1) {
            Some(&next) if !marker(next) && role_of(tokens, toes[k]).is_none() => {
                !straight(prev, toes[k], next)
            }
            _ => true,
        }
    });
    Some(k.unwrap_or(0))
}

fn arm_chain(
    g: &Geo,
    tokens: &[Vec<String>],
    hips: [usize; 2],
    chest: usize,
    start: usize,
) -> Result<Limb, NotHumanoid> {
    let path = g.path(start);
    let c = g.candidates(tokens, g.rest[chest], &path, false);
    let short = || {
        NotHumanoid(format!(
            "the arm chain from '{}' has fewer than three joints",
            g.names[start]
        ))
    };
    if c.len() < 3 {
        return Err(short());
    }
    // Shoulder, elbow and wrist: joints named for them fix their slot;
    // the free slots take the joints whose segment lengths (arc length
    // along the chain, rest offsets) best match the body's proportions:
    // upper arm / forearm ≈ 1.27 and forearm / hand (wrist to the chain's
    // far end) ≈ 1.35 (Drillis & Contini 1966: 0.186 H, 0.146 H, 0.108 H).
    let (arc, far) = g.arcs(&path);
    let ac: Vec<f64> = c
        .iter()
        .map(|&j| path.iter().position(|&p| p == j).map_or(0.0, |k| arc[k]))
        .collect();
    let a = |k: usize| ac[k];
    let w_named = first_role(tokens, &c, |r| r == Role::Wrist)
        .or_else(|| first_role(tokens, &c, |r| r == Role::Hand));
    let collar = first_role(tokens, &c, |r| r == Role::Collar).is_some();
    // A collar (clavicle) starts near the body's mid-plane and the shoulder
    // joint well out from it: c[0] is a collar when its median distance
    // from the chest along the hip-to-hip axis is under 0.6 of c[1]'s
    // (collar/shoulder 0.0-0.48 on CMU, CC, Bandai, Mixamo, SMPL and Daz
    // rigs; shoulder/elbow ≥ 0.8 with the arms down). Proportions alone
    // cannot tell: CC's forearm is as long as its upper arm, so collar +
    // upper arm fits 1.27 better than the upper arm alone.
    let lateral = |j: usize| {
        let mut d: Vec<f64> = g
            .poses
            .iter()
            .map(|(p, _)| {
                let lr = (p[hips[0]] - p[hips[1]]).normalize_or_zero();
                (p[j] - p[chest]).dot(lr).abs()
            })
            .collect();
        d.sort_by(f64::total_cmp);
        d.get(d.len() / 2).copied().unwrap_or(0.0)
    };
    let geo_collar = c.len() >= 4 && lateral(c[0]) < 0.6 * lateral(c[1]);
    let named_upper = first_role(tokens, &c, |r| {
        r == Role::UpperArm || (collar && r == Role::ShoulderWord)
    })
    .filter(|&s| w_named.is_none_or(|w| s < w));
    // The collar by geometry leaves room for an elbow before the named
    // wrist and gives way to a named elbow right after the first joint:
    // with the arms held out (a T-pose as the only frame) the elbow sits
    // as far out from the chest as the upper arm is long, and a shoulder
    // read as the collar left no elbow ("the arm chain from
    // 'ShoulderLeft' has fewer than three joints": Kinect names, CMU
    // 01_01's rest, the finger joints unnamed).
    let elbow_at = first_role(tokens, &c, |r| r == Role::Elbow);
    let collar_fits = elbow_at.is_none_or(|e| e > 1) && w_named.is_none_or(|w| w > 2);
    let s_named = named_upper.or(Some(usize::from(geo_collar && collar_fits)));
    let e_named =
        elbow_at.filter(|&e| s_named.is_none_or(|s| e > s) && w_named.is_none_or(|w| e < w));
    let ln_off = |x: f64, want: f64| {
        if x.is_finite() && x > 0.0 {
            (x / want).ln().abs()
        } else {
            f64::INFINITY
        }
    };
    let score = |s: usize, e: usize, w: usize| {
        let (upper, fore, hand) = (a(e) - a(s), a(w) - a(e), far - a(w));
        let h = if hand > 0.1 * fore {
            ln_off(fore / hand, 1.35)
        } else {
            0.6 // no hand: a wrist at the chain's end costs as a 1.8× mismatch
        };
        ln_off(upper / fore, 1.27) + h
    };
    let n = c.len();
    let mut best: Option<(f64, usize, usize, usize)> = None;
    for s in 0..n {
        if s_named.is_some_and(|x| x != s) {
            continue;
        }
        for e in s + 1..n {
            if e_named.is_some_and(|x| x != e) {
                continue;
            }
            for w in e + 1..n {
                if w_named.is_some_and(|x| x != w) {
                    continue;
                }
                let sc = score(s, e, w);
                if best.is_none_or(|b| sc < b.0) {
                    best = Some((sc, s, e, w));
                }
            }
        }
    }
    let Some((_, s_k, e_k, w_k)) = best else {
        return Err(short());
    };
    let w = c[w_k];
    let named = |j: usize, r: &[Role]| role_of(tokens, j).is_some_and(|x| r.contains(&x));
    let (s, e) = (c[s_k], c[e_k]);
    Ok(Limb {
        picks: [
            Some((s, named(s, &[Role::UpperArm, Role::ShoulderWord]))),
            Some((e, named(e, &[Role::Elbow]))),
            Some((w, named(w, &[Role::Wrist, Role::Hand]))),
            None,
        ],
        derive_end: None,
        subtree: g.subtree(start),
        note: None,
    })
}
