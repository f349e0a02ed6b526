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

use super::autorig::{
    AutorigEvalError, AutorigReport, agree, body_meshes, db_init_options, embed_as_db_init,
    rest_as_db_init, synth_motions,
};
use crate::embed::Embedding;
use crate::embed::auto::neck::NeckReading;
use crate::embed::auto::rig::auto_rig;
use crate::embed::parts::{Part, neighbours};
use crate::mesh::MeshSequence;
use crate::mesh::io::{LoadOptions, load_sequence};
use crate::rig::Canonical;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Where a body is cut.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Cut {
    /// Not cut.
    Whole,
    /// The fixture rig's head part dropped (`embed::partial`'s cut: the
    /// neck goes with it, down to the shoulders).
    HeadPart,
    /// Every vertex of the head part and the torso beyond the plane across
    /// the neck→head bone at `f` of its length from the neck joint (the
    /// embedding puts them 5 % of the height below and 3 % above the
    /// chin): a stump of neck left.
    Plane(f64),
}

impl Cut {
    /// The cuts the table shows.
    pub const ALL: [Cut; 4] = [Cut::Whole, Cut::HeadPart, Cut::Plane(0.4), Cut::Plane(0.0)];

    /// The cut's name in the table.
    pub fn name(self) -> String {
        match self {
            Cut::Whole => "whole".into(),
            Cut::HeadPart => "head part".into(),
            Cut::Plane(f) => format!("neck at {:.0}%", 100.0 * f),
        }
    }

    /// Which vertices of `rest` (rigged by `rig`) are kept.
    pub fn keep(self, rest: &[[f64; 3]], rig: &Embedding) -> Vec<bool> {
        let j = |c: Canonical| DVec3::from_array(rig.joints()[c.index()]);
        let (neck, head) = (j(Canonical::Neck), j(Canonical::Head));
        let axis = (head - neck).normalize_or_zero();
        let at = neck + (head - neck) * if let Cut::Plane(f) = self { f } else { 0.0 };
        let (hp, tp) = (Part::Head.index() as u8, Part::Torso.index() as u8);
        (0..rest.len())
            .map(|v| {
                let l = rig.labels()[v];
                match self {
                    Cut::Whole => true,
                    Cut::HeadPart => l != hp,
                    Cut::Plane(_) => {
                        !((l == hp || l == tp) && (DVec3::from_array(rest[v]) - at).dot(axis) > 0.0)
                    }
                }
            })
            .collect()
    }
}

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
    use crate::synth::database::{Dynamics, drive};
    let _ = writeln!(
        w.tables,
        "| body | motion | cut | vertices cut | trunk below the top (% height) | head | joints but the head vs truth (% height, every frame) | parts agree (kept vertices) | time (s) |\n|---|---|---|---|---|---|---|---|---|"
    );
    let motions = synth_motions(data, w);
    for (bname, rest, rig) in body_meshes(data, w)? {
        let n = rest.vertex_count();
        for (mname, cp) in &motions {
            let out = drive(
                &rest,
                &rig,
                &cp.poses,
                &cp.reference,
                30.0,
                Dynamics::default(),
            );
            for cut in Cut::ALL {
                let keep = cut.keep(rest.positions(), &rig);
                let Some((m, old)) = rest.keep_vertices(&keep).ok() else {
                    let _ = writeln!(w.tables, "| {bname} | {mname} | {} | no mesh |", cut.name());
                    continue;
                };
                let own: Vec<Vec<[f64; 3]>> = out
                    .positions
                    .chunks(n)
                    .map(|f| old.iter().map(|&v| f[v]).collect())
                    .collect();
                let frames: Vec<&[[f64; 3]]> = own.iter().map(Vec::as_slice).collect();
                let row = format!("| {bname} | {mname} | {} | {} |", cut.name(), n - old.len());
                let t = Instant::now();
                let (rest_frame, _) = rest_as_db_init(&m, &frames);
                let auto = match auto_rig(&m, &frames, &db_init_options(rest_frame)) {
                    Ok(a) => a,
                    Err(e) => {
                        let _ = writeln!(w.tables, "{row} refused: {e} |");
                        continue;
                    }
                };
                let secs = t.elapsed().as_secs_f64();
                let head = if auto.headless { "none" } else { "rigged" };
                let depth = 100.0 * auto.trunk_depth;
                let Some(mine) = embed_as_db_init(&m, &frames, rest_frame, &auto.landmarks) else {
                    let _ = writeln!(w.tables, "{row} {depth:.0} | {head} | embedding refused |");
                    continue;
                };
                let (mut s, mut k) = (0.0, 0usize);
                for (f, pose) in frames.iter().zip(&out.poses) {
                    let j = mine.frame_joints(f);
                    for c in Canonical::ALL.iter().filter(|c| **c != Canonical::Head) {
                        s += j[c.index()].distance(pose[c.index()]);
                        k += 1;
                    }
                }
                let truth: Vec<u8> = old.iter().map(|&v| rig.labels()[v]).collect();
                let _ = writeln!(
                    w.tables,
                    "{row} {depth:.0} | {head} | {:.2} | {:.1}% | {secs:.1} |",
                    100.0 * s / k.max(1) as f64 / rig.height(),
                    100.0 * agree(mine.labels(), &truth),
                );
                for note in auto.notes.iter().filter(|x| x.starts_with("no head")) {
                    let _ = writeln!(w.details, "  {bname}, {mname}, {}: {note}", cut.name());
                }
            }
        }
    }
    every_frame(data, w);
    Ok(())
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
