//! The decomposition's settled merges (`embed::auto::decompose`,
//! `MergeRule::Settle` and `SettleSplit`, issue 41): on generated tubes
//! bent at two joints and skinned linearly across a band at each (the
//! vertices' motions change continuously there, as a body's do), every
//! k-means draw (`DecomposeOptions::salt`) gives three parts, one per
//! bone, every vertex outside the skinned bands in its bone's part (inside
//! the bands the draws may part the vertices otherwise: their agreement
//! is printed). Two tube resolutions, so that no one mesh is tuned to.

use glam::{DQuat, DVec3};
use surfmotion::embed::auto::consensus::adjusted_rand;
use surfmotion::embed::auto::decompose::{DecomposeOptions, Decomposition, MergeRule, decompose};

/// A tube along +y (length 1, radius 0.05, `rings` rings of 12
/// vertices) bent at y = 1/3 and 2/3 about +z by `angles` per frame,
/// skinned linearly across ±0.03 of each joint (so the vertices'
/// motions change continuously there, as a body's do): the rest
/// positions, the frames and the neighbour lists.
#[allow(clippy::type_complexity)]
fn bent_tube(
    rings: usize,
    angles: &[(f64, f64)],
) -> (Vec<[f64; 3]>, Vec<Vec<[f64; 3]>>, Vec<Vec<u32>>) {
    let seg = 12;
    let mut rest = Vec::new();
    for r in 0..rings {
        let y = r as f64 / (rings - 1) as f64;
        for s in 0..seg {
            let a = std::f64::consts::TAU * s as f64 / seg as f64;
            rest.push([0.05 * a.cos(), y, 0.05 * a.sin()]);
        }
    }
    let mut tris = Vec::new();
    for r in 0..rings - 1 {
        for s in 0..seg {
            let (a, b) = ((r * seg + s) as u32, (r * seg + (s + 1) % seg) as u32);
            let (c, d) = (a + seg as u32, b + seg as u32);
            tris.push([a, b, d]);
            tris.push([a, d, c]);
        }
    }
    let nb = surfmotion::embed::parts::neighbours(rest.len(), &tris);
    let joints = [1.0 / 3.0, 2.0 / 3.0];
    let weight = |y: f64, j: f64| ((y - j) / 0.06 + 0.5).clamp(0.0, 1.0);
    let frames = angles
        .iter()
        .map(|&(a1, a2)| {
            // Bone 1 turns about joint 1; bone 2 with it, and about joint 2.
            let r1 = DQuat::from_rotation_z(a1);
            let r2 = r1 * DQuat::from_rotation_z(a2);
            let j1 = DVec3::new(0.0, joints[0], 0.0);
            let j2 = j1 + r1 * DVec3::new(0.0, joints[1] - joints[0], 0.0);
            rest.iter()
                .map(|&p| {
                    let q = DVec3::from_array(p);
                    let b1 = j1 + r1 * (q - j1);
                    let b2 = j2 + r2 * (q - DVec3::new(0.0, joints[1], 0.0));
                    let (w1, w2) = (weight(q.y, joints[0]), weight(q.y, joints[1]));
                    let p1 = q.lerp(b1, w1);
                    p1.lerp(b2, w2).to_array()
                })
                .collect()
        })
        .collect();
    (rest, frames, nb)
}

/// The part most vertices with y in `lo..hi` of `rest` have.
fn part_of(rest: &[[f64; 3]], labels: &[u32], lo: f64, hi: f64) -> u32 {
    let mut count = std::collections::BTreeMap::new();
    for (p, &l) in rest.iter().zip(labels) {
        if (lo..hi).contains(&p[1]) {
            *count.entry(l).or_insert(0usize) += 1;
        }
    }
    count
        .into_iter()
        .max_by_key(|&(l, c)| (c, std::cmp::Reverse(l)))
        .map_or(u32::MAX, |x| x.0)
}

#[test]
fn settled_parts_are_the_bones_whichever_draw_seeded_them() {
    for (rings, merge) in [
        (61, MergeRule::Settle),
        (73, MergeRule::Settle),
        (61, MergeRule::SettleSplit),
        (73, MergeRule::SettleSplit),
    ] {
        let angles: Vec<(f64, f64)> = (0..12)
            .map(|f| {
                let t = f as f64 / 11.0;
                (0.6 * (3.0 * t).sin(), 0.7 * (2.0 * t + 1.0).cos() - 0.3)
            })
            .collect();
        let (rest, frames, nb) = bent_tube(rings, &angles);
        let frames: Vec<&[[f64; 3]]> = frames.iter().map(Vec::as_slice).collect();
        let runs: Vec<Decomposition> = (0..4)
            .map(|salt| {
                let opts = DecomposeOptions {
                    salt,
                    merge,
                    ..DecomposeOptions::default()
                };
                decompose(&rest, &frames, &nb, 1.0, &opts)
            })
            .collect();
        for (salt, d) in runs.iter().enumerate() {
            // Three bones, each with its own part, the boundaries
            // within the skinned bands (±0.03 of the joints).
            let bones = [
                part_of(&rest, &d.labels, 0.0, 0.3),
                part_of(&rest, &d.labels, 0.37, 0.63),
                part_of(&rest, &d.labels, 0.7, 1.01),
            ];
            assert!(
                bones[0] != bones[1] && bones[1] != bones[2] && bones[0] != bones[2],
                "{rings} rings, {merge:?}, salt {salt}: bones' parts {bones:?} ({} parts)",
                d.count
            );
            for (p, &l) in rest.iter().zip(&d.labels) {
                let want = match p[1] {
                    y if y < 0.3 => bones[0],
                    y if (0.37..0.63).contains(&y) => bones[1],
                    y if y > 0.7 => bones[2],
                    _ => continue,
                };
                assert_eq!(
                    l, want,
                    "{rings} rings, {merge:?}, salt {salt}: a vertex at y {:.3} outside its bone's part",
                    p[1]
                );
            }
            // How far the draws agree inside the bands (printed, not
            // bounded: session 31's first run of this test asked for an
            // adjusted Rand index over 0.99 and salt 1 of 61 rings gave
            // 0.952, the bands' vertices parted otherwise).
            let ari = adjusted_rand(&d.labels, &runs[0].labels);
            eprintln!(
                "{rings} rings, {merge:?}, salt {salt}: {} parts, adjusted Rand index {ari:.4} to salt 0's",
                d.count
            );
        }
    }
}
