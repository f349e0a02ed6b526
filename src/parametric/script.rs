//! Scripted sessions: a JSON list of timed control requests played through
//! a [`Controller`], with a report of the parameters asked and achieved per
//! second and the transitions taken.
//!
//! ```json
//! [{"t": 0, "space": "locomotion", "speed": 1.2},
//!  {"t": 3, "speed": 2.0}, {"t": 5, "turn": 30}, {"t": 8, "space": "turning"}]
//! ```
//!
//! `t` (seconds, required, non-decreasing), `space` (a space's name) and
//! parameter values (`speed` in m/s, `turn` in degrees per second, left
//! positive) that some space of the database declares. A value keeps until
//! a later request changes it.

use super::Parameter;
use super::controller::{Control, Controller, Notice, TransitionRecord};
use super::space::{Motion, SpaceSummary};
use crate::util::numfmt::Short;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A malformed script.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {msg}")]
pub struct ScriptError {
    /// The script file.
    pub path: PathBuf,
    /// What is wrong, naming the request (0-based) and key.
    pub msg: String,
}

/// One timed request.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Request {
    /// Time in seconds.
    pub t: f64,
    /// The space to be in.
    pub space: Option<String>,
    /// Speed, m/s.
    pub speed: Option<f64>,
    /// Turn rate, deg/s.
    pub turn: Option<f64>,
}

/// Longest session a script may ask for (seconds): one hour.
pub const MAX_SECONDS: f64 = 3600.0;

/// Largest speed a script may ask for (m/s, either sign): far beyond any
/// space's range, which the controller clamps to; a larger value
/// (`"speed": 1e300`) is a typo, and was echoed as a 300-digit number.
pub(crate) const MAX_SPEED: f64 = 100.0;

/// Largest turn rate a script may ask for (deg/s, either sign): ten turns
/// a second. The steering turn is not clamped by a space's range, so
/// `"turn": -1e300` played a character spun by 1e300 degrees a second
/// (exit 0).
pub(crate) const MAX_TURN: f64 = 3600.0;

/// Parses and checks a script against the model's spaces and parameters.
pub(crate) fn parse_script(
    text: &str,
    path: &Path,
    motion: &Motion,
) -> Result<Vec<Request>, ScriptError> {
    let spaces: Vec<(&str, &[Parameter])> = motion
        .spaces
        .iter()
        .map(|s| (s.name(), s.parameters()))
        .collect();
    parse_script_for(text, path, &spaces)
}

/// [`parse_script`] against spaces given by name and parameters (what a
/// script is checked against; the fuzz target and the malformed-input
/// tests call it without building a model).
pub fn parse_script_for(
    text: &str,
    path: &Path,
    spaces: &[(&str, &[Parameter])],
) -> Result<Vec<Request>, ScriptError> {
    let err = |msg: String| ScriptError {
        path: path.to_path_buf(),
        msg,
    };
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| {
        err(format!("not JSON ({e}): expected a list of requests like [{{\"t\": 0, \"space\": \"NAME\", \"speed\": 1.2}}]"))
    })?;
    let list = v
        .as_array()
        .ok_or_else(|| err("expected a JSON list of requests".into()))?;
    if list.is_empty() {
        return Err(err("the script has no requests".into()));
    }
    // Each name once ("expected t, space, speed, turn, turn" with two
    // spaces steering by turn).
    let mut declared: Vec<&str> = Vec::new();
    for p in spaces
        .iter()
        .flat_map(|(_, ps)| ps.iter().map(|p| p.name()))
    {
        if !declared.contains(&p) {
            declared.push(p);
        }
    }
    let names: Vec<&str> = spaces.iter().map(|(n, _)| *n).collect();
    let mut out = Vec::with_capacity(list.len());
    let mut last = 0.0;
    for (i, r) in list.iter().enumerate() {
        let at = |msg: String| err(format!("request {i}: {msg}"));
        let o = r
            .as_object()
            .ok_or_else(|| at("expected an object like {\"t\": 0, \"speed\": 1.2}".into()))?;
        let num = |k: &str| -> Result<Option<f64>, ScriptError> {
            match o.get(k) {
                None => Ok(None),
                Some(x) => x
                    .as_f64()
                    .filter(|v| v.is_finite())
                    .map(Some)
                    .ok_or_else(|| {
                        at(format!(
                            "\"{k}\" is {}, expected a number",
                            crate::db::manifest::printable(&x.to_string(), 40)
                        ))
                    }),
            }
        };
        let t = num("t")?.ok_or_else(|| at("no \"t\" (the request's time in seconds)".into()))?;
        if !(0.0..=MAX_SECONDS).contains(&t) {
            return Err(at(format!(
                "t = {}: expected seconds in [0, {MAX_SECONDS}]",
                Short(t)
            )));
        }
        if t < last {
            return Err(at(format!(
                "t = {} is before the previous request's {}: requests must be in time order",
                Short(t),
                Short(last)
            )));
        }
        last = t;
        for k in o.keys() {
            if k == "t" || k == "space" {
                continue;
            }
            if Parameter::parse(k).is_none() || !declared.contains(&k.as_str()) {
                return Err(at(format!(
                    "unknown key \"{}\" (expected t, space{})",
                    crate::db::manifest::printable(k, 40),
                    declared
                        .iter()
                        .map(|d| format!(", {d}"))
                        .collect::<String>()
                )));
            }
        }
        let space = match o.get("space") {
            None => None,
            Some(s) => {
                let s = s
                    .as_str()
                    .ok_or_else(|| at(format!("\"space\" is {s}, expected a space's name")))?;
                if !names.contains(&s) {
                    return Err(at(format!(
                        "no space '{}' in the database (spaces: {})",
                        crate::db::manifest::printable(s, 40),
                        names.join(", ")
                    )));
                }
                Some(s.to_string())
            }
        };
        let bounded = |k: &str, max: f64, unit: &str| -> Result<Option<f64>, ScriptError> {
            match num(k)? {
                Some(v) if v.abs() > max => Err(at(format!(
                    "\"{k}\" is {} {unit}: expected at most {max} {unit} either way",
                    Short(v)
                ))),
                v => Ok(v),
            }
        };
        out.push(Request {
            t,
            space,
            speed: bounded("speed", MAX_SPEED, "m/s")?,
            turn: bounded("turn", MAX_TURN, "deg/s")?,
        });
    }
    Ok(out)
}

/// One second of a session.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SecondReport {
    /// Start of the second.
    pub second: usize,
    /// Space at the end of the second.
    pub space: String,
    /// Speed asked (m/s) at the end of the second.
    pub speed_asked: Option<f64>,
    /// Speed achieved: root path length over the second (m/s).
    pub speed: f64,
    /// Turn asked (deg/s).
    pub turn_asked: Option<f64>,
    /// Turn achieved: heading change over the second (deg/s).
    pub turn: f64,
    /// Weight coordinate at the end of the second.
    pub weight: f64,
    /// A transition was under way during the second.
    pub transition: bool,
}

/// A notice with the request that caused it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TimedNotice {
    /// Request index.
    pub request: usize,
    /// Request time.
    pub t: f64,
    /// What happened.
    pub notice: Notice,
    /// The same as one line.
    pub message: String,
}

/// What a session did.
#[derive(Debug, Clone, Serialize)]
pub struct SessionReport {
    /// Frames played.
    pub frames: usize,
    /// Frames per second.
    pub fps: f64,
    /// Seconds of motion.
    pub seconds: f64,
    /// Seconds spent synthesising (controller only, no output writing).
    pub synthesis_seconds: f64,
    /// `seconds / synthesis_seconds`.
    pub realtime_factor: f64,
    /// Per second: parameters asked and achieved.
    pub per_second: Vec<SecondReport>,
    /// Transitions taken.
    pub transitions: Vec<TransitionRecord>,
    /// Requests that could not be done as asked.
    pub notices: Vec<TimedNotice>,
    /// The spaces.
    pub spaces: Vec<SpaceSummary>,
}

/// Frames of a session of `seconds` (default: the last request's time +
/// 2 s, at most [`MAX_SECONDS`]) at `fps`: those [`play`] makes.
pub(crate) fn session_frames(script: &[Request], seconds: Option<f64>, fps: f64) -> usize {
    let seconds = seconds
        .unwrap_or_else(|| script.last().map_or(0.0, |r| r.t) + 2.0)
        .clamp(0.0, MAX_SECONDS);
    (seconds * fps).round() as usize
}

/// Plays a script: every frame's mesh goes to `sink` as it is made (a
/// session of any length needs the memory of one frame); the first error
/// of `sink` ends the session. The session lasts `seconds` (default: the
/// last request's time + 2 s), [`session_frames`] frames. The report's
/// synthesis time leaves out the time spent in `sink`.
pub fn play<E>(
    motion: &Motion,
    script: &[Request],
    seconds: Option<f64>,
    mut sink: impl FnMut(&[[f64; 3]]) -> Result<(), E>,
) -> Result<SessionReport, E> {
    let fps = motion.fps;
    let frames = session_frames(script, seconds, fps);
    let first = script
        .iter()
        .find_map(|r| r.space.as_deref())
        .and_then(|s| motion.space_index(s))
        .unwrap_or(0);
    let mut c = Controller::new(motion, first);
    let mut next = 0;
    let mut notices = Vec::new();
    let mut per_second = Vec::new();
    let mut asked = [None, None];
    let (mut sec_root, mut sec_heading, mut sec_path) = (c.root(), c.heading(), 0.0);
    let mut sec_transition = false;
    let per = fps.round().max(1.0) as usize;
    let t0 = Instant::now();
    let mut in_sink = 0.0;
    for f in 0..frames {
        let time = f as f64 / fps;
        while next < script.len() && script[next].t <= time + 1e-9 {
            let r = &script[next];
            if r.speed.is_some() {
                asked[0] = r.speed;
            }
            if r.turn.is_some() {
                asked[1] = r.turn;
            }
            let ctl = Control {
                space: r.space.as_deref().and_then(|s| motion.space_index(s)),
                speed: r.speed,
                turn: r.turn,
            };
            for n in c.control(&ctl) {
                notices.push(TimedNotice {
                    request: next,
                    t: r.t,
                    message: n.to_string(),
                    notice: n,
                });
            }
            next += 1;
        }
        let frame = c.advance();
        let ts = Instant::now();
        sink(frame)?;
        in_sink += ts.elapsed().as_secs_f64();
        sec_transition |= c.in_transition();
        sec_path += (c.root() - sec_root).length();
        sec_root = c.root();
        if (f + 1) % per == 0 || f + 1 == frames {
            let n = (f + 1) % per;
            let dur = if n == 0 { 1.0 } else { n as f64 / fps };
            per_second.push(SecondReport {
                second: f / per,
                space: motion.spaces[c.space()].name().to_owned(),
                speed_asked: asked[0],
                speed: sec_path / dur,
                turn_asked: asked[1],
                turn: (c.heading() - sec_heading).to_degrees() / dur,
                weight: c.weight(),
                transition: sec_transition,
            });
            sec_heading = c.heading();
            sec_path = 0.0;
            sec_transition = false;
        }
    }
    let synthesis_seconds = (t0.elapsed().as_secs_f64() - in_sink).max(0.0);
    Ok(SessionReport {
        frames,
        fps,
        seconds: frames as f64 / fps,
        synthesis_seconds,
        realtime_factor: frames as f64 / fps / synthesis_seconds.max(1e-9),
        per_second,
        transitions: c.transitions.clone(),
        notices,
        spaces: motion.summary(),
    })
}
