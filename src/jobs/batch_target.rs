//! The converter of a batch ([`super::batch_folder`]): a 4D character
//! database driven by the retarget job, or a scan with landmarks taken by
//! the scan transfer job, loaded or factored once for every clip; the
//! options of the other target refused ([`check_target_options`]).

use super::{RetargetJob, RetargetJobOptions, ScanTransferJob, ScanTransferOptions};
use crate::batch::Converter;
use crate::db::BuildProgress;
use crate::embed::landmarks::Landmarks;
use std::path::PathBuf;

use super::JobError;

/// What a batch converts its clips onto.
// One value per batch, consumed at once: its size does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum BatchTarget {
    /// A 4D character database, each clip retargeted through it
    /// ([`RetargetJob`]).
    Database {
        /// The database folder.
        db: PathBuf,
        /// The retarget job's options.
        options: RetargetJobOptions,
    },
    /// A static mesh, each clip transferred onto it
    /// ([`ScanTransferJob`]).
    Scan {
        /// The scan (a file, or `SEQ.pc2:FRAME`).
        scan: String,
        /// Only these OBJ groups of the scan (none: all).
        groups: Vec<String>,
        /// Landmarks on the scan.
        landmarks: PathBuf,
        /// The transfer job's options.
        options: ScanTransferOptions,
    },
}

/// Options given for the other target than the batch's, refused before
/// anything loads. The messages name the option groups; the CLI prints
/// its flags.
#[derive(Debug, thiserror::Error)]
pub enum TargetOptionsError {
    /// Scan transfer options with a database target.
    #[error(
        "`ScanTransferOptions` (groups, markers, fps) apply to a scan target (a database has its own frame rate)"
    )]
    ScanOptionsOnDatabase,
    /// Retarget options with a scan target.
    #[error(
        "`RetargetJobOptions` (deform, t_skel, w_retr, interpolate, blend, skeleton, repair_budget) apply to a database target"
    )]
    DatabaseOptionsOnScan,
}

/// Refuses scan transfer options with a database target (`database`) and
/// retarget options with a scan target; `scan_default` and
/// `retarget_default` say whether the caller left each unset. Setting one
/// to its default value counts as setting it: the CLI passes whether the
/// command line gave any of the group's flags (`batch --db --fps 30` is
/// refused as `--fps 25` is), not whether the values differ.
pub fn check_target_options(
    database: bool,
    scan_default: bool,
    retarget_default: bool,
) -> Result<(), TargetOptionsError> {
    match (database, scan_default, retarget_default) {
        (true, false, _) => Err(TargetOptionsError::ScanOptionsOnDatabase),
        (false, _, false) => Err(TargetOptionsError::DatabaseOptionsOnScan),
        _ => Ok(()),
    }
}

impl BatchTarget {
    /// The converter: the database loaded (its graph built if needed,
    /// `progress` told) or the scan loaded and its transfer factored.
    pub fn converter(self, progress: &dyn BuildProgress) -> Result<Box<dyn Converter>, JobError> {
        Ok(match self {
            BatchTarget::Database { db, options } => {
                Box::new(RetargetJob::load(&db, options, progress)?)
            }
            BatchTarget::Scan {
                scan,
                groups,
                landmarks,
                options,
            } => {
                let mesh = super::mesh::load_mesh_groups(&scan, &groups)?;
                let landmarks = Landmarks::load(&landmarks, mesh.vertex_count())?;
                Box::new(ScanTransferJob::prepare(&mesh, &landmarks, &scan, options)?)
            }
        })
    }
}
