//! Exporting skeletons: the one JSON schema of a sequence's per-frame
//! canonical joints ([`SkeletonFile`], written by `db skeleton` and as the
//! ground truth of a synthetic database), and [`export_skeletons`], which
//! extracts every frame's skeleton of a database (Huang et al. 2015,
//! Sec. 3; the rigid fit of [`crate::embed::rigid`]) and writes JSON and BVH.

use super::JobError;
use crate::db::Manifest;
use crate::db::skeletons::extract;
use crate::embed::frames::{SkeletonKind, bone_length_spread};
use crate::pose::{
    Pose,
    measure::{BVH_NAMES, pose_clip},
};
use crate::rig::Canonical;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One sequence's skeletons: `SEQ.skeleton.json`. Keys are written sorted
/// (`fps`, `frames`, `joints`, `kind`, `sequence`, `source`).
#[derive(Debug, Clone, Serialize)]
pub struct SkeletonFile {
    /// Sequence name.
    pub sequence: String,
    /// Frames per second.
    pub fps: f64,
    /// How the joints were read off the surface (absent for a synthetic
    /// database's ground truth, which drove the surface).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kind: Option<SkeletonKind>,
    /// The clip that drove a synthetic sequence (absent for extracted
    /// skeletons).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source: Option<PathBuf>,
    /// Joint names, [`Canonical::ALL`] order.
    pub joints: Vec<&'static str>,
    /// Per frame, per joint, `[x, y, z]`.
    pub frames: Vec<Vec<[f64; 3]>>,
}

impl SkeletonFile {
    /// The file of `poses` at `fps` (no `kind` or `source`: set them).
    pub fn new(sequence: &str, fps: f64, poses: &[Pose]) -> Self {
        SkeletonFile {
            sequence: sequence.to_string(),
            fps,
            kind: None,
            source: None,
            joints: Canonical::ALL.iter().map(|c| c.name()).collect(),
            frames: poses
                .iter()
                .map(|p| p.iter().map(|q| q.to_array()).collect())
                .collect(),
        }
    }

    /// Writes it (compact JSON, sorted keys) atomically.
    pub fn save(&self, path: &Path) -> Result<(), JobError> {
        let v = serde_json::to_value(self)?;
        crate::util::fsutil::write_bytes_atomic(path, serde_json::to_string(&v)?.as_bytes())?;
        Ok(())
    }
}

/// Per-bone values keyed by the bone's BVH name (sorted).
pub(crate) type ByBone = BTreeMap<&'static str, f64>;

/// What [`export_skeletons`] wrote for one sequence.
#[derive(Debug, Clone, Serialize)]
pub struct SequenceSkeletons {
    /// Sequence name.
    pub sequence: String,
    /// Frames.
    pub frames: usize,
    /// The JSON written.
    pub json: PathBuf,
    /// The BVH written.
    pub bvh: PathBuf,
    /// Per bone, the largest relative deviation of its length from its
    /// median over the frames.
    pub bone_length_max_deviation: ByBone,
    /// The bone that varies most.
    pub worst_bone: &'static str,
    /// Its deviation.
    pub worst_deviation: f64,
    /// With the rigid skeleton: the fit and the measured joints it was
    /// fitted to (lengths and residuals in the database's units).
    #[serde(flatten)]
    pub rigid: Option<RigidFit>,
}

/// The rigid skeleton's fit to the regressor joints of one sequence.
#[derive(Debug, Clone, Serialize)]
pub struct RigidFit {
    /// The calibrated bone lengths.
    pub bone_lengths: ByBone,
    /// The measured (regressor) bones' largest relative deviation.
    pub regressor_bone_length_max_deviation: ByBone,
    /// The measured bone that varies most.
    pub regressor_worst_bone: &'static str,
    /// Its deviation.
    pub regressor_worst_deviation: f64,
    /// Median over frames of the fit's RMS joint distance.
    pub fit_rms_median: f64,
    /// Largest per-frame RMS joint distance.
    pub fit_rms_max: f64,
    /// Largest single joint distance.
    pub fit_joint_max: f64,
}

/// The report of [`export_skeletons`].
#[derive(Debug, Clone, Serialize)]
pub struct SkeletonsReport {
    /// Extraction time (embedding included).
    pub seconds: f64,
    /// The kind extracted.
    pub kind: SkeletonKind,
    /// The database's length unit (of bone lengths and fit residuals).
    pub units: String,
    /// Per sequence.
    pub sequences: Vec<SequenceSkeletons>,
    /// Notes of the rig embedding.
    pub notes: Vec<String>,
    /// Where the files went.
    #[serde(skip)]
    pub output: PathBuf,
}

/// Options of [`export_skeletons`].
#[derive(Debug, Clone, Default)]
pub struct SkeletonsOptions {
    /// How joints are read off a frame. Default: [`SkeletonKind::Rigid`].
    pub kind: SkeletonKind,
    /// Output folder. Default (`None`): `DIR/skeletons`.
    pub output: Option<PathBuf>,
}

/// Extracts the canonical skeleton of every frame of the database in
/// `dir` and writes, per sequence, `SEQ.skeleton.json` ([`SkeletonFile`])
/// and `SEQ.bvh` (the rigid skeleton's BVH plays its fits back exactly; the
/// measured joints' BVH has the rest frame's bones turned to their
/// directions), and `rig.json`.
pub fn export_skeletons(dir: &Path, opts: &SkeletonsOptions) -> Result<SkeletonsReport, JobError> {
    let t = Instant::now();
    let (rig, seqs, rigid) = extract(dir, opts.kind)?;
    let seconds = t.elapsed().as_secs_f64();
    let out = opts.output.clone().unwrap_or_else(|| dir.join("skeletons"));
    rig.save(&out.join("rig.json"))?;
    let rest_pose = rig.joints.map(glam::DVec3::from_array);
    let by_bone = |v: [f64; Canonical::COUNT]| -> ByBone {
        Canonical::ALL
            .iter()
            .skip(1)
            .map(|c| (BVH_NAMES[c.index()], v[c.index()]))
            .collect()
    };
    let worst = |v: &[f64; Canonical::COUNT]| {
        (1..Canonical::COUNT)
            .max_by(|&x, &y| v[x].total_cmp(&v[y]))
            .unwrap_or(1)
    };
    let mut sequences = Vec::new();
    for s in &seqs {
        let jp = out.join(format!("{}.skeleton.json", s.name));
        SkeletonFile {
            kind: Some(opts.kind),
            ..SkeletonFile::new(&s.name, s.fps, &s.poses)
        }
        .save(&jp)?;
        let clip = match &rigid {
            Some(r) => r.clip(&s.fits, s.fps)?,
            None => pose_clip(&rest_pose, &s.poses, s.fps)?,
        };
        let bp = out.join(format!("{}.bvh", s.name));
        crate::mocap::bvh::write_bvh(&clip, &bp)?;
        let spread = bone_length_spread(&s.poses);
        let w = worst(&spread);
        let fit = rigid.as_ref().map(|r| {
            let mut rms: Vec<f64> = s.fits.iter().map(|x| x.rms).collect();
            rms.sort_by(f64::total_cmp);
            let measured = bone_length_spread(&s.measured);
            let mw = worst(&measured);
            RigidFit {
                bone_lengths: by_bone(r.lengths()),
                regressor_bone_length_max_deviation: by_bone(measured),
                regressor_worst_bone: BVH_NAMES[mw],
                regressor_worst_deviation: measured[mw],
                fit_rms_median: rms.get(rms.len() / 2).copied().unwrap_or(0.0),
                fit_rms_max: rms.last().copied().unwrap_or(0.0),
                fit_joint_max: s.fits.iter().map(|x| x.max).fold(0.0, f64::max),
            }
        });
        sequences.push(SequenceSkeletons {
            sequence: s.name.clone(),
            frames: s.poses.len(),
            json: jp,
            bvh: bp,
            bone_length_max_deviation: by_bone(spread),
            worst_bone: BVH_NAMES[w],
            worst_deviation: spread[w],
            rigid: fit,
        });
    }
    let units = Manifest::load(dir).map(|m| m.units).unwrap_or_default();
    Ok(SkeletonsReport {
        seconds,
        kind: opts.kind,
        units,
        sequences,
        notes: rig.notes.clone(),
        output: out,
    })
}
