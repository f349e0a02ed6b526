//! The batch report in the output folder: `batch.json` (everything),
//! `batch.svg` (per-clip time and error bars) and `batch.html` (a table of
//! clips with the plot), all written atomically.
//!
//! The report describes every output of the run's clips, not only those
//! converted now: a clip skipped because its output is complete keeps the
//! frames, time and error its earlier run recorded ([`Earlier`]). While the
//! batch runs, all three are rewritten after each clip (`"finished":
//! false`, and the page says "running"), so a killed run leaves a valid
//! report of what it finished.

use super::runner::{ClipOutcome, ClipStatus, Preparation};
use crate::util::fsutil::{FsError, write_bytes_atomic};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Totals of a batch.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BatchSummary {
    /// What was run (e.g. `retarget --db DIR` from the CLI, `retarget onto DIR`
    /// by default: [`crate::jobs::BatchOptions::describe`]).
    pub what: String,
    /// False while the batch runs (and in the report of a killed run):
    /// `outcomes` then lists the clips finished so far.
    pub finished: bool,
    /// Clips in this run (this shard).
    pub clips: usize,
    /// Converted now.
    pub done: usize,
    /// Already complete.
    pub skipped: usize,
    /// Failed.
    pub failed: usize,
    /// Frames in the outputs listed (converted now, or skipped with an
    /// earlier report's count).
    pub frames: usize,
    /// Frames written by this run.
    pub frames_written: usize,
    /// Wall-clock seconds.
    pub seconds: f64,
    /// Clips converted per minute (done only).
    pub clips_per_minute: f64,
    /// Output frames written per second (done only).
    pub frames_per_second: f64,
    /// Parallel jobs.
    pub jobs: usize,
    /// The shard, `i/n`.
    pub shard: Option<String>,
    /// Clips whose result has plausibility warnings.
    #[serde(default)]
    pub with_warnings: usize,
    /// Times the converter factored its system (the character's blender
    /// and deformer, or the scan's): once for the whole batch.
    pub factorisations: usize,
    /// Seconds that preparation took (once).
    pub prepare_seconds: f64,
    /// Mean per-clip fixed cost of the clips converted now (seconds: the
    /// wall clock minus the per-frame work, [`ClipOutcome::fixed_seconds`]),
    /// when measured.
    pub fixed_seconds_per_clip: Option<f64>,
    /// Clips in the whole library before sharding (a shard's report only:
    /// `batch merge` checks that the shards add up to it).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub library_clips: Option<usize>,
    /// The shard reports a merged report was made of (`batch merge`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub merged_from: Vec<PathBuf>,
    /// Every clip.
    pub outcomes: Vec<ClipOutcome>,
}

/// The old name of [`BatchSummary`] (before session 40: one name per concept,
/// issue 40 — `Summary` named a batch's totals and two other things).
#[deprecated(note = "renamed BatchSummary")]
pub type Summary = BatchSummary;

impl BatchSummary {
    /// Totals from outcomes.
    pub fn new(
        what: String,
        outcomes: Vec<ClipOutcome>,
        seconds: f64,
        jobs: usize,
        shard: Option<String>,
    ) -> BatchSummary {
        let count = |s| outcomes.iter().filter(|o| o.status == s).count();
        let done = count(ClipStatus::Done);
        let frames = outcomes.iter().map(|o| o.frames).sum();
        let frames_written = outcomes
            .iter()
            .filter(|o| o.status == ClipStatus::Done)
            .map(|o| o.frames)
            .sum();
        BatchSummary {
            what,
            finished: true,
            clips: outcomes.len(),
            done,
            skipped: count(ClipStatus::Skipped),
            failed: count(ClipStatus::Failed),
            frames,
            frames_written,
            seconds,
            clips_per_minute: 60.0 * done as f64 / seconds.max(1e-9),
            frames_per_second: frames_written as f64 / seconds.max(1e-9),
            jobs,
            shard,
            with_warnings: outcomes.iter().filter(|o| !o.warnings.is_empty()).count(),
            factorisations: 0,
            prepare_seconds: 0.0,
            fixed_seconds_per_clip: {
                let fixed: Vec<f64> = outcomes
                    .iter()
                    .filter(|o| o.status == ClipStatus::Done)
                    .filter_map(|o| o.fixed_seconds)
                    .collect();
                (!fixed.is_empty()).then(|| fixed.iter().sum::<f64>() / fixed.len() as f64)
            },
            library_clips: None,
            merged_from: Vec::new(),
            outcomes,
        }
    }

    /// Records what the converter prepared once ([`Preparation`]).
    pub(crate) fn set_preparation(&mut self, p: Preparation) {
        self.factorisations = p.factorisations;
        self.prepare_seconds = p.seconds;
    }
}

impl BatchSummary {
    /// One line of totals: clips converted, skipped, failed, frames, speed.
    pub fn line(&self) -> String {
        format!(
            "{}: {}: {} converted, {} already done, {} failed, {} with plausibility warnings; {} frames written in {:.1} s, {} in the outputs ({:.1} clips/min, {:.0} frames/s, {}{}); {} ({:.1} s){}",
            self.what,
            count(self.clips, "clip"),
            self.done,
            self.skipped,
            self.failed,
            self.with_warnings,
            self.frames_written,
            self.seconds,
            self.frames,
            self.clips_per_minute,
            self.frames_per_second,
            count(self.jobs, "job"),
            self.shard
                .as_ref()
                .map(|x| format!(", shard {x}"))
                .unwrap_or_default(),
            count(self.factorisations, "factorisation"),
            self.prepare_seconds,
            self.fixed_seconds_per_clip
                .map(|s| format!(", {s:.2} s fixed cost per clip"))
                .unwrap_or_default()
        )
    }
}

/// `n` and `noun`, in the plural unless `n` is 1 ("1 clip", "2 jobs",
/// "3 vertices", "2 matches", "9 queries"; the batch line said "1 clips"
/// and "1 jobs").
pub fn count(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else if let Some(stem) = noun.strip_suffix("ex") {
        format!("{n} {stem}ices")
    } else if let Some(stem) = noun
        .strip_suffix('y')
        .filter(|s| !s.ends_with(['a', 'e', 'o', 'u']))
    {
        format!("{n} {stem}ies")
    } else if noun.ends_with('s') || noun.ends_with('x') || noun.ends_with("ch") {
        format!("{n} {noun}es")
    } else {
        format!("{n} {noun}s")
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A bar chart: per clip, seconds (blue, left scale) and joint-velocity
/// error (orange, right scale); failed clips marked red.
pub(crate) fn plot_svg(s: &BatchSummary) -> String {
    let n = s.outcomes.len().max(1);
    // At least wide enough for the two axis titles (a report of one or two
    // clips, as a killed run leaves, overlapped them).
    let (w, h, left, bottom) = ((60.0 + 14.0 * n as f64).max(440.0), 260.0, 50.0, 40.0);
    let tmax = s.outcomes.iter().map(|o| o.seconds).fold(1e-9, f64::max);
    let emax = s
        .outcomes
        .iter()
        .filter_map(|o| o.error_cm)
        .fold(1e-9, f64::max);
    let ph = h - bottom - 20.0;
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" font-family=\"sans-serif\" font-size=\"10\">\n"
    );
    let _ = writeln!(
        svg,
        "<text x=\"4\" y=\"12\" fill=\"#1f77b4\">time (max {tmax:.2} s)</text><text x=\"{:.0}\" y=\"12\" fill=\"#ff7f0e\" text-anchor=\"end\">joint-velocity error (max {emax:.2} cm/frame)</text>",
        w - 4.0
    );
    let _ = writeln!(
        svg,
        "<line x1=\"{left}\" y1=\"{:.0}\" x2=\"{:.0}\" y2=\"{:.0}\" stroke=\"#000\"/>",
        h - bottom,
        w - 10.0,
        h - bottom
    );
    for (i, o) in s.outcomes.iter().enumerate() {
        let x = left + 14.0 * i as f64;
        let name = esc(&o.clip.display().to_string());
        if o.status == ClipStatus::Failed {
            let _ = writeln!(
                svg,
                "<rect x=\"{x:.1}\" y=\"20\" width=\"12\" height=\"{ph:.1}\" fill=\"#d62728\" opacity=\"0.25\"><title>{name}: failed</title></rect>"
            );
        }
        let th = ph * o.seconds / tmax;
        let _ = writeln!(
            svg,
            "<rect x=\"{x:.1}\" y=\"{:.1}\" width=\"6\" height=\"{th:.1}\" fill=\"#1f77b4\"><title>{name}: {:.2} s</title></rect>",
            h - bottom - th,
            o.seconds
        );
        if let Some(e) = o.error_cm {
            let eh = ph * e / emax;
            let _ = writeln!(
                svg,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"6\" height=\"{eh:.1}\" fill=\"#ff7f0e\"><title>{name}: {e:.2} cm/frame</title></rect>",
                x + 6.0,
                h - bottom - eh
            );
        }
        let _ = writeln!(
            svg,
            "<text transform=\"translate({:.1},{:.0}) rotate(60)\" font-size=\"7\">{}</text>",
            x + 3.0,
            h - bottom + 4.0,
            esc(&o.clip.file_stem().unwrap_or_default().to_string_lossy())
        );
    }
    svg.push_str("</svg>\n");
    svg
}

/// An HTML page: totals, the plot, a table of clips.
pub fn html(s: &BatchSummary) -> String {
    let mut h = String::from(
        "<!doctype html>\n<meta charset=\"utf-8\">\n<title>surfmotion batch</title>\n<style>body{font-family:sans-serif;margin:2em}td,th{padding:2px 8px;text-align:left}.failed{color:#b00}</style>\n",
    );
    let _ = writeln!(h, "<h1>surfmotion batch</h1>\n<p>{}.</p>", esc(&s.line()));
    if !s.merged_from.is_empty() {
        let _ = writeln!(
            h,
            "<p class=\"merged\">Merged from {}: {}.</p>",
            count(s.merged_from.len(), "shard report"),
            esc(&s
                .merged_from
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(", "))
        );
    }
    if !s.finished {
        h.push_str("<p class=\"running\"><b>running</b> (or stopped before its end): the clips listed are those finished so far.</p>\n");
    }
    h.push_str(&plot_svg(s));
    h.push_str("<table>\n<tr><th>clip</th><th>status</th><th>frames</th><th>seconds</th><th>error (cm/frame)</th><th>warnings</th><th>output / reason</th></tr>\n");
    for o in &s.outcomes {
        let status = match o.status {
            ClipStatus::Done => "done",
            ClipStatus::Skipped => "skipped",
            ClipStatus::Failed => "failed",
        };
        let label = if o.earlier {
            "skipped (done earlier)"
        } else {
            status
        };
        let _ = writeln!(
            h,
            "<tr class=\"{status}\"><td>{}</td><td>{label}</td><td>{}</td><td>{:.2}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            esc(&o.clip.display().to_string()),
            o.frames,
            o.seconds,
            o.error_cm.map(|e| format!("{e:.2}")).unwrap_or_default(),
            o.warnings
                .iter()
                .map(|w| esc(&w.message))
                .collect::<Vec<_>>()
                .join("<br>"),
            esc(&o
                .reason
                .clone()
                .unwrap_or_else(|| o.output.display().to_string()))
        );
    }
    h.push_str("</table>\n");
    h
}

/// Writes `batch.json`, `batch.svg` and `batch.html` into `dir` (names
/// carry the shard, `batch-2of8.json`, so shards sharing a folder do not
/// overwrite each other). Returns the files.
pub fn write_summary(dir: &Path, s: &BatchSummary) -> Result<Vec<PathBuf>, FsError> {
    let stem = report_stem(s.shard.as_deref());
    let json = dir.join(format!("{stem}.json"));
    let svg = dir.join(format!("{stem}.svg"));
    let page = dir.join(format!("{stem}.html"));
    let text = serde_json::to_string_pretty(s).unwrap_or_default();
    // The JSON last: whoever sees a clip in it finds it in the page and
    // the plot too (a run killed between two writes leaves the page at
    // most one clip ahead).
    write_bytes_atomic(&svg, plot_svg(s).as_bytes())?;
    write_bytes_atomic(&page, html(s).as_bytes())?;
    write_bytes_atomic(&json, text.as_bytes())?;
    Ok(vec![json, page, svg])
}

/// What earlier reports in an output folder recorded for the outputs they
/// converted: output path → (clip, frames, seconds, error, warnings).
#[derive(Debug, Default)]
pub struct Earlier {
    by_output: HashMap<PathBuf, Recorded>,
}

/// What an earlier report recorded of one output.
type Recorded = (
    PathBuf,
    usize,
    f64,
    Option<f64>,
    Vec<crate::batch::ClipWarning>,
);

impl Earlier {
    /// Reads every `batch*.json` in `dir` (any shard split, so a folder
    /// first converted whole and then by shards keeps its records); the
    /// report named `own` wins over the others. Unreadable reports are
    /// ignored.
    pub fn load(dir: &Path, own: &str) -> Earlier {
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
            .map(|rd| {
                rd.flatten()
                    .map(|e| e.path())
                    .filter(|p| {
                        let n = p.file_name().unwrap_or_default().to_string_lossy();
                        n.starts_with("batch") && n.ends_with(".json")
                    })
                    .collect()
            })
            .unwrap_or_default();
        // Own report last, so its records overwrite the others'.
        files.sort_by_key(|p| (p.file_name().is_some_and(|n| n == own), p.clone()));
        let mut e = Earlier::default();
        for f in files {
            let Ok(text) = crate::util::fsutil::read_text(&f) else {
                continue;
            };
            let Ok(v) = serde_json::from_str::<serde_json::Value>(&text) else {
                continue;
            };
            for o in v["outcomes"].as_array().into_iter().flatten() {
                let done = o["status"] == "done" || o["earlier"] == true;
                let (Some(clip), Some(out), Some(frames)) = (
                    o["clip"].as_str(),
                    o["output"].as_str(),
                    o["frames"].as_u64(),
                ) else {
                    continue;
                };
                if done {
                    e.by_output.insert(
                        PathBuf::from(out),
                        (
                            PathBuf::from(clip),
                            frames as usize,
                            o["seconds"].as_f64().unwrap_or(0.0),
                            o["error_cm"].as_f64(),
                            serde_json::from_value(o["warnings"].clone()).unwrap_or_default(),
                        ),
                    );
                }
            }
        }
        e
    }

    /// A skipped outcome with what the run that wrote its output recorded
    /// (the same clip to the same output); others unchanged.
    pub fn fill(&self, o: &mut ClipOutcome) {
        if o.status != ClipStatus::Skipped {
            return;
        }
        if let Some((clip, frames, seconds, error, warnings)) = self.by_output.get(&o.output)
            && *clip == o.clip
        {
            o.frames = *frames;
            o.seconds = *seconds;
            o.error_cm = *error;
            o.warnings = warnings.clone();
            o.earlier = true;
        }
    }
}

/// The name of a run's report files without extension: `batch`, or
/// `batch-2of8` for shard 2/8.
pub fn report_stem(shard: Option<&str>) -> String {
    match shard {
        Some(x) => format!("batch-{}", x.replace('/', "of")),
        None => "batch".into(),
    }
}

/// Writes only `batch.json` (the report while the batch runs).
pub fn write_json(dir: &Path, s: &BatchSummary) -> Result<PathBuf, FsError> {
    let json = dir.join(format!("{}.json", report_stem(s.shard.as_deref())));
    let text = serde_json::to_string_pretty(s).unwrap_or_default();
    write_bytes_atomic(&json, text.as_bytes())?;
    Ok(json)
}

#[cfg(test)]
mod tests {
    /// Plurals of the nouns the reports count (moved from the CLI, which
    /// forwards to this function).
    #[test]
    fn count_says_one_frame_and_two_vertices() {
        assert_eq!(super::count(1, "frame"), "1 frame");
        assert_eq!(super::count(0, "transition"), "0 transitions");
        assert_eq!(super::count(3, "vertex"), "3 vertices");
        assert_eq!(super::count(2, "match"), "2 matches");
        assert_eq!(super::count(9, "query"), "9 queries");
        assert_eq!(super::count(2, "key"), "2 keys");
    }
}
