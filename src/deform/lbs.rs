//! Linear blend skinning constraints (Huang et al. 2015, Sec. 5.2.3): the
//! retrieved frame, bound to its own extracted skeleton, is skinned to the
//! query pose with the rig's weights (`synth::database::skin_into`), and the
//! positions of a fixed set of constraint vertices become the soft
//! constraints `x_c` of Eq. 32.

use crate::retarget::character::Character;
use crate::rig::embed::bones_of;
use glam::DVec3;

/// Constraint vertices of a character, chosen once: bound (≥ 95 %) to one
/// bone, projecting into the middle 60 % of that bone on the rest frame
/// (LBS collapses near joints), and not loose (skin no farther from its
/// bone than 1.5× the body's median, see
/// [`crate::synth::database::softness`]: LBS would weld a skirt to a
/// thigh), every `stride`-th such vertex.
pub fn constraint_vertices(ch: &Character, stride: usize) -> Vec<u32> {
    let bones = bones_of(&ch.rig);
    let rest = ch.topology.positions();
    let soft = crate::synth::database::softness(&ch.topology, &ch.rig);
    let mut out = Vec::new();
    let mut count = 0usize;
    for (v, (js, ws)) in ch.rig.skin.iter().enumerate() {
        let (k, w) = ws
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map(|(k, w)| (k, *w))
            .unwrap_or((0, 0.0));
        if w < 0.95 || soft[v] > 0.0 {
            continue;
        }
        let joint = js[k] as usize;
        let Some(b) = bones.iter().find(|b| b.joint.index() == joint) else {
            continue;
        };
        let p = DVec3::from_array(rest[v]);
        let ab = b.b - b.a;
        let t = (p - b.a).dot(ab) / ab.length_squared().max(1e-12);
        if !(0.2..=0.8).contains(&t) {
            continue;
        }
        if count % stride.max(1) == 0 {
            out.push(v as u32);
        }
        count += 1;
    }
    out
}
