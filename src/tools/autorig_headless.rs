//! `autorig_eval … headless`: issue 41's partial bodies. Samba's frame 0, the SMPL
//! template and MakeHuman's body ([`super::body_meshes`]), each driven by
//! [`super::synth_motions`] through its fixture's rig, are rigged as
//! `db init` rigs them whole and cut at the neck ([`Cut`]): the trunk's
//! depth below the top ([`crate::embed::auto::neck`]), whether the rig has
//! a head, its joints (all but the head, every frame) against the skeleton
//! that drove the frame and its parts against the fixture rig's on the
//! vertices kept. Then every frame of samba and crane taken as the rest,
//! whole and cut: the trunk's depth below the highest of the five branch
//! tips, least and greatest (the rule's margin over the captures' poses).

use super::autorig::{AutorigEvalError, AutorigReport, agree};
use super::autorig_cut::{CutRig, Outcome, each_cut_rig};
use crate::embed::Embedding;
use crate::embed::auto::neck::NeckReading;
use crate::embed::parts::{Part, neighbours};
use crate::mesh::MeshSequence;
use crate::mesh::io::{LoadOptions, load_sequence};
use crate::rig::Canonical;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

pub use super::autorig_cut::Cut;

/// The tables (`db init`'s rules for the automatic rig,
/// `SURFMOTION_AUTORIG` applied).
pub fn evaluate_headless(data: &Path) -> Result<AutorigReport, AutorigEvalError> {
    crate::embed::auto::options::automatic_setup(
        &crate::embed::auto::options::AutoOptions::default(),
    )
    .map_err(AutorigEvalError::Options)?;
    let mut w = AutorigReport::default();
    headless(data, &mut w)?;
    Ok(w)
}

/// The tables into `w`.
fn headless(data: &Path, w: &mut AutorigReport) -> Result<(), AutorigEvalError> {
    let _ = writeln!(
        w.tables,
        "| body | motion | cut | vertices cut | trunk below the top (% height) | head | joints but the head vs truth (% height, every frame) | parts agree (kept vertices) | time (s) | head joint to the rim's centre (% height) | neck vs truth (% height, every frame) |\n|---|---|---|---|---|---|---|---|---|---|---|"
    );
    each_cut_rig(data, &Cut::ALL, None, w, |w, case, rest, nb| {
        row(w, case, rest, nb)
    })?;
    every_frame(data, w);
    Ok(())
}

/// The table's row of `case` (the whole body's rest positions `rest`,
/// neighbours `nb`), and its "no head" notes and where its neck lies
/// ([`super::autorig_stump`]) into the details.
fn row(w: &mut AutorigReport, case: &CutRig, rest: &[[f64; 3]], nb: &[Vec<u32>]) {
    let (bname, mname, cut) = (case.body, case.motion, case.cut.name());
    let row = format!("| {bname} | {mname} | {cut} | {} |", case.vertices_cut);
    let (auto, mine) = match &case.outcome {
        Outcome::NoMesh => {
            let _ = writeln!(w.tables, "| {bname} | {mname} | {cut} | no mesh |");
            return;
        }
        Outcome::Refused(e) => {
            let _ = writeln!(w.tables, "{row} refused: {e} |");
            return;
        }
        Outcome::NotEmbedded(auto) => (auto.as_ref(), None),
        Outcome::Rigged(b) => (&b.0, Some(&b.1)),
    };
    let head = if auto.headless { "none" } else { "rigged" };
    let depth = 100.0 * auto.trunk_depth;
    let Some(mine) = mine else {
        let _ = writeln!(w.tables, "{row} {depth:.0} | {head} | embedding refused |");
        return;
    };
    let (mut s, mut k) = (0.0, 0usize);
    for (f, pose) in case.frames.iter().zip(case.poses) {
        let j = mine.frame_joints(f);
        for c in Canonical::ALL.iter().filter(|c| **c != Canonical::Head) {
            s += j[c.index()].distance(pose[c.index()]);
            k += 1;
        }
    }
    let neck = super::autorig_stump::neck_and_head(case, mine, rest, nb);
    let head_to_rim = neck
        .head_to_rim
        .map_or("–".to_string(), |x| format!("{x:.2}"));
    let _ = writeln!(
        w.tables,
        "{row} {depth:.0} | {head} | {:.2} | {:.1}% | {:.1} | {head_to_rim} | {:.2} |",
        100.0 * s / k.max(1) as f64 / case.rig.height(),
        100.0 * agree(mine.labels(), &case.truth()),
        case.secs,
        neck.neck_error,
    );
    let _ = writeln!(w.details, "  {bname}, {mname}, {cut}: {}", neck.depths);
    for note in auto.notes.iter().filter(|x| x.starts_with("no head")) {
        let _ = writeln!(w.details, "  {bname}, {mname}, {cut}: {note}");
    }
}

/// Every frame of samba and crane taken as the rest, whole and cut: the
/// trunk's depth below the highest of the five branch tips (+Y up, the
/// height the frame's extent along it; of four, the highest vertex),
/// least, median and greatest over the frames whose top is the head or the
/// trunk (the landmark rig's parts; the others' top is a hand or a foot),
/// and the frames read as cut.
fn every_frame(data: &Path, w: &mut AutorigReport) {
    use crate::embed::auto::branches::{body_tips, sixth_limit};
    use crate::embed::auto::centre::TipSeed;
    let _ = writeln!(
        w.tables,
        "\n| capture | cut | frames topped by a limb | trunk below the top (% height): least / median / greatest | frames read wrong (a whole body cut, a cut one whole) |\n|---|---|---|---|---|"
    );
    for name in ["samba", "crane"] {
        let (seq, rig) = match capture_with_rig(data, name) {
            Ok(x) => x,
            Err(why) => {
                let _ = writeln!(w.tables, "| {name} | {why} |");
                continue;
            }
        };
        for cut in [Cut::Whole, Cut::HeadPart, Cut::Plane(0.4)] {
            let keep = cut.keep(seq.mesh().positions(), &rig);
            let Some((m, old)) = seq.mesh().keep_vertices(&keep).ok() else {
                continue;
            };
            let nb = neighbours(m.vertex_count(), m.triangles());
            let (mut depths, mut wrong, mut limb_top) = (Vec::new(), Vec::new(), 0);
            for f in 0..seq.frame_count() {
                let p: Vec<[f64; 3]> = old.iter().map(|&v| seq.frame(f)[v]).collect();
                let tips = body_tips(&p, m.triangles(), &nb, sixth_limit, TipSeed::Centroid);
                let high = |a: &usize, b: &usize| p[*a][1].total_cmp(&p[*b][1]);
                let top = match tips.five.len() {
                    4 => (0..p.len()).max_by(high),
                    _ => tips.five.iter().map(|t| t.0 as usize).max_by(high),
                };
                let Some(top) = top else {
                    continue;
                };
                let part = rig.labels()[old[top]] as usize;
                if part != Part::Head.index() && part != Part::Torso.index() {
                    limb_top += 1;
                    continue;
                }
                let (lo, hi) = p
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(a, b), q| (a.min(q[1]), b.max(q[1])));
                let r = NeckReading::read(&p, &nb, DVec3::Y, hi - lo, top as u32);
                if r.cut().is_some() == (cut == Cut::Whole) {
                    wrong.push(f);
                }
                depths.push(100.0 * r.trunk_depth);
            }
            depths.sort_by(f64::total_cmp);
            let at = |q: f64| depths.get((q * (depths.len() as f64 - 1.0)) as usize);
            let _ = writeln!(
                w.tables,
                "| {name} | {} | {limb_top} | {:.0} / {:.0} / {:.0} | {} of {}: {:?} |",
                cut.name(),
                at(0.0).copied().unwrap_or(f64::NAN),
                at(0.5).copied().unwrap_or(f64::NAN),
                at(1.0).copied().unwrap_or(f64::NAN),
                wrong.len(),
                depths.len(),
                &wrong[..wrong.len().min(12)]
            );
        }
    }
}

/// The shared capture `name` (`4d/NAME/NAME.pc2` under `data`) and its
/// landmark rig (`tests/fixtures/NAME.landmarks.json`), or the table's word
/// for what is missing ("not run", "no landmark rig").
pub(crate) fn capture_with_rig(
    data: &Path,
    name: &str,
) -> Result<(MeshSequence, Embedding), &'static str> {
    let pc2 = data.join(format!("4d/{name}/{name}.pc2"));
    let seq =
        load_sequence(&pc2.to_string_lossy(), &LoadOptions::default()).map_err(|_| "not run")?;
    let fixture = PathBuf::from(format!("tests/fixtures/{name}.landmarks.json"));
    let rig = crate::embed::landmarks::Landmarks::load(&fixture, seq.mesh().vertex_count())
        .ok()
        .and_then(|lm| Embedding::new(seq.mesh(), &lm, None).ok())
        .ok_or("no landmark rig")?;
    Ok((seq, rig))
}
