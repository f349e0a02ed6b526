//! The key-frame problem: its errors, key-frames by name, targets, options and
//! the key graph.

use super::graph::KeyGraph;
use super::options::SearchOptions;
use super::{select, smoothness};
use crate::db::Character;
use crate::drive::timeline::TimelineOptions;
use crate::graph::FlatFrame;
use serde::Serialize;

/// Bad key-frames or targets.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KeyframeError {
    /// Not `SEQUENCE:FRAME`.
    #[error("key-frame '{0}': expected SEQUENCE:FRAME (e.g. walk:12)")]
    Syntax(String),
    /// No such sequence.
    #[error("key-frame '{key}': no sequence '{name}' (the database has {known})")]
    Sequence {
        /// As written.
        key: String,
        /// The name.
        name: String,
        /// The database's sequences.
        known: String,
    },
    /// Frame out of range.
    #[error(
        "key-frame '{key}': sequence '{name}' has {len} frames (0 to {})",
        .len.saturating_sub(1)
    )]
    Frame {
        /// As written.
        key: String,
        /// The sequence.
        name: String,
        /// Its frame count.
        len: usize,
    },
    /// A target that is negative or not a number.
    #[error("{what} {value}: expected a finite number ≥ 0")]
    Target {
        /// Which target.
        what: String,
        /// The value.
        value: f64,
    },
    /// A target beyond [`MAX_TARGET_SECONDS`] or [`MAX_TARGET_METRES`].
    #[error("{what} {value}: at most {max} {unit} (the search's horizon grows with the target)")]
    TooLarge {
        /// Which target.
        what: String,
        /// The value.
        value: f64,
        /// The largest accepted.
        max: f64,
        /// Its unit.
        unit: &'static str,
    },
    /// Per-segment targets whose count does not match the segments.
    #[error("{what}: {given} values for {segments} segments (give one, or one per segment)")]
    Count {
        /// Which target.
        what: String,
        /// Values given.
        given: usize,
        /// Segments.
        segments: usize,
    },
    /// Fewer than two key-frames.
    #[error("at least two key-frames are needed")]
    TooFew,
    /// The search failed.
    #[error("{0}")]
    Search(String),
    /// The prepared character ([`crate::drive::Prepared`]) was made for
    /// another character.
    #[error("the prepared character does not fit this key-frame query: {0}")]
    Unprepared(String),
    /// The path found is longer than the memory budget can hold as a
    /// mesh sequence (far-out-of-range targets give long compromises, and
    /// many key-frames long paths; the text says which).
    #[error("{0}")]
    OverBudget(#[from] crate::util::budget::OverBudget),
}

impl From<std::convert::Infallible> for KeyframeError {
    fn from(e: std::convert::Infallible) -> Self {
        match e {}
    }
}

/// The longest target time of a query, in seconds (an hour, as `play
/// --seconds`): the search's horizon grows with it, and `--time 1e6`
/// aborted on a 43 GB allocation.
pub const MAX_TARGET_SECONDS: f64 = 3600.0;

/// The longest target distance of a query, in metres.
pub const MAX_TARGET_METRES: f64 = 100_000.0;

/// The frame of a key-frame written `SEQUENCE:FRAME`.
pub fn parse_key(ch: &Character, key: &str) -> Result<FlatFrame, KeyframeError> {
    let (name, f) = key
        .rsplit_once(':')
        .ok_or_else(|| KeyframeError::Syntax(key.into()))?;
    let name = name.trim();
    let s = ch
        .graph()
        .sequences()
        .iter()
        .position(|q| q.name == name)
        .ok_or_else(|| KeyframeError::Sequence {
            key: key.into(),
            name: name.into(),
            known: ch
                .graph()
                .sequences()
                .iter()
                .map(|q| q.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        })?;
    let len = ch.graph().sequences()[s].len;
    let f = f.trim();
    // All digits but too many for a number (`walk:99999999999999999999`):
    // out of range, not a syntax error.
    let f: usize = match f.parse() {
        Ok(f) => f,
        Err(_) if !f.is_empty() && f.bytes().all(|b| b.is_ascii_digit()) => usize::MAX,
        Err(_) => return Err(KeyframeError::Syntax(key.into())),
    };
    if f >= len {
        return Err(KeyframeError::Frame {
            key: key.into(),
            name: name.into(),
            len,
        });
    }
    Ok(ch.graph().flat_id(s, f))
}

/// `SEQUENCE:FRAME` of a frame.
pub fn key_name(ch: &Character, id: FlatFrame) -> String {
    let (s, f) = ch.graph().frame_of(id);
    format!("{}:{}", ch.graph().sequences()[s].name, f)
}

/// Distance and time targets.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Targets {
    /// One target for the whole path, split optimally over its segments.
    Global {
        /// Metres.
        distance: f64,
        /// Seconds.
        time: f64,
    },
    /// One target per segment (between consecutive key-frames).
    PerSegment(Vec<(f64, f64)>),
}

impl Targets {
    /// From the command line's lists (one value, or one per segment).
    pub fn from_lists(
        distance: &[f64],
        time: &[f64],
        segments: usize,
    ) -> Result<Targets, KeyframeError> {
        for (what, v, max, unit) in [
            ("distance", distance, MAX_TARGET_METRES, "m"),
            ("time", time, MAX_TARGET_SECONDS, "s"),
        ] {
            if let Some(&x) = v.iter().find(|x| !x.is_finite() || **x < 0.0) {
                return Err(KeyframeError::Target {
                    what: what.into(),
                    value: x,
                });
            }
            if let Some(&x) = v.iter().find(|x| **x > max) {
                return Err(KeyframeError::TooLarge {
                    what: what.into(),
                    value: x,
                    max,
                    unit,
                });
            }
            if v.len() != 1 && v.len() != segments {
                return Err(KeyframeError::Count {
                    what: what.into(),
                    given: v.len(),
                    segments,
                });
            }
        }
        if distance.len() == 1 && time.len() == 1 {
            return Ok(Targets::Global {
                distance: distance[0],
                time: time[0],
            });
        }
        let at = |v: &[f64], i: usize| if v.len() == 1 { v[0] } else { v[i] };
        Ok(Targets::PerSegment(
            (0..segments)
                .map(|i| (at(distance, i), at(time, i)))
                .collect(),
        ))
    }
}

/// Options of a key-frame query.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct KeyframeOptions {
    /// The search (weights, bounds, solver).
    pub search: SearchOptions,
    /// Blending across transitions.
    pub timeline: TimelineOptions,
    /// What a transition costs the search.
    pub transition_cost: TransitionCost,
    /// Which transitions the search may take.
    pub transitions: TransitionSet,
}

/// Which transitions the key-frame search may take.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum TransitionSet {
    /// The Surface Motion Graph's (top N local minima of the shape
    /// matrix, Sec. 4.2), priced by [`TransitionCost`].
    #[default]
    Graph,
    /// Re-chosen among the matrix's local minima by their measured
    /// distortion, with their windows, priced by it ([`select`]; Sec. 4.2's
    /// Eq. 5 with Sec. 6.1's weighted Hausdorff distance). Key-frame only:
    /// the graph and `retarget` are unchanged.
    Measured,
}

/// The frame graph of a character priced as `opts` asks.
pub fn key_graph(ch: &Character, opts: &KeyframeOptions) -> KeyGraph {
    key_graph_with(ch, opts, &mut |_| {})
}

/// [`key_graph`], telling `progress` what it is doing (the measured
/// transitions' sequence pairs: 35 s on synth3).
pub fn key_graph_with(
    ch: &Character,
    opts: &KeyframeOptions,
    progress: &mut dyn FnMut(&str),
) -> KeyGraph {
    if opts.transitions == TransitionSet::Measured {
        let jumps: Vec<(FlatFrame, FlatFrame, f64, usize)> =
            select::measured_with(ch, &select::SelectOptions::default(), &mut |d, t| {
                progress(&format!(
                    "choosing transitions by measured smoothness: {d}/{t} sequence pairs"
                ))
            })
            .into_iter()
            .map(|c| (c.from, c.to, c.smoothness, c.window))
            .collect();
        return KeyGraph::of_character_with(ch, Some(&jumps));
    }
    let mut g = KeyGraph::of_character(ch);
    if opts.transition_cost == TransitionCost::Smoothness {
        price_by_smoothness(ch, &mut g);
    }
    g
}

/// What a transition costs the search (Eq. 8's distortion `D`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum TransitionCost {
    /// The graph's: the shape dissimilarity of the overlapping frames
    /// (Eqs. 2-3), as the paper.
    #[default]
    Graph,
    /// The measured smoothness of the transition (metres: the weighted
    /// Hausdorff distance of the overlapping frames over the graph's blend
    /// window, [`smoothness::transition_smoothness`]), the measure Table
    /// III reports. Costs one Hausdorff distance per blended frame of every
    /// transition once, at preparation.
    Smoothness,
}

/// Prices every transition of `g` by its measured smoothness (see
/// [`TransitionCost::Smoothness`]), in parallel over the transitions.
pub fn price_by_smoothness(ch: &Character, g: &mut KeyGraph) {
    use rayon::prelude::*;
    let mut window = std::collections::HashMap::new();
    for t in ch.graph().transitions() {
        let from = ch.graph().flat_id(t.from, t.m);
        let to = ch.graph().flat_id(t.to, t.n).next();
        window.insert((from, to), t.window);
    }
    let jumps: Vec<(usize, FlatFrame, FlatFrame)> = FlatFrame::all(g.len())
        .flat_map(|f| {
            let lo = g.offsets[f.index()] as usize;
            g.successors(f)
                .iter()
                .enumerate()
                .filter(|(_, e)| e.jump)
                .map(move |(i, e)| (lo + i, f, e.to))
                .collect::<Vec<_>>()
        })
        .collect();
    let priced: Vec<(usize, f64)> = jumps
        .par_iter()
        .map(|&(i, from, to)| {
            let l = window.get(&(from, to)).copied().unwrap_or(4);
            (i, smoothness::transition_smoothness(ch, from, to, l))
        })
        .collect();
    for (i, c) in priced {
        g.edges[i].cost = c;
    }
}
