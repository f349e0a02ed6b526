//! From rigid parts to the canonical humanoid.
//!
//! The body's five extremities are the first five geodesic farthest
//! points from its centre (the ends of the part tree's branches: the
//! structure `rig::structure` reads off a mocap rig's joint tree, read here
//! off the surface). Up is the direction along which two extremities (the
//! feet) rest on a floor: the lowest vertices over the sequence hold a
//! nearly constant height. The head is the highest of the other three;
//! facing is where the feet point (toe tips ahead of the knees); left is
//! `up × facing`, each pair of limbs sided by its root's position. Along
//! each limb, from its tip to the trunk, the boundaries between rigid parts
//! that bend in the capture are its joints, matched in order to the limb's
//! joints (wrist, elbow, shoulder; ankle, knee, hip) near their usual
//! distances from the tip (proportions after Drillis & Contini 1966, as in
//! [`crate::embed::joints`]); a joint the motion does not show (a hand that
//! never bends at the wrist) is placed by proportion and said so.

use super::decompose::Decomposition;
use super::joints::{PartJoint, joint_between};
use glam::DVec3;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Edge-length geodesic distances from `sources` (Dijkstra), and each
/// vertex's predecessor towards the nearest source.
pub fn geodesic(p: &[[f64; 3]], nb: &[Vec<u32>], sources: &[u32]) -> (Vec<f64>, Vec<u32>) {
    let n = p.len();
    let mut d = vec![f64::INFINITY; n];
    let mut prev = vec![u32::MAX; n];
    let mut heap = BinaryHeap::new();
    for &s in sources {
        d[s as usize] = 0.0;
        heap.push(Reverse((Ord64(0.0), s)));
    }
    while let Some(Reverse((Ord64(dv), v))) = heap.pop() {
        if dv > d[v as usize] {
            continue;
        }
        let pv = DVec3::from_array(p[v as usize]);
        for &u in &nb[v as usize] {
            let du = dv + pv.distance(DVec3::from_array(p[u as usize]));
            if du < d[u as usize] {
                d[u as usize] = du;
                prev[u as usize] = v;
                heap.push(Reverse((Ord64(du), u)));
            }
        }
    }
    (d, prev)
}

#[derive(PartialEq, Clone, Copy)]
struct Ord64(f64);
impl Eq for Ord64 {}
impl PartialOrd for Ord64 {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Ord64 {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}

/// The first `k` geodesic farthest points from `seed`, each with its
/// distance to the seed and the earlier points when picked.
pub fn extremities(p: &[[f64; 3]], nb: &[Vec<u32>], seed: u32, k: usize) -> Vec<(u32, f64)> {
    let (mut d, _) = geodesic(p, nb, &[seed]);
    let mut out = Vec::new();
    for _ in 0..k {
        let Some((v, dv)) = farthest(&d) else {
            break;
        };
        out.push((v as u32, dv));
        let (dn, _) = geodesic(p, nb, &[v as u32]);
        for (a, b) in d.iter_mut().zip(dn) {
            *a = a.min(b);
        }
    }
    out
}

/// The vertex with the largest finite distance in `d`, and the distance.
pub(crate) fn farthest(d: &[f64]) -> Option<(usize, f64)> {
    d.iter()
        .enumerate()
        .filter(|(_, x)| x.is_finite())
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(v, &x)| (v, x))
}

/// One boundary crossed by a limb's path from its tip to the trunk.
#[derive(Debug, Clone, Copy)]
pub struct Crossing {
    /// The part on the tip's side.
    pub distal: u32,
    /// The part on the trunk's side.
    pub proximal: u32,
    /// Geodesic distance from the tip along the path where it crosses.
    pub from_tip: f64,
    /// The joint between the two parts.
    pub joint: PartJoint,
}

/// The path from vertex `tip` to the source of `prev` (vertex ids, tip
/// first) and the geodesic distance from the tip of each.
pub(crate) fn path_to_source(p: &[[f64; 3]], prev: &[u32], tip: u32) -> Vec<(u32, f64)> {
    let mut out = vec![(tip, 0.0)];
    let mut v = tip;
    while prev[v as usize] != u32::MAX && out.len() <= p.len() {
        let u = prev[v as usize];
        let d = out.last().map_or(0.0, |x| x.1)
            + DVec3::from_array(p[v as usize]).distance(DVec3::from_array(p[u as usize]));
        out.push((u, d));
        v = u;
    }
    out
}

/// Centre of the boundary between parts `a` and `b` (their vertices that
/// touch the other part), if they touch.
pub(crate) fn boundary_centre(
    p: &[[f64; 3]],
    nb: &[Vec<u32>],
    labels: &[u32],
    a: u32,
    b: u32,
) -> Option<DVec3> {
    let (mut s, mut k) = (DVec3::ZERO, 0usize);
    for v in 0..p.len() {
        let l = labels[v];
        if l != a && l != b {
            continue;
        }
        let other = if l == a { b } else { a };
        if nb[v].iter().any(|&u| labels[u as usize] == other) {
            s += DVec3::from_array(p[v]);
            k += 1;
        }
    }
    (k > 0).then(|| s / k as f64)
}

/// The crossings of a limb's path (tip first), one per distinct part it
/// enters, each with the joint between the part left and the part entered.
pub(crate) fn crossings(
    p: &[[f64; 3]],
    nb: &[Vec<u32>],
    dec: &Decomposition,
    path: &[(u32, f64)],
    lambda: f64,
) -> Vec<Crossing> {
    let mut seen = vec![false; dec.count];
    let mut out = Vec::new();
    let mut cur = dec.labels[path[0].0 as usize];
    seen[cur as usize] = true;
    for &(v, d) in path {
        let l = dec.labels[v as usize];
        if l == cur || seen[l as usize] {
            continue;
        }
        seen[l as usize] = true;
        let c = boundary_centre(p, nb, &dec.labels, cur, l)
            .unwrap_or_else(|| DVec3::from_array(p[v as usize]));
        let joint = joint_between(
            &dec.motions[cur as usize],
            &dec.motions[l as usize],
            c,
            lambda,
        );
        out.push(Crossing {
            distal: cur,
            proximal: l,
            from_tip: d,
            joint,
        });
        cur = l;
    }
    out
}

/// A limb joint as placed: by the motion or by proportion.
#[derive(Debug, Clone, Copy)]
pub struct Placed {
    /// Rest-frame position.
    pub position: DVec3,
    /// Found from the parts' motion, or at the centre of the cut an arm
    /// ends in (`embed::auto::cut_ends`); else by proportion along the limb.
    pub by_motion: bool,
    /// How much it bends in the capture (degrees; 0 when by proportion).
    pub articulation_deg: f64,
}

/// Matches a limb's crossings to its joints: for each expected distance
/// from the tip (in order, distal first; fractions of `height`), the
/// first crossing after the previous match that bends at least `min_deg`
/// within `tol` of the height of the expected distance: the end of the
/// most distal rigid part (the shin, the forearm and hand). The nearest
/// to the expected distance was chosen before; on a dancer in a skirt
/// it was the skirt's hem above the shin (the skirt moves in bands that
/// bend with neither thigh), and the knee landed at the hem.
pub(crate) fn match_joints(
    crossings: &[Crossing],
    expected: &[f64],
    height: f64,
    min_deg: f64,
    tol: f64,
) -> Vec<Option<Crossing>> {
    let mut out = Vec::new();
    let mut from = 0;
    for &e in expected {
        let target = e * height;
        let best = crossings.iter().enumerate().skip(from).find(|(_, c)| {
            c.joint.articulation_deg >= min_deg && (c.from_tip - target).abs() <= tol * height
        });
        match best {
            Some((i, c)) => {
                out.push(Some(*c));
                from = i + 1;
            }
            None => out.push(None),
        }
    }
    out
}

/// The point of `path` at geodesic distance `d` from its tip.
pub fn along(p: &[[f64; 3]], path: &[(u32, f64)], d: f64) -> DVec3 {
    let i = path.partition_point(|x| x.1 < d).min(path.len() - 1);
    DVec3::from_array(p[path[i].0 as usize])
}

/// Joint `name` of `found` (the origin, by proportion, when missing).
pub fn get_joint(found: &[(String, Placed)], name: &str) -> Placed {
    found
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, p)| *p)
        .unwrap_or(Placed {
            position: DVec3::ZERO,
            by_motion: false,
            articulation_deg: 0.0,
        })
}
