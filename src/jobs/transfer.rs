//! Transferring mocap clips onto a scan (Confluent Motion, de Aguiar et al.
//! 2007): the scan is repaired, its markers placed and its system factored
//! once ([`ScanTransferJob::prepare`]); each clip is then one marker motion
//! and one transfer ([`ScanTransferJob::run`]). A moving template source is
//! a one-off ([`crate::transfer::Job::new`]).

use super::JobError;
use crate::batch::{Converted, Converter};
use crate::eval::{VelocityError, velocity_error};
use crate::mesh::io::glb::GlbOptions;
use crate::mesh::io::{SaveOptions, save_sequence_with};
use crate::mesh::{Mesh, MeshSequence};
use crate::retarget::query::{MocapPoses, load_mocap, to_character};
use crate::rig::LoadOptions;
use crate::rig::embed::landmarks::Landmarks;
use crate::skeleton::Pose;
use crate::transfer::{
    Confluent, MarkerOptions, MarkerSpec, PreparedScan, TransferOptions, TransferStats,
    mocap_motion, prepare, transfer,
};
use std::path::{Path, PathBuf};

/// Options of a [`ScanTransferJob`].
#[derive(Debug, Clone)]
pub struct ScanTransferOptions {
    /// Generated markers. Default: [`MarkerOptions::default`] (180, margin
    /// 0.25).
    pub markers: MarkerOptions,
    /// Output frame rate (clips are resampled). Default: 30.
    pub fps: f64,
    /// The transfer (quaternion signs). Default: consistent signs.
    pub transfer: TransferOptions,
    /// How clips are read. Default: decide from the file.
    pub load: LoadOptions,
    /// GLB output. Default: [`GlbOptions::DEFAULT`].
    pub glb: GlbOptions,
}

impl Default for ScanTransferOptions {
    fn default() -> Self {
        ScanTransferOptions {
            markers: MarkerOptions::default(),
            fps: 30.0,
            transfer: TransferOptions::default(),
            load: LoadOptions::default(),
            glb: GlbOptions::DEFAULT,
        }
    }
}

/// A scan prepared and factored once for any number of clips.
pub struct ScanTransferJob {
    /// The repaired scan with its markers and rig.
    pub prepared: PreparedScan,
    /// The factored system of the bone markers.
    pub confluent: Confluent,
    /// The options.
    pub options: ScanTransferOptions,
    /// What the job is, for reports (`transfer --scan SCAN`).
    pub what: String,
}

/// One clip transferred.
pub struct ScanTransferRun {
    /// The clip as read.
    pub mocap: MocapPoses,
    /// Positions, frame-major (the scan's units).
    pub positions: Vec<[f64; 3]>,
    /// What the transfer did.
    pub stats: TransferStats,
}

impl ScanTransferJob {
    /// Repairs `scan`, places markers from `landmarks` and factors the
    /// system once; `name` names the scan in reports.
    pub fn prepare(
        scan: &Mesh,
        landmarks: &Landmarks,
        name: &str,
        options: ScanTransferOptions,
    ) -> Result<ScanTransferJob, JobError> {
        let prepared = prepare(scan, MarkerSpec::Landmarks(landmarks, options.markers))?;
        let (confluent, _) = crate::transfer::Job::factor_mocap(&prepared)?;
        Ok(ScanTransferJob {
            prepared,
            confluent,
            options,
            what: format!("transfer --scan {name}"),
        })
    }

    /// Transfers the clip at `clip` onto the scan.
    pub fn run(&self, clip: &Path) -> Result<ScanTransferRun, JobError> {
        let mocap = load_mocap(clip, &self.options.load, self.options.fps)?;
        if mocap.poses.is_empty() {
            return Err(JobError::Input {
                path: clip.to_path_buf(),
                msg: "the clip has no frames".into(),
            });
        }
        let mut motion = mocap_motion(&self.prepared, &mocap.poses, &mocap.reference)?;
        let (positions, stats) = transfer(
            &self.confluent,
            &mut motion,
            &self.options.transfer,
            &|_| {},
        );
        Ok(ScanTransferRun {
            mocap,
            positions,
            stats,
        })
    }

    /// The joint-velocity error of a result against its clip (on the
    /// scan's embedded skeleton); `None` without a rig.
    pub fn velocity_error(&self, run: &ScanTransferRun) -> Option<VelocityError> {
        let rig = self.prepared.rig.as_ref()?;
        let n = self.prepared.mesh.vertex_count();
        let rest: Pose = rig.joints.map(glam::DVec3::from_array);
        let query = to_character(&rest, &run.mocap.reference, &run.mocap.poses);
        let skel: Vec<Pose> = run
            .positions
            .chunks(n.max(1))
            .map(|p| rig.skeleton(p))
            .collect();
        Some(velocity_error(&query, &skel))
    }

    /// Writes `positions` (the repaired scan's vertices, frame-major) to
    /// `out` (by extension); returns the files written.
    pub fn write(&self, positions: Vec<[f64; 3]>, out: &Path) -> Result<Vec<PathBuf>, JobError> {
        let fps = self.options.fps;
        let seq = MeshSequence::new(self.prepared.mesh.clone(), positions, Some(fps))?;
        Ok(save_sequence_with(
            &seq,
            out,
            &SaveOptions {
                fps: Some(fps),
                glb: self.options.glb,
            },
        )?)
    }
}

impl Converter for ScanTransferJob {
    fn describe(&self) -> String {
        self.what.clone()
    }

    fn convert(&self, clip: &Path, out: &Path) -> Result<Converted, String> {
        let run = self.run(clip).map_err(|e| match e {
            JobError::Input { msg, .. } => msg,
            e => e.to_string(),
        })?;
        let e = self.velocity_error(&run).ok_or("no rig")?;
        let frames = run.stats.frames;
        self.write(run.positions, out).map_err(|e| e.to_string())?;
        Ok(Converted {
            frames,
            error_cm: Some(e.mean_cm),
        })
    }
}
