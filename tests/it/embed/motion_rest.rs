//! Skin weights from motion from two rest frames (issue 41): the crane
//! capture rigged on its upright frame 0 and on its bent frame 64 (the
//! fixtures `crane.landmarks.json`, `crane64.landmarks.json`), each with
//! the weights fitted to every fifth frame (as a database of those frames
//! embeds it). The fit must not move the part boundaries along the blend
//! zones of the joints: with one rigid motion for the whole (bending)
//! torso it handed the pelvis ring to the thighs, and the torso's slab at
//! the pelvis — the hips of the head-to-torso measure — shrank from 271 to
//! 59 vertices on frame 0 and from 294 to 137 on frame 64, which moved the
//! crane's head figures apart (`pose::character_neutral`). Labels the two
//! rigs disagree on must not grow either.

use crate::common;

use glam::DVec3;
use surfmotion::embed::Embedding;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::mesh::io::{LoadOptions, load_sequence};
use surfmotion::rig::Canonical as C;
use surfmotion::tools::eval::head::{HeadOptions, HeadTorso};

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn fitted_weights_keep_the_part_boundaries_and_agree_across_rest_frames() {
    let Some(d) = common::data_dir() else { return };
    let seq = load_sequence(
        d.join("4d/crane/crane.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    let frames: Vec<&[[f64; 3]]> = (0..seq.frame_count())
        .step_by(5)
        .map(|f| seq.frame(f))
        .collect();
    let fixtures = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures");
    let mut rigs = Vec::new();
    for (rest, file) in [(0, "crane.landmarks.json"), (64, "crane64.landmarks.json")] {
        let mesh = seq.mesh().with_positions(seq.frame(rest)).unwrap();
        let lm = Landmarks::load(&fixtures.join(file), mesh.vertex_count()).unwrap();
        let heat = Embedding::new(&mesh, &lm, None).unwrap();
        let moving = Embedding::new_moving(&mesh, &lm, None, &frames).unwrap();
        assert!(
            moving
                .notes()
                .iter()
                .any(|n| n.contains("fitted to the motion")),
            "{:?}",
            moving.notes()
        );
        let hips = |e: &Embedding| {
            let pelvis = DVec3::from_array(e.joints()[C::Pelvis.index()]);
            HeadTorso::with_pelvis(
                mesh.positions(),
                e.labels(),
                DVec3::Y,
                Some(pelvis),
                &HeadOptions::default(),
            )
            .unwrap()
            .hips
            .len()
        };
        let (hh, hm) = (hips(&heat), hips(&moving));
        let relabelled = heat
            .labels()
            .iter()
            .zip(moving.labels())
            .filter(|(a, b)| a != b)
            .count();
        println!(
            "crane rest {rest}: hips slab {hh} → {hm} vertices; {relabelled} vertices relabelled by the fit"
        );
        assert!(hm * 10 >= hh * 9, "rest {rest}: hips {hh} → {hm}");
        rigs.push((heat, moving));
    }
    let differ = |a: &Embedding, b: &Embedding| {
        a.labels()
            .iter()
            .zip(b.labels())
            .filter(|(x, y)| x != y)
            .count()
    };
    let (h, m) = (
        differ(&rigs[0].0, &rigs[1].0),
        differ(&rigs[0].1, &rigs[1].1),
    );
    println!("labels differing between the two rest frames' rigs: bone heat {h}, fitted {m}");
    assert!(m <= h, "{h} → {m}");
}
