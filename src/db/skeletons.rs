//! Per-frame skeletons of a character database (Huang et al. 2015, Sec. 3):
//! the rig embedded once on the topology's rest frame, then every frame's
//! canonical joints from the embedding's regressors (or, as in the paper,
//! the plain centres of the joints' vertex sets), and by default the one
//! rigid skeleton of the character posed to explain them ([`crate::embed::rigid`]).

use super::manifest::{DbError, Manifest};
use crate::embed::landmarks::Landmarks;
use crate::embed::rigid::{Fit, FitOptions, RigidSkeleton};
use crate::embed::{Embedding, parse_parts};
use crate::fsutil::read_text;
use crate::mesh::Mesh;
use crate::pose::{Pose, measure::bone_lengths};
use crate::rig::Canonical;
use rayon::prelude::*;
use serde::Serialize;
use std::path::Path;

/// How joints are read off a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SkeletonKind {
    /// The character's rigid skeleton (bone lengths calibrated over the
    /// database) posed per frame nearest the regressor joints.
    #[default]
    Rigid,
    /// Affine regressors: exact on the rest frame, rigid-motion equivariant.
    Regressor,
    /// Plain centres of each joint's vertex set (Huang et al. 2015, Sec. 3).
    Centroid,
}

impl std::fmt::Display for SkeletonKind {
    /// The words a report uses for the kind.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::Rigid => "rigid skeleton fitted to the regressed joints",
            Self::Regressor => "regressed joints",
            Self::Centroid => "centres of the joints' vertex sets",
        })
    }
}

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
    let Some(lp) = &m.rig.landmarks else {
        if let Some(g) = &m.rig.gltf_skin {
            let g = Manifest::resolve(dir, g);
            let asset = crate::mesh::io::gltf::read_gltf(&g)?;
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
            msg: "no [rig] landmarks or gltf_skin: add `landmarks = \"FILE.json\"` under [rig] (see `surfmotion rig embed --help`)".into(),
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
    Embedding::new(topology, &lm, parts).map_err(DbError::Rig)
}

/// The poses of frames laid out one after another (`n` positions each).
/// [`SkeletonKind::Rigid`] calibrates the bone lengths over these frames.
pub fn poses(rig: &Embedding, frames: &[[f64; 3]], n: usize, kind: SkeletonKind) -> Vec<Pose> {
    let measure = |kind| -> Vec<Pose> {
        frames
            .par_chunks(n.max(1))
            .map(|f| match kind {
                SkeletonKind::Centroid => rig.centroid_skeleton(f),
                _ => rig.skeleton(f),
            })
            .collect()
    };
    match kind {
        SkeletonKind::Rigid => {
            let m = measure(SkeletonKind::Regressor);
            let (_, fits) = rigid_fit(rig, &[&m]);
            fits.into_iter().flatten().map(|f| f.pose).collect()
        }
        k => measure(k),
    }
}

/// Calibrates the character's rigid skeleton over every measured sequence
/// (one bone length for all) and fits it to each frame, in parallel.
pub fn rigid_fit(rig: &Embedding, measured: &[&[Pose]]) -> (RigidSkeleton, Vec<Vec<Fit>>) {
    let all: Vec<Pose> = measured.iter().flat_map(|s| s.iter().copied()).collect();
    let rest = rig.joints.map(glam::DVec3::from_array);
    let sk = RigidSkeleton::calibrate(&rest, &all);
    let opts = FitOptions::default();
    let fits = measured
        .iter()
        .map(|s| s.par_iter().map(|m| sk.fit(m, &opts)).collect())
        .collect();
    (sk, fits)
}

/// Largest relative deviation of each bone's length from its median over
/// the poses (indexed by the child joint; 0 for the root).
pub fn bone_length_spread(poses: &[Pose]) -> [f64; Canonical::COUNT] {
    let lens: Vec<[f64; Canonical::COUNT]> = poses.iter().map(bone_lengths).collect();
    std::array::from_fn(|b| {
        let mut v: Vec<f64> = lens.iter().map(|l| l[b]).collect();
        if v.is_empty() {
            return 0.0;
        }
        v.sort_by(f64::total_cmp);
        let med = v[v.len() / 2];
        if med <= 0.0 {
            return 0.0;
        }
        v.iter().map(|x| (x / med - 1.0).abs()).fold(0.0, f64::max)
    })
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
