//! A batch's verdict: it fails when a clip failed, naming the report
//! that lists them (`batch` and `batch merge` exit 1).

use crate::batch::BatchSummary;
use std::path::PathBuf;

/// Clips of a batch failed.
#[derive(Debug, thiserror::Error)]
#[error("{failed} of {clips} clips failed (see {})", .report.display())]
pub struct ClipsFailed {
    /// Clips failed.
    pub failed: usize,
    /// Clips in the run.
    pub clips: usize,
    /// The report that lists them (the first file written).
    pub report: PathBuf,
}

/// Ok when no clip of `s` failed; else [`ClipsFailed`] naming `files[0]`,
/// the report written.
pub fn none_failed(s: &BatchSummary, files: &[PathBuf]) -> Result<(), ClipsFailed> {
    if s.failed == 0 {
        return Ok(());
    }
    Err(ClipsFailed {
        failed: s.failed,
        clips: s.clips,
        report: files.first().cloned().unwrap_or_default(),
    })
}
