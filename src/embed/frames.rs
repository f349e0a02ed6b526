//! The joints of a character's frames read off its [`Embedding`]: by the
//! regressors, as the centres of the joints' vertex sets (Huang et al.
//! 2015, Sec. 3), or as the one rigid skeleton of the character posed to
//! explain the regressed joints ([`super::rigid`]), and how much the bone
//! lengths of measured joints spread.

use super::Embedding;
use super::rigid::{Fit, FitOptions, RigidSkeleton};
use crate::pose::Pose;
use crate::pose::measure::bone_lengths;
use crate::rig::Canonical;
use rayon::prelude::*;
use serde::Serialize;

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

/// The poses of frames laid out one after another (`n` positions each).
/// [`SkeletonKind::Rigid`] calibrates the bone lengths over these frames.
pub fn poses(rig: &Embedding, frames: &[[f64; 3]], n: usize, kind: SkeletonKind) -> Vec<Pose> {
    let measure = |kind| -> Vec<Pose> {
        frames
            .par_chunks(n.max(1))
            .map(|f| match kind {
                SkeletonKind::Centroid => rig.centroid_joints(f),
                _ => rig.frame_joints(f),
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
pub(crate) fn rigid_fit(rig: &Embedding, measured: &[&[Pose]]) -> (RigidSkeleton, Vec<Vec<Fit>>) {
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
