//! Which vertices the cloth stitch ([`super::cloth`]) solves: the cloth
//! ([`super::soft::softness`] above 0) grown by
//! [`super::DeformOptions::cloth_rings`] rings of vertices (issue 42).
//!
//! Softness marks the skirt where it hangs away from the bones (1.5-2.5
//! times the body's median skin-to-bone distance); the skirt's top, the
//! waist and the thighs' skin under it lie closer and are not cloth, yet
//! they belong to the same overlapping pelvis and thigh regions whose
//! blended results step between one solve and the next
//! ([`super::regions`]). Grown by `k` rings, the stitch solves those
//! vertices too — their captured Laplacian coordinates turned by rotations
//! fitted to the blended surface (Sorkine & Alexa 2007, Eq. 6), pulled to
//! the blend — and holds the ring beyond them at the blend.

use crate::embed::Embedding;
use crate::embed::parts::Part;

/// Which joints' blend zones the stitch solves besides the cloth
/// ([`super::DeformOptions::stitch_joints`]): the vertices a part's region
/// shares with its parent's (the knee: the thigh's and shin's regions),
/// where the two solves' results are blended by skin weight.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StitchJoints {
    /// None (the cloth alone).
    #[default]
    None,
    /// The knees.
    Knees,
    /// The knees, elbows, hips and shoulders.
    Limbs,
}

impl StitchJoints {
    /// The (parent, child) parts whose shared vertices are stitched.
    fn pairs(self) -> &'static [(Part, Part)] {
        use Part::*;
        match self {
            StitchJoints::None => &[],
            StitchJoints::Knees => &[(LThigh, LShin), (RThigh, RShin)],
            StitchJoints::Limbs => &[
                (LThigh, LShin),
                (RThigh, RShin),
                (LUpperArm, LForearm),
                (RUpperArm, RForearm),
                (Torso, LThigh),
                (Torso, RThigh),
                (Torso, LUpperArm),
                (Torso, RUpperArm),
            ],
        }
    }
}

/// The vertices in both regions of each joint `which` names (a region:
/// [`Embedding::regions`] and the vertices labelled with the part), one
/// flag per vertex of the rig's mesh.
pub(crate) fn joint_zones(rig: &Embedding, which: StitchJoints) -> Vec<bool> {
    let n = rig.labels.len();
    let member = |p: Part| {
        let mut m: Vec<bool> = rig
            .labels
            .iter()
            .map(|&l| l as usize == p.index())
            .collect();
        for &v in rig.regions.get(p.index()).map(Vec::as_slice).unwrap_or(&[]) {
            if let Some(x) = m.get_mut(v as usize) {
                *x = true;
            }
        }
        m
    };
    let mut on = vec![false; n];
    for &(a, b) in which.pairs() {
        let (ma, mb) = (member(a), member(b));
        for v in 0..n {
            on[v] |= ma[v] && mb[v];
        }
    }
    on
}

/// `cloth` (one flag per vertex) grown by `rings` rings of vertices over
/// the mesh's `triangles`; `cloth` itself when `rings` is 0 or nothing is
/// marked. Triangles naming a vertex beyond `cloth` are skipped.
pub(crate) fn grown(triangles: &[[u32; 3]], cloth: &[bool], rings: usize) -> Vec<bool> {
    let n = cloth.len();
    let mut on = cloth.to_vec();
    for _ in 0..rings {
        let last = on.clone();
        for t in triangles {
            if t.iter().any(|&v| v as usize >= n) {
                continue;
            }
            if t.iter().any(|&v| last[v as usize]) {
                for &v in t {
                    on[v as usize] = true;
                }
            }
        }
    }
    on
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `k` vertices in a row, two per column: one ring reaches
    /// the next column on each side (and no further), two rings two
    /// columns; a bad index is skipped; 0 rings changes nothing.
    #[test]
    fn rings_reach_one_column_each() {
        let k = 8u32;
        let mut tris = Vec::new();
        for c in 0..k - 1 {
            let (a, b, c2, d) = (2 * c, 2 * c + 1, 2 * c + 2, 2 * c + 3);
            tris.push([a, c2, b]);
            tris.push([b, c2, d]);
        }
        tris.push([0, 1, 99]);
        let n = 2 * k as usize;
        let mut cloth = vec![false; n];
        cloth[8] = true; // column 4
        let col = |m: &[bool]| -> Vec<u32> {
            let mut c: Vec<u32> = (0..n).filter(|&v| m[v]).map(|v| v as u32 / 2).collect();
            c.dedup();
            c
        };
        assert_eq!(col(&grown(&tris, &cloth, 0)), vec![4]);
        assert_eq!(col(&grown(&tris, &cloth, 1)), vec![3, 4, 5]);
        assert_eq!(col(&grown(&tris, &cloth, 2)), vec![2, 3, 4, 5, 6]);
        assert_eq!(grown(&tris, &vec![false; n], 3), vec![false; n]);
    }
}
