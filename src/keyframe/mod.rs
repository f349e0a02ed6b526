//! Key-frame animation (Huang et al. 2015, Secs. 5.1 and 6.1): the path
//! through the Surface Motion Graph that passes the animator's key-frames
//! in order and best meets a travel distance and time.
//!
//! Pipeline: [`graph`] (the frame graph with each frame's floor step),
//! [`search`] (walks, loops and pruning, Eqs. 13-22) with [`repeats`] (the
//! loop repetition counts, Eqs. 20-25), [`place`] (blending across
//! transitions and placement along the accumulated root motion),
//! [`smoothness`] (Table III's transition smoothness), [`floor`] (its
//! lower bounds over a database), [`select`] (the
//! key-frame transitions re-chosen by that measured distortion) and [`grid`] (the
//! Table III evaluation over a grid of targets); [`lattice`] is the
//! exact-length search (the default) and [`pose`] resolves key-frames
//! given as skeleton poses to database frames.
//!
//! The cost of a path `P` (Eq. 7) is
//! `C_tran(P) + w_dist |dist(P) − d_V| + w_time |time(P) − t_V|`, with
//! `C_tran` the sum of its transitions' costs (Eq. 8), `dist` the floor
//! distance travelled by the mesh centroid (Eq. 10) and `time = N_f Δt`
//! (Eq. 12). Zero targets ask for the shortest path.

pub mod clock;
pub mod floor;
pub mod graph;
pub mod grid;
pub mod heatmap;
pub mod lattice;
pub mod place;
pub mod pose;
pub mod repeats;
pub mod search;
pub mod select;
pub mod smoothest;
pub mod smoothness;

use crate::retarget::character::Character;
use crate::retarget::timeline::{TimelineOptions, timeline};
use graph::KeyGraph;
use repeats::Measure;
use search::{Method, SearchError, SearchOptions, Segment, SegmentPath, Stats, Target};
use serde::Serialize;
use std::time::Instant;

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
    /// The path found is longer than the memory budget can hold as a
    /// mesh sequence (far-out-of-range targets give long compromises, and
    /// many key-frames long paths; the text says which).
    #[error("{0}")]
    OverBudget(#[from] crate::util::budget::OverBudget),
}

/// The longest target time of a query, in seconds (an hour, as `play
/// --seconds`): the search's horizon grows with it, and `--time 1e6`
/// aborted on a 43 GB allocation.
pub const MAX_TARGET_SECONDS: f64 = 3600.0;

/// The longest target distance of a query, in metres.
pub const MAX_TARGET_METRES: f64 = 100_000.0;

/// Frame id of a key-frame written `SEQUENCE:FRAME`.
pub fn parse_key(ch: &Character, key: &str) -> Result<u32, KeyframeError> {
    let (name, f) = key
        .rsplit_once(':')
        .ok_or_else(|| KeyframeError::Syntax(key.into()))?;
    let name = name.trim();
    let s = ch
        .graph()
        .sequences
        .iter()
        .position(|q| q.name == name)
        .ok_or_else(|| KeyframeError::Sequence {
            key: key.into(),
            name: name.into(),
            known: ch
                .graph()
                .sequences
                .iter()
                .map(|q| q.name.as_str())
                .collect::<Vec<_>>()
                .join(", "),
        })?;
    let len = ch.graph().sequences[s].len;
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
    Ok(ch.graph().frame_id(s, f))
}

/// `SEQUENCE:FRAME` of a frame id.
pub fn key_name(ch: &Character, id: u32) -> String {
    let (s, f) = ch.graph().frame_of(id);
    format!("{}:{}", ch.graph().sequences[s].name, f)
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
        let jumps: Vec<(u32, u32, f64, usize)> =
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

/// The search prepared for a list of key-frames: the compressed graph of
/// every segment with its loops (built once, queried for any target).
pub struct Planner {
    /// The frame graph.
    pub graph: KeyGraph,
    /// Key-frame ids, in order.
    pub keys: Vec<u32>,
    /// One per consecutive pair.
    pub segments: Vec<Segment>,
    /// The segments joined at their key-frames for the exact-length search
    /// of one global target ([`lattice::Chain`]; `None` with a repeated
    /// key-frame).
    pub chain: Option<lattice::Chain>,
    /// The end key-frame's facing minus the start's (radians, from their
    /// skeletons, [`pose::facing`]): the output's final facing is this
    /// plus the path's turn. 0 unless set (graphs without skeletons).
    pub facing: f64,
    /// Frames per second.
    pub fps: f64,
    /// Each segment's own chain, for per-segment targets (its extremes
    /// kept across queries, [`lattice::Chain::extremes`]).
    seg_chains: Vec<Option<lattice::Chain>>,
    /// Seconds spent preparing.
    pub prepare_seconds: f64,
}

/// What the database can make of a global target ([`Planner::reach_of`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TargetReach {
    /// Least and most distance (metres) of the paths of exactly the
    /// target's frame count (`None`: no path has that length).
    pub at_time: Option<(f64, f64)>,
    /// Fewest seconds in which some frame count's extremes admit the
    /// distance within 1 % (`None`: not within the horizon).
    pub min_time: Option<f64>,
    /// The query's horizon (seconds, [`search::Horizon`]).
    pub horizon: f64,
    /// The most distance of any path within the horizon (metres).
    pub max_in_horizon: Option<f64>,
}

/// The cost terms of Eq. 7.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CostTerms {
    /// Sum of transition costs (Eq. 8).
    pub transition: f64,
    /// `w_dist · |dist − d_V|` (summed over segments with per-segment
    /// targets).
    pub distance: f64,
    /// `w_time · |time − t_V|` (frames).
    pub time: f64,
    /// `w_head · |facing − target|` (degrees, wrapped; 0 without a heading
    /// target).
    pub heading: f64,
    /// Their sum.
    pub total: f64,
}

/// One segment of the result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SegmentReport {
    /// Start key-frame (`SEQUENCE:FRAME`).
    pub from: String,
    /// End key-frame.
    pub to: String,
    /// Target distance (metres; `None` with one global target).
    pub target_distance: Option<f64>,
    /// Target time (seconds).
    pub target_time: Option<f64>,
    /// Achieved distance (metres).
    pub distance: f64,
    /// Achieved time (seconds; frames of the segment · Δt, the first
    /// segment counting its start frame).
    pub time: f64,
    /// Transition cost.
    pub transition_cost: f64,
    /// The loop-free walk as runs `SEQUENCE[a..b]`.
    pub walk: Vec<String>,
    /// Loops and their repetitions.
    pub loops: Vec<LoopReport>,
}

/// A repeated loop.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoopReport {
    /// Where it starts and ends.
    pub at: String,
    /// One repetition as runs.
    pub frames: Vec<String>,
    /// Repetitions.
    pub repeats: u32,
    /// One repetition's cost, distance, frames.
    pub measure: Measure,
}

/// The result of a query.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Plan {
    /// Segments in order.
    pub segments: Vec<SegmentPath>,
    /// The whole frame path (key-frame to key-frame).
    pub path: Vec<u32>,
    /// Transition cost, distance and frames of the whole path.
    pub measure: Measure,
    /// Eq. 7's terms.
    pub cost: CostTerms,
    /// The heading's turn over the path (radians).
    pub turn: f64,
    /// The final facing relative to the start key-frame's (degrees,
    /// wrapped to ±180; [`Planner::facing`] plus the turn).
    pub facing_deg: f64,
    /// Search counts and bounds hit.
    pub stats: Stats,
    /// Seconds of the search (preparation excluded).
    pub search_seconds: f64,
    /// CPU seconds of the calling thread during the search ([`clock`];
    /// `None` where the platform does not say).
    pub search_cpu_seconds: Option<f64>,
}

/// The frame path of consecutive segments (each shares its first frame
/// with the previous one's last).
pub fn join(segs: &[SegmentPath]) -> Vec<u32> {
    let mut path: Vec<u32> = Vec::new();
    for s in segs {
        let skip = usize::from(!path.is_empty());
        path.extend_from_slice(&s.path[skip..]);
    }
    path
}

/// Runs of consecutive frames as `SEQUENCE[a..b]`.
pub fn runs(ch: &Character, frames: &[u32]) -> Vec<String> {
    let mut out: Vec<(usize, usize, usize)> = Vec::new();
    for &f in frames {
        let (s, t) = ch.graph().frame_of(f);
        match out.last_mut() {
            Some((ls, _, b)) if *ls == s && t == *b + 1 => *b = t,
            _ => out.push((s, t, t)),
        }
    }
    out.into_iter()
        .map(|(s, a, b)| format!("{}[{a}..{b}]", ch.graph().sequences[s].name))
        .collect()
}

impl Planner {
    /// Prepares the search through `keys` (frame ids, at least two).
    pub fn new(
        graph: KeyGraph,
        keys: &[u32],
        fps: f64,
        opts: &SearchOptions,
    ) -> Result<Planner, SearchError> {
        let t0 = Instant::now();
        let segments = keys
            .windows(2)
            .enumerate()
            .map(|(i, w)| Segment::new(&graph, w[0], w[1], i == 0, &opts.limits))
            .collect::<Result<Vec<_>, _>>()?;
        let chain = lattice::Chain::of(&segments);
        let seg_chains = if segments.len() == 1 {
            vec![chain.clone()]
        } else {
            segments
                .iter()
                .map(|s| lattice::Chain::of(std::slice::from_ref(s)))
                .collect()
        };
        Ok(Planner {
            graph,
            keys: keys.to_vec(),
            segments,
            chain,
            seg_chains,
            facing: 0.0,
            fps,
            prepare_seconds: t0.elapsed().as_secs_f64(),
        })
    }

    /// The heading term of the search for a target facing (module docs
    /// of [`lattice`]).
    fn heading(&self, opts: &SearchOptions) -> Option<lattice::Heading> {
        opts.heading.map(|h| lattice::Heading {
            turn: h.degrees.to_radians() - self.facing,
            weight: h.weight.to_degrees(),
            sectors: h.sectors,
        })
    }

    /// One segment: the exact-length search (with the heading term when
    /// `heading`), else the walks and loops.
    fn solve_one(
        &self,
        i: usize,
        t: &Target,
        heading: Option<&lattice::Heading>,
        opts: &SearchOptions,
        stats: &mut Stats,
    ) -> Result<SegmentPath, SearchError> {
        let s = &self.segments[i];
        if opts.method == Method::Lattice {
            let found = match &self.seg_chains[i] {
                Some(c) => s.solve_lattice_on(c, t, heading, opts)?,
                None => None,
            };
            if let Some((p, _)) = found {
                s.count(stats);
                stats.exact_length += 1;
                return Ok(p);
            }
        }
        let walks = SearchOptions {
            method: Method::Walks,
            ..*opts
        };
        s.solve(t, heading, &walks, stats)
    }

    /// The best path for the targets (Eq. 13 per segment, or over the
    /// whole path for one global target: the exact-length search over the
    /// chain of segments, which splits the target optimally, else the
    /// walks-and-loops split [`search::solve_split`]). A heading target
    /// ([`SearchOptions::heading`]) applies to the last segment with per
    /// segment targets, after the turns of the earlier ones.
    pub fn plan(&self, targets: &Targets, opts: &SearchOptions) -> Result<Plan, SearchError> {
        let t0 = clock::Stopwatch::start();
        let mut stats = Stats::default();
        let w = opts.weights;
        let heading = self.heading(opts);
        // The exact-length search considers paths of at most `max_frames`
        // frames: a longer time target is met by nothing it finds, and the
        // result must say so (a 3600 s query at 25 fps returned an 800 s
        // path with no word; attack run, s14).
        let longest = match targets {
            Targets::Global { time, .. } => *time,
            Targets::PerSegment(v) => v.iter().map(|&(_, t)| t).fold(0.0, f64::max),
        };
        let cap = opts.lattice.max_frames as f64;
        if opts.method == Method::Lattice && longest * self.fps > cap {
            stats.bounds_hit.push(format!(
                "the time target ({longest:.1} s, {:.0} frames at {:.3} fps) is longer than the longest path the exact-length search considers ({cap:.0} frames, {:.1} s at this rate)",
                longest * self.fps,
                self.fps,
                cap / self.fps
            ));
        }
        let segs = match targets {
            Targets::Global { distance, time } => {
                let t = Target {
                    distance: *distance,
                    frames: time * self.fps,
                };
                let found = match (&self.chain, opts.method) {
                    (Some(c), Method::Lattice) if self.segments.len() > 1 => {
                        lattice::search(c, &t, heading.as_ref(), opts)?
                    }
                    _ => None,
                };
                if let (Some((f, _)), Some(c)) = (found, &self.chain) {
                    stats.exact_length += self.segments.len();
                    c.split(&f.arcs)
                        .iter()
                        .zip(&self.segments)
                        .map(|(arcs, s)| {
                            s.count(&mut stats);
                            s.decompose(arcs)
                        })
                        .collect()
                } else if self.segments.len() == 1 {
                    vec![self.solve_one(0, &t, heading.as_ref(), opts, &mut stats)?]
                } else {
                    search::solve_split(&self.segments, &t, heading.as_ref(), opts, &mut stats)?
                }
            }
            Targets::PerSegment(v) => {
                let mut out: Vec<SegmentPath> = Vec::new();
                for (i, &(d, tm)) in v.iter().enumerate() {
                    let t = Target {
                        distance: d,
                        frames: tm * self.fps,
                    };
                    let last = i + 1 == self.segments.len();
                    let h = heading.filter(|_| last).map(|mut h| {
                        let before: f64 = out.iter().map(|p| self.turn_of(&p.path)).sum();
                        h.turn -= before;
                        h
                    });
                    out.push(self.solve_one(i, &t, h.as_ref(), opts, &mut stats)?);
                }
                out
            }
        };
        if stats.beamed > 0 {
            stats.bounds_hit.push(format!(
                "{} repetition problems kept more than {} labels and were finished with {} labels per frame count",
                stats.beamed, opts.limits.labels, opts.beam
            ));
        }
        let path = join(&segs);
        let measure = segs
            .iter()
            .fold(Measure::default(), |a, s| a.plus(s.measure));
        let (dterm, tterm) = match targets {
            Targets::Global { distance, time } => (
                w.distance * (measure.distance - distance).abs(),
                w.time * (measure.frames as f64 - time * self.fps).abs(),
            ),
            Targets::PerSegment(v) => segs.iter().zip(v).fold((0.0, 0.0), |acc, (s, &(d, t))| {
                (
                    acc.0 + w.distance * (s.measure.distance - d).abs(),
                    acc.1 + w.time * (s.measure.frames as f64 - t * self.fps).abs(),
                )
            }),
        };
        let turn = self.turn_of(&path);
        let hterm = heading.map_or(0.0, |h| h.cost(turn));
        Ok(Plan {
            cost: CostTerms {
                transition: measure.cost,
                distance: dterm,
                time: tterm,
                heading: hterm,
                total: measure.cost + dterm + tterm + hterm,
            },
            turn,
            facing_deg: lattice::wrap(turn + self.facing).to_degrees(),
            segments: segs,
            path,
            measure,
            stats,
            search_cpu_seconds: t0.cpu(),
            search_seconds: t0.wall(),
        })
    }

    /// What the key-frames can physically make of a global target, from
    /// the chain's exact-length extremes (cheap: they are kept across
    /// queries) up to the query's horizon ([`search::Horizon`]). `None`
    /// without a chain or with a zero target.
    pub fn reach_of(&self, distance: f64, time: f64, opts: &SearchOptions) -> Option<TargetReach> {
        let c = self.chain.as_ref()?;
        if distance <= 0.0 || time <= 0.0 || !distance.is_finite() || !time.is_finite() {
            return None;
        }
        let cs = i64::from(c.counts_start());
        let frames = time * self.fps;
        let horizon = opts.horizon.frames(frames).floor() as i64;
        let top = (horizon - cs).max(0) as usize;
        let ext = c.extremes(top).ok()?;
        let n = (frames.round() as i64 - cs).clamp(0, top as i64) as usize;
        let (a, b) = ext.at(c.start_node(), n);
        let tol = 0.01 * distance;
        let min_time = (0..=top)
            .find(|&m| {
                let (lo, hi) = ext.at(c.start_node(), m);
                lo.is_finite() && lo < distance + tol && hi > distance - tol
            })
            .map(|m| (m as i64 + cs) as f64 / self.fps);
        let max_in_horizon = (0..=top)
            .map(|m| ext.at(c.start_node(), m).1)
            .fold(f64::NEG_INFINITY, f64::max);
        Some(TargetReach {
            at_time: a.is_finite().then_some((a, b)),
            min_time,
            horizon: horizon as f64 / self.fps,
            max_in_horizon: max_in_horizon.is_finite().then_some(max_in_horizon),
        })
    }

    /// The heading's turn along a frame path: the sum of its transitions'
    /// turns ([`graph::FrameEdge::turn`]).
    pub fn turn_of(&self, path: &[u32]) -> f64 {
        path.windows(2)
            .filter_map(|w| self.graph.edge(w[0], w[1]))
            .map(|e| e.turn)
            .sum()
    }
}

/// The report of a key-frame animation.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Key-frames in order.
    pub keys: Vec<String>,
    /// The targets.
    pub targets: Targets,
    /// Weights used (per metre, per frame).
    pub weights: search::Weights,
    /// Repetition solver.
    pub solver: search::Solver,
    /// Frames per second.
    pub fps: f64,
    /// Output frames.
    pub frames: usize,
    /// Achieved distance (metres) and time (seconds).
    pub distance: f64,
    /// Seconds.
    pub time: f64,
    /// `distance − target` (global target), metres.
    pub distance_error: Option<f64>,
    /// `time − target`, seconds.
    pub time_error: Option<f64>,
    /// Eq. 7's terms.
    pub cost: CostTerms,
    /// Per segment.
    pub segments: Vec<SegmentReport>,
    /// Transitions taken, with their blend windows and smoothness (metres).
    pub transitions: Vec<TransitionReport>,
    /// Mean smoothness over the transitions (metres; `None` without any).
    pub smoothness: Option<f64>,
    /// The same with the vertex-set Hausdorff distance (the measure before
    /// the surface one; [`smoothness::Smoothness::vertex`]).
    pub smoothness_vertex: Option<f64>,
    /// Final placement rotation relative to the first key-frame's capture
    /// (degrees, the sum of the transitions' turns).
    pub final_heading_deg: f64,
    /// Final facing of the character relative to the first key-frame's
    /// (degrees, ±180: the turn plus the end key-frame's own facing minus
    /// the start's, [`pose::facing`]).
    pub final_facing_deg: f64,
    /// The heading target (`--heading`), degrees.
    pub heading_target_deg: Option<f64>,
    /// `final_facing − target`, wrapped to ±180 degrees.
    pub heading_error_deg: Option<f64>,
    /// Key-frames given as skeleton poses and the frames they resolved to
    /// (filled by the caller that resolved them).
    pub poses: Vec<pose::Resolved>,
    /// Search counts and bounds hit.
    pub stats: Stats,
    /// Seconds preparing the search (compressed graph, loops).
    pub prepare_seconds: f64,
    /// Seconds searching.
    pub search_seconds: f64,
    /// CPU seconds of the searching thread ([`clock`]; `None` where the
    /// platform does not say).
    pub search_cpu_seconds: Option<f64>,
    /// Seconds blending and placing the meshes.
    pub mesh_seconds: f64,
    /// What the database can make of a global target (`None` with
    /// per-segment targets).
    pub reach: Option<TargetReach>,
}

/// A transition of the output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TransitionReport {
    /// Output frame after the jump.
    pub at: usize,
    /// Frame left.
    pub from: String,
    /// Frame entered.
    pub to: String,
    /// Blend half-window.
    pub window: usize,
    /// Transition cost of the graph edge.
    pub cost: f64,
    /// Weighted surface Hausdorff distance of the overlapping frames
    /// (metres, [`smoothness::Smoothness::surface`]).
    pub smoothness: f64,
    /// Weighted vertex-set Hausdorff distance ([`smoothness::Smoothness::vertex`]).
    pub smoothness_vertex: f64,
}

/// The report's segments.
pub fn segment_reports(
    ch: &Character,
    planner: &Planner,
    plan: &Plan,
    targets: &Targets,
) -> Vec<SegmentReport> {
    plan.segments
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let (td, tt) = match targets {
                Targets::Global { .. } => (None, None),
                Targets::PerSegment(v) => (Some(v[i].0), Some(v[i].1)),
            };
            SegmentReport {
                from: key_name(ch, s.from),
                to: key_name(ch, s.to),
                target_distance: td,
                target_time: tt,
                distance: s.measure.distance,
                time: s.measure.frames as f64 / planner.fps,
                transition_cost: s.measure.cost,
                walk: runs(ch, &s.walk),
                loops: s
                    .loops
                    .iter()
                    .map(|l| LoopReport {
                        at: key_name(ch, l.at),
                        frames: runs(ch, &l.frames),
                        repeats: l.repeats,
                        measure: l.measure,
                    })
                    .collect(),
            }
        })
        .collect()
}

/// Transitions of a path with their blend windows (from the timeline) and
/// smoothness, measured through `cache` (each overlapping frame pair once,
/// [`smoothness::Measurer`]; the path's new pairs in parallel).
pub fn transitions(
    ch: &Character,
    g: &KeyGraph,
    path: &[u32],
    opts: &TimelineOptions,
    cache: &mut smoothness::Measurer,
) -> Vec<TransitionReport> {
    let (_, jumps) = timeline(path, &graph::KeyFrames { ch, graph: g }, opts);
    let asked: Vec<(u32, u32, usize)> = jumps.iter().map(|j| (j.from, j.to, j.window)).collect();
    cache.prefill(ch, &asked);
    jumps
        .iter()
        .map(|j| {
            let s = cache.transition(ch, j.from, j.to, j.window);
            TransitionReport {
                at: j.at,
                from: key_name(ch, j.from),
                to: key_name(ch, j.to),
                window: j.window,
                cost: g.edge(j.from, j.to).map_or(0.0, |e| e.cost),
                smoothness: s.surface,
                smoothness_vertex: s.vertex,
            }
        })
        .collect()
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
    for t in &ch.graph().transitions {
        let from = ch.graph().frame_id(t.from, t.m);
        let to = ch.graph().frame_id(t.to, t.n) + 1;
        window.insert((from, to), t.window);
    }
    let jumps: Vec<(usize, u32, u32)> = (0..g.len() as u32)
        .flat_map(|f| {
            let lo = g.offsets[f as usize] as usize;
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

/// The mean of the transitions' smoothness (per transition, then over the
/// path, as Sec. 6.1 averages).
pub fn mean_smoothness(t: &[TransitionReport]) -> Option<f64> {
    (!t.is_empty()).then(|| t.iter().map(|x| x.smoothness).sum::<f64>() / t.len() as f64)
}

/// [`mean_smoothness`] of the vertex-set distance.
pub fn mean_smoothness_vertex(t: &[TransitionReport]) -> Option<f64> {
    (!t.is_empty()).then(|| t.iter().map(|x| x.smoothness_vertex).sum::<f64>() / t.len() as f64)
}

/// The synthesised key-frame animation.
pub struct Output {
    /// Positions, frame-major (metres, Y-up).
    pub positions: Vec<[f64; 3]>,
    /// The plan.
    pub plan: Plan,
    /// The report.
    pub report: Report,
}

/// Plans and synthesises: key-frame ids `keys` (at least two), targets,
/// options. Errors: the search's (no path between two key-frames) or a
/// failed factorisation of the blender. Every frame is held
/// ([`plan_path`] then [`Planned::synthesise_each`] into one buffer);
/// the CLI streams its output instead.
pub fn synthesise(
    ch: &Character,
    keys: &[u32],
    targets: &Targets,
    opts: &KeyframeOptions,
) -> Result<Output, KeyframeError> {
    let planned = plan_path(ch, keys, targets, opts, &mut |_| {})?;
    // The positions held below.
    let what = if keys.len() > 2 {
        format!(
            "the key-frame path through {} key-frames (use fewer --via, or lower --distance or --time)",
            keys.len()
        )
    } else {
        "the key-frame path (lower --distance or --time)".to_string()
    };
    crate::util::budget::check_frames(&what, planned.frames(), ch.n(), 1)?;
    let mut positions = Vec::with_capacity(planned.frames() * ch.n());
    let s = planned.synthesise_each(ch, targets, opts, |_, p| -> Result<(), KeyframeError> {
        positions.extend_from_slice(p);
        Ok(())
    })?;
    Ok(Output {
        positions,
        plan: s.plan,
        report: s.report,
    })
}

/// A key-frame path found ([`plan_path`]), its meshes not yet made.
pub struct Planned {
    planner: Planner,
    plan: Plan,
}

impl Planned {
    /// Bounds the search hit (e.g. a time target beyond the longest path
    /// it considers), for messages about the path it found.
    pub fn bounds_hit(&self) -> &[String] {
        &self.plan.stats.bounds_hit
    }
}

/// [`Output`] without the positions, which went to the caller frame by
/// frame ([`Planned::synthesise_each`]).
pub struct Streamed {
    /// The plan.
    pub plan: Plan,
    /// The report.
    pub report: Report,
}

/// Finds the path through key-frame ids `keys` (at least two) for the
/// targets (Eq. 7). Errors: too few keys, or the search's (no path
/// between two key-frames).
/// `progress` is told each stage (the graph, preparing, searching).
pub fn plan_path(
    ch: &Character,
    keys: &[u32],
    targets: &Targets,
    opts: &KeyframeOptions,
    progress: &mut dyn FnMut(&str),
) -> Result<Planned, KeyframeError> {
    if keys.len() < 2 {
        return Err(KeyframeError::TooFew);
    }
    let fps = ch.manifest().fps;
    progress("the frame graph");
    let g = key_graph_with(ch, opts, progress);
    progress("preparing the search (segments, loops)");
    let mut planner = Planner::new(g, keys, fps, &opts.search)
        .map_err(|e| KeyframeError::Search(describe(ch, &e)))?;
    planner.facing = facing_change(ch, keys);
    progress("searching");
    let plan = planner
        .plan(targets, &opts.search)
        .map_err(|e| KeyframeError::Search(describe(ch, &e)))?;
    Ok(Planned { planner, plan })
}

/// An error of [`Planned::synthesise_each`]: the blender's, or the
/// caller's.
enum EachError<E> {
    Solve(crate::mesh::solver::SolveError),
    Caller(E),
}

impl<E> From<crate::mesh::solver::SolveError> for EachError<E> {
    fn from(e: crate::mesh::solver::SolveError) -> Self {
        EachError::Solve(e)
    }
}

impl Planned {
    /// Output frames of the path.
    pub fn frames(&self) -> usize {
        self.plan.path.len()
    }

    /// Blends and places the path's meshes ([`place::place_each`]),
    /// handing each output frame (its index and the character's vertices,
    /// metres, Y-up) to `each` in order, and reports. A path of any length
    /// needs the memory of one chunk of frames, not of every frame. The
    /// report's `mesh_seconds` leaves out the time spent in `each`.
    pub fn synthesise_each<E: From<KeyframeError>>(
        self,
        ch: &Character,
        targets: &Targets,
        opts: &KeyframeOptions,
        mut each: impl FnMut(usize, &[[f64; 3]]) -> Result<(), E>,
    ) -> Result<Streamed, E> {
        let Planned { planner, plan } = self;
        let fps = ch.manifest().fps;
        let t0 = Instant::now();
        let mut in_each = 0.0;
        let track = place::place_each(
            ch,
            &planner.graph,
            &plan.path,
            &opts.timeline,
            |k, p| -> Result<(), EachError<E>> {
                let t = Instant::now();
                let r = each(k, p).map_err(EachError::Caller);
                in_each += t.elapsed().as_secs_f64();
                r
            },
        )
        .map_err(|e| match e {
            EachError::Solve(e) => E::from(KeyframeError::Search(format!("blending: {e}"))),
            EachError::Caller(e) => e,
        })?;
        let mesh_seconds = (t0.elapsed().as_secs_f64() - in_each).max(0.0);
        let mut cache = smoothness::Measurer::new(ch);
        let trans = transitions(ch, &planner.graph, &plan.path, &opts.timeline, &mut cache);
        let (de, te) = match targets {
            Targets::Global { distance, time } => (
                Some(plan.measure.distance - distance),
                Some(plan.measure.frames as f64 / fps - time),
            ),
            Targets::PerSegment(_) => (None, None),
        };
        let report = Report {
            keys: planner.keys.iter().map(|&k| key_name(ch, k)).collect(),
            targets: targets.clone(),
            weights: opts.search.weights,
            solver: opts.search.solver,
            fps,
            frames: plan.path.len(),
            distance: plan.measure.distance,
            time: plan.measure.frames as f64 / fps,
            distance_error: de,
            time_error: te,
            cost: plan.cost,
            segments: segment_reports(ch, &planner, &plan, targets),
            smoothness: mean_smoothness(&trans),
            smoothness_vertex: mean_smoothness_vertex(&trans),
            transitions: trans,
            final_heading_deg: track.heading.last().copied().unwrap_or(0.0).to_degrees(),
            final_facing_deg: plan.facing_deg,
            heading_target_deg: opts.search.heading.map(|h| h.degrees),
            heading_error_deg: opts
                .search
                .heading
                .map(|h| lattice::wrap((plan.facing_deg - h.degrees).to_radians()).to_degrees()),
            poses: Vec::new(),
            stats: plan.stats.clone(),
            prepare_seconds: planner.prepare_seconds,
            search_seconds: plan.search_seconds,
            search_cpu_seconds: plan.search_cpu_seconds,
            mesh_seconds,
            reach: match targets {
                Targets::Global { distance, time } => {
                    planner.reach_of(*distance, *time, &opts.search)
                }
                Targets::PerSegment(_) => None,
            },
        };
        Ok(Streamed { plan, report })
    }
}

/// The end key-frame's facing minus the start's (radians, from their
/// skeletons; [`Planner::facing`]).
pub fn facing_change(ch: &Character, keys: &[u32]) -> f64 {
    match (keys.first(), keys.last()) {
        (Some(&a), Some(&b)) if (a.max(b) as usize) < ch.poses().len() => {
            pose::facing(&ch.poses()[b as usize]) - pose::facing(&ch.poses()[a as usize])
        }
        _ => 0.0,
    }
}

/// A search error in the database's words (`SEQUENCE:FRAME`).
pub fn describe(ch: &Character, e: &SearchError) -> String {
    match e {
        SearchError::NoPath { from, to } => format!(
            "no path from key-frame {} to {} in the graph (no sequence of transitions joins them{}; see `surfmotion graph`)",
            key_name(ch, *from),
            key_name(ch, *to),
            no_path_hint(ch, *from, *to)
        ),
        other => other.to_string(),
    }
}

/// Which key-frame to move when no path joins `from` to `to`: the earliest
/// frame of `to`'s sequence a transition of the graph enters (a frame
/// before it is reached only along its own sequence), and the last frame
/// of `from`'s sequence a transition leaves. Empty when neither explains it.
fn no_path_hint(ch: &Character, from: u32, to: u32) -> String {
    let g = ch.graph();
    let adj = ch.adjacency();
    let n = g.frame_count() as u32;
    let ((sf, ff), (st, ft)) = (g.frame_of(from), g.frame_of(to));
    let (mut entered, mut left): (Option<usize>, Option<usize>) = (None, None);
    for f in 0..n.min(adj.offsets.len().saturating_sub(1) as u32) {
        for (t, _) in adj.successors(f) {
            if t == f + 1 || t >= n {
                continue;
            }
            let ((sa, a), (sb, b)) = (g.frame_of(f), g.frame_of(t));
            if sb == st {
                entered = Some(entered.map_or(b, |e| e.min(b)));
            }
            if sa == sf {
                left = Some(left.map_or(a, |l| l.max(a)));
            }
        }
    }
    let seq = |s: usize| &g.sequences[s].name;
    let mut out = Vec::new();
    // `to` is reachable along its own sequence from an earlier `from`.
    let along = sf == st && ff <= ft;
    match entered {
        Some(e) if ft < e && !along => out.push(format!(
            "; the earliest frame of {0} a transition enters is {0}:{e}: move key-frame {0}:{ft} to {0}:{e} or later",
            seq(st)
        )),
        None if !along => out.push(format!("; no transition enters {}", seq(st))),
        _ => {}
    }
    match left {
        Some(l) if ff > l && !along => out.push(format!(
            "; the last frame of {0} a transition leaves is {0}:{l}: move key-frame {0}:{ff} to {0}:{l} or earlier",
            seq(sf)
        )),
        None if !along => out.push(format!("; no transition leaves {}", seq(sf))),
        _ => {}
    }
    out.concat()
}
