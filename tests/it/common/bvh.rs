//! BVH variants for the readers' and the kernel's tests.

use std::path::Path;
use surfmotion::mocap::bvh::{read_bvh, write_bvh};
use surfmotion::mocap::{Channel, Clip};

/// `src` (a BVH) written to `out` with every joint's rotation channels in
/// the order X Y Z, its rotations unchanged (the writer re-expresses the
/// values in the declared order). Returns how many joints' rotation order
/// changed.
pub fn in_xyz_order(src: &Path, out: &Path) -> usize {
    let mut clip = read_bvh(src, &Default::default()).unwrap().into_parts();
    let rot = [Channel::Xrotation, Channel::Yrotation, Channel::Zrotation];
    let mut changed = 0;
    for j in &mut clip.joints {
        let pos: Vec<Channel> = j
            .channels
            .iter()
            .copied()
            .filter(|c| !c.is_rotation())
            .collect();
        if pos.len() == j.channels.len() {
            continue;
        }
        changed += usize::from(j.channels.iter().filter(|c| c.is_rotation()).ne(rot.iter()));
        j.channels = pos.into_iter().chain(rot).collect();
    }
    write_bvh(&Clip::from_parts(clip).unwrap(), out).unwrap();
    changed
}
