//! `autorig_eval … tips`: where the body's extremities are sought from
//! (issue 41, [`crate::embed::auto::guard`]). Every frame of samba, crane
//! and samba without hands (the forearm parts beyond the wrists cut off)
//! taken as the rest: the five tips from the vertex nearest the centroid,
//! from the geodesic centre and by the guard, each right when they lie on
//! the landmark rig's feet, forearms and head parts, with no sixth; the
//! guard's measures (the centroid's vertex's distance to a tip found from
//! the centre, the sixths' scores), least and greatest where the
//! centroid's tips are right and where they are wrong.

use super::autorig::AutorigReport;
use super::autorig_headless::capture_with_rig;
use crate::embed::Embedding;
use crate::embed::auto::branches::{Tips, body_tips, sixth_limit};
use crate::embed::auto::centre::TipSeed;
use crate::embed::parts::{Part, neighbours};
use crate::rig::Canonical;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::Path;

/// The hands cut off (`embed::auto_branches`' cut): the forearm parts'
/// vertices more than 1 % of the height beyond the wrist.
fn without_hands(rig: &Embedding, rest: &[[f64; 3]]) -> Vec<bool> {
    let j = |c: Canonical| DVec3::from_array(rig.joints()[c.index()]);
    let arms = [
        (j(Canonical::LElbow), j(Canonical::LWrist), Part::LForearm),
        (j(Canonical::RElbow), j(Canonical::RWrist), Part::RForearm),
    ];
    (0..rest.len())
        .map(|v| {
            let q = DVec3::from_array(rest[v]);
            let part = rig.labels()[v] as usize;
            !arms.iter().any(|(e, w, arm)| {
                part == arm.index() && (q - *w).dot((*w - *e).normalize()) > 0.01 * rig.height()
            })
        })
        .collect()
}

/// The parts (label bytes, sorted) that the body's five tips lie on: the
/// head, the feet and the forearms.
pub fn five_on_extremities() -> Vec<u8> {
    let mut want: Vec<u8> = [
        Part::Head,
        Part::LFoot,
        Part::RFoot,
        Part::LForearm,
        Part::RForearm,
    ]
    .iter()
    .map(|p| p.index() as u8)
    .collect();
    want.sort_unstable();
    want
}

/// The five tips lie on the feet, the forearms and the head, no sixth.
fn right(t: &Tips, labels: &[u8]) -> bool {
    let want = five_on_extremities();
    let mut got: Vec<u8> = t.five.iter().map(|&(v, _)| labels[v as usize]).collect();
    got.sort_unstable();
    got == want && t.sixth.is_none()
}

/// Least and greatest of `x` (NaN for none).
fn span(x: &[f64]) -> String {
    let lo = x.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if x.is_empty() {
        "–".into()
    } else {
        format!("{lo:.2}-{hi:.2}")
    }
}

/// The evaluation (see the module).
pub fn evaluate_tips(data: &Path) -> AutorigReport {
    let mut w = AutorigReport {
        tables: String::new(),
        details: String::new(),
    };
    let _ = writeln!(
        w.tables,
        "| capture | frames | wrong from the centroid's vertex | wrong from the centre | wrong guarded | centre kept by the guard | seed to a centre tip (× fifth reach): centroid right / wrong | centre's sixth: score, its five's least |\n|---|---|---|---|---|---|---|---|"
    );
    for (name, hands) in [("samba", true), ("crane", true), ("samba", false)] {
        let (seq, rig) = match capture_with_rig(data, name) {
            Ok(x) => x,
            Err(why) => {
                let _ = writeln!(w.tables, "| {name} | {why} |");
                continue;
            }
        };
        let keep = if hands {
            vec![true; seq.mesh().vertex_count()]
        } else {
            without_hands(&rig, seq.mesh().positions())
        };
        let Ok((m, old)) = seq.mesh().keep_vertices(&keep) else {
            continue;
        };
        let what = if hands {
            name.to_string()
        } else {
            format!("{name} without hands")
        };
        let labels: Vec<u8> = old.iter().map(|&v| rig.labels()[v]).collect();
        let nb = neighbours(m.vertex_count(), m.triangles());
        let (mut wrong, mut kept) = ([Vec::new(), Vec::new(), Vec::new()], Vec::new());
        let (mut near_right, mut near_wrong, mut sixths) = (Vec::new(), Vec::new(), Vec::new());
        for f in 0..seq.frame_count() {
            let p: Vec<[f64; 3]> = old.iter().map(|&v| seq.frame(f)[v]).collect();
            let tips = [TipSeed::Centroid, TipSeed::Centre, TipSeed::Guarded]
                .map(|how| body_tips(&p, m.triangles(), &nb, sixth_limit, how));
            let ok = tips.each_ref().map(|t| right(t, &labels));
            for k in 0..3 {
                if !ok[k] {
                    wrong[k].push(f);
                }
            }
            let Some(g) = tips[2].guard else {
                continue;
            };
            if g.kept_centre {
                kept.push(f);
            }
            let near = if ok[0] {
                &mut near_right
            } else {
                &mut near_wrong
            };
            near.push(g.seed_to_tip);
            if let Some(s) = g.centre_sixth {
                sixths.push(format!("f{f} {s:.2}, {:.2}", g.centre_least));
            }
            let part = |v: u32| Part::ALL[labels[v as usize] as usize].name();
            let _ = writeln!(
                w.details,
                "{what} frame {f}: right (centroid, centre, guarded) {ok:?}; centroid's vertex on {}, {:.2} × the fifth reach from a centre tip; sixth score centroid {:?} centre {:?}, centre's five from {:.2}; centre kept {}",
                part(tips[0].seed),
                g.seed_to_tip,
                g.centroid_sixth,
                g.centre_sixth,
                g.centre_least,
                g.kept_centre
            );
        }
        let list = |x: &Vec<usize>| format!("{}: {:?}", x.len(), &x[..x.len().min(8)]);
        let _ = writeln!(
            w.tables,
            "| {what} | {} | {} | {} | {} | {} | {} / {} | {} |",
            seq.frame_count(),
            list(&wrong[0]),
            list(&wrong[1]),
            list(&wrong[2]),
            list(&kept),
            span(&near_right),
            span(&near_wrong),
            if sixths.is_empty() {
                "none".into()
            } else {
                sixths.join("; ")
            }
        );
    }
    w
}
