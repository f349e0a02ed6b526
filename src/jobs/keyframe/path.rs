//! One key-frame query written to a mesh output frame by frame.

use super::KeyframeJobError;
use super::keys::Keys;
use super::verdict::{Missed, missed_targets};
use crate::db::Character;
use crate::drive::Each;
use crate::keyframe::{KeyframeOptions, Plan, Report, Targets, plan_path, prepare};
use crate::mesh::io::SaveOptions;
use crate::mesh::io::stream::SequenceWriter;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// The report of a key-frame path: [`Report`] (its key-frame poses
/// filled in) and the targets it misses.
#[derive(Debug, Clone, Serialize)]
pub struct PathReport {
    /// The query's report.
    #[serde(flatten)]
    pub report: Report,
    /// The targets missed ([`missed_targets`]).
    pub missed: Vec<Missed>,
}

/// A key-frame path written ([`write_path`]).
pub struct PathRun {
    /// The plan.
    pub plan: Plan,
    /// The report.
    pub report: PathReport,
    /// The files written.
    pub written: Vec<PathBuf>,
}

/// Finds the path through `keys` for `targets` (Eq. 7) and writes its
/// meshes to `out` frame by frame (a [`SequenceWriter`]: point caches and
/// OBJ folders stream, a GLB is checked against the memory budget before
/// the first frame is made), telling `progress` each stage. The character
/// is prepared once ([`prepare`]: the topology in metres, the factored
/// blender) for the writer and the synthesis. Every frame
/// was held, then the whole file's bytes (attack s14, item 3: 8.6 MB per
/// output second, 7.1 GB for an hour).
pub fn write_path(
    ch: &Character,
    keys: &Keys,
    targets: &Targets,
    opts: &KeyframeOptions,
    out: &Path,
    progress: &mut dyn FnMut(&str),
) -> Result<PathRun, KeyframeJobError> {
    write_path_with(
        ch,
        keys,
        targets,
        opts,
        out,
        &SaveOptions::default(),
        progress,
    )
}

/// [`write_path`] with the writer's format options `formats` (GLB, USD;
/// its frame rate is the database's).
pub fn write_path_with(
    ch: &Character,
    keys: &Keys,
    targets: &Targets,
    opts: &KeyframeOptions,
    out: &Path,
    formats: &SaveOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<PathRun, KeyframeJobError> {
    let planned = plan_path(ch, &keys.ids, targets, opts, progress)?;
    let total = planned.frames();
    let fps = ch.manifest().fps;
    let save = SaveOptions {
        fps: Some(fps),
        ..*formats
    };
    let prepared = prepare(ch)?;
    let mut writer = SequenceWriter::create(prepared.topology_metres(), out, total, &save)
        .map_err(|e| {
            // "a GLB of 16,559 frames would need 11.9 GB" for a one-hour
            // time without a word that the search had stopped short of
            // the target (issue 46.12).
            let notes = planned.bounds_hit();
            if notes.is_empty() {
                KeyframeJobError::from(e)
            } else {
                KeyframeJobError::Bounded {
                    source: e,
                    frames: total,
                    bounds: notes.join("; "),
                }
            }
        })?;
    let mut k = 0;
    let sink = Each(|p: &[[f64; 3]]| -> Result<(), KeyframeJobError> {
        if k % 16 == 0 {
            progress(&format!(
                "blending and writing the meshes: frame {k}/{total}"
            ));
        }
        if k + 1 == total {
            progress("measuring the transitions' smoothness");
        }
        k += 1;
        Ok(writer.push(p)?)
    });
    let s = planned.synthesise_into::<_, KeyframeJobError>(ch, &prepared, targets, opts, sink)?;
    let written = writer.finish()?;
    let mut report = s.report;
    report.poses = keys.resolved.clone();
    let missed = missed_targets(&report);
    Ok(PathRun {
        plan: s.plan,
        report: PathReport { report, missed },
        written,
    })
}
