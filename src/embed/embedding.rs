//! The [`Embedding`] of a character's rig, made once from its rest frame
//! ([`Embedding::new`]: joints placed from landmarks, bone-heat skin,
//! contiguous parts and overlapping regions, per-joint regressors), its
//! file form and the joints it reads off any frame.

use super::heat::{Bone, bone_heat, sparsify};
use super::joints::{JointEstimate, place_joints};
use super::landmarks::{LandmarkError, Landmarks};
use super::parts::{Part, contiguous_labels, make_contiguous, neighbours, part_weights, regions};
use super::regress::Regressor;
use crate::mesh::Mesh;
use crate::mesh::solver::SolveError;
use crate::rig::Canonical;
use crate::util::fsutil::{FsError, read_text, write_atomic};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Why a rig cannot be embedded.
#[derive(Debug, thiserror::Error)]
pub enum EmbedError {
    /// Bad landmark file.
    #[error(transparent)]
    Landmarks(#[from] LandmarkError),
    /// The heat system could not be solved (mesh problems).
    #[error("bone-heat weights: {0}")]
    Solve(#[from] SolveError),
    /// A bad part-label or embedding file.
    #[error("{path}: {reason}")]
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// Reading or writing failed.
    #[error(transparent)]
    Io(#[from] FsError),
    /// The mesh cannot hold a rig: no triangles, or flat.
    #[error("the mesh {0}: a rig needs a closed body surface")]
    Mesh(String),
    /// No regressor could be fitted for a joint.
    #[error(
        "joint {joint}: no vertices around it span a volume (is the landmark on the right body part?)"
    )]
    Regressor {
        /// The joint.
        joint: &'static str,
    },
    /// The embedding was made for a different mesh.
    #[error("{path}: the embedding has {have} vertices, the mesh {want}")]
    Mismatch {
        /// The file.
        path: PathBuf,
        /// Its vertex count.
        have: usize,
        /// The mesh's.
        want: usize,
    },
}

/// A character's rig: everything derived once from its rest frame.
/// Its fields are read through accessors and built or edited through
/// [`super::EmbeddingParts`] ([`Embedding::from_parts`] checks them); a file is
/// read through the same check.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "super::EmbeddingParts")]
pub struct Embedding {
    /// Number of vertices of the mesh it was made for.
    pub(crate) vertex_count: usize,
    /// Rest-frame joint positions, in [`Canonical::ALL`] order.
    pub(crate) joints: [[f64; 3]; Canonical::COUNT],
    /// Top of the head.
    pub(crate) head_top: [f64; 3],
    /// Left and right hand tips.
    pub(crate) hand_tips: [[f64; 3]; 2],
    /// Left and right toe tips.
    pub(crate) toe_tips: [[f64; 3]; 2],
    /// Up, facing and left directions of the rest frame.
    pub(crate) up: [f64; 3],
    /// Facing direction.
    pub(crate) facing: [f64; 3],
    /// The character's left.
    pub(crate) left: [f64; 3],
    /// Height of the rest frame along `up`.
    pub(crate) height: f64,
    /// Part of each vertex ([`Part::ALL`] index); every part one connected region.
    pub(crate) labels: Vec<u8>,
    /// Overlapping region of each part (vertex lists, [`Part::ALL`] order).
    pub(crate) regions: Vec<Vec<u32>>,
    /// Skin: up to four (joint index, weight) per vertex, weights summing to 1.
    pub(crate) skin: Vec<([u8; 4], [f64; 4])>,
    /// One regressor per joint, [`Canonical::ALL`] order.
    pub(crate) regressors: Vec<Regressor>,
    /// What was assumed while embedding.
    pub(crate) notes: Vec<String>,
    /// The body ends the mesh lacks (issue 41's partial bodies): `head`
    /// (the landmarks declare it, the chin placed at the top of the neck).
    /// The checks of an absent end are skipped. Empty (and not written)
    /// for a whole body.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) absent: Vec<String>,
}

/// Refuses meshes no rig can be embedded in, with the reason (a face-less,
/// tiny or flat mesh used to fail later with "joint pelvis: no vertices
/// around it span a volume"; issue 18, item 17).
pub fn check_body(mesh: &Mesh) -> Result<(), EmbedError> {
    if mesh.triangle_count() == 0 {
        return Err(EmbedError::Mesh(format!(
            "has {} vertices and no triangles (a point cloud?)",
            mesh.vertex_count()
        )));
    }
    if mesh.vertex_count() < 4 || mesh.triangle_count() < 4 {
        return Err(EmbedError::Mesh(format!(
            "has only {} vertices and {} triangles",
            mesh.vertex_count(),
            mesh.triangle_count()
        )));
    }
    let b = mesh.bounds();
    let ext: Vec<f64> = (0..3).map(|k| b.max[k] - b.min[k]).collect();
    let big = ext.iter().copied().fold(0.0, f64::max);
    if let Some(k) = (0..3).find(|&k| ext[k].is_nan() || ext[k] <= 1e-3 * big) {
        return Err(EmbedError::Mesh(format!(
            "is flat: its extent along {} is {:.3e} against {:.3e} along the largest axis",
            ["x", "y", "z"][k],
            ext[k],
            big
        )));
    }
    Ok(())
}

/// The bone segments of an estimate, each with its driving joint: every
/// joint's segments to its children, plus end segments to the head top,
/// hand tips and toe tips.
pub fn bones(est: &JointEstimate) -> Vec<Bone> {
    bone_list(&est.joints, est.head_top, est.hand_tips, est.toe_tips)
}

/// [`bones`] of a stored embedding.
pub fn bones_of(e: &Embedding) -> Vec<Bone> {
    let v = DVec3::from_array;
    bone_list(
        &e.joints.map(v),
        v(e.head_top),
        e.hand_tips.map(v),
        e.toe_tips.map(v),
    )
}

fn bone_list(
    joints: &[DVec3; Canonical::COUNT],
    head_top: DVec3,
    hand_tips: [DVec3; 2],
    toe_tips: [DVec3; 2],
) -> Vec<Bone> {
    let mut out = Vec::new();
    for c in Canonical::ALL {
        if let Some(p) = c.parent() {
            out.push(Bone {
                joint: p,
                a: joints[p.index()],
                b: joints[c.index()],
            });
        }
    }
    let ends = [
        (Canonical::Head, head_top),
        (Canonical::LWrist, hand_tips[0]),
        (Canonical::RWrist, hand_tips[1]),
        (Canonical::LToe, toe_tips[0]),
        (Canonical::RToe, toe_tips[1]),
    ];
    for (j, tip) in ends {
        out.push(Bone {
            joint: j,
            a: joints[j.index()],
            b: tip,
        });
    }
    out
}

/// Parses explicit part labels `{part: [vertex ids]}`. A vertex listed for
/// several parts takes the first in [`Part::ALL`] order; vertices listed for
/// none take the part of the nearest labelled vertex along the mesh.
pub fn parse_parts(
    text: &str,
    path: &Path,
    triangles: &[[u32; 3]],
    n: usize,
) -> Result<(Vec<u8>, usize), EmbedError> {
    let bad = |reason: String| EmbedError::File {
        path: path.to_path_buf(),
        reason,
    };
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| bad(e.to_string()))?;
    let obj = v
        .as_object()
        .ok_or_else(|| bad("expected a JSON object {part: [vertex ids]}".into()))?;
    let mut labels = vec![u8::MAX; n];
    let mut listed: Vec<(Part, Vec<u32>)> = Vec::new();
    for (k, ids) in obj {
        let part = Part::from_name(k).ok_or_else(|| {
            let known: Vec<&str> = Part::ALL.iter().map(|p| p.name()).collect();
            bad(format!("unknown part {k:?} (known: {})", known.join(", ")))
        })?;
        let arr = ids
            .as_array()
            .ok_or_else(|| bad(format!("part {k}: expected an array of vertex ids")))?;
        let mut vs = Vec::with_capacity(arr.len());
        for (i, x) in arr.iter().enumerate() {
            match x.as_u64() {
                Some(v) if (v as usize) < n => vs.push(v as u32),
                _ => {
                    return Err(bad(format!(
                        "part {k}, entry {i}: {x} is not a vertex id below {n}"
                    )));
                }
            }
        }
        listed.push((part, vs));
    }
    listed.sort_by_key(|(p, _)| std::cmp::Reverse(*p));
    for (p, vs) in &listed {
        for &v in vs {
            labels[v as usize] = p.index() as u8;
        }
    }
    // Unlabelled vertices: breadth-first from the labelled ones.
    let nb = neighbours(n, triangles);
    let mut queue: std::collections::VecDeque<u32> = (0..n as u32)
        .filter(|&v| labels[v as usize] != u8::MAX)
        .collect();
    if queue.is_empty() {
        return Err(bad("no vertex is labelled".into()));
    }
    let filled = n - queue.len();
    while let Some(v) = queue.pop_front() {
        for &u in &nb[v as usize] {
            if labels[u as usize] == u8::MAX {
                labels[u as usize] = labels[v as usize];
                queue.push_back(u);
            }
        }
    }
    for l in &mut labels {
        if *l == u8::MAX {
            *l = 0;
        }
    }
    Ok((labels, filled))
}

impl Embedding {
    /// Embeds the rig in a rest mesh from landmarks; `parts` overrides the
    /// computed part labels (see [`parse_parts`]). Degenerate landmark sets
    /// are refused first ([`Landmarks::validate`]); [`check`] judges the
    /// result.
    pub fn new(
        mesh: &Mesh,
        lm: &Landmarks,
        parts: Option<Vec<u8>>,
    ) -> Result<Embedding, EmbedError> {
        Embedding::new_moving(mesh, lm, parts, &[])
    }

    /// [`Embedding::new`] with the skin weights fitted to the motion of
    /// `frames` (each one position per vertex of `mesh`: the character's
    /// sequences), [`super::motion_weights::refine`]: a vertex that
    /// touched a bone in the rest frame but does not follow it over the
    /// frames loses its weight on it: the skin and regions follow the
    /// motion, and the part labels where the fit takes a vertex off its
    /// part ([`super::motion_weights::motion_labels`]; explicit `parts`
    /// stay). With no frames, bone heat alone, as [`Embedding::new`].
    pub fn new_moving(
        mesh: &Mesh,
        lm: &Landmarks,
        parts: Option<Vec<u8>>,
        frames: &[&[[f64; 3]]],
    ) -> Result<Embedding, EmbedError> {
        check_body(mesh)?;
        if let Some(c) = super::stray::Compact::of(mesh) {
            // Embedded without its vertices in no triangle, then given to
            // them ([`super::stray`]).
            let frames: Vec<Vec<[f64; 3]>> = frames
                .iter()
                .map(|f| c.frame(f))
                .filter(|f| !f.is_empty())
                .collect();
            let frames: Vec<&[[f64; 3]]> = frames.iter().map(Vec::as_slice).collect();
            let lm = c.landmarks(lm, mesh.positions());
            let parts = parts.map(|l| c.labels(&l));
            let compact = c.mesh(mesh).map_err(|e| {
                EmbedError::Mesh(format!("without its vertices in no triangle: {e}"))
            })?;
            let e = Embedding::new_moving(&compact, &lm, parts, &frames)?;
            return e.with_stray(&c);
        }
        let (p, t) = (mesh.positions(), mesh.triangles());
        // A headless body's chin: the top of its neck.
        let headless = lm.headless();
        let full;
        let lm = if headless {
            full = lm.completed(p, t);
            &full
        } else {
            lm
        };
        // The vertical as `place_joints` takes it ([`super::axes::body_up`]).
        let up = match (
            lm.point(super::landmarks::Landmark::Chin, p),
            lm.point(super::landmarks::Landmark::Groin, p),
        ) {
            (Some(c), Some(g)) => super::axes::body_up(DVec3::from_array(c) - DVec3::from_array(g)),
            _ => DVec3::Y,
        };
        lm.validate(p, t, up.to_array())?;
        let mut est = place_joints(p, t, lm, headless);
        let mut absent: Vec<String> = if headless {
            vec!["head".into()]
        } else {
            Vec::new()
        };
        let cut = super::footless::cut_feet(p, t, &est.joints, est.height);
        if let [true, false] | [false, true] = cut {
            super::footless::mirror_foot(&mut est, usize::from(cut[1]));
        }
        absent.extend(super::footless::absent_names(cut).map(String::from));
        let bs = bones(&est);
        let mut w = bone_heat(mesh, &bs)?;
        let mut moved = None;
        let mut parts = parts;
        if !frames.is_empty() {
            let nb = neighbours(p.len(), t);
            let labels = contiguous_labels(&part_weights(&w), &nb);
            let o = super::motion_weights::MotionWeightOptions::default();
            let r = super::motion_weights::refine(p, &mut w, &labels, frames, est.height, &o);
            if parts.is_none() && r.frames > 0 {
                let mut l = super::motion_weights::motion_labels(&labels, &w, o.keep_label);
                make_contiguous(&mut l, &nb);
                parts = Some(l);
            }
            moved = Some(r);
        }
        let explicit = parts.is_some() && moved.as_ref().is_none_or(|r| r.frames == 0);
        let mut e = Embedding::assemble_labelled(mesh, est, &w, parts, explicit)?;
        if let Some(r) = moved.filter(|r| r.frames > 0) {
            e.notes.push(r.note());
        }
        if headless {
            e.notes
                .push("no head: the chin placed at the top of the neck".into());
        }
        e.absent = absent;
        Ok(e)
    }

    /// [`Embedding::new`] on another frame of the mesh than its own
    /// positions: the rest frame chosen clear of contact
    /// ([`super::rest::choose_rest_frame`]). The landmarks, marked on
    /// `mesh`'s positions, are carried to `rest` ([`Landmarks::moved`]); the
    /// labels, skin and regressors are made on `rest`; then the rest
    /// quantities are carried back to `mesh`'s positions, so that the
    /// embedding stays the mesh's like any other: the joints read off them
    /// by the regressors, the head, hand and toe tips and the directions
    /// moved by their part's rigid motion ([`super::rigidity::robust_motion`]).
    /// The height stays the rest frame's. A note says so.
    pub fn new_on_frame(
        mesh: &Mesh,
        rest: &[[f64; 3]],
        lm: &Landmarks,
        parts: Option<Vec<u8>>,
    ) -> Result<Embedding, EmbedError> {
        Embedding::new_on_frame_moving(mesh, rest, lm, parts, &[])
    }

    /// [`Embedding::new_on_frame`] with the skin weights fitted to the
    /// motion of `frames` ([`Embedding::new_moving`]).
    pub(crate) fn new_on_frame_moving(
        mesh: &Mesh,
        rest: &[[f64; 3]],
        lm: &Landmarks,
        parts: Option<Vec<u8>>,
        frames: &[&[[f64; 3]]],
    ) -> Result<Embedding, EmbedError> {
        let frame = mesh
            .with_positions(rest)
            .map_err(|e| EmbedError::Mesh(format!("the rest frame: {e}")))?;
        let moved = lm.moved(mesh.positions(), rest, mesh.triangles());
        let mut e =
            Embedding::new_moving(&frame, &moved, parts, frames)?.carried(rest, mesh.positions());
        e.notes.push(
            "embedded on the rest frame chosen clear of contact; the joints read off the topology's own positions by the regressors".into(),
        );
        Ok(e)
    }

    /// The embedding with its rest quantities carried from the frame `from`
    /// (the one its joints are on) to the frame `to` of the same mesh: the
    /// joints read off `to` by the regressors, the tips and directions moved
    /// by their part's rigid motion; labels, skin and regressors unchanged.
    pub fn carried(&self, from: &[[f64; 3]], to: &[[f64; 3]]) -> Embedding {
        let mut e = self.clone();
        e.carry(from, to);
        e
    }

    fn carry(&mut self, from: &[[f64; 3]], to: &[[f64; 3]]) {
        use super::rigidity::{Rigid, robust_motion};
        let part_motion = |part: Part| {
            let verts: Vec<u32> = (0..self.labels.len() as u32)
                .filter(|&v| self.labels[v as usize] as usize == part.index())
                .collect();
            robust_motion(from, to, &verts).unwrap_or(Rigid::IDENTITY)
        };
        let v = DVec3::from_array;
        let head = part_motion(Part::of_joint(Canonical::Head));
        let hands = [Canonical::LWrist, Canonical::RWrist].map(|j| part_motion(Part::of_joint(j)));
        let toes = [Canonical::LToe, Canonical::RToe].map(|j| part_motion(Part::of_joint(j)));
        let torso = part_motion(Part::of_joint(Canonical::Pelvis));
        self.head_top = head.apply(v(self.head_top)).to_array();
        for k in 0..2 {
            self.hand_tips[k] = hands[k].apply(v(self.hand_tips[k])).to_array();
            self.toe_tips[k] = toes[k].apply(v(self.toe_tips[k])).to_array();
        }
        let up = super::axes::body_up(torso.turn(v(self.up)));
        let left = torso.turn(v(self.left));
        let left = (left - up * left.dot(up)).normalize_or(v(self.left));
        self.up = up.to_array();
        self.left = left.to_array();
        self.facing = left.cross(up).to_array();
        self.joints = self.frame_joints(to).map(|j| j.to_array());
    }

    /// The embedding of joints `est` and dense skin weights `w` (one row
    /// of [`Canonical::COUNT`] per vertex): part labels (or the given
    /// ones, made contiguous), overlapping regions, sparse skin, regressors.
    pub fn assemble(
        mesh: &Mesh,
        est: JointEstimate,
        w: &super::heat::Weights,
        parts: Option<Vec<u8>>,
    ) -> Result<Embedding, EmbedError> {
        let explicit = parts.is_some();
        Embedding::assemble_labelled(mesh, est, w, parts, explicit)
    }

    /// [`Embedding::assemble`]; `explicit` says whether `parts` were given
    /// by the user (noted) or made by the motion fit
    /// ([`super::motion_weights::motion_labels`]).
    fn assemble_labelled(
        mesh: &Mesh,
        est: JointEstimate,
        w: &super::heat::Weights,
        parts: Option<Vec<u8>>,
        explicit: bool,
    ) -> Result<Embedding, EmbedError> {
        let (p, t) = (mesh.positions(), mesh.triangles());
        let pw = part_weights(w);
        let nb = neighbours(p.len(), t);
        let mut notes = est.notes.clone();
        let labels = match parts {
            Some(mut l) => {
                make_contiguous(&mut l, &nb);
                if explicit {
                    notes.push("part labels: given explicitly".into());
                }
                l
            }
            None => contiguous_labels(&pw, &nb),
        };
        let regions = regions(&labels, &pw, 0.1, &nb);
        let skin = sparsify::<4>(w, 0.01);
        let mut regressors = Vec::with_capacity(Canonical::COUNT);
        for j in Canonical::ALL {
            regressors.push(
                fit_regressor(p, &labels, &est, j)
                    .ok_or(EmbedError::Regressor { joint: j.name() })?,
            );
        }
        let a = |v: DVec3| v.to_array();
        Ok(Embedding {
            vertex_count: p.len(),
            joints: est.joints.map(a),
            head_top: a(est.head_top),
            hand_tips: est.hand_tips.map(a),
            toe_tips: est.toe_tips.map(a),
            up: a(est.up),
            facing: a(est.facing),
            left: a(est.left),
            height: est.height,
            labels,
            regions,
            skin,
            regressors,
            notes,
            absent: Vec::new(),
        })
    }

    /// The joints of a frame by the regressors, [`Canonical::ALL`] order.
    pub fn frame_joints(&self, positions: &[[f64; 3]]) -> [DVec3; Canonical::COUNT] {
        std::array::from_fn(|j| self.regressors[j].apply(positions))
    }

    /// The joints of a frame as plain centres of each joint's vertex set
    /// (the part-centroid skeleton of Huang et al. 2015, Sec. 3).
    pub(crate) fn centroid_joints(&self, positions: &[[f64; 3]]) -> [DVec3; Canonical::COUNT] {
        std::array::from_fn(|j| self.regressors[j].centroid(positions))
    }

    /// Writes the embedding as JSON (atomically).
    pub fn save(&self, path: &Path) -> Result<(), EmbedError> {
        let s = serde_json::to_vec(self).map_err(|e| EmbedError::File {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        write_atomic(path, |w| w.write_all(&s))?;
        Ok(())
    }

    /// Reads an embedding and checks it against the mesh's vertex count.
    pub fn load(path: &Path, vertex_count: usize) -> Result<Embedding, EmbedError> {
        Self::parse(&read_text(path)?, path, vertex_count)
    }

    /// [`Embedding::load`] of a file's text (`path` names it in errors); the
    /// file is checked as [`Embedding::from_parts`] checks.
    pub fn parse(text: &str, path: &Path, vertex_count: usize) -> Result<Embedding, EmbedError> {
        let e: Embedding = serde_json::from_str(text).map_err(|e| EmbedError::File {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        if e.vertex_count != vertex_count {
            return Err(EmbedError::Mismatch {
                path: path.to_path_buf(),
                have: e.vertex_count,
                want: vertex_count,
            });
        }
        Ok(e)
    }
}

/// The regressor of joint `j`: a band of vertices just beyond the joint on
/// its distal side (in the parts the joint drives), widened until it spans
/// a volume. A joint is a fixed point of the segment it drives, so the
/// surface right next to it on that side moves rigidly with it, while the
/// proximal side slides and bulges as the joint bends.
fn fit_regressor(
    p: &[[f64; 3]],
    labels: &[u8],
    est: &JointEstimate,
    j: Canonical,
) -> Option<Regressor> {
    use Canonical as C;
    let jp = |c: Canonical| est.joints[c.index()];
    let here = jp(j);
    let child = Canonical::ALL.into_iter().find(|c| c.parent() == Some(j));
    let tip = match j {
        C::Head => Some(est.head_top),
        C::LWrist => Some(est.hand_tips[0]),
        C::RWrist => Some(est.hand_tips[1]),
        C::LToe => Some(est.toe_tips[0]),
        C::RToe => Some(est.toe_tips[1]),
        _ => None,
    };
    let out = match (child, tip) {
        (Some(c), _) => jp(c) - here,
        (None, Some(t)) => t - here,
        (None, None) => j.parent().map_or(est.up, |par| here - jp(par)),
    };
    let axis = out.normalize_or(est.up);
    // Hips and neck sit at fixed places in the pelvis and chest (the
    // shoulder girdle, by contrast, moves on the chest): their band is taken
    // from the parent's part, on both sides.
    let branch = j
        .parent()
        .filter(|_| matches!(j, C::LHip | C::RHip | C::Neck));
    let parts: Vec<u8> = match branch {
        Some(par) => vec![Part::of_joint(par).index() as u8],
        None => {
            let mut v = vec![Part::of_joint(j).index() as u8];
            if let Some(c) = child {
                v.push(Part::of_joint(c).index() as u8);
            }
            v
        }
    };
    let behind = if branch.is_some() {
        f64::INFINITY
    } else {
        0.01
    };
    let h = est.height;
    for slab in [0.02, 0.04, 0.08, 0.16] {
        let mut cand: Vec<(f64, u32)> = (0..p.len() as u32)
            .filter_map(|v| {
                let d = DVec3::from_array(p[v as usize]) - here;
                let along = d.dot(axis);
                (parts.contains(&labels[v as usize])
                    && along > -behind.min(slab) * h
                    && along < slab * h
                    && d.length() < 0.25 * h)
                    .then_some((d.length(), v))
            })
            .collect();
        if cand.len() < 12 {
            continue;
        }
        // Keep the tight ring: vertices not much farther from the joint
        // than its nearest fifth. Loose clothing (a skirt over a knee) and
        // the far side of a bulky part move less rigidly with the joint.
        cand.sort_by(|a, b| a.0.total_cmp(&b.0));
        let r0 = cand[cand.len() / 5].0;
        let tight: Vec<u32> = cand
            .iter()
            .filter(|(d, _)| *d <= 1.6 * r0)
            .map(|&(_, v)| v)
            .collect();
        let support = if tight.len() >= 12 {
            tight
        } else {
            cand.iter().map(|&(_, v)| v).collect()
        };
        if let Some(r) = Regressor::fit(p, support, here) {
            return Some(r);
        }
    }
    let mut near: Vec<u32> = (0..p.len() as u32).collect();
    near.sort_by(|&a, &b| {
        let d = |v: u32| DVec3::from_array(p[v as usize]).distance(here);
        d(a).total_cmp(&d(b))
    });
    near.truncate(64);
    Regressor::fit(p, near, here)
}
