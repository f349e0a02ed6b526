//! Body parts: a label per vertex from the skin weights, made contiguous,
//! and overlapping part regions (Huang et al. 2015, Sec. 3 and Fig. 9: the
//! paper marks parts by hand; here they follow from the embedded skeleton).

use super::heat::Weights;
use crate::rig::Canonical;
use serde::{Deserialize, Serialize};

/// A body part: the vertices that move with one or two joints.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[allow(missing_docs)]
pub enum Part {
    Torso,
    Head,
    LUpperArm,
    LForearm,
    RUpperArm,
    RForearm,
    LThigh,
    LShin,
    LFoot,
    RThigh,
    RShin,
    RFoot,
}

impl Part {
    /// All parts, the torso first, then outwards (the order of the
    /// hierarchical part-based deformation).
    pub const ALL: [Part; 12] = [
        Part::Torso,
        Part::Head,
        Part::LUpperArm,
        Part::LForearm,
        Part::RUpperArm,
        Part::RForearm,
        Part::LThigh,
        Part::LShin,
        Part::LFoot,
        Part::RThigh,
        Part::RShin,
        Part::RFoot,
    ];

    /// Number of parts.
    pub const COUNT: usize = 12;

    /// Index into [`Part::ALL`].
    pub fn index(self) -> usize {
        self as usize
    }

    /// snake_case name.
    pub fn name(self) -> &'static str {
        match self {
            Part::Torso => "torso",
            Part::Head => "head",
            Part::LUpperArm => "l_upper_arm",
            Part::LForearm => "l_forearm",
            Part::RUpperArm => "r_upper_arm",
            Part::RForearm => "r_forearm",
            Part::LThigh => "l_thigh",
            Part::LShin => "l_shin",
            Part::LFoot => "l_foot",
            Part::RThigh => "r_thigh",
            Part::RShin => "r_shin",
            Part::RFoot => "r_foot",
        }
    }

    /// Parses a name.
    pub fn from_name(s: &str) -> Option<Part> {
        Part::ALL.into_iter().find(|p| p.name() == s)
    }

    /// The part the bones driven by `j` belong to.
    pub fn of_joint(j: Canonical) -> Part {
        use Canonical as C;
        match j {
            C::Pelvis | C::Spine | C::Chest => Part::Torso,
            C::Neck | C::Head => Part::Head,
            C::LShoulder => Part::LUpperArm,
            C::LElbow | C::LWrist => Part::LForearm,
            C::RShoulder => Part::RUpperArm,
            C::RElbow | C::RWrist => Part::RForearm,
            C::LHip => Part::LThigh,
            C::LKnee => Part::LShin,
            C::LAnkle | C::LToe => Part::LFoot,
            C::RHip => Part::RThigh,
            C::RKnee => Part::RShin,
            C::RAnkle | C::RToe => Part::RFoot,
        }
    }

    /// The part this one hangs from (`None` for the torso).
    pub fn parent(self) -> Option<Part> {
        Some(match self {
            Part::Torso => return None,
            Part::Head | Part::LUpperArm | Part::RUpperArm | Part::LThigh | Part::RThigh => {
                Part::Torso
            }
            Part::LForearm => Part::LUpperArm,
            Part::RForearm => Part::RUpperArm,
            Part::LShin => Part::LThigh,
            Part::LFoot => Part::LShin,
            Part::RShin => Part::RThigh,
            Part::RFoot => Part::RShin,
        })
    }
}

/// Per-vertex weight of each part (sum of its joints' weights).
pub(crate) fn part_weights(w: &Weights) -> Vec<[f64; Part::COUNT]> {
    w.iter()
        .map(|row| {
            let mut p = [0.0; Part::COUNT];
            for j in Canonical::ALL {
                p[Part::of_joint(j).index()] += row[j.index()];
            }
            p
        })
        .collect()
}

/// Vertex neighbours from triangles.
pub fn neighbours(n: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut nb = vec![Vec::new(); n];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            nb[a as usize].push(b);
            nb[b as usize].push(a);
        }
    }
    for v in &mut nb {
        v.sort_unstable();
        v.dedup();
    }
    nb
}

/// Connected pieces of the vertices labelled `part`.
fn pieces(labels: &[u8], nb: &[Vec<u32>], part: u8) -> Vec<Vec<u32>> {
    let mut seen = vec![false; labels.len()];
    let mut out = Vec::new();
    for s in 0..labels.len() {
        if labels[s] != part || seen[s] {
            continue;
        }
        seen[s] = true;
        let mut stack = vec![s as u32];
        let mut piece = Vec::new();
        while let Some(v) = stack.pop() {
            piece.push(v);
            for &u in &nb[v as usize] {
                if labels[u as usize] == part && !seen[u as usize] {
                    seen[u as usize] = true;
                    stack.push(u);
                }
            }
        }
        out.push(piece);
    }
    out
}

/// Labels each vertex with its heaviest part, then makes every part one
/// connected region: each stray island of a part joins the neighbouring part
/// it shares most edges with. Repeats until nothing changes.
pub(crate) fn contiguous_labels(pw: &[[f64; Part::COUNT]], nb: &[Vec<u32>]) -> Vec<u8> {
    let mut labels: Vec<u8> = pw
        .iter()
        .map(|row| {
            (0..Part::COUNT)
                .max_by(|&a, &b| row[a].total_cmp(&row[b]))
                .unwrap_or(0) as u8
        })
        .collect();
    make_contiguous(&mut labels, nb);
    labels
}

/// Merges every part's islands but the largest into their neighbours.
pub(crate) fn make_contiguous(labels: &mut [u8], nb: &[Vec<u32>]) {
    for _ in 0..32 {
        let mut changed = false;
        for p in 0..Part::COUNT as u8 {
            let mut ps = pieces(labels, nb, p);
            if ps.len() < 2 {
                continue;
            }
            ps.sort_by_key(|x| std::cmp::Reverse(x.len()));
            for island in &ps[1..] {
                let mut votes = [0usize; Part::COUNT];
                for &v in island {
                    for &u in &nb[v as usize] {
                        let l = labels[u as usize];
                        if l != p {
                            votes[l as usize] += 1;
                        }
                    }
                }
                let best = (0..Part::COUNT).max_by_key(|&k| votes[k]).unwrap_or(0);
                if votes[best] == 0 {
                    continue;
                }
                for &v in island {
                    labels[v as usize] = best as u8;
                }
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
}

/// Number of connected pieces of each part (1 for a contiguous part, 0 for
/// an empty one).
pub fn piece_counts(labels: &[u8], nb: &[Vec<u32>]) -> [usize; Part::COUNT] {
    std::array::from_fn(|p| pieces(labels, nb, p as u8).len())
}

/// Overlapping regions: a part's region is its labelled vertices plus every
/// vertex where the part's weight is at least `min` (so the leg regions of
/// a skirted character reach into the skirt, as in Huang's Fig. 9), joined
/// to them along the mesh's edges (`nb`, [`neighbours`]): a piece of such
/// weight apart from the part is left out. The deformation solves each
/// region's Laplacian held by its seam with the parent region and its
/// constraint vertices; a piece apart has neither and floats (on samba
/// rigged on its contact frame 155 with the skin fitted to motion, vertex
/// 5142, alone in the right forearm's region, left its one-ring by 98 cm
/// in a retarget of CMU 02_02).
pub fn regions(
    labels: &[u8],
    pw: &[[f64; Part::COUNT]],
    min: f64,
    nb: &[Vec<u32>],
) -> Vec<Vec<u32>> {
    (0..Part::COUNT)
        .map(|p| {
            let inside: Vec<bool> = (0..labels.len())
                .map(|v| labels[v] as usize == p || pw[v][p] >= min)
                .collect();
            joined_to_part(labels, p as u8, &inside, nb)
        })
        .collect()
}

/// The vertices of `inside` reached from those labelled `part` along
/// edges between vertices of `inside`, sorted.
fn joined_to_part(labels: &[u8], part: u8, inside: &[bool], nb: &[Vec<u32>]) -> Vec<u32> {
    let mut seen: Vec<bool> = labels.iter().map(|&l| l == part).collect();
    let mut stack: Vec<u32> = (0..labels.len() as u32)
        .filter(|&v| seen[v as usize])
        .collect();
    while let Some(v) = stack.pop() {
        for &u in &nb[v as usize] {
            if inside[u as usize] && !seen[u as usize] {
                seen[u as usize] = true;
                stack.push(u);
            }
        }
    }
    (0..labels.len() as u32)
        .filter(|&v| seen[v as usize])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn islands_join_their_neighbours() {
        // A path 0-1-2-3-4-5 labelled 0 0 1 0 1 1: part 0 has two pieces.
        let tris: Vec<[u32; 3]> = (0..5).map(|i| [i, i + 1, i]).collect();
        let nb = neighbours(6, &tris);
        let mut l = vec![0u8, 0, 1, 0, 1, 1];
        make_contiguous(&mut l, &nb);
        let c = piece_counts(&l, &nb);
        assert!(c[0] <= 1 && c[1] <= 1, "{l:?}");
        assert!(Part::ALL.iter().enumerate().all(|(i, p)| p.index() == i));
        assert_eq!(Part::of_joint(Canonical::LKnee), Part::LShin);
    }
}
