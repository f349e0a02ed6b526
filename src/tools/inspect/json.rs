//! The JSON files the project reads and writes (landmarks, markers, rigs,
//! rig maps, skeletons, graph caches, reports), told apart by content.

use super::error::InspectError;
use crate::batch::summary::count;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// What a JSON input holds (landmarks or Confluent markers).
#[derive(Debug, Clone, Serialize)]
pub struct JsonReport {
    /// The file.
    pub path: PathBuf,
    /// What it is ([`json_kind`]): `landmarks`, `markers`, `rig`, `rig
    /// map`, `skeletons`, `graph cache` or a `retarget|transfer|keyframe
    /// report`.
    pub format: String,
    /// One line per fact.
    pub lines: Vec<String>,
}

/// What kind of JSON file `v` is, by its content: every JSON file the
/// project reads or writes has its own top-level keys. `None`: none of
/// them (a file is never read as landmarks unless it has a landmark name;
/// `inspect DB/cache/graph-shape.json` said `unknown landmark "graph"`).
pub fn json_kind(v: &serde_json::Value) -> Option<&'static str> {
    if let Some(a) = v.as_array() {
        let triple = |x: &serde_json::Value| x.as_array().is_some_and(|p| p.len() == 3);
        return if !a.is_empty() && a.iter().all(triple) {
            Some("pose")
        } else if !a.is_empty() && a.iter().all(|r| r.get("t").is_some()) {
            Some("play script")
        } else {
            None
        };
    }
    let o = v.as_object()?;
    let has = |k: &str| o.contains_key(k);
    let kind = if has("key")
        && o.get("graph")
            .is_some_and(|g| g.get("transitions").is_some())
    {
        "graph cache"
    } else if o.get("markers").is_some_and(|m| m.is_array()) {
        "markers"
    } else if has("vertex_count") && has("joints") && has("skin") {
        "rig"
    } else if has("convention") && o.get("joints").is_some_and(|j| j.is_object()) {
        "rig map"
    } else if has("sequence") && has("joints") && o.get("frames").is_some_and(|f| f.is_array()) {
        "skeletons"
    } else if has("keys") && has("segments") && has("targets") {
        "keyframe report"
    } else if has("keys") && has("distances") && has("times") && has("reachable") {
        "keyframe grid report"
    } else if has("outcomes") && has("clips_per_minute") {
        "batch report"
    } else if has("per_second") && has("realtime_factor") {
        "play report"
    } else if o.get("format").and_then(|f| f.as_str()) == Some("surfmotion-web") {
        "web site manifest"
    } else if has("retrieval") && has("frames") {
        "retarget report"
    } else if has("transfer") && has("scan") {
        "transfer report"
    } else if !o.is_empty()
        && o.iter()
            .all(|(k, v)| crate::embed::parts::Part::from_name(k).is_some() && v.is_array())
        && o.values()
            .flat_map(|v| v.as_array().into_iter().flatten())
            .all(|x| x.is_u64())
    {
        "parts"
    } else if o
        .keys()
        .any(|k| crate::embed::landmarks::Landmark::from_name(k).is_some())
    {
        "landmarks"
    } else {
        return None;
    };
    Some(kind)
}

/// Landmarks (`{name: vertex | [x, y, z]}`), markers (`{"markers": […]}`),
/// and the other JSON files the project writes (rig, rig map, graph cache,
/// skeletons, reports), told apart by [`json_kind`].
pub(super) fn inspect_json(path: &Path) -> Result<JsonReport, InspectError> {
    let (text, v, format) = read_kind(path)?;
    let lines = match format {
        "markers" => markers_lines(&text, path)?,
        "landmarks" => landmarks_lines(&text, path)?,
        "graph cache" => graph_cache_lines(&v),
        "rig" => rig_lines(&v),
        "parts" => parts_lines(&v),
        "pose" => pose_lines(&v),
        "play script" => play_script_lines(&v),
        "keyframe grid report" => grid_report_lines(&v),
        "batch report" => batch_report_lines(&v),
        "play report" => play_report_lines(&v),
        "web site manifest" => site_manifest_lines(&v),
        "rig map" => rig_map_lines(&v),
        "skeletons" => skeletons_lines(&v),
        _ => report_lines(&v, format),
    };
    Ok(JsonReport {
        path: path.to_path_buf(),
        format: format.into(),
        lines,
    })
}

fn json_err(e: String) -> InspectError {
    InspectError::Json(e)
}

/// The file's text, its value and its kind ([`json_kind`], its fields
/// checked): refuses an unknown or malformed file.
fn read_kind(path: &Path) -> Result<(String, serde_json::Value, &'static str), InspectError> {
    let err = json_err;
    let text = crate::util::fsutil::read_text(path).map_err(|e| err(e.to_string()))?;
    let v: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| err(format!("{}: {e}", path.display())))?;
    let Some(format) = json_kind(&v) else {
        let keys = match v.as_object() {
            Some(o) if o.is_empty() => "an empty object".to_string(),
            Some(o) => format!(
                "top-level keys {}",
                o.keys().take(8).cloned().collect::<Vec<_>>().join(", ")
            ),
            None => "not an object".to_string(),
        };
        return Err(err(format!(
            "{}: unknown JSON ({keys}); inspect reads landmarks, markers, rigs, rig maps, skeletons, poses, play scripts, graph caches, web site manifests and retarget, transfer, keyframe, grid, batch and play reports",
            path.display()
        )));
    };
    // A file that has a kind's keys but not its values is malformed, not
    // that kind ("a keyframe report: 238 frames at NaN fps", exit 0, for a
    // report whose `fps` was `[[[[1e308]]]]`).
    if let Err(why) = check_fields(&v, format).and_then(|()| holds_together(&v, format)) {
        return Err(err(format!(
            "{}: a malformed {format}: {why}",
            path.display()
        )));
    }
    Ok((text, v, format))
}

/// The number at key `k` of `v`.
fn num(v: &serde_json::Value, k: &str) -> Option<f64> {
    v.get(k).and_then(|x| x.as_f64())
}

/// The length of the array at key `k` of `v` (0 if none).
fn len(v: &serde_json::Value, k: &str) -> usize {
    v.get(k).and_then(|x| x.as_array()).map_or(0, |a| a.len())
}

/// The length of `v` as an array (0 if not one).
fn len_of(v: &serde_json::Value) -> usize {
    v.as_array().map_or(0, |a| a.len())
}

fn markers_lines(text: &str, path: &Path) -> Result<Vec<String>, InspectError> {
    let mut lines = Vec::new();
    let f = crate::transfer::MarkerFile::parse(text, path, usize::MAX)
        .map_err(|e| json_err(e.to_string()))?;
    lines.push(format!(
        "{} markers{}",
        f.markers.len(),
        f.triangle_count
            .map(|t| format!(" on a mesh of {t} triangles"))
            .unwrap_or_default()
    ));
    let mut per: std::collections::BTreeMap<String, usize> = Default::default();
    for m in &f.markers {
        let b = m
            .bone
            .map_or("(no bone)".to_string(), |b| b.name().to_string());
        *per.entry(b).or_default() += 1;
    }
    lines.push(format!(
        "by bone: {}",
        per.iter()
            .map(|(b, n)| format!("{b} {n}"))
            .collect::<Vec<_>>()
            .join(", ")
    ));
    Ok(lines)
}

fn landmarks_lines(text: &str, path: &Path) -> Result<Vec<String>, InspectError> {
    use crate::embed::landmarks::{Landmark, Landmarks, Mark};
    let mut lines = Vec::new();
    let lm = Landmarks::parse(text, path, usize::MAX).map_err(|e| json_err(e.to_string()))?;
    for (l, m) in &lm.marks {
        lines.push(match m {
            Mark::Vertex(i) => format!("{:<11} vertex {i}", l.name()),
            Mark::Point(p) => {
                format!("{:<11} point [{}, {}, {}]", l.name(), p[0], p[1], p[2])
            }
            Mark::Surface(a) => format!(
                "{:<11} on triangle {:?} (weights {:?}, offset {:?})",
                l.name(),
                a.triangle,
                a.weights,
                a.offset
            ),
        });
    }
    let optional: Vec<&str> = Landmark::ALL
        .iter()
        .filter(|l| !lm.marks.contains_key(l))
        .map(|l| l.name())
        .collect();
    if !optional.is_empty() {
        lines.push(format!(
            "not given (optional, placed by body proportions): {}",
            optional.join(", ")
        ));
    }
    Ok(lines)
}

fn graph_cache_lines(v: &serde_json::Value) -> Vec<String> {
    let mut lines = Vec::new();
    let g = &v["graph"];
    lines.push(format!(
        "the Surface Motion Graph cached by `db build` (measure {}); rebuilt whenever the database changes",
        g["measure"].as_str().unwrap_or("?")
    ));
    let seqs = named_frames(g, "len");
    lines.push(format!("{} sequences: {}", seqs.len(), seqs.join(", ")));
    lines.push(format!(
        "{} transitions, {} edges",
        len(g, "transitions"),
        len(g, "edges")
    ));
    lines
}

fn rig_lines(v: &serde_json::Value) -> Vec<String> {
    let mut lines = Vec::new();
    lines.push(format!(
        "a rig embedded by `rig embed`: {} joints on a mesh of {} vertices, {:.3} m tall",
        len(v, "joints"),
        v["vertex_count"],
        num(v, "height").unwrap_or(f64::NAN)
    ));
    for n in v["notes"].as_array().into_iter().flatten() {
        lines.push(format!("note: {}", n.as_str().unwrap_or_default()));
    }
    lines
}

fn parts_lines(v: &serde_json::Value) -> Vec<String> {
    let o = v.as_object().into_iter().flatten();
    vec![format!(
        "part labels (`InitOptions::parts` of `db::init`): {}",
        o.map(|(k, ids)| format!("{k} {}", len_of(ids)))
            .collect::<Vec<_>>()
            .join(", ")
    )]
}

fn pose_lines(v: &serde_json::Value) -> Vec<String> {
    let n = len_of(v);
    vec![format!(
        "a key-frame pose (a `jobs::keyframe` key from POSE.json): {n} joints [x, y, z] in metres, Y up{}",
        if n == crate::rig::Canonical::COUNT {
            String::new()
        } else {
            format!(" (keyframe needs {})", crate::rig::Canonical::COUNT)
        }
    )]
}

fn play_script_lines(v: &serde_json::Value) -> Vec<String> {
    let mut lines = Vec::new();
    let a = v.as_array().map_or(&[][..], |a| a.as_slice());
    let last = a.iter().filter_map(|r| r["t"].as_f64()).fold(0.0, f64::max);
    let mut spaces: Vec<&str> = a.iter().filter_map(|r| r["space"].as_str()).collect();
    spaces.dedup();
    lines.push(format!(
        "a `play` script: {} over {} s, spaces {}; `jobs::play::play_session` checks it against the database's spaces",
        count(a.len(), "request"),
        crate::util::numfmt::Short(last),
        if spaces.is_empty() { "-".to_string() } else { spaces.join(", ") }
    ));
    // The times `play` refuses whatever the database ("1 request
    // over 1e308 s" was printed as if the script were sound).
    use crate::parametric::script::MAX_SECONDS;
    use crate::util::numfmt::Short;
    let mut before = 0.0;
    for (i, r) in a.iter().enumerate() {
        let Some(t) = r["t"].as_f64() else {
            lines.push(format!(
                "problem: request {i}: no \"t\" (seconds); `play` refuses it"
            ));
            break;
        };
        if !(0.0..=MAX_SECONDS).contains(&t) || t < before {
            lines.push(format!(
                "problem: request {i}: t = {}: expected seconds in [0, {MAX_SECONDS}], in time order; `play` refuses it",
                Short(t)
            ));
            break;
        }
        before = t;
    }
    lines
}

fn grid_report_lines(v: &serde_json::Value) -> Vec<String> {
    let keys: Vec<&str> = v["keys"]
        .as_array()
        .into_iter()
        .flatten()
        .filter_map(|k| k.as_str())
        .collect();
    vec![
        format!(
            "a key-frame grid (the report of `jobs::keyframe::grid`): {}, {} × {}",
            keys.join(" -> "),
            count(len(v, "distances"), "distance"),
            count(len(v, "times"), "time")
        ),
        format!(
            "reachable {}, unreachable {}; query time {:.2} ms mean",
            v["reachable"]["distance_m"]["count"],
            v["unreachable"]["distance_m"]["count"],
            num(v, "query_ms_mean").unwrap_or(f64::NAN)
        ),
    ]
}

fn batch_report_lines(v: &serde_json::Value) -> Vec<String> {
    vec![format!(
        "a `batch` report: {}: {}, {} converted, {} already done, {} failed{}",
        v["what"].as_str().unwrap_or("?"),
        count(len(v, "outcomes"), "clip"),
        v["done"],
        v["skipped"],
        v["failed"],
        if v["finished"] == false {
            " (the run did not finish)"
        } else {
            ""
        }
    )]
}

fn play_report_lines(v: &serde_json::Value) -> Vec<String> {
    vec![format!(
        "a `play` report: {} at {} fps ({:.2} s), {}, {}",
        count(v["frames"].as_u64().unwrap_or(0) as usize, "frame"),
        num(v, "fps").unwrap_or(f64::NAN),
        num(v, "seconds").unwrap_or(f64::NAN),
        count(len(v, "transitions"), "transition"),
        count(len(v, "notices"), "notice")
    )]
}

fn site_manifest_lines(v: &serde_json::Value) -> Vec<String> {
    let seqs = named_frames(v, "frames");
    vec![
        format!(
            "the manifest of a site written by `web export` ({} mode, character '{}'): geometry {}, max vertex error {:.3} mm",
            v["mode"].as_str().unwrap_or("?"),
            v["name"].as_str().unwrap_or("?"),
            v["geometry"].as_str().unwrap_or("?"),
            1e3 * num(v, "max_error").unwrap_or(f64::NAN)
        ),
        format!("{}: {}", count(seqs.len(), "sequence"), seqs.join(", ")),
    ]
}

fn rig_map_lines(v: &serde_json::Value) -> Vec<String> {
    vec![format!(
        "a rig map (`mocap rigmap`, for `LoadOptions::rig_map`): convention {}, {} canonical joints mapped",
        v["convention"].as_str().unwrap_or("?"),
        v["joints"].as_object().map_or(0, |o| o.len())
    )]
}

fn skeletons_lines(v: &serde_json::Value) -> Vec<String> {
    vec![format!(
        "per-frame skeletons of sequence {}: {} frames at {} fps, {} joints",
        v["sequence"].as_str().unwrap_or("?"),
        len(v, "frames"),
        num(v, "fps").unwrap_or(f64::NAN),
        len(v, "joints")
    )]
}

/// A retarget, transfer or keyframe report.
fn report_lines(v: &serde_json::Value, format: &str) -> Vec<String> {
    let mut lines = vec![format!(
        "a {format}: {} frames at {} fps",
        v["frames"],
        num(v, "fps").unwrap_or(f64::NAN)
    )];
    if let (Some(d), Some(t)) = (num(v, "distance"), num(v, "time")) {
        lines.push(format!(
            "travelled {d:.3} m in {t:.3} s over {}, {}",
            count(len(v, "segments"), "segment"),
            count(len(v, "transitions"), "transition")
        ));
    }
    lines
}

/// What a field of a file [`inspect`] recognises must hold.
#[derive(Debug, Clone, Copy)]
enum Field {
    /// A whole number ≥ 0.
    Count,
    /// A frame rate ([`crate::util::budget::is_frame_rate`]).
    Fps,
    /// A finite number.
    Number,
    /// A string.
    Text,
    /// `true` or `false`.
    Flag,
    /// An array.
    List,
    /// An array of finite numbers.
    Numbers,
    /// An array of strings.
    Texts,
    /// An object.
    Object,
}

impl Field {
    fn holds(self, x: &serde_json::Value) -> bool {
        let finite = |x: &serde_json::Value| x.as_f64().is_some_and(f64::is_finite);
        match self {
            Field::Count => x.is_u64(),
            Field::Fps => x.as_f64().is_some_and(crate::util::budget::is_frame_rate),
            Field::Number => finite(x),
            Field::Text => x.is_string(),
            Field::Flag => x.is_boolean(),
            Field::List => x.is_array(),
            Field::Numbers => x.as_array().is_some_and(|a| a.iter().all(finite)),
            Field::Texts => x
                .as_array()
                .is_some_and(|a| a.iter().all(|s| s.is_string())),
            Field::Object => x.is_object(),
        }
    }

    fn expected(self) -> String {
        match self {
            Field::Count => "a whole number".into(),
            Field::Fps => format!(
                "a frame rate of {}-{} fps",
                crate::util::budget::MIN_FPS,
                crate::util::budget::MAX_FPS
            ),
            Field::Number => "a finite number".into(),
            Field::Text => "a string".into(),
            Field::Flag => "true or false".into(),
            Field::List => "an array".into(),
            Field::Numbers => "an array of finite numbers".into(),
            Field::Texts => "an array of strings".into(),
            Field::Object => "an object".into(),
        }
    }
}

/// The fields each kind of file [`json_kind`] recognises must hold, as the
/// tool writes them (those `inspect` reads and those that identify it).
fn fields_of(kind: &str) -> &'static [(&'static str, Field)] {
    use Field::*;
    match kind {
        "keyframe report" => &[
            ("keys", Texts),
            ("fps", Fps),
            ("frames", Count),
            ("distance", Number),
            ("time", Number),
            ("cost", Object),
            ("segments", List),
            ("transitions", List),
        ],
        "keyframe grid report" => &[
            ("keys", Texts),
            ("distances", Numbers),
            ("times", Numbers),
            ("reachable", Object),
            ("unreachable", Object),
            ("query_ms_mean", Number),
        ],
        "batch report" => &[
            ("what", Text),
            ("finished", Flag),
            ("done", Count),
            ("skipped", Count),
            ("failed", Count),
            ("clips_per_minute", Number),
            ("outcomes", List),
        ],
        "play report" => &[
            ("frames", Count),
            ("fps", Fps),
            ("seconds", Number),
            ("realtime_factor", Number),
            ("per_second", List),
            ("transitions", List),
            ("notices", List),
        ],
        "retarget report" => &[
            ("frames", Count),
            ("fps", Fps),
            ("retrieval", Object),
            ("jumps", List),
            ("steps", List),
        ],
        "transfer report" => &[
            ("frames", Count),
            ("fps", Fps),
            ("scan", Object),
            ("transfer", Object),
        ],
        "skeletons" => &[
            ("sequence", Text),
            ("fps", Fps),
            ("frames", List),
            ("joints", List),
        ],
        "graph cache" => &[("key", Count), ("graph", Object)],
        "rig" => &[("vertex_count", Count), ("joints", List)],
        "rig map" => &[("convention", Text), ("joints", Object)],
        _ => &[],
    }
}

/// `Err` naming the first field of `v` that does not hold what a `kind`
/// file holds there (missing, or of another type or range).
fn check_fields(v: &serde_json::Value, kind: &str) -> Result<(), String> {
    for &(key, field) in fields_of(kind) {
        match v.get(key) {
            None => return Err(format!("no field \"{key}\" ({})", field.expected())),
            Some(x) if !field.holds(x) => {
                let mut found = x.to_string();
                if found.len() > 40 {
                    found = format!("{}…", found.chars().take(40).collect::<String>());
                }
                return Err(format!(
                    "field \"{key}\" is {found}, expected {}",
                    field.expected()
                ));
            }
            _ => {}
        }
    }
    Ok(())
}

/// Whether a file whose fields are right also holds together as the value
/// it names. A graph cache is read through the graph's validated
/// constructor ([`crate::graph::SurfaceMotionGraph::new`]): a transition past
/// its sequence's end, an edge naming no transition or a sequence that does
/// not exist is refused here as `db build` refuses it (it then rebuilds the
/// cache), not summarised as if the graph were whole.
fn holds_together(v: &serde_json::Value, kind: &str) -> Result<(), String> {
    if kind != "graph cache" {
        return Ok(());
    }
    serde_json::from_value::<crate::graph::SurfaceMotionGraph>(v["graph"].clone())
        .map(drop)
        .map_err(|e| format!("{e}; `db build` rebuilds it"))
}

/// `name (N frames)` of each entry of `v["sequences"]`, its frame count
/// read from the key `frames` (a graph cache calls it `len`).
fn named_frames(v: &serde_json::Value, frames: &str) -> Vec<String> {
    v["sequences"]
        .as_array()
        .into_iter()
        .flatten()
        .map(|s| {
            format!(
                "{} ({} frames)",
                s["name"].as_str().unwrap_or("?"),
                s[frames]
            )
        })
        .collect()
}
