//! The hands of a rig whose wrists are the automatic rig's (issue 41).
//! Samba's landmark fixture with only its two wrists moved to where the
//! automatic rig puts them (1.3-1.6 % of the height away) once sank a
//! retargeted CMU 02_02 by 16 cm: the left hand's tip (the farthest vertex
//! beyond the wrist) was taken on the skirt at the hip, 16 cm from the
//! fingers, and bone heat gave the hip and skirt to the hand (its bone's
//! total weight 265 → 684 vertices' worth). Here, on samba and on generated
//! variants (mirrored, Z-up, cm), each hand's tip must lie within 3 % of
//! the height of the fixture rig's and each hand bone's total skin weight
//! within 10 % of it.

use crate::common;

use glam::DVec3;
use surfmotion::embed::Embedding;
use surfmotion::embed::landmarks::Landmarks;
use surfmotion::mesh::Mesh;
use surfmotion::rig::Canonical;

/// The automatic rig's wrists on samba (`db init` without landmarks,
/// `auto.landmarks.json`, session 21's code and this one's).
const AUTO_WRISTS: [(&str, [f64; 3]); 2] = [
    ("l_wrist", [0.53695, 0.97152, -0.33711]),
    ("r_wrist", [0.4219, 0.96328, 0.30355]),
];

/// Bound on a hand tip's distance, % of the height.
const TIP_BOUND: f64 = 3.0;
/// Bound on a hand bone's total skin weight, relative.
const WEIGHT_BOUND: f64 = 0.10;

/// `lm`'s JSON with every point mapped by `f` and, when `swap`, the left
/// and right names exchanged (a mirrored body's left is the fixture's
/// right).
fn landmarks_json(lm: &serde_json::Value, f: &dyn Fn([f64; 3]) -> [f64; 3], swap: bool) -> String {
    let mut out = serde_json::Map::new();
    for (k, v) in lm.as_object().unwrap() {
        let k = match (swap, k.strip_prefix("l_"), k.strip_prefix("r_")) {
            (true, Some(r), _) => format!("r_{r}"),
            (true, _, Some(l)) => format!("l_{l}"),
            _ => k.clone(),
        };
        let v = match v.as_array() {
            Some(a) => {
                let p = [0, 1, 2].map(|i| a[i].as_f64().unwrap());
                serde_json::json!(f(p))
            }
            None => v.clone(),
        };
        out.insert(k, v);
    }
    serde_json::Value::Object(out).to_string()
}

/// The total skin weight on each hand's bone (left, right).
fn hand_weights(e: &Embedding) -> [f64; 2] {
    let on = |j: Canonical| {
        e.skin()
            .iter()
            .map(|(b, w)| {
                b.iter()
                    .zip(w)
                    .filter(|(b, _)| **b as usize == j.index())
                    .map(|(_, w)| *w)
                    .sum::<f64>()
            })
            .sum::<f64>()
    };
    [on(Canonical::LWrist), on(Canonical::RWrist)]
}

#[test]
#[cfg_attr(no_shared_data, ignore = "needs ../shared/data (set SURFMOTION_DATA)")]
fn the_automatic_wrists_keep_the_hands_on_the_hands() {
    let Some(d) = common::data_dir() else { return };
    let c = super::auto::capture(&d, "samba");
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/samba.landmarks.json"),
    )
    .unwrap();
    let mut lm: serde_json::Value = serde_json::from_str(&text).unwrap();
    for (k, p) in AUTO_WRISTS {
        lm[k] = serde_json::json!(p);
    }
    let h = c.truth.height();
    let truth_w = hand_weights(&c.truth);
    type Point = fn([f64; 3]) -> [f64; 3];
    let variants: [(&str, Point, bool, f64); 4] = [
        ("samba", |p| p, false, 1.0),
        ("mirrored", |p| [-p[0], p[1], p[2]], true, 1.0),
        ("Z-up", |p| [p[0], -p[2], p[1]], false, 1.0),
        ("cm", |p| p.map(|x| 100.0 * x), false, 100.0),
    ];
    for (what, f, swap, scale) in variants {
        let mut tris = c.mesh.triangles().to_vec();
        if swap {
            for t in &mut tris {
                t.swap(1, 2);
            }
        }
        let m = Mesh::new(c.mesh.positions().iter().map(|p| f(*p)).collect(), tris).unwrap();
        let marks = Landmarks::parse(
            &landmarks_json(&lm, &f, swap),
            std::path::Path::new("auto-wrists.json"),
            m.vertex_count(),
        )
        .unwrap();
        let e = Embedding::new(&m, &marks, None).unwrap();
        let w = hand_weights(&e);
        for (k, &wk) in w.iter().enumerate() {
            let t = if swap { 1 - k } else { k };
            let tip = DVec3::from_array(e.hand_tips()[k]);
            let want = DVec3::from_array(f(c.truth.hand_tips()[t]));
            let off = 100.0 * tip.distance(want) / (h * scale);
            let rel = (wk - truth_w[t]).abs() / truth_w[t];
            assert!(
                off <= TIP_BOUND && rel <= WEIGHT_BOUND,
                "{what}, hand {k}: tip {off:.2}% of the height from the fixture rig's (bound {TIP_BOUND}%), hand bone weight {:.0} against {:.0} ({:.0}% apart, bound {:.0}%)",
                wk,
                truth_w[t],
                100.0 * rel,
                100.0 * WEIGHT_BOUND
            );
        }
    }
}
