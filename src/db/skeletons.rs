//! Per-frame skeletons of a character database (Huang et al. 2015, Sec. 3):
//! the rig embedded once on the topology's rest frame, then every frame's
//! canonical joints read off it ([`crate::embed::frames`]: the embedding's
//! regressors or, as in the paper, the plain centres of the joints' vertex
//! sets), and by default the one rigid skeleton of the character posed to
//! explain them ([`crate::embed::rigid`]).

use super::manifest::{DbError, Manifest};
use crate::embed::frames::{SkeletonKind, poses, rigid_fit};
use crate::embed::landmarks::Landmarks;
use crate::embed::rigid::{Fit, RigidSkeleton};
use crate::embed::{Embedding, parse_parts};
use crate::mesh::Mesh;
use crate::pose::Pose;
use crate::util::fsutil::read_text;
use serde::Serialize;
use std::path::Path;

/// The fingerprint of the code that makes and reads the skeleton cache
/// (`cache/poses-KIND.bin`): `build.rs` hashes the rig's sources (the
/// embedding, the per-frame joints, the rigid fit) and the cache's reader
/// and writer (`src/db/frames.rs`); the cache's key carries it
/// ([`super::frames::keys`]), so a build whose skeleton code changed
/// rebuilds the cache instead of reading the skeletons the old code made.
pub(crate) const SKELETON_SOURCE: &str = env!("SURFMOTION_SKELETON_SOURCE");

/// The skeletons of one sequence.
#[derive(Debug, Clone, Serialize)]
pub struct SequenceSkeleton {
    /// Sequence name.
    pub name: String,
    /// Frames per second.
    pub fps: f64,
    /// One pose per frame.
    pub poses: Vec<Pose>,
    /// For [`SkeletonKind::Rigid`]: the regressor joints the poses were
    /// fitted to, and each frame's fit; empty otherwise.
    #[serde(skip)]
    pub measured: Vec<Pose>,
    /// Per frame, the rigid fit (pose, rotations, residuals).
    #[serde(skip)]
    pub fits: Vec<Fit>,
}

/// Embeds the database's rig (landmarks, optionally with explicit parts).
pub fn embed_rig(dir: &Path, m: &Manifest, topology: &Mesh) -> Result<Embedding, DbError> {
    embed_rig_with(dir, m, topology, None)
}

/// [`embed_rig`] given each sequence's frame count (`lens`, in the
/// manifest's order: a built graph's spans), so that only the frames the
/// skin's motion fit reads are held, a sequence at a time
/// ([`motion_frames`]); the same embedding.
pub(crate) fn embed_rig_with(
    dir: &Path,
    m: &Manifest,
    topology: &Mesh,
    lens: Option<&[usize]>,
) -> Result<Embedding, DbError> {
    let Some(lp) = &m.rig.landmarks else {
        if let Some(g) = &m.rig.gltf_skin {
            let g = Manifest::resolve(dir, g);
            let asset = crate::rig::read_rigged_character(&g)?;
            let map = match &m.rig.rig_map {
                Some(p) => Some(
                    crate::rig::RigMap::load(&Manifest::resolve(dir, p)).map_err(|e| {
                        DbError::Manifest {
                            path: dir.join(super::MANIFEST),
                            msg: e.to_string(),
                        }
                    })?,
                ),
                None => None,
            };
            return crate::embed::skin::from_skin(topology, &asset, map.as_ref(), &g)
                .map_err(DbError::Rig);
        }
        return Err(DbError::Manifest {
            path: dir.join(super::MANIFEST),
            msg: "no [rig] landmarks or gltf_skin: add `landmarks = \"FILE.json\"` under [rig] (see `jobs::rig::embed_rig`)".into(),
        });
    };
    let n = topology.vertex_count();
    let lp = Manifest::resolve(dir, lp);
    let lm = Landmarks::load(&lp, n).map_err(|e| DbError::Rig(e.into()))?;
    let parts = match &m.rig.parts {
        Some(p) => {
            let p = Manifest::resolve(dir, p);
            let text = read_text(&p)?;
            Some(
                parse_parts(&text, &p, topology.triangles(), n)
                    .map_err(DbError::Rig)?
                    .0,
            )
        }
        None => None,
    };
    // The skin weights are fitted to the sequences' motion (issue 41):
    // bone heat on one frame wires a contact into the weights.
    let kept = motion_frames(dir, m, n, lens)?;
    let frames: Vec<&[[f64; 3]]> = kept.iter().map(|f| f.as_slice()).collect();
    match rest_frame(dir, m, topology)? {
        Some(rest) => Embedding::new_on_frame_moving(topology, &rest, &lm, parts, &frames)
            .map_err(DbError::Rig),
        None => Embedding::new_moving(topology, &lm, parts, &frames).map_err(DbError::Rig),
    }
}

/// The frames of the database the skin's motion fit reads
/// ([`crate::embed::motion_weights::refine`]: of the frames with `n`
/// vertices, every `step`-th from the first, `step` = ⌈frames /
/// `max_frames`⌉), in order. With `lens` (each sequence's frame count) only
/// those frames are kept, a sequence at a time, and `refine` takes every
/// one of them (at most `max_frames`: its step is 1), so the fit is the same
/// as on every frame; at 10⁴ frames of 10K vertices holding every frame
/// took 2.3 GB (issue 43). Without `lens`, or when a sequence is not what
/// `lens` says, every frame with `n` vertices (`refine` samples them).
fn motion_frames(
    dir: &Path,
    m: &Manifest,
    n: usize,
    lens: Option<&[usize]>,
) -> Result<Vec<Vec<[f64; 3]>>, DbError> {
    let every = || -> Result<Vec<Vec<[f64; 3]>>, DbError> {
        let mut all = Vec::new();
        for s in &m.sequences {
            let q = m.load_sequence(dir, s)?;
            if q.mesh().vertex_count() == n {
                all.extend((0..q.frame_count()).map(|f| q.frame(f).to_vec()));
            }
        }
        Ok(all)
    };
    let Some(lens) = lens.filter(|l| l.len() == m.sequences.len()) else {
        return every();
    };
    let max = crate::embed::motion_weights::MotionWeightOptions::default()
        .max_frames
        .max(1);
    let step = lens.iter().sum::<usize>().div_ceil(max).max(1);
    let mut kept = Vec::new();
    let mut at = 0usize;
    for (s, &len) in m.sequences.iter().zip(lens) {
        let first = at.div_ceil(step) * step;
        if first < at + len {
            let q = m.load_sequence(dir, s)?;
            if q.mesh().vertex_count() != n || q.frame_count() != len {
                return every();
            }
            kept.extend(
                (first..at + len)
                    .step_by(step)
                    .map(|g| q.frame(g - at).to_vec()),
            );
        }
        at += len;
    }
    Ok(kept)
}

/// The positions of the manifest's `[rig] rest` frame (`SEQUENCE:FRAME`),
/// `None` when it is not set (the topology's own positions).
pub fn rest_frame(
    dir: &Path,
    m: &Manifest,
    topology: &Mesh,
) -> Result<Option<Vec<[f64; 3]>>, DbError> {
    let Some(spec) = &m.rig.rest else {
        return Ok(None);
    };
    let bad = |msg: String| DbError::Manifest {
        path: dir.join(super::MANIFEST),
        msg: format!("[rig] rest = \"{spec}\": {msg}"),
    };
    let (name, frame) = spec
        .rsplit_once(':')
        .ok_or_else(|| bad("expected SEQUENCE:FRAME".into()))?;
    let frame: usize = frame
        .trim()
        .parse()
        .map_err(|_| bad(format!("{frame:?} is not a frame number")))?;
    let s = m
        .sequences
        .iter()
        .find(|s| s.name == name.trim())
        .ok_or_else(|| bad(format!("no sequence {name:?}")))?;
    let seq = m.load_sequence(dir, s)?;
    if seq.mesh().vertex_count() != topology.vertex_count() {
        return Err(bad(format!(
            "the sequence has {} vertices, the topology {}",
            seq.mesh().vertex_count(),
            topology.vertex_count()
        )));
    }
    if frame >= seq.frame_count() {
        return Err(bad(format!(
            "the sequence has {} frames",
            seq.frame_count()
        )));
    }
    Ok(Some(seq.frame(frame).to_vec()))
}

/// Skeletons of every sequence of the database in `dir`; for
/// [`SkeletonKind::Rigid`] also the calibrated skeleton.
#[allow(clippy::type_complexity)]
pub fn extract(
    dir: &Path,
    kind: SkeletonKind,
) -> Result<(Embedding, Vec<SequenceSkeleton>, Option<RigidSkeleton>), DbError> {
    let m = Manifest::load(dir)?;
    let topo = m.load_topology(dir)?;
    let rig = embed_rig(dir, &m, &topo)?;
    let mut out = Vec::with_capacity(m.sequences.len());
    for s in &m.sequences {
        let seq = m.load_sequence(dir, s)?;
        if seq.mesh().vertex_count() != topo.vertex_count() {
            return Err(DbError::Manifest {
                path: dir.join(super::MANIFEST),
                msg: format!(
                    "sequence {}: {} vertices, the topology has {}",
                    s.name,
                    seq.mesh().vertex_count(),
                    topo.vertex_count()
                ),
            });
        }
        out.push(SequenceSkeleton {
            name: s.name.clone(),
            fps: s.fps.unwrap_or(m.fps),
            poses: poses(
                &rig,
                seq.all_positions(),
                topo.vertex_count(),
                match kind {
                    SkeletonKind::Rigid => SkeletonKind::Regressor,
                    k => k,
                },
            ),
            measured: Vec::new(),
            fits: Vec::new(),
        });
    }
    if kind != SkeletonKind::Rigid {
        return Ok((rig, out, None));
    }
    let measured: Vec<&[Pose]> = out.iter().map(|s| s.poses.as_slice()).collect();
    let (sk, fits) = rigid_fit(&rig, &measured);
    for (s, f) in out.iter_mut().zip(fits) {
        s.measured = std::mem::replace(&mut s.poses, f.iter().map(|x| x.pose).collect());
        s.fits = f;
    }
    Ok((rig, out, Some(sk)))
}
