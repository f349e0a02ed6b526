//! The parts of a [`super::SurfaceMotionGraph`] (Huang et al. 2015, Sec. 4.3) and
//! the check that they agree: [`super::SurfaceMotionGraph::new`] and the graph
//! cache's reader go through [`GraphParts::check`], so a graph in hand names
//! only sequences, frames and transitions that exist, and its fields are read
//! through accessors.

use super::transitions::{Transition, TransitionOptions};
use crate::similarity::{Measure, Span};
use serde::{Deserialize, Serialize};

/// A sequence edge (one or more transitions between two sequences).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SequenceEdge {
    /// Source sequence.
    pub from: usize,
    /// Target sequence.
    pub to: usize,
    /// Transitions on this edge (indices into [`super::SurfaceMotionGraph::transitions`]).
    pub transitions: Vec<usize>,
    /// Cheapest transition cost.
    pub cost: f64,
}

/// A graph's parts as the cache stores them (the same JSON as a serialised
/// [`super::SurfaceMotionGraph`]).
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct GraphParts {
    /// The measure the transitions were found with.
    pub measure: Measure,
    /// The transition search's options.
    pub options: TransitionOptions,
    /// Sequences (nodes) with their frame spans, numbered flat in order.
    pub sequences: Vec<Span>,
    /// All transitions, grouped by ordered sequence pair, best first.
    pub transitions: Vec<Transition>,
    /// Sequence-level edges, one per ordered pair with a transition.
    pub edges: Vec<SequenceEdge>,
    /// What the edits removed, for the report.
    pub removed: Vec<String>,
}

impl GraphParts {
    /// Checks the parts alone: the sequences numbered flat one after the
    /// other from frame 0; every transition between existing sequences, its
    /// frames inside them, its cost finite and its half-window no longer than
    /// the longer sequence; one edge per ordered sequence pair that has a
    /// transition, listing exactly that pair's transitions (each once) at the
    /// cheapest one's cost. The error says what disagrees.
    pub fn check(&self) -> Result<(), String> {
        self.check_sequences()?;
        for (k, t) in self.transitions.iter().enumerate() {
            self.check_transition(k, t)?;
        }
        self.check_edges()
    }

    fn check_sequences(&self) -> Result<(), String> {
        let mut start = 0usize;
        for (i, s) in self.sequences.iter().enumerate() {
            if s.start != start {
                return Err(format!(
                    "sequence {i} ('{}') starts at flat frame {}, not {start} where sequence {} ends",
                    s.name,
                    s.start,
                    i.saturating_sub(1)
                ));
            }
            start = start
                .checked_add(s.len)
                .ok_or_else(|| format!("sequence {i} ('{}') has {} frames", s.name, s.len))?;
        }
        Ok(())
    }

    fn check_transition(&self, k: usize, t: &Transition) -> Result<(), String> {
        let seqs = &self.sequences;
        let (Some(a), Some(b)) = (seqs.get(t.from), seqs.get(t.to)) else {
            return Err(format!(
                "transition {k} joins sequences {} -> {} of {}",
                t.from,
                t.to,
                seqs.len()
            ));
        };
        if t.m >= a.len || t.n >= b.len {
            return Err(format!(
                "transition {k} ({}:{} -> {}:{}) is past the end of a sequence ({} and {} frames)",
                a.name, t.m, b.name, t.n, a.len, b.len
            ));
        }
        if !t.cost.is_finite() || t.window > a.len.max(b.len) {
            return Err(format!(
                "transition {k} has cost {} and half-window {}",
                t.cost, t.window
            ));
        }
        Ok(())
    }

    fn check_edges(&self) -> Result<(), String> {
        let seqs = self.sequences.len();
        let mut listed = vec![false; self.transitions.len()];
        let mut pairs = std::collections::HashSet::new();
        for (k, e) in self.edges.iter().enumerate() {
            if e.from >= seqs || e.to >= seqs {
                return Err(format!("edge {k} joins sequences that do not exist"));
            }
            if !pairs.insert((e.from, e.to)) {
                return Err(format!(
                    "edge {k} repeats the sequence pair {} -> {}",
                    e.from, e.to
                ));
            }
            let mut cheapest = f64::INFINITY;
            for &i in &e.transitions {
                match self.transitions.get(i) {
                    Some(t) if t.from == e.from && t.to == e.to && !listed[i] => {
                        listed[i] = true;
                        cheapest = cheapest.min(t.cost);
                    }
                    Some(t) if t.from == e.from && t.to == e.to => {
                        return Err(format!("edge {k} lists transition {i} twice"));
                    }
                    _ => return Err(format!("edge {k} lists transition {i}, not one of its own")),
                }
            }
            if e.transitions.is_empty() || e.cost != cheapest {
                return Err(format!(
                    "edge {k} costs {} but its {} transitions' cheapest is {cheapest}",
                    e.cost,
                    e.transitions.len()
                ));
            }
        }
        match listed.iter().position(|&l| !l) {
            Some(i) => Err(format!("transition {i} is on no edge")),
            None => Ok(()),
        }
    }
}
