//! Bodies cut at the neck for `autorig_eval … headless` and `… confusion`
//! (issue 41, partial bodies): where a body is cut ([`Cut`]) and each body
//! of [`super::autorig::body_meshes`] driven by each of
//! [`super::autorig::synth_motions`] through its fixture's rig, cut, and
//! rigged from the motion alone as `db init` rigs it ([`each_cut_rig`]).

use super::autorig::{
    AutorigEvalError, AutorigReport, body_meshes, db_init_options, embed_as_db_init,
    rest_as_db_init, synth_motions,
};
use crate::embed::Embedding;
use crate::embed::auto::report::AutoRig;
use crate::embed::auto::rig::auto_rig;
use crate::embed::parts::Part;
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::DVec3;
use std::path::Path;
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

/// What the automatic rig made of a cut body.
pub enum Outcome {
    /// Nothing was left to rig.
    NoMesh,
    /// The automatic rig refused (why).
    Refused(String),
    /// Rigged, but the embedding from its landmarks refused.
    NotEmbedded(Box<AutoRig>),
    /// Rigged and embedded (`db init`'s rest frame, carried to the
    /// topology).
    Rigged(Box<(AutoRig, Embedding)>),
}

/// One body driven by one motion and cut, rigged as `db init` rigs it.
pub struct CutRig<'a> {
    /// The body's name.
    pub body: &'static str,
    /// The motion's name.
    pub motion: &'a str,
    /// The cut.
    pub cut: Cut,
    /// Vertices the cut removed.
    pub vertices_cut: usize,
    /// The fixture rig: the truth, on the whole body.
    pub rig: &'a Embedding,
    /// The cut body (`None`: nothing kept).
    pub mesh: Option<crate::mesh::Mesh>,
    /// The kept vertices' numbers in the whole body.
    pub old: Vec<usize>,
    /// The cut body's vertex positions, frame after frame.
    pub frames: Vec<Vec<[f64; 3]>>,
    /// The skeleton that drove each frame.
    pub poses: &'a [Pose],
    /// Rigging time (wall seconds; the automatic rig only).
    pub secs: f64,
    /// The result.
    pub outcome: Outcome,
}

impl CutRig<'_> {
    /// The fixture rig's part labels of the kept vertices.
    pub fn truth(&self) -> Vec<u8> {
        self.old.iter().map(|&v| self.rig.labels()[v]).collect()
    }

    /// The cut's rim: the kept vertices next to a removed one (empty for
    /// [`Cut::Whole`]), on the rest (the whole body's positions, `rest`,
    /// neighbours `nb`).
    pub fn rim(&self, rest: &[[f64; 3]], nb: &[Vec<u32>]) -> Vec<DVec3> {
        let mut kept = vec![false; rest.len()];
        self.old.iter().for_each(|&v| kept[v] = true);
        self.old
            .iter()
            .filter(|&&v| nb[v].iter().any(|&u| !kept[u as usize]))
            .map(|&v| DVec3::from_array(rest[v]))
            .collect()
    }
}

/// Calls `each` on every body of [`body_meshes`] (whose name contains
/// `only`, any case; all: `None`) driven by every motion of
/// [`synth_motions`] and cut by each of `cuts`, rigged from the motion
/// alone as `db init` rigs it (its rest frame; the embedding on it); with
/// the whole body's positions and neighbours.
pub fn each_cut_rig(
    data: &Path,
    cuts: &[Cut],
    only: Option<&str>,
    w: &mut AutorigReport,
    mut each: impl FnMut(&mut AutorigReport, &CutRig, &[[f64; 3]], &[Vec<u32>]),
) -> Result<(), AutorigEvalError> {
    use crate::synth::database::{Dynamics, drive};
    let motions = synth_motions(data, w);
    let wanted = |b: &str| only.is_none_or(|o| b.to_lowercase().contains(&o.to_lowercase()));
    for (body, rest, rig) in body_meshes(data, w)? {
        if !wanted(body) {
            continue;
        }
        let n = rest.vertex_count();
        let nb = crate::embed::parts::neighbours(n, rest.triangles());
        for (mname, cp) in &motions {
            let out = drive(
                &rest,
                &rig,
                &cp.poses,
                &cp.reference,
                30.0,
                Dynamics::default(),
            );
            for &cut in cuts {
                let keep = cut.keep(rest.positions(), &rig);
                let mut case = CutRig {
                    body,
                    motion: mname,
                    cut,
                    vertices_cut: n,
                    rig: &rig,
                    mesh: None,
                    old: Vec::new(),
                    frames: Vec::new(),
                    poses: &out.poses,
                    secs: 0.0,
                    outcome: Outcome::NoMesh,
                };
                if let Ok((m, old)) = rest.keep_vertices(&keep) {
                    case.frames = out
                        .positions
                        .chunks(n)
                        .map(|f| old.iter().map(|&v| f[v]).collect())
                        .collect();
                    case.vertices_cut = n - old.len();
                    case.old = old;
                    (case.outcome, case.secs) = rig_cut(&m, &case.frames);
                    case.mesh = Some(m);
                }
                each(w, &case, rest.positions(), &nb);
            }
        }
    }
    Ok(())
}

/// The cut body `m` with its `frames` rigged as `db init` rigs it, and
/// the wall seconds the rest frame and the automatic rig took.
fn rig_cut(m: &crate::mesh::Mesh, frames: &[Vec<[f64; 3]>]) -> (Outcome, f64) {
    let frames: Vec<&[[f64; 3]]> = frames.iter().map(Vec::as_slice).collect();
    let t = Instant::now();
    let (rest_frame, _) = rest_as_db_init(m, &frames);
    let auto = auto_rig(m, &frames, &db_init_options(rest_frame));
    let secs = t.elapsed().as_secs_f64();
    let auto = match auto {
        Ok(a) => a,
        Err(e) => return (Outcome::Refused(e.to_string()), secs),
    };
    let outcome = match embed_as_db_init(m, &frames, rest_frame, &auto.landmarks) {
        Some(e) => Outcome::Rigged(Box::new((auto, e))),
        None => Outcome::NotEmbedded(Box::new(auto)),
    };
    (outcome, secs)
}
