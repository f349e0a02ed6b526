//! Which limb of a pair is the left one, from the body's mid-plane and the
//! limbs' motion, none of it from the rigid parts.
//!
//! Each frame the decomposition fits is brought back onto the rest frame
//! by the rigid motion (Kabsch) of a patch of the trunk (the vertices
//! within [`CORE`] of the height, along the surface, of the trunk's seed,
//! where the limbs' paths meet): in the trunk's own frame, a left arm stays
//! left of the body's mid-plane however the body turns. A limb's lateral
//! offset in one frame is the median, over its path from the tip to the
//! expected distance of its root, of its vertices' distance from the
//! mid-plane (through the patch's centroid, normal to the body's left); the
//! limb's offset is the median over the frames and the rest frame. Of a
//! pair, the limb with the greater offset is the left one.
//!
//! The sides were read off one joint per limb before (the hip or knee, the
//! shoulder or elbow: the fixed point of two parts' motion). A joint that
//! barely bends has a loose fixed point: in one draw of the decomposition
//! (crane, `merge=settle,salt=3`) one arm's "shoulder" (a boundary bending
//! 6°) lay 23 cm across the body, on the other arm's side, the arms were
//! swapped and `db init` refused the rig (the left knee on the right of
//! the mid-plane the swapped arms set). The paths do not depend on the
//! parts (geodesics from the tips to the trunk's seed), nor the patch.

use super::decompose::kabsch;
use glam::{DMat3, DVec3};

/// Radius (fraction of the height, along the surface) of the trunk's
/// patch around its seed whose rigid motion takes each frame back onto
/// the rest frame: 12 %, a hand's span on the belly or back (21 cm on a
/// 1.75 m body), short of the limbs' roots.
pub const CORE: f64 = 0.12;

/// The frames the sides are read on, each with the rigid motion of the
/// trunk's patch from the rest frame onto it.
pub struct TrunkFrames<'a> {
    rest: &'a [[f64; 3]],
    frames: &'a [&'a [[f64; 3]]],
    /// Per frame, the patch's motion from the rest frame (rotation,
    /// translation).
    fits: Vec<(DMat3, DVec3)>,
    /// The patch's centroid on the rest frame.
    centre: DVec3,
}

impl<'a> TrunkFrames<'a> {
    /// The frames `frames` (each the rest frame's vertices in order) and
    /// the motion of the trunk's patch `core` (rest-frame vertex ids) onto
    /// each. O(frames × patch).
    pub fn new(rest: &'a [[f64; 3]], frames: &'a [&'a [[f64; 3]]], core: &[u32]) -> Self {
        let fits = frames.iter().map(|f| kabsch(rest, f, core)).collect();
        let k = core.len().max(1) as f64;
        let centre = core
            .iter()
            .map(|&v| DVec3::from_array(rest[v as usize]))
            .sum::<DVec3>()
            / k;
        TrunkFrames {
            rest,
            frames,
            fits,
            centre,
        }
    }

    /// The lateral offset of a limb from the body's mid-plane (positive to
    /// `left`, a unit vector of the rest frame): the median over the rest
    /// frame and every frame (in the trunk's frame) of the median over
    /// `path`'s vertices within `reach` of its tip (vertex, distance from
    /// the tip) of their distance from the mid-plane. O(frames × path).
    pub fn lateral(&self, left: DVec3, path: &[(u32, f64)], reach: f64) -> f64 {
        let on: Vec<u32> = path
            .iter()
            .take_while(|x| x.1 <= reach)
            .map(|x| x.0)
            .collect();
        let on = if on.is_empty() {
            vec![path.first().map_or(0, |x| x.0)]
        } else {
            on
        };
        let mut per_frame = Vec::with_capacity(self.frames.len() + 1);
        let mut d = Vec::with_capacity(on.len());
        let mut read = |at: &dyn Fn(u32) -> DVec3| {
            d.clear();
            d.extend(on.iter().map(|&v| (at(v) - self.centre).dot(left)));
            per_frame.push(crate::embed::midplane::median(&mut d));
        };
        read(&|v| DVec3::from_array(self.rest[v as usize]));
        for (f, (r, t)) in self.frames.iter().zip(&self.fits) {
            let back = r.transpose();
            read(&|v| back * (DVec3::from_array(f[v as usize]) - *t));
        }
        crate::embed::midplane::median(&mut per_frame)
    }
}

/// Whether the first of two limbs is the left one: its lateral offset
/// ([`TrunkFrames::lateral`]) the greater. Returns that and both offsets
/// (first, second).
pub fn first_is_left(
    trunk: &TrunkFrames,
    left: DVec3,
    paths: [&[(u32, f64)]; 2],
    reach: f64,
) -> (bool, [f64; 2]) {
    let s = paths.map(|p| trunk.lateral(left, p, reach));
    (s[0] >= s[1], s)
}
