//! The Surface Motion Graph (Huang et al. 2015, Sec. 4.3): sequences as
//! nodes, transitions as edges, the user's edits, and the flat frame-level
//! adjacency the searches walk.
//!
//! Frames are numbered globally ([`FlatFrame`]), sequence after sequence. The frame
//! graph has an edge `t → t+1` inside every sequence (cost 0) and, for every
//! transition `(i, m) → (j, n)` with half-window `L`, an edge from frame `m`
//! of `i` to frame `n+1` of `j` with the transition's cost: a path taking it
//! plays `i` up to `m` and continues in `j` after `n`; the blend over
//! `m−L..=m+L` / `n−L..=n+L` is applied when the path is turned into meshes.

use super::frame::{FlatFrame, FrameId};
use super::parts::{GraphParts, SequenceEdge};
use super::transitions::{self, Transition, TransitionOptions};
use crate::similarity::{Dissimilarity, Measure, Span};
use serde::{Deserialize, Serialize};
use std::fmt::Write;

/// User edits of the graph (manifest `[graph]`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GraphEdits {
    /// Sequence edges never to create, as `"from -> to"` (`*` matches any
    /// sequence).
    pub forbid: Vec<String>,
    /// Single transitions to drop, as `"from:m -> to:n"`.
    pub remove: Vec<String>,
}

/// The graph. Made by [`SurfaceMotionGraph::build`] or, from its parts
/// (a cache, a test), by [`SurfaceMotionGraph::new`], which checks that they
/// agree ([`GraphParts::check`]); its fields are read through accessors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "GraphParts")]
pub struct SurfaceMotionGraph {
    measure: Measure,
    options: TransitionOptions,
    sequences: Vec<Span>,
    transitions: Vec<Transition>,
    edges: Vec<SequenceEdge>,
    removed: Vec<String>,
}

impl TryFrom<GraphParts> for SurfaceMotionGraph {
    type Error = String;
    fn try_from(parts: GraphParts) -> Result<Self, String> {
        SurfaceMotionGraph::new(parts)
    }
}

/// An edit that names something that does not exist.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
#[error("graph edit '{edit}': {msg}")]
pub struct EditError {
    /// The edit as written.
    pub edit: String,
    /// What is wrong.
    pub msg: String,
}

impl SurfaceMotionGraph {
    /// A graph from its parts, when they agree ([`GraphParts::check`]);
    /// the error says what disagrees.
    pub fn new(parts: GraphParts) -> Result<SurfaceMotionGraph, String> {
        parts.check()?;
        let GraphParts {
            measure,
            options,
            sequences,
            transitions,
            edges,
            removed,
        } = parts;
        Ok(SurfaceMotionGraph {
            measure,
            options,
            sequences,
            transitions,
            edges,
            removed,
        })
    }

    /// The graph's parts (to edit and remake with [`SurfaceMotionGraph::new`]).
    pub fn into_parts(self) -> GraphParts {
        GraphParts {
            measure: self.measure,
            options: self.options,
            sequences: self.sequences,
            transitions: self.transitions,
            edges: self.edges,
            removed: self.removed,
        }
    }

    /// The measure the transitions were found with.
    pub fn measure(&self) -> Measure {
        self.measure
    }

    /// The transition search's options.
    pub fn options(&self) -> &TransitionOptions {
        &self.options
    }

    /// Sequences (nodes) with their frame spans, numbered flat in order.
    pub fn sequences(&self) -> &[Span] {
        &self.sequences
    }

    /// All transitions, grouped by ordered sequence pair, best first.
    pub fn transitions(&self) -> &[Transition] {
        &self.transitions
    }

    /// Sequence-level edges, one per ordered pair with a transition.
    pub fn edges(&self) -> &[SequenceEdge] {
        &self.edges
    }

    /// What the edits removed, for the report.
    pub fn removed(&self) -> &[String] {
        &self.removed
    }

    /// Finds the transitions of every ordered sequence pair (in parallel)
    /// and builds the graph, applying `edits`.
    pub fn build(
        matrix: &(impl Dissimilarity + ?Sized),
        measure: Measure,
        options: &TransitionOptions,
        edits: &GraphEdits,
    ) -> Result<SurfaceMotionGraph, EditError> {
        use rayon::prelude::*;
        let spans = matrix.spans().to_vec();
        let forbid = parse_forbid(&edits.forbid, &spans)?;
        let remove = parse_remove(&edits.remove, &spans)?;
        let pairs: Vec<(usize, usize)> = (0..spans.len())
            .flat_map(|i| (0..spans.len()).map(move |j| (i, j)))
            .collect();
        let found: Vec<Vec<Transition>> = pairs
            .par_iter()
            .map(|&(i, j)| {
                if forbid.iter().any(|f| f.matches(i, j)) {
                    return Vec::new();
                }
                let (si, sj) = (spans[i].start, spans[j].start);
                let c = |r: usize, s: usize| matrix.value(si + r, sj + s);
                let (rows, cols, same) = (spans[i].len, spans[j].len, i == j);
                match matrix.cells(i, j) {
                    None => transitions::find(&c, rows, cols, same, options),
                    Some(cells) => {
                        transitions::find_among(&c, rows, cols, same, options, cells.into_iter())
                    }
                }
                .into_iter()
                .map(|(m, n, window, cost)| Transition {
                    from: i,
                    to: j,
                    m,
                    n,
                    window,
                    cost,
                })
                .collect()
            })
            .collect();
        let mut removed = Vec::new();
        let mut all = Vec::new();
        for t in found.into_iter().flatten() {
            if remove.contains(&(t.from, t.m, t.to, t.n)) {
                removed.push(format!(
                    "{}:{} -> {}:{}",
                    spans[t.from].name, t.m, spans[t.to].name, t.n
                ));
            } else {
                all.push(t);
            }
        }
        // A `remove` rule that matched no transition is most likely a typo
        // or a stale frame number: say so rather than ignore it (issue 18,
        // item 16).
        for (rule, r) in edits.remove.iter().zip(&remove) {
            if !found_any(&removed, &spans, r) {
                tracing::warn!(
                    "graph edit remove '{rule}': no such transition was found, nothing removed"
                );
            }
        }
        for f in &edits.forbid {
            removed.push(format!("forbidden: {f}"));
        }
        // Edges in the order of their first transition; found by a map (a
        // scan of the edges per transition grew with sequences⁴: 10⁵
        // transitions and edges at 10⁵ frames, issue 43).
        let mut edges: Vec<SequenceEdge> = Vec::new();
        let mut edge_of: std::collections::HashMap<(usize, usize), usize> =
            std::collections::HashMap::new();
        for (k, t) in all.iter().enumerate() {
            match edge_of.get(&(t.from, t.to)) {
                Some(&e) => {
                    let e = &mut edges[e];
                    e.transitions.push(k);
                    e.cost = e.cost.min(t.cost);
                }
                None => {
                    edge_of.insert((t.from, t.to), edges.len());
                    edges.push(SequenceEdge {
                        from: t.from,
                        to: t.to,
                        transitions: vec![k],
                        cost: t.cost,
                    });
                }
            }
        }
        Ok(SurfaceMotionGraph {
            measure,
            options: *options,
            sequences: spans,
            transitions: all,
            edges,
            removed,
        })
    }

    /// Checks a graph read from a cache against the similarity matrix it
    /// claims to come from: the same sequences (names, starts, lengths).
    /// The graph's own parts agree by construction ([`SurfaceMotionGraph::new`]):
    /// a cache edited by hand (or by a bug) with a valid key made `retarget`
    /// and `graph --json` panic and `graph --dot` print nonsense (issue 18,
    /// item 13). Returns what is wrong.
    pub fn validate(&self, matrix: &(impl Dissimilarity + ?Sized)) -> Result<(), String> {
        if self.sequences != matrix.spans() {
            return Err("its sequences differ from the similarity matrix's".into());
        }
        Ok(())
    }

    /// Total frames.
    pub fn frame_count(&self) -> usize {
        self.sequences.iter().map(|s| s.len).sum()
    }

    /// The flat id of frame `t` of sequence `s` (`s` must be a sequence of
    /// the graph; [`SurfaceMotionGraph::checked_flat_id`] checks).
    pub fn flat_id(&self, s: usize, t: usize) -> FlatFrame {
        FlatFrame::from_index(self.sequences[s].start + t)
    }

    /// The flat id of a frame (`None` when out of range).
    pub fn checked_flat_id(&self, f: FrameId) -> Option<FlatFrame> {
        let q = self.sequences.get(f.seq as usize)?;
        ((f.frame as usize) < q.len).then(|| self.flat_id(f.seq as usize, f.frame as usize))
    }

    /// The frame of a flat id ([`SurfaceMotionGraph::frame_of`] typed).
    pub fn frame_at(&self, id: FlatFrame) -> FrameId {
        let (s, t) = self.frame_of(id);
        FrameId {
            seq: s as u32,
            frame: t as u32,
        }
    }

    /// Sequence and frame of a flat id (the last sequence's for an id past
    /// the end).
    pub fn frame_of(&self, id: FlatFrame) -> (usize, usize) {
        let id = id.index();
        let s = self
            .sequences
            .partition_point(|q| q.start + q.len <= id)
            .min(self.sequences.len().saturating_sub(1));
        (s, id - self.sequences[s].start)
    }

    /// The frame-level adjacency (successors of each frame with costs).
    pub fn adjacency(&self) -> FrameAdjacency {
        let n = self.frame_count();
        let mut out: Vec<Vec<(FlatFrame, f32)>> = vec![Vec::new(); n];
        for (s, span) in self.sequences.iter().enumerate() {
            for t in 0..span.len.saturating_sub(1) {
                out[self.flat_id(s, t).index()].push((self.flat_id(s, t + 1), 0.0));
            }
        }
        for t in &self.transitions {
            if t.n + 1 < self.sequences[t.to].len {
                out[self.flat_id(t.from, t.m).index()]
                    .push((self.flat_id(t.to, t.n + 1), t.cost as f32));
            }
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let mut targets = Vec::new();
        let mut costs = Vec::new();
        offsets.push(0u32);
        for o in out {
            for (t, c) in o {
                targets.push(t);
                costs.push(c);
            }
            offsets.push(targets.len() as u32);
        }
        FrameAdjacency {
            offsets,
            targets,
            costs,
        }
    }

    /// Graphviz DOT: one node per sequence (with its frame count), one edge
    /// per sequence pair labelled with its transitions `m→n (L, cost)`.
    pub fn to_dot(&self) -> String {
        let mut s = String::from(
            "digraph surface_motion_graph {\n  rankdir=LR;\n  node [shape=box, style=rounded];\n",
        );
        for (i, q) in self.sequences.iter().enumerate() {
            let _ = writeln!(
                s,
                "  s{i} [label=\"{}\\n{} frames\"];",
                escape(&q.name),
                q.len
            );
        }
        for e in &self.edges {
            let label: Vec<String> = e
                .transitions
                .iter()
                .map(|&k| {
                    let t = &self.transitions[k];
                    format!("{}→{} (L={}, {:.3})", t.m, t.n, t.window, t.cost)
                })
                .collect();
            let _ = writeln!(
                s,
                "  s{} -> s{} [label=\"{}\"];",
                e.from,
                e.to,
                label.join("\\n")
            );
        }
        s.push_str("}\n");
        s
    }
}

fn escape(s: &str) -> String {
    s.replace('\\', "\\\\").replace('"', "\\\"")
}

/// Successors of every frame in compressed rows.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameAdjacency {
    /// Row starts, `frames + 1` entries.
    pub offsets: Vec<u32>,
    /// Successor frames.
    pub targets: Vec<FlatFrame>,
    /// Edge costs (0 along a sequence, the transition cost on a jump).
    pub costs: Vec<f32>,
}

impl FrameAdjacency {
    /// Successors of frame `f` with costs.
    pub fn successors(&self, f: FlatFrame) -> impl Iterator<Item = (FlatFrame, f32)> + '_ {
        let (a, b) = (
            self.offsets[f.index()] as usize,
            self.offsets[f.index() + 1] as usize,
        );
        self.targets[a..b]
            .iter()
            .copied()
            .zip(self.costs[a..b].iter().copied())
    }
}

struct Forbid(Option<usize>, Option<usize>);
impl Forbid {
    fn matches(&self, i: usize, j: usize) -> bool {
        self.0.is_none_or(|a| a == i) && self.1.is_none_or(|b| b == j)
    }
}

fn seq_index(spans: &[Span], name: &str, edit: &str) -> Result<usize, EditError> {
    spans
        .iter()
        .position(|s| s.name == name)
        .ok_or_else(|| EditError {
            edit: edit.into(),
            msg: format!(
                "no sequence '{name}' (the database has {})",
                spans
                    .iter()
                    .map(|s| s.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        })
}

fn split_arrow(e: &str) -> Result<(&str, &str), EditError> {
    e.split_once("->")
        .map(|(a, b)| (a.trim(), b.trim()))
        .ok_or_else(|| EditError {
            edit: e.into(),
            msg: "expected 'FROM -> TO'".into(),
        })
}

fn parse_forbid(edits: &[String], spans: &[Span]) -> Result<Vec<Forbid>, EditError> {
    edits
        .iter()
        .map(|e| {
            let (a, b) = split_arrow(e)?;
            let side = |x: &str| {
                if x == "*" {
                    Ok(None)
                } else {
                    seq_index(spans, x, e).map(Some)
                }
            };
            Ok(Forbid(side(a)?, side(b)?))
        })
        .collect()
}

/// True when `removed` (as [`SurfaceMotionGraph::build`] words it) holds the
/// transition `r`.
fn found_any(removed: &[String], spans: &[Span], r: &(usize, usize, usize, usize)) -> bool {
    let (i, m, j, n) = *r;
    let text = format!("{}:{} -> {}:{}", spans[i].name, m, spans[j].name, n);
    removed.contains(&text)
}

fn parse_remove(
    edits: &[String],
    spans: &[Span],
) -> Result<Vec<(usize, usize, usize, usize)>, EditError> {
    edits
        .iter()
        .map(|e| {
            let (a, b) = split_arrow(e)?;
            let frame = |x: &str| -> Result<(usize, usize), EditError> {
                let (name, f) = x.rsplit_once(':').ok_or_else(|| EditError {
                    edit: e.clone(),
                    msg: format!("'{x}': expected SEQUENCE:FRAME"),
                })?;
                let s = seq_index(spans, name.trim(), e)?;
                let f: usize = f.trim().parse().map_err(|_| EditError {
                    edit: e.clone(),
                    msg: format!("'{f}' is not a frame number"),
                })?;
                if f >= spans[s].len {
                    return Err(EditError {
                        edit: e.clone(),
                        msg: format!(
                            "frame {f} is past the end of {} ({} frames)",
                            spans[s].name, spans[s].len
                        ),
                    });
                }
                Ok((s, f))
            };
            let (i, m) = frame(a)?;
            let (j, n) = frame(b)?;
            Ok((i, m, j, n))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::similarity::SimilarityMatrix;

    fn two_sequences() -> SimilarityMatrix {
        // "a" (40 frames) and "b" (30 frames) of a 1-D motion; b repeats
        // a's frames 10..30 at 5..25.
        let a: Vec<f64> = (0..40).map(|t| (t as f64 * 0.41).sin() * 2.0).collect();
        let mut b: Vec<f64> = (0..30).map(|t| 5.0 + (t as f64 * 0.3).cos()).collect();
        b[5..25].copy_from_slice(&a[10..30]);
        let all: Vec<f64> = a.iter().chain(&b).copied().collect();
        let n = all.len();
        let data = (0..n * n)
            .map(|k| (all[k / n] - all[k % n]).abs() as f32)
            .collect();
        let spans = vec![
            Span {
                name: "a".into(),
                start: 0,
                len: 40,
            },
            Span {
                name: "b".into(),
                start: 40,
                len: 30,
            },
        ];
        SimilarityMatrix::new(spans, data).unwrap()
    }

    #[test]
    fn build_edit_and_walk() {
        let m = two_sequences();
        let o = TransitionOptions::default();
        let g = SurfaceMotionGraph::build(&m, Measure::Shape, &o, &GraphEdits::default()).unwrap();
        let ab: Vec<&Transition> = g
            .transitions
            .iter()
            .filter(|t| t.from == 0 && t.to == 1)
            .collect();
        assert!(!ab.is_empty() && ab.len() <= 4);
        assert_eq!(ab[0].m - ab[0].n, 5);
        assert!(g.edges.iter().any(|e| e.from == 1 && e.to == 0));
        // Adjacency: sequence steps plus one jump per transition that lands
        // inside its target.
        let adj = g.adjacency();
        let steps = 39 + 29;
        let jumps = g
            .transitions
            .iter()
            .filter(|t| t.n + 1 < g.sequences[t.to].len)
            .count();
        assert_eq!(adj.targets.len(), steps + jumps);
        let f = g.flat_id(0, ab[0].m);
        assert!(
            adj.successors(f)
                .any(|(t, _)| t == g.flat_id(1, ab[0].n + 1))
        );
        assert_eq!(g.frame_of(g.flat_id(1, 7)), (1, 7));
        assert!(g.to_dot().contains("s0 -> s1"));
        // Edits.
        let edits = GraphEdits {
            forbid: vec!["a -> b".into()],
            remove: vec![format!("b:{} -> a:{}", ab[0].n, ab[0].m)],
        };
        let g2 = SurfaceMotionGraph::build(&m, Measure::Shape, &o, &edits).unwrap();
        assert!(!g2.transitions.iter().any(|t| t.from == 0 && t.to == 1));
        assert!(
            !g2.transitions
                .iter()
                .any(|t| t.from == 1 && t.to == 0 && t.m == ab[0].n && t.n == ab[0].m)
        );
        let bad = GraphEdits {
            forbid: vec!["a -> nope".into()],
            ..Default::default()
        };
        assert!(
            SurfaceMotionGraph::build(&m, Measure::Shape, &o, &bad)
                .unwrap_err()
                .msg
                .contains("no sequence 'nope'")
        );
    }
}
