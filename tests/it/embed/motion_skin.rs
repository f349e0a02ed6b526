//! Skin weights from motion (issue 41): samba re-ordered so that a frame
//! where a forearm lies against the belly comes first, its topology that
//! frame and the landmark fixture carried onto it, the rig embedded on
//! that contact frame itself (as `db init --keep-rest-frame` does). Bone
//! heat alone gives the belly weight on the forearm (the ridge of the
//! issue); fitted to the sequence's motion
//! ([`surfmotion::embed::motion_weights`]) the belly follows the torso.
//! Variant: re-ordered (mirrored and cm not yet: see the test).

use crate::common;

use std::path::Path;
use surfmotion::embed::Embedding;
use surfmotion::embed::contact::{ContactFinder, ContactOptions};
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::embed::parts::Part;
use surfmotion::mesh::io::{LoadOptions, load_sequence};
use surfmotion::mesh::{Mesh, MeshSequence};
use surfmotion::rig::Canonical;

fn is_forearm(l: u8) -> bool {
    l as usize == Part::LForearm.index() || l as usize == Part::RForearm.index()
}

/// A vertex's skin weight on the forearms' joints (elbows, wrists).
fn forearm_weight(e: &Embedding, v: usize) -> f64 {
    let (j, w) = e.skin()[v];
    j.iter()
        .zip(w)
        .filter(|(j, _)| {
            let c = Canonical::ALL[**j as usize];
            matches!(Part::of_joint(c), Part::LForearm | Part::RForearm)
        })
        .map(|(_, w)| w)
        .sum()
}

/// The frame whose contacts between a forearm and the torso (sides named
/// by `labels`) touch the most torso vertices, and those torso vertices.
fn forearm_on_belly(seq: &MeshSequence, labels: &[u8]) -> (usize, Vec<u32>) {
    let finder = ContactFinder::new(&seq.frame_mesh(0), ContactOptions::default());
    let torso = Part::Torso.index() as u8;
    let major = |side: &[u32]| {
        let mut votes = [0usize; Part::COUNT];
        side.iter()
            .for_each(|&v| votes[labels[v as usize] as usize] += 1);
        (0..Part::COUNT).max_by_key(|&k| votes[k]).unwrap() as u8
    };
    let mut best = (0, Vec::new());
    for f in 0..seq.frame_count() {
        let found = finder.find(seq.frame(f));
        let mut belly = Vec::new();
        for c in &found.contacts {
            let sides: Vec<u8> = c.sides.iter().map(|s| major(s)).collect();
            if sides.iter().any(|&l| is_forearm(l)) {
                for (s, &l) in c.sides.iter().zip(&sides) {
                    if l == torso {
                        belly.extend(s.iter().filter(|&&v| labels[v as usize] == torso));
                    }
                }
            }
        }
        if belly.len() > best.1.len() {
            best = (f, belly);
        }
    }
    best
}

/// The sequence re-ordered to start at `first`, each position mapped by
/// `map`, triangles flipped when `flip`.
fn variant(
    seq: &MeshSequence,
    first: usize,
    map: &dyn Fn([f64; 3]) -> [f64; 3],
    flip: bool,
) -> MeshSequence {
    let n = seq.mesh().vertex_count();
    let nf = seq.frame_count();
    let mut frames = Vec::with_capacity(nf * n);
    for k in 0..nf {
        frames.extend(seq.frame((first + k) % nf).iter().map(|p| map(*p)));
    }
    let tris: Vec<[u32; 3]> = seq
        .mesh()
        .triangles()
        .iter()
        .map(|t| if flip { [t[0], t[2], t[1]] } else { *t })
        .collect();
    let pos: Vec<[f64; 3]> = frames[..n].to_vec();
    MeshSequence::new(Mesh::new(pos, tris).unwrap(), frames, seq.fps).unwrap()
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn belly_vertices_are_not_weighted_to_a_forearm_after_a_contact_rest_frame() {
    let Some(d) = common::data_dir() else { return };
    let seq = load_sequence(
        d.join("4d/samba/samba.pc2").to_str().unwrap(),
        &LoadOptions::default(),
    )
    .unwrap();
    let n = seq.mesh().vertex_count();
    let clear = seq.frame_mesh(0);
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/samba.landmarks.json");
    let lm = Landmarks::load(&fixture, n).unwrap();
    let truth = Embedding::new(&clear, &lm, None).unwrap();
    let (contact, belly) = forearm_on_belly(&seq, truth.labels());
    assert!(
        belly.len() >= 20,
        "samba has a frame with a forearm on the belly: frame {contact}, {} belly vertices",
        belly.len()
    );
    let torso: Vec<usize> = (0..n)
        .filter(|&v| truth.labels()[v] as usize == Part::Torso.index())
        .collect();
    // Mirrored and cm variants are not here yet: `Landmarks::moved` keeps
    // the fixture's point landmarks (the groin) where they were, so the
    // rig of a mirrored or scaled body is refused or wrong (measured: groin
    // off the surface in cm; parts 40 % in agreement mirrored).
    #[allow(clippy::type_complexity)]
    let variants: [(&str, Box<dyn Fn([f64; 3]) -> [f64; 3]>, bool); 1] =
        [("re-ordered", Box::new(|p| p), false)];
    for (name, map, flip) in &variants {
        let var = variant(&seq, contact, map.as_ref(), *flip);
        let topo = var.mesh().clone();
        let on_clear = variant(&seq, 0, map.as_ref(), *flip);
        let lm_var = lm.moved(
            on_clear.mesh().positions(),
            topo.positions(),
            topo.triangles(),
        );
        let frames: Vec<&[[f64; 3]]> = (0..var.frame_count()).map(|f| var.frame(f)).collect();
        let t0 = std::time::Instant::now();
        let heat = Embedding::new(&topo, &lm_var, None).unwrap();
        let t1 = t0.elapsed().as_secs_f64();
        let moving = Embedding::new_moving(&topo, &lm_var, None, &frames).unwrap();
        let t2 = t0.elapsed().as_secs_f64() - t1;
        let stats = |e: &Embedding, set: &[usize]| {
            let w: Vec<f64> = set.iter().map(|&v| forearm_weight(e, v)).collect();
            let over = w.iter().filter(|&&x| x > 0.1).count();
            let labelled = set.iter().filter(|&&v| is_forearm(e.labels()[v])).count();
            (w.iter().sum::<f64>() / w.len() as f64, over, labelled)
        };
        let belly: Vec<usize> = belly.iter().map(|&v| v as usize).collect();
        let (hb, ho, hl) = stats(&heat, &belly);
        let (mb, mo, ml) = stats(&moving, &belly);
        let (ht, hto, _) = stats(&heat, &torso);
        let (mt, mto, _) = stats(&moving, &torso);
        let agree = |e: &Embedding| {
            e.labels()
                .iter()
                .zip(truth.labels())
                .filter(|(a, b)| a == b)
                .count() as f64
                / n as f64
        };
        eprintln!(
            "samba {name}, frame {contact} first, {} belly vertices: forearm weight mean {hb:.3} → {mb:.3}, \
             > 0.1 on {ho} → {mo}, labelled forearm {hl} → {ml}; all {} torso vertices: mean {ht:.4} → {mt:.4}, > 0.1 on {hto} → {mto}; \
             parts agree with the clear rig {:.1} % → {:.1} %; bone heat {t1:.2} s, with motion {t2:.2} s",
            belly.len(),
            torso.len(),
            100.0 * agree(&heat),
            100.0 * agree(&moving),
        );
        // Bone heat alone wires the contact in (what the test guards
        // against is there to be removed).
        assert!(
            ho * 4 >= belly.len(),
            "{name}: heat gives the belly {ho} forearm-weighted vertices"
        );
        // From motion: at most 3 % of the belly keeps a forearm weight
        // over 0.1 (the fit per segment: 3 of 106, mean 0.038; per part it
        // was 1, mean 0.012, but it moved the part boundaries: see
        // `embed::motion_rest`), none is labelled forearm.
        assert!(
            mo * 100 <= 3 * belly.len(),
            "{name}: {mo} of {} belly vertices",
            belly.len()
        );
        assert!(mb <= 0.05, "{name}: belly forearm weight {hb} → {mb}");
        assert_eq!(ml, 0, "{name}: belly vertices labelled forearm");
        assert!(mto <= hto, "{name}: torso {hto} → {mto}");
    }
}
