//! `autorig_eval … confusion [BODY]`: where the automatic rig's parts
//! lie on bodies whole and cut at the neck (issue 41). For each body of
//! [`super::autorig::body_meshes`] (whose name contains BODY, any case),
//! driven by each motion and cut ([`super::autorig_cut::each_cut_rig`]),
//! the embedding from the automatic landmarks against the fixture's rig:
//! - per automatic part, which of the fixture rig's parts its kept
//!   vertices belong to (a row of the confusion matrix, as shares of the
//!   automatic part's vertices; the tables show the parts under 90 %
//!   own, the details every part);
//! - the rest joints against the fixture rig's (% of the height; those
//!   over 2 %), and the head and neck joints against the cut's rim (the
//!   kept vertices next to removed ones: the stump's top): the head's
//!   and the neck's height above the rim's centroid and the head's
//!   distance to it.
//!
//! `confusion BODY DIR` also writes each cut body driven by the first
//! motion into DIR (`BODY_CUT.obj`, its frames `BODY_CUT.pc2`), for
//! `db init` and `render`.

use super::autorig::{AutorigEvalError, AutorigReport};
use super::autorig_cut::{Cut, CutRig, Outcome, each_cut_rig};
use crate::embed::Embedding;
use crate::embed::parts::Part;
use crate::rig::Canonical;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::Path;

/// The tables for the bodies whose name contains `only` (all: `None`);
/// with `write`, the cut bodies driven by the first motion written there.
pub fn evaluate_confusion(
    data: &Path,
    only: Option<&str>,
    write: Option<&Path>,
) -> Result<AutorigReport, AutorigEvalError> {
    crate::embed::auto::options::automatic_setup(
        &crate::embed::auto::options::AutoOptions::default(),
    )
    .map_err(AutorigEvalError::Options)?;
    let mut w = AutorigReport::default();
    let _ = writeln!(
        w.tables,
        "| body | motion | cut | parts agree | automatic part (vertices): fixture rig's parts, share | rest joints off by over 2% of the height | head, neck above the rim; head to the rim's centre (% height) |\n|---|---|---|---|---|---|---|"
    );
    let mut first = None;
    each_cut_rig(data, &Cut::ALL, only, &mut w, |w, case, rest, nb| {
        row(w, case, rest, nb);
        let motion = first.get_or_insert_with(|| case.motion.to_string());
        if let (Some(dir), true) = (write, case.motion == motion.as_str()) {
            save(w, case, dir);
        }
    })?;
    Ok(w)
}

/// The row of `case` (the whole body's `rest`, neighbours `nb`) and its
/// full matrix into the details.
fn row(w: &mut AutorigReport, case: &CutRig, rest: &[[f64; 3]], nb: &[Vec<u32>]) {
    let head = format!("| {} | {} | {} |", case.body, case.motion, case.cut.name());
    let mine = match &case.outcome {
        Outcome::Rigged(b) => &b.1,
        Outcome::NoMesh => return say(w, &format!("{head} no mesh |")),
        Outcome::Refused(e) => return say(w, &format!("{head} refused: {e} |")),
        Outcome::NotEmbedded(_) => return say(w, &format!("{head} embedding refused |")),
    };
    let truth = case.truth();
    let m = matrix(mine.labels(), &truth);
    let total: usize = m.iter().flatten().sum();
    let agree: usize = (0..Part::COUNT).map(|p| m[p][p]).sum();
    let _ = writeln!(w.details, "{head}");
    let mut wrong = Vec::new();
    for (p, r) in m.iter().enumerate() {
        let n: usize = r.iter().sum();
        if n == 0 {
            continue;
        }
        let line = shares(r, n);
        let _ = writeln!(w.details, "  {} ({n}): {line}", Part::ALL[p].name());
        if (r[p] as f64) < 0.9 * n as f64 {
            wrong.push(format!("{} ({n}): {line}", Part::ALL[p].name()));
        }
    }
    let h = case.rig.height();
    let off: Vec<String> = Canonical::ALL
        .iter()
        .map(|&c| (c, joint_off(mine, case.rig, c) / h))
        .filter(|(_, d)| *d > 0.02)
        .map(|(c, d)| format!("{} {:.1}", c.name(), 100.0 * d))
        .collect();
    let _ = writeln!(
        w.tables,
        "{head} {:.1}% | {} | {} | {} |",
        100.0 * agree as f64 / total.max(1) as f64,
        wrong.join("; "),
        off.join(", "),
        stump(mine, case, rest, nb),
    );
}

/// `case`'s cut body as `DIR/BODY_CUT.obj` and its frames as `.pc2`
/// (names lower case, spaces and `%` as `_`); a failure in the details.
fn save(w: &mut AutorigReport, case: &CutRig, dir: &Path) {
    let Some(m) = &case.mesh else {
        return;
    };
    let slug: String = format!("{}_{}", case.body, case.cut.name())
        .to_lowercase()
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let flat: Vec<[f64; 3]> = case.frames.concat();
    let obj = dir.join(format!("{slug}.obj"));
    let pc2 = dir.join(format!("{slug}.pc2"));
    let r = crate::mesh::io::obj::write_obj(m, None, &obj)
        .and_then(|_| crate::mesh::io::pc2::write_pc2(m.vertex_count(), &flat, &pc2));
    match r {
        Ok(()) => {
            let _ = writeln!(w.details, "wrote {} and {}", obj.display(), pc2.display());
        }
        Err(e) => {
            let _ = writeln!(w.details, "{}: {e}", obj.display());
        }
    }
}

/// A line of the tables.
fn say(w: &mut AutorigReport, line: &str) {
    let _ = writeln!(w.tables, "{line}");
}

/// `m[a][t]`: vertices labelled `a` by the automatic rig and `t` by the
/// fixture's.
fn matrix(auto: &[u8], truth: &[u8]) -> [[usize; Part::COUNT]; Part::COUNT] {
    let mut m = [[0; Part::COUNT]; Part::COUNT];
    for (&a, &t) in auto.iter().zip(truth) {
        if let (Some(r), true) = (m.get_mut(a as usize), (t as usize) < Part::COUNT) {
            r[t as usize] += 1;
        }
    }
    m
}

/// The fixture parts of row `r` (`n` vertices) with over 1 %, largest
/// first, as "name share%".
fn shares(r: &[usize; Part::COUNT], n: usize) -> String {
    let mut by: Vec<(usize, usize)> = r.iter().copied().enumerate().collect();
    by.sort_by_key(|b| std::cmp::Reverse(b.1));
    by.iter()
        .filter(|(_, k)| *k * 100 > n)
        .map(|(t, k)| {
            format!(
                "{} {:.0}%",
                Part::ALL[*t].name(),
                100.0 * *k as f64 / n as f64
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// Rest joint `c` of `mine` against the fixture rig's (length units).
fn joint_off(mine: &Embedding, rig: &Embedding, c: Canonical) -> f64 {
    let j = |e: &Embedding| DVec3::from_array(e.joints()[c.index()]);
    j(mine).distance(j(rig))
}

/// The head and neck joints against the cut's rim: their heights above
/// its centroid along the fixture rig's up and the head's distance to it
/// (% of the height); "–" for a whole body.
fn stump(mine: &Embedding, case: &CutRig, rest: &[[f64; 3]], nb: &[Vec<u32>]) -> String {
    let rim = case.rim(rest, nb);
    if rim.is_empty() {
        return "–".into();
    }
    let c = rim.iter().copied().sum::<DVec3>() / rim.len() as f64;
    let up = DVec3::from_array(case.rig.up());
    let h = case.rig.height();
    let j = |k: Canonical| DVec3::from_array(mine.joints()[k.index()]);
    let above = |q: DVec3| 100.0 * (q - c).dot(up) / h;
    format!(
        "{:.1}, {:.1}; {:.1}",
        above(j(Canonical::Head)),
        above(j(Canonical::Neck)),
        100.0 * j(Canonical::Head).distance(c) / h
    )
}
