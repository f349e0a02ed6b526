//! Where the triangles turned over against the rest frame lie (issue 42,
//! session 37): of `retarget` outputs onto the real samba capture, each
//! triangle the surface measure flags, with its frame, part, rest
//! position, nearest joint and whether it is on the cloth, so two
//! deformations' flags can be told apart (which are extra, and where).

use crate::common;

use surfmotion::db::Character;
use surfmotion::rig::Canonical;
use surfmotion::tools::eval::surface::{SurfaceOptions, SurfaceReference, captured_of, frame_ids};

/// Prints every flagged triangle of each PC2 in `SURFACE_TURNED`
/// (comma-separated `retarget -o X.pc2` outputs onto the samba capture
/// built as the tests build it), one line each: `frame triangle part
/// nearest-joint distance-cm cloth dx dy dz` (the rest centroid's offset
/// from that joint, cm). A measurement: prints.
#[test]
#[ignore = "measurement: prints where the turned-over triangles lie"]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn where_the_turned_over_triangles_lie() {
    let Some(d) = common::data_dir() else { return };
    let Ok(list) = std::env::var("SURFACE_TURNED") else {
        eprintln!("SURFACE_TURNED not set: nothing to read");
        return;
    };
    let ch = Character::load(&crate::deform::samba_capture_db(&d), &surfmotion::db::Quiet).unwrap();
    let rest = ch.topology_metres();
    let ids = frame_ids(&ch);
    let reference = SurfaceReference::new(
        captured_of(&ch, rest.positions(), &ids),
        SurfaceOptions::default(),
    )
    .unwrap();
    let tris = rest.triangles();
    let joints = ch.rig().frame_joints(rest.positions());
    let soft = surfmotion::deform::soft::softness(ch.topology(), ch.rig());
    let n = ch.n();
    for path in list.split(',') {
        let pc = surfmotion::mesh::io::pc2::read_pc2(std::path::Path::new(path)).unwrap();
        assert_eq!(pc.points, n, "{path}: not a result on this database");
        let mut total = 0;
        for (f, frame) in pc.positions.chunks_exact(n).enumerate() {
            for t in reference.turned_rest_triangles(frame) {
                total += 1;
                let c = tris[t as usize]
                    .iter()
                    .map(|&v| glam::DVec3::from_array(rest.positions()[v as usize]))
                    .sum::<glam::DVec3>()
                    / 3.0;
                let (j, dist) = Canonical::ALL
                    .iter()
                    .map(|j| (*j, (c - joints[j.index()]).length()))
                    .min_by(|a, b| a.1.total_cmp(&b.1))
                    .unwrap();
                let v0 = tris[t as usize][0] as usize;
                let part = surfmotion::embed::parts::Part::ALL[ch.rig().labels()[v0] as usize];
                let cloth = tris[t as usize].iter().any(|&v| soft[v as usize] > 0.0);
                let o = 100.0 * (c - joints[j.index()]);
                eprintln!(
                    "{path} {f} {t} {} {} {:.1} {} {:.1} {:.1} {:.1}",
                    part.name(),
                    j.name(),
                    100.0 * dist,
                    cloth,
                    o.x,
                    o.y,
                    o.z
                );
            }
        }
        eprintln!("{path}: {total} triangle-frames turned over against the rest frame");
    }
}
