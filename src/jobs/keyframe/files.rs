//! The files a key-frame job writes besides its mesh output, after the
//! work: its JSON report (`report`: pretty JSON, written atomically) and
//! the grid's heat-map (`plot`: `.svg` with axes and legend, else PNG).
//! The CLI's `--report` and `--plot`.

use super::KeyframeJobError;
use super::path::PathRun;
use crate::keyframe::grid::GridReport;
use serde::Serialize;
use std::path::Path;

/// `v` as pretty JSON written to `path` atomically, when given.
pub fn write_report<T: Serialize + ?Sized>(
    path: Option<&Path>,
    v: &T,
) -> Result<(), KeyframeJobError> {
    let Some(path) = path else { return Ok(()) };
    let json = serde_json::to_string_pretty(v)?;
    Ok(crate::util::fsutil::write_bytes_atomic(
        path,
        json.as_bytes(),
    )?)
}

/// A path's report ([`super::PathReport`], the targets it missed
/// included) as JSON, written to `report` when given; the value is
/// returned for the caller to print.
pub fn write_path_report(
    run: &PathRun,
    report: Option<&Path>,
) -> Result<serde_json::Value, KeyframeJobError> {
    let v = serde_json::to_value(&run.report)?;
    write_report(report, &v)?;
    Ok(v)
}

/// A grid's report written to `report` and its heat-map to `plot`
/// ([`crate::keyframe::heatmap::save`]), each when given, in that order.
pub fn write_grid_files(
    g: &GridReport,
    report: Option<&Path>,
    plot: Option<&Path>,
) -> Result<(), KeyframeJobError> {
    write_report(report, g)?;
    if let Some(p) = plot {
        crate::keyframe::heatmap::save(g, p)?;
    }
    Ok(())
}
