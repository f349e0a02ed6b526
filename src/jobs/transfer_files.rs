//! `jobs::transfer_files`: one transfer onto a loaded scan, written to
//! files, as the `transfer` verb runs it. The frames go to the output as
//! they are solved when nothing needs them all at once (issue 18, item
//! 12); a contact sheet or a comparison with a ground truth holds them.
//! The JSON report is written when asked.

use super::{
    FrameProgress, JobError, TransferReport, TransferSpec, transfer_onto_scan,
    transfer_onto_scan_to,
};
use crate::mesh::Mesh;
use crate::tools::render::preview::PreviewOptions;
use std::path::PathBuf;

/// The files of [`transfer_files`]. The writers' options are the
/// spec's ([`ScanTransferOptions::glb`](super::ScanTransferOptions::glb),
/// [`usd`](super::ScanTransferOptions::usd)).
#[derive(Debug, Clone, Default)]
pub struct TransferFiles {
    /// The mesh output; its extension picks the format (a path without
    /// one: a folder of OBJ frames).
    pub output: PathBuf,
    /// Where the JSON report (per-frame data included) is written.
    /// Default: none (not written).
    pub report: Option<PathBuf>,
    /// Where the contact sheet of the result is written, and its options.
    /// Default: none (no sheet; the frames are streamed unless
    /// [`TransferSpec::truth`] is given).
    pub preview: Option<(PathBuf, PreviewOptions)>,
}

/// Transfers `spec` onto `scan` and writes `files`: the output, then the
/// report. `progress` is called with every frame solved (its total known
/// once the source is read). Returns the report.
pub fn transfer_files(
    scan: &Mesh,
    spec: &TransferSpec,
    files: &TransferFiles,
    progress: &(dyn Fn(FrameProgress) + Sync),
) -> Result<TransferReport, JobError> {
    let (glb, usd) = (spec.options.glb, spec.options.usd);
    let per_frame = files.report.is_some();
    let report = if spec.truth.is_none() && files.preview.is_none() {
        transfer_onto_scan_to(scan, spec, &files.output, glb, usd, per_frame, progress)?
    } else {
        let outcome = transfer_onto_scan(scan, spec, progress)?;
        if let Some((path, opts)) = &files.preview {
            outcome.write_preview(path, opts)?;
        }
        outcome.write(&files.output, glb, usd, per_frame)?
    };
    if let Some(p) = &files.report {
        let json = serde_json::to_string_pretty(&serde_json::to_value(&report)?)?;
        crate::util::fsutil::write_bytes_atomic(p, json.as_bytes())?;
    }
    Ok(report)
}
