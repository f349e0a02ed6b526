//! Part rigidity over a sequence: each body part's vertices should follow
//! one rigid motion from the rest frame, up to the capture's own
//! deformation (issue 41). The rigid motion of a part in a frame is the
//! least-squares one (Kabsch: the rotation of the polar decomposition of
//! the cross-covariance, [`crate::mesh::frames::polar`]), fitted twice —
//! the second time without the fifth of the vertices that fit worst, so a
//! mislabelled region does not drag the fit. A vertex that strays far from
//! its own part's motion while following another part's is flagged, with
//! the frames where it strays.

use super::parts::Part;
use crate::mesh::frames::polar;
use glam::{DMat3, DQuat, DVec3};
use serde::Serialize;

/// A rigid motion `x ↦ rotation · (x − from) + to`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rigid {
    /// The rotation.
    pub rotation: DQuat,
    /// The centre on the source frame.
    pub from: DVec3,
    /// The centre on the target frame.
    pub to: DVec3,
}

impl Rigid {
    /// The identity.
    pub const IDENTITY: Rigid = Rigid {
        rotation: DQuat::IDENTITY,
        from: DVec3::ZERO,
        to: DVec3::ZERO,
    };

    /// A point moved.
    pub fn apply(&self, x: DVec3) -> DVec3 {
        self.rotation * (x - self.from) + self.to
    }

    /// A direction turned.
    pub fn turn(&self, d: DVec3) -> DVec3 {
        self.rotation * d
    }
}

/// The least-squares rigid motion taking `vertices` of `from` onto
/// `to` (Kabsch). `None` for fewer than three vertices.
pub(crate) fn rigid_motion(from: &[[f64; 3]], to: &[[f64; 3]], vertices: &[u32]) -> Option<Rigid> {
    if vertices.len() < 3 {
        return None;
    }
    let k = vertices.len() as f64;
    let at = |p: &[[f64; 3]], v: u32| DVec3::from_array(p[v as usize]);
    let cf = vertices.iter().map(|&v| at(from, v)).sum::<DVec3>() / k;
    let ct = vertices.iter().map(|&v| at(to, v)).sum::<DVec3>() / k;
    let mut h = DMat3::ZERO;
    for &v in vertices {
        let (x, y) = (at(from, v) - cf, at(to, v) - ct);
        // h = Σ y xᵀ: its polar rotation maximises Σ y · R x.
        h += DMat3::from_cols(y * x.x, y * x.y, y * x.z);
    }
    let (rotation, _) = polar(h);
    rotation.is_finite().then_some(Rigid {
        rotation,
        from: cf,
        to: ct,
    })
}

/// [`rigid_motion`] fitted again without the fifth of the vertices that
/// fit worst (a mislabelled region or a contact does not drag it).
pub(crate) fn robust_motion(from: &[[f64; 3]], to: &[[f64; 3]], vertices: &[u32]) -> Option<Rigid> {
    let first = rigid_motion(from, to, vertices)?;
    let mut r: Vec<(f64, u32)> = vertices
        .iter()
        .map(|&v| {
            let e = first
                .apply(DVec3::from_array(from[v as usize]))
                .distance(DVec3::from_array(to[v as usize]));
            (e, v)
        })
        .collect();
    r.sort_by(|a, b| a.0.total_cmp(&b.0));
    let keep: Vec<u32> = r[..(r.len() * 4 / 5).max(3)].iter().map(|x| x.1).collect();
    rigid_motion(from, to, &keep).or(Some(first))
}

/// Thresholds of [`part_rigidity`]; lengths are fractions of the height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RigidityOptions {
    /// A vertex strays in a frame when its own part's motion misses it by
    /// more than this. Default 0.04 (7 cm on a 1.7 m person: more than a
    /// bulging muscle or a swinging skirt's hem near its part).
    pub stray: f64,
    /// …in at least this fraction of the frames examined. Default 0.25.
    pub frames: f64,
    /// …and another part's motion misses it, on average, by at most this
    /// fraction of its own part's miss: it belongs there. Default 0.5.
    pub better: f64,
    /// At most this many frames are examined, evenly spread. Default 60.
    pub max_frames: usize,
}

impl Default for RigidityOptions {
    fn default() -> Self {
        RigidityOptions {
            stray: 0.04,
            frames: 0.25,
            better: 0.5,
            max_frames: 60,
        }
    }
}

/// One part's rigidity over the frames examined.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PartRigidity {
    /// The part.
    pub part: &'static str,
    /// Its vertices.
    pub vertices: usize,
    /// Root mean square distance of its vertices from its rigid motion,
    /// over the frames examined, in % of the height (0 for fewer than
    /// three vertices).
    pub rms_percent: f64,
    /// Vertices that follow another part's motion (mislabelled).
    pub stray: Vec<Stray>,
}

/// A region of a part's vertices that follows another part.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Stray {
    /// The part it follows.
    pub follows: &'static str,
    /// Its vertices, sorted.
    pub vertices: Vec<u32>,
    /// The frames (indices into the frames given) where they stray most,
    /// worst first, at most five.
    pub frames: Vec<usize>,
}

/// A part followed, the vertices following it, their (miss, frame)s.
type Followed = (usize, Vec<u32>, Vec<(f64, usize)>);

/// The rigidity of every part of `labels` ([`Part::ALL`] indices) from the
/// frame `rest` over `frames`, with the vertices that follow another part's
/// motion better than their own (see [`RigidityOptions`]). `height` in the
/// frames' units. Cost: parts × frames × vertices distance evaluations over
/// at most [`RigidityOptions::max_frames`] frames.
pub(crate) fn part_rigidity(
    labels: &[u8],
    rest: &[[f64; 3]],
    frames: &[&[[f64; 3]]],
    height: f64,
    opts: &RigidityOptions,
) -> Vec<PartRigidity> {
    let n = labels.len();
    let step = frames.len().div_ceil(opts.max_frames.max(1)).max(1);
    let picked: Vec<usize> = (0..frames.len())
        .step_by(step)
        .filter(|&f| frames[f].len() == n && rest.len() == n)
        .collect();
    let members: Vec<Vec<u32>> = Part::ALL
        .iter()
        .map(|p| {
            (0..n as u32)
                .filter(|&v| labels[v as usize] as usize == p.index())
                .collect()
        })
        .collect();
    let h = height.max(f64::MIN_POSITIVE);
    // Per vertex: frames where its own part misses it by more than
    // `stray`, the sum of its own miss, and the sum of each part's miss.
    let mut strays = vec![0usize; n];
    let mut own_sum = vec![0.0; n];
    let mut sums = vec![[0.0f64; Part::COUNT]; n];
    let mut worst: Vec<Vec<(f64, usize)>> = vec![Vec::new(); n];
    let mut sq = [0.0f64; Part::COUNT];
    for &f in &picked {
        let to = frames[f];
        let motions: Vec<Option<Rigid>> =
            members.iter().map(|m| robust_motion(rest, to, m)).collect();
        for v in 0..n {
            let x = DVec3::from_array(rest[v]);
            let y = DVec3::from_array(to[v]);
            let own = labels[v] as usize;
            for (p, m) in motions.iter().enumerate() {
                let e = m.map_or(f64::INFINITY, |m| m.apply(x).distance(y));
                sums[v][p] += e;
                if p == own {
                    own_sum[v] += e;
                    sq[p] += e * e;
                    if e > opts.stray * h {
                        strays[v] += 1;
                        worst[v].push((e, f));
                    }
                }
            }
        }
    }
    let k = picked.len().max(1);
    let need = ((opts.frames * k as f64).ceil() as usize).max(1);
    Part::ALL
        .iter()
        .map(|p| {
            let vs = &members[p.index()];
            // (the part followed, its vertices, their (miss, frame)s)
            let mut by_target: Vec<Followed> = Vec::new();
            for &v in vs {
                let vi = v as usize;
                if picked.is_empty() || strays[vi] < need {
                    continue;
                }
                let best = (0..Part::COUNT)
                    .filter(|&q| q != p.index())
                    .min_by(|&a, &b| sums[vi][a].total_cmp(&sums[vi][b]));
                let Some(q) = best else { continue };
                if sums[vi][q] > opts.better * own_sum[vi] {
                    continue;
                }
                match by_target.iter_mut().find(|t| t.0 == q) {
                    Some(t) => {
                        t.1.push(v);
                        t.2.extend_from_slice(&worst[vi]);
                    }
                    None => by_target.push((q, vec![v], worst[vi].clone())),
                }
            }
            let stray = by_target
                .into_iter()
                .map(|(q, vertices, mut w)| {
                    // Frames by their total miss over the region.
                    let mut per: std::collections::BTreeMap<usize, f64> = Default::default();
                    for (e, f) in w.drain(..) {
                        *per.entry(f).or_default() += e;
                    }
                    let mut fs: Vec<(usize, f64)> = per.into_iter().collect();
                    fs.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
                    Stray {
                        follows: Part::ALL[q].name(),
                        vertices,
                        frames: fs.into_iter().take(5).map(|x| x.0).collect(),
                    }
                })
                .collect();
            let count = vs.len() * picked.len();
            PartRigidity {
                part: p.name(),
                vertices: vs.len(),
                // Fewer than three vertices have no rigid motion to be
                // off (`rigid_motion`): 0, not an infinite figure (the
                // foot of a leg cut above it kept one vertex).
                rms_percent: if count == 0 || vs.len() < 3 {
                    0.0
                } else {
                    100.0 * (sq[p.index()] / count as f64).sqrt() / h
                },
                stray,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kabsch_recovers_a_rigid_motion_and_flags_a_mislabelled_vertex() {
        // Two "parts": a cube's corners (0) and a second cube (1) far away;
        // part 1 rotates about z, part 0 stays; one vertex of part 1 is
        // labelled 0.
        let cube = |o: [f64; 3]| -> Vec<[f64; 3]> {
            (0..8)
                .map(|i| {
                    [
                        o[0] + (i & 1) as f64 * 0.2,
                        o[1] + ((i >> 1) & 1) as f64 * 0.2,
                        o[2] + ((i >> 2) & 1) as f64 * 0.2,
                    ]
                })
                .collect()
        };
        let mut rest = cube([0.0, 0.0, 0.0]);
        rest.extend(cube([1.0, 0.0, 0.0]));
        let rot = DQuat::from_rotation_z(0.8);
        let centre = DVec3::new(1.1, 0.1, 0.1);
        let frame: Vec<[f64; 3]> = rest
            .iter()
            .enumerate()
            .map(|(v, &x)| {
                let x = DVec3::from_array(x);
                if v < 8 {
                    x
                } else {
                    rot * (x - centre) + centre + DVec3::Y * 0.3
                }
                .to_array()
            })
            .collect();
        let part1: Vec<u32> = (8..16).collect();
        let m = rigid_motion(&rest, &frame, &part1).unwrap();
        for &v in &part1 {
            let e = m
                .apply(DVec3::from_array(rest[v as usize]))
                .distance(DVec3::from_array(frame[v as usize]));
            assert!(e < 1e-9, "vertex {v}: {e}");
        }
        let mut labels = vec![Part::Torso.index() as u8; 8];
        labels.extend(vec![Part::Head.index() as u8; 8]);
        labels[8] = Part::Torso.index() as u8;
        let frames: Vec<&[[f64; 3]]> = vec![&frame, &frame];
        let r = part_rigidity(&labels, &rest, &frames, 1.8, &RigidityOptions::default());
        let torso = &r[Part::Torso.index()];
        assert_eq!(torso.stray.len(), 1, "{torso:?}");
        assert_eq!(torso.stray[0].vertices, vec![8]);
        assert_eq!(torso.stray[0].follows, "head");
        assert!(r[Part::Head.index()].stray.is_empty());
    }
}
