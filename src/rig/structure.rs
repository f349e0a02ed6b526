//! Structural mapping of a humanoid clip onto the canonical joints, from the
//! hierarchy and the rest/motion geometry (names are hints only).
//!
//! Steps, all O(joints · sampled frames):
//! 1. Bone lengths and "reach" (longest path to an end point) per joint;
//!    joints joined by zero-length offsets form one node; helper bones
//!    (twist, roll, fingers, ...; see [`super::names::is_helper`]) and their
//!    helper-only subtrees are ignored.
//! 2. A branch of a node is *significant* when its reach is at least 12% of
//!    the rest skeleton's bounding-box diagonal (legs ≈ 35%, arms ≈ 30%,
//!    fingers and toes ≈ 7%, measured on CMU, CC and Bandai rigs).
//! 3. The pelvis is the first node where exactly three significant chains
//!    meet: two legs without further junctions and a spine that reaches a
//!    node where two arms branch off (the chest). Legs must point away from
//!    the chest (cosine below −0.5 in the rest pose or a sampled frame):
//!    a quadruped's spine is horizontal above vertical legs.
//! 4. Joints along a chain are chosen by position: hip = first joint off the
//!    pelvis, ankle = first joint below 25% of the hip's height over the
//!    chain's lowest point (height along pelvis→chest), knee = joint nearest
//!    the hip–ankle midpoint, toe = next joint after the ankle; elbow = the
//!    joint whose upper/fore-arm length ratio is closest to 1.2 (Drillis &
//!    Contini's 0.186 H / 0.146 H ≈ 1.27); joints that stay collinear with
//!    their neighbours in every sampled frame are pass-through helpers.
//!    A joint whose name has the matching role wins inside its chain.
//! 5. Left/right from the body's own frame, never from names: up =
//!    pelvis→neck, forward = the feet's heel→toe direction (else the knees'
//!    bend, else the root's travel), left = up × forward (Y-up, facing +Z:
//!    left is +X).

use super::canonical::Canonical;
use super::map::Derive;
use super::names::{Role, Side, is_helper, role, side};
use crate::mocap::Clip;
use glam::{DQuat, DVec3};

/// Where a canonical joint came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
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
    pub source: Source,
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
    /// Sampled poses: (positions, rotations); the rest pose first.
    poses: Vec<(Vec<DVec3>, Vec<DQuat>)>,
}

impl<'a> Geo<'a> {
    fn new(clip: &'a Clip, tokens: &[Vec<String>]) -> Result<Geo<'a>, NotHumanoid> {
        let n = clip.joint_count();
        let parent: Vec<Option<usize>> = clip
            .joints
            .iter()
            .map(|j| j.parent.map(|p| p.idx()))
            .collect();
        let mut children = vec![Vec::new(); n];
        for (i, p) in parent.iter().enumerate() {
            if let Some(p) = p {
                children[*p].push(i);
            }
        }
        let len: Vec<f64> = clip.joints.iter().map(|j| j.offset.length()).collect();
        let helper: Vec<bool> = (0..n)
            .map(|i| tokens.get(i).is_some_and(|t| is_helper(t)))
            .collect();
        let (rest, _) = clip.rest_positions();
        let tail_rest: Vec<Option<DVec3>> = clip
            .joints
            .iter()
            .enumerate()
            .map(|(i, j)| j.tail.map(|t| rest[i] + t))
            .collect();
        let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        for p in rest.iter().chain(tail_rest.iter().flatten()) {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let diag = (hi - lo).length();
        if !(diag.is_finite() && diag > 0.0) {
            return Err(NotHumanoid("the rest skeleton has no extent".into()));
        }
        let eps = 1e-3 * diag;
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
        let mut rep: Vec<usize> = (0..n).collect();
        for i in 0..n {
            if let Some(p) = parent[i]
                && len[i] < eps
            {
                rep[i] = rep[p];
            }
        }
        let mut poses = Vec::new();
        let mut rot = vec![DQuat::IDENTITY; n];
        poses.push((rest.clone(), rot.clone()));
        let frames = clip.frame_count();
        let step = (frames / MAX_FRAMES).max(1);
        let mut pos = vec![DVec3::ZERO; n];
        let mut f = 0;
        while f < frames {
            clip.world_into(f, &mut pos, &mut rot);
            poses.push((pos.clone(), rot.clone()));
            f += step;
        }
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
            thr: 0.12 * diag,
            poses,
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
    /// longest reach, until an end.
    fn path(&self, start: usize) -> Vec<usize> {
        let mut out = vec![start];
        let mut j = start;
        while let Some(&c) =
            self.children[j]
                .iter()
                .filter(|&&c| self.useful[c])
                .max_by(|&&a, &&b| {
                    (self.len[a] + self.reach[a]).total_cmp(&(self.len[b] + self.reach[b]))
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
    fn junction_below(&self, start: usize) -> Option<usize> {
        let mut j = self.rep[start];
        for _ in 0..=self.clip.joint_count() {
            let b = self.branches(j);
            match b.len() {
                0 => return None,
                1 => j = self.rep[b[0]],
                _ => return Some(j),
            }
        }
        None
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
}

/// Maps a clip's joints onto the canonical skeleton by structure, using
/// `tokens` (from [`super::names::all_tokens`]) as hints inside chains.
pub fn analyse(clip: &Clip, tokens: &[Vec<String>]) -> Result<Body, NotHumanoid> {
    let g = Geo::new(clip, tokens)?;
    let n = clip.joint_count();
    let mut reasons: Vec<String> = Vec::new();
    for p in 0..n {
        if g.rep[p] != p || !g.useful[p] {
            continue;
        }
        let b = g.branches(p);
        if b.len() < 3 {
            continue;
        }
        if b.len() > 3 {
            reasons.push(format!(
                "{} chains meet at '{}' (two legs and a spine expected)",
                b.len(),
                g.names[p]
            ));
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

fn body(
    g: &Geo,
    tokens: &[Vec<String>],
    pelvis: usize,
    spine_start: usize,
    chest: usize,
    legs: [usize; 2],
) -> Result<Body, NotHumanoid> {
    let name = |j: usize| g.names[j].clone();
    // Leg/arm symmetry and the legs pointing away from the chest.
    let reach = |j: usize| g.len[j] + g.reach[j];
    let ratio = |a: f64, b: f64| a.max(b) / a.min(b).max(1e-300);
    if ratio(reach(legs[0]), reach(legs[1])) > 1.6 {
        return Err(NotHumanoid(format!(
            "the two chains below '{}' differ in length ({:.3} vs {:.3})",
            name(pelvis),
            reach(legs[0]),
            reach(legs[1])
        )));
    }
    let cb = g.branches(chest);
    let (arms, neck_start) = match cb.len() {
        2 | 3 => {
            // The neck continues the spine: the child most aligned with pelvis→chest.
            let up = (g.rest[chest] - g.rest[pelvis]).normalize_or_zero();
            let far = |c: usize| {
                let path = g.path(c);
                let end = *path.last().unwrap_or(&c);
                (g.tail_rest[end].unwrap_or(g.rest[end]) - g.rest[chest]).normalize_or_zero()
            };
            if cb.len() == 3 {
                // The neck: the branch whose path names a neck or head; else
                // the odd one out of the three (the arms are the most alike
                // pair in reach), ties broken by pointing up.
                let named = (0..3).find(|&k| {
                    g.path(cb[k])
                        .iter()
                        .any(|&j| matches!(role_of(tokens, j), Some(Role::Neck) | Some(Role::Head)))
                });
                let odd = |k: usize| {
                    let (a, b) = ((k + 1) % 3, (k + 2) % 3);
                    -ratio(reach(cb[a]), reach(cb[b])) + 0.05 * far(cb[k]).dot(up)
                };
                let k = named.unwrap_or_else(|| {
                    (0..3)
                        .max_by(|&a, &b| odd(a).total_cmp(&odd(b)))
                        .unwrap_or(0)
                });
                let arms: Vec<usize> = (0..3).filter(|&i| i != k).map(|i| cb[i]).collect();
                ([arms[0], arms[1]], Some(cb[k]))
            } else {
                let others: Vec<usize> = g
                    .node_children(chest)
                    .into_iter()
                    .filter(|c| !cb.contains(c) && role_of(tokens, *c) != Some(Role::Collar))
                    .collect();
                let neck = others
                    .into_iter()
                    .max_by(|&a, &b| far(a).dot(up).total_cmp(&far(b).dot(up)));
                ([cb[0], cb[1]], neck)
            }
        }
        k => {
            return Err(NotHumanoid(format!(
                "{k} limbs branch off '{}' (two arms expected)",
                name(chest)
            )));
        }
    };
    if ratio(reach(arms[0]), reach(arms[1])) > 1.6 {
        return Err(NotHumanoid(format!(
            "the two chains off '{}' differ in length",
            name(chest)
        )));
    }
    // Legs point away from the chest in at least one pose.
    let mut best_cos = f64::MAX;
    let mut ref_pose = 0;
    for (k, (p, _)) in g.poses.iter().enumerate() {
        let up = (p[chest] - p[pelvis]).normalize_or_zero();
        let mut c = 0.0;
        for &l in &legs {
            let path = g.path(l);
            let end = *path.last().unwrap_or(&l);
            c += 0.5 * (p[end] - p[pelvis]).normalize_or_zero().dot(up);
        }
        // The rest pose (usually neutral, legs straight) when it stands
        // upright enough; else the most upright sampled pose.
        if c < best_cos && !(k > 0 && ref_pose == 0 && best_cos < -0.8) {
            best_cos = c;
            ref_pose = k;
        }
    }
    if best_cos > -0.5 {
        return Err(NotHumanoid(format!(
            "the chains below '{}' never point away from the spine (cosine {best_cos:.2}): a horizontal body",
            name(pelvis)
        )));
    }
    let Some(neck_start) = neck_start else {
        return Err(NotHumanoid(format!("no neck above '{}'", name(chest))));
    };

    let mut picks: Vec<Pick> = (0..Canonical::COUNT)
        .map(|_| Pick {
            joint: None,
            source: Source::Structure,
            confidence: 0.0,
            derive: None,
        })
        .collect();
    let set = |picks: &mut Vec<Pick>, c: Canonical, j: usize, named: bool| {
        picks[c.index()] = Pick {
            joint: Some(j),
            source: if named {
                Source::Names
            } else {
                Source::Structure
            },
            confidence: if named { 0.95 } else { 0.8 },
            derive: None,
        };
    };
    let derive = |picks: &mut Vec<Pick>, c: Canonical, d: Derive| {
        picks[c.index()] = Pick {
            joint: None,
            source: Source::Derived,
            confidence: 0.5,
            derive: Some(d),
        };
    };

    // Pelvis: a pelvis-named joint of the node, else the node.
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
        });
    set(
        &mut picks,
        Canonical::Pelvis,
        pj.unwrap_or(pelvis),
        pj.is_some(),
    );

    // Spine chain between the pelvis and the chest.
    let mut between = Vec::new();
    let mut j = chest;
    while let Some(p) = g.parent[j] {
        if g.rep[p] == pelvis {
            break;
        }
        between.push(p);
        j = p;
    }
    between.reverse();
    let _ = spine_start;
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
            set(&mut picks, Canonical::Spine, j, true);
            j
        }
        None => match spine_c.first() {
            Some(&j) if Some(j) != chest_j || chest_named_neck => {
                set(&mut picks, Canonical::Spine, j, false);
                j
            }
            _ => {
                set(&mut picks, Canonical::Spine, chest, false);
                chest
            }
        },
    };
    let chest_derived = match chest_j {
        Some(c) if c != spine_j => {
            set(
                &mut picks,
                Canonical::Chest,
                c,
                role_of(tokens, c) == Some(Role::Chest),
            );
            false
        }
        _ => true,
    };

    // Neck and head.
    let neck_path = g.path(neck_start);
    let neck_c = g.candidates(tokens, g.rest[chest], &neck_path, false);
    let (neck_j, head_c): (usize, Vec<usize>) = match neck_from_chest {
        Some(nj) => (nj, neck_c.clone()),
        None => {
            let k = first_role(tokens, &neck_c, |r| r == Role::Neck).unwrap_or(0);
            let Some(&nj) = neck_c.get(k) else {
                return Err(NotHumanoid(format!("no neck above '{}'", name(chest))));
            };
            (nj, neck_c[k + 1..].to_vec())
        }
    };
    set(
        &mut picks,
        Canonical::Neck,
        neck_j,
        role_of(tokens, neck_j) == Some(Role::Neck),
    );
    if chest_derived {
        derive(
            &mut picks,
            Canonical::Chest,
            Derive::Between {
                from: Canonical::Spine,
                to: Canonical::Neck,
                t: 0.5,
            },
        );
    }
    match first_role(tokens, &head_c, |r| r == Role::Head).or(if head_c.is_empty() {
        None
    } else {
        Some(0)
    }) {
        Some(k) => {
            let h = head_c[k];
            set(
                &mut picks,
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
            derive(&mut picks, Canonical::Head, d);
        }
    }

    // Limbs.
    let leg = |start: usize| -> Result<Limb, NotHumanoid> {
        leg_chain(g, tokens, pelvis, chest, ref_pose, start)
    };
    let arm = |start: usize| -> Result<Limb, NotHumanoid> { arm_chain(g, tokens, chest, start) };
    let l0 = leg(legs[0])?;
    let l1 = leg(legs[1])?;
    let a0 = arm(arms[0])?;
    let a1 = arm(arms[1])?;

    // Left/right from the body frame.
    let pj = picks[Canonical::Pelvis.index()].joint.unwrap_or(pelvis);
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
    let mut votes = [0.0f64; 3]; // feet, knees, travel
    let mut leg_s = [0.0f64; 3];
    let mut arm_s = [0.0f64; 3];
    for (p, r) in &g.poses {
        let up = (p[neck_j] - p[pj]).normalize_or_zero();
        let flat = |v: DVec3| v - up * v.dot(up);
        let mut fw = [DVec3::ZERO; 3];
        if let (Some(t0), Some(t1)) = (toe_pt(&l0, p, r), toe_pt(&l1, p, r)) {
            let (a0, a1) = (pt(&l0, 2, p), pt(&l1, 2, p));
            let len = t0.distance(a0) + t1.distance(a1);
            if len > 0.0 {
                fw[0] = (flat(t0 - a0) + flat(t1 - a1)) / len;
            }
        }
        for l in [&l0, &l1] {
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
            leg_s[m] += w
                * (mean3(&l0, p) - mean3(&l1, p))
                    .normalize_or_zero()
                    .dot(left);
            arm_s[m] += w
                * (mean3(&a0, p) - mean3(&a1, p))
                    .normalize_or_zero()
                    .dot(left);
        }
    }
    let m = (0..3).find(|&m| votes[m] > 0.0 && leg_s[m].abs() > 0.1 * votes[m]);
    let forward_from = match m {
        Some(0) => "feet",
        Some(1) => "knees",
        Some(2) => "travel",
        _ => "none",
    };
    let (leg_sign, arm_sign, conf) = match m {
        Some(m) => (
            leg_s[m],
            arm_s[m],
            (leg_s[m].abs().min(arm_s[m].abs()) / votes[m]).clamp(0.0, 1.0),
        ),
        None => (1.0, 1.0, 0.0),
    };
    let (ll, rl) = if leg_sign >= 0.0 { (l0, l1) } else { (l1, l0) };
    let (la, ra) = if arm_sign >= 0.0 { (a0, a1) } else { (a1, a0) };
    let sc = 0.5 + 0.5 * conf;
    let mut named_sides = [0i32; 2];
    let lim = |picks: &mut Vec<Pick>,
               l: &Limb,
               cs: [Canonical; 4],
               s: Side,
               named_sides: &mut [i32; 2]| {
        for (k, c) in cs.into_iter().enumerate() {
            match l.picks[k] {
                Some((j, named)) => {
                    set(picks, c, j, named);
                    picks[c.index()].confidence *= sc;
                    match tokens.get(j).and_then(|t| side(t)) {
                        Some(ns) if ns == s => named_sides[0] += 1,
                        Some(_) => named_sides[1] += 1,
                        None => {}
                    }
                }
                None => {
                    if let Some(d) = &l.derive_end {
                        derive(picks, c, d.clone());
                        picks[c.index()].confidence *= sc;
                    }
                }
            }
        }
    };
    use Canonical as C;
    lim(
        &mut picks,
        &ll,
        [C::LHip, C::LKnee, C::LAnkle, C::LToe],
        Side::Left,
        &mut named_sides,
    );
    lim(
        &mut picks,
        &rl,
        [C::RHip, C::RKnee, C::RAnkle, C::RToe],
        Side::Right,
        &mut named_sides,
    );
    lim(
        &mut picks,
        &la,
        [C::LShoulder, C::LElbow, C::LWrist, C::LToe],
        Side::Left,
        &mut named_sides,
    );
    lim(
        &mut picks,
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
    Ok(Body {
        picks,
        left_leg: ll.subtree,
        right_leg: rl.subtree,
        left_arm: la.subtree,
        right_arm: ra.subtree,
        forward_from,
        side_confidence: conf,
        names_mirrored: named_sides[1] > named_sides[0],
    })
}

fn leg_chain(
    g: &Geo,
    tokens: &[Vec<String>],
    pelvis: usize,
    chest: usize,
    ref_pose: usize,
    start: usize,
) -> Result<Limb, NotHumanoid> {
    let path = g.path(start);
    let c = g.candidates(tokens, g.rest[pelvis], &path, true);
    let short = || {
        NotHumanoid(format!(
            "the leg chain from '{}' has fewer than three joints",
            g.names[start]
        ))
    };
    if c.len() < 3 {
        return Err(short());
    }
    let hip_k = first_role(tokens, &c, |r| r == Role::Thigh).unwrap_or(0);
    let after = &c[hip_k + 1..];
    let p = &g.poses[ref_pose.min(g.poses.len() - 1)].0;
    let up = (p[chest] - p[pelvis]).normalize_or_zero();
    let h = |q: DVec3| (q - p[pelvis]).dot(up);
    let ankle_named = first_role(tokens, after, |r| r == Role::Ankle);
    let foot_named = first_role(tokens, after, |r| r == Role::Foot);
    let ankle_k = match ankle_named.or(foot_named) {
        Some(k) if k >= 1 => k,
        _ => {
            let end = *path.last().unwrap_or(&start);
            let lowest = after
                .iter()
                .map(|&j| h(p[j]))
                .chain(g.clip.joints[end].tail.map(|_| {
                    // the end point of the last joint in this pose
                    let (pp, rr) = &g.poses[ref_pose.min(g.poses.len() - 1)];
                    h(pp[end] + rr[end] * g.clip.joints[end].tail.unwrap_or_default())
                }))
                .fold(f64::MAX, f64::min);
            let hh = h(p[c[hip_k]]);
            let thr = lowest + 0.25 * (hh - lowest);
            let k = after
                .iter()
                .position(|&j| h(p[j]) <= thr)
                .unwrap_or(after.len() - 1);
            k.max(1).min(after.len().saturating_sub(1))
        }
    };
    if after.len() < 2 || ankle_k >= after.len() {
        return Err(short());
    }
    let hip = c[hip_k];
    let ankle = after[ankle_k];
    let mids = &after[..ankle_k];
    let knee_k = first_role(tokens, mids, |r| r == Role::Knee).unwrap_or_else(|| {
        let m = 0.5 * (g.rest[hip] + g.rest[ankle]);
        (0..mids.len())
            .min_by(|&a, &b| {
                g.rest[mids[a]]
                    .distance(m)
                    .total_cmp(&g.rest[mids[b]].distance(m))
            })
            .unwrap_or(0)
    });
    let knee = *mids.get(knee_k).ok_or_else(short)?;
    let toes = &after[ankle_k + 1..];
    let toe_k = if ankle_named.is_some() && foot_named.is_some_and(|f| f > ankle_k) {
        foot_named.map(|f| f - ankle_k - 1)
    } else {
        first_role(tokens, toes, |r| r == Role::Toe).or(if toes.is_empty() {
            None
        } else {
            Some(0)
        })
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
    })
}

fn arm_chain(
    g: &Geo,
    tokens: &[Vec<String>],
    chest: usize,
    start: usize,
) -> Result<Limb, NotHumanoid> {
    let path = g.path(start);
    let c = g.candidates(tokens, g.rest[chest], &path, true);
    let short = || {
        NotHumanoid(format!(
            "the arm chain from '{}' has fewer than three joints",
            g.names[start]
        ))
    };
    if c.len() < 3 {
        return Err(short());
    }
    // The wrist: by name, else the first joint where the chain branches
    // (a hand into fingers), else the chain's last joint.
    let branching = c.iter().position(|&j| {
        let real = |&&k: &&usize| g.len[k] >= g.eps && !(g.helper[k] && g.children[k].is_empty());
        g.children[j].iter().filter(real).count() >= 2
    });
    let w_k = first_role(tokens, &c, |r| r == Role::Wrist)
        .or_else(|| first_role(tokens, &c, |r| r == Role::Hand))
        .or(branching)
        .unwrap_or(c.len() - 1);
    if w_k < 2 {
        return Err(short());
    }
    let before = &c[..w_k];
    let collar = first_role(tokens, before, |r| r == Role::Collar).is_some();
    let s_named = first_role(tokens, before, |r| {
        r == Role::UpperArm || (collar && r == Role::ShoulderWord)
    });
    let e_named =
        first_role(tokens, before, |r| r == Role::Elbow).filter(|&e| s_named.is_none_or(|s| e > s));
    let w = c[w_k];
    let d = |a: usize, b: usize| g.rest[a].distance(g.rest[b]);
    let (s_k, e_k) = match (s_named, e_named) {
        (Some(s), Some(e)) => (s, e),
        (None, Some(e)) if e >= 1 => (e - 1, e),
        (Some(s), _) if s + 1 < w_k => {
            let m = 0.5 * (g.rest[before[s]] + g.rest[w]);
            let e = (s + 1..w_k)
                .min_by(|&a, &b| {
                    g.rest[before[a]]
                        .distance(m)
                        .total_cmp(&g.rest[before[b]].distance(m))
                })
                .unwrap_or(s + 1);
            (s, e)
        }
        _ => {
            let e = (1..w_k)
                .min_by(|&a, &b| {
                    let score = |k: usize| {
                        let r = d(before[k - 1], before[k]) / d(before[k], w).max(1e-300);
                        (r / 1.2).ln().abs()
                    };
                    score(a).total_cmp(&score(b))
                })
                .unwrap_or(1);
            (e - 1, e)
        }
    };
    let named = |j: usize, r: &[Role]| role_of(tokens, j).is_some_and(|x| r.contains(&x));
    let (s, e) = (before[s_k], before[e_k]);
    Ok(Limb {
        picks: [
            Some((s, named(s, &[Role::UpperArm, Role::ShoulderWord]))),
            Some((e, named(e, &[Role::Elbow]))),
            Some((w, named(w, &[Role::Wrist, Role::Hand]))),
            None,
        ],
        derive_end: None,
        subtree: g.subtree(start),
    })
}
