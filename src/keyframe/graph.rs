//! The frame graph the key-frame search walks (Huang et al. 2015, Sec. 5.1):
//! the Surface Motion Graph's frame-level adjacency with, for every frame,
//! the floor distance its centroid moves when the path enters it (Eq. 10).
//!
//! A path of frames `f_0 … f_{N−1}` travels `Σ step[f_k]` for `k ≥ 1`: the
//! step of a frame is the floor-projected distance between the mesh
//! centroid of that frame and of the frame before it in its own sequence.
//! Inside a sequence this is Eq. 10 exactly; across a transition
//! `(i, m) → (j, n+1)` it is the step `n → n+1` of `j`, i.e. the motion the
//! character makes once the new segment is aligned to where the previous
//! one left off ([`super::place`] places the output so, and the output
//! travels exactly this distance).

use crate::db::Character;
use crate::drive::timeline::Frames;
use crate::graph::{FlatFrame, FrameAdjacency};
use std::collections::HashMap;

/// An arc of the frame graph as the search sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameEdge {
    /// Frame entered.
    pub to: FlatFrame,
    /// Transition cost (0 along a sequence).
    pub cost: f64,
    /// True for a transition (a jump), false for the next frame of the
    /// sequence.
    pub jump: bool,
    /// The turn of the output's heading at this arc (radians about Y,
    /// [`crate::pose::measure::rotate_yaw`]'s sense): for a transition `a → b`
    /// the floor rotation fitting the skeleton of `b − 1` onto that of `a`
    /// ([`super::place`]); 0 along a sequence and in graphs built without
    /// skeletons.
    pub turn: f64,
}

/// The frame graph with per-frame steps. Frames are numbered as in
/// [`crate::graph::SurfaceMotionGraph::flat_id`].
#[derive(Debug, Clone, PartialEq)]
pub struct KeyGraph {
    /// Successors of every frame (CSR rows: `offsets[f]..offsets[f+1]`).
    pub offsets: Vec<u32>,
    /// The arcs.
    pub edges: Vec<FrameEdge>,
    /// Floor distance (metres) of every frame's centroid from the previous
    /// frame of its sequence; 0 on a sequence's first frame.
    pub step: Vec<f64>,
    /// Floor-projected centroid `(x, z)` of every frame, metres, in its own
    /// capture's world frame.
    pub centre: Vec<[f64; 2]>,
    /// Sequence of every frame.
    pub sequence: Vec<u32>,
    /// Blend half-window of every jump `(frame left, frame entered)` when
    /// the jumps are not the Surface Motion Graph's (key-frame transitions
    /// chosen by [`super::select`]); empty: the graph's windows.
    pub windows: HashMap<(FlatFrame, FlatFrame), usize>,
}

impl KeyGraph {
    /// Builds the graph from successor lists and per-frame centroids.
    /// `sequence[f]` names the sequence of frame `f`; frames of one
    /// sequence are consecutive. An arc `f → f+1` inside a sequence with
    /// cost 0 is a plain step; any other arc is a jump.
    pub fn new(
        succ: &[Vec<(FlatFrame, f64)>],
        centre: Vec<[f64; 2]>,
        sequence: Vec<u32>,
    ) -> KeyGraph {
        let n = succ.len();
        let mut offsets = Vec::with_capacity(n + 1);
        let mut edges = Vec::new();
        offsets.push(0);
        for (f, row) in succ.iter().enumerate() {
            for &(to, cost) in row {
                let plain =
                    to.index() == f + 1 && sequence.get(f + 1) == sequence.get(f) && cost == 0.0;
                edges.push(FrameEdge {
                    to,
                    cost,
                    jump: !plain,
                    turn: 0.0,
                });
            }
            offsets.push(edges.len() as u32);
        }
        let step = (0..n)
            .map(|f| {
                if f > 0 && sequence[f - 1] == sequence[f] {
                    let (a, b) = (centre[f - 1], centre[f]);
                    (b[0] - a[0]).hypot(b[1] - a[1])
                } else {
                    0.0
                }
            })
            .collect();
        KeyGraph {
            offsets,
            edges,
            step,
            centre,
            sequence,
            windows: HashMap::new(),
        }
    }

    /// From a frame adjacency and centroids.
    pub(crate) fn from_adjacency(
        adj: &FrameAdjacency,
        centre: Vec<[f64; 2]>,
        sequence: Vec<u32>,
    ) -> KeyGraph {
        let n = adj.offsets.len().saturating_sub(1);
        let succ: Vec<Vec<(FlatFrame, f64)>> = FlatFrame::all(n)
            .map(|f| adj.successors(f).map(|(t, c)| (t, c as f64)).collect())
            .collect();
        KeyGraph::new(&succ, centre, sequence)
    }

    /// The graph of a loaded character: its adjacency, and the centroid of
    /// every frame (mean of the vertices, metres, Y-up, projected on the
    /// floor).
    pub fn of_character(ch: &Character) -> KeyGraph {
        Self::of_character_with(ch, None)
    }

    /// [`KeyGraph::of_character`] with the jumps replaced by `jumps`
    /// (`(frame left, frame entered, cost, half-window)`) when given.
    pub fn of_character_with(
        ch: &Character,
        jumps: Option<&[(FlatFrame, FlatFrame, f64, usize)]>,
    ) -> KeyGraph {
        let centre = frame_centres(ch);
        let mut sequence = vec![0u32; ch.frame_count()];
        for (s, span) in ch.graph().sequences().iter().enumerate() {
            for f in span.start..span.start + span.len {
                if let Some(x) = sequence.get_mut(f) {
                    *x = s as u32;
                }
            }
        }
        let mut g = match jumps {
            None => KeyGraph::from_adjacency(ch.adjacency(), centre, sequence),
            Some(jumps) => {
                let n = ch.frame_count();
                let mut succ: Vec<Vec<(FlatFrame, f64)>> = (0..n)
                    .map(|f| {
                        if f + 1 < n && sequence[f + 1] == sequence[f] {
                            vec![(FlatFrame::from_index(f + 1), 0.0)]
                        } else {
                            Vec::new()
                        }
                    })
                    .collect();
                for &(a, b, c, _) in jumps {
                    if let Some(row) = succ.get_mut(a.index()) {
                        row.push((b, c));
                    }
                }
                let mut g = KeyGraph::new(&succ, centre, sequence);
                g.windows = jumps.iter().map(|&(a, b, _, l)| ((a, b), l)).collect();
                g
            }
        };
        // The placement's turn at every transition (as `place` turns).
        for f in 0..g.len() {
            let (lo, hi) = (g.offsets[f] as usize, g.offsets[f + 1] as usize);
            for e in &mut g.edges[lo..hi] {
                let b = e.to.index();
                if e.jump && b > 0 && b < ch.poses().len() && f < ch.poses().len() {
                    e.turn = crate::drive::Floor::fit(&ch.poses()[b - 1], &ch.poses()[f]).theta;
                }
            }
        }
        g
    }

    /// Number of frames.
    pub fn len(&self) -> usize {
        self.step.len()
    }

    /// True without frames.
    pub fn is_empty(&self) -> bool {
        self.step.is_empty()
    }

    /// Arcs leaving `f`.
    pub fn successors(&self, f: FlatFrame) -> &[FrameEdge] {
        &self.edges[self.offsets[f.index()] as usize..self.offsets[f.index() + 1] as usize]
    }

    /// Floor distance of frame `f`'s centroid from the previous frame of
    /// its sequence ([`KeyGraph::step`]).
    pub fn step_of(&self, f: FlatFrame) -> f64 {
        self.step[f.index()]
    }

    /// The arc `a → b`, the cheapest if several.
    pub fn edge(&self, a: FlatFrame, b: FlatFrame) -> Option<FrameEdge> {
        self.successors(a)
            .iter()
            .filter(|e| e.to == b)
            .min_by(|x, y| x.cost.total_cmp(&y.cost))
            .copied()
    }
}

/// The character's frame layout with the blend windows of a key graph's
/// jumps ([`KeyGraph::windows`]; the graph's when empty), for
/// [`crate::drive::timeline::timeline`].
pub(crate) struct KeyFrames<'a> {
    /// The character.
    pub ch: &'a Character,
    /// The graph whose jumps are walked.
    pub graph: &'a KeyGraph,
}

impl Frames for KeyFrames<'_> {
    fn frame_of(&self, id: FlatFrame) -> (usize, usize) {
        Frames::frame_of(self.ch, id)
    }
    fn flat_id(&self, s: usize, t: usize) -> FlatFrame {
        Frames::flat_id(self.ch, s, t)
    }
    fn len(&self, s: usize) -> usize {
        Frames::len(self.ch, s)
    }
    fn transition_window(&self, from: FlatFrame, to_prev: FlatFrame) -> Option<usize> {
        if self.graph.windows.is_empty() {
            Frames::transition_window(self.ch, from, to_prev)
        } else {
            self.graph.windows.get(&(from, to_prev.next())).copied()
        }
    }
}

/// Floor-projected mean vertex `(x, z)` of every frame of a character
/// (metres, Y-up).
pub fn frame_centres(ch: &Character) -> Vec<[f64; 2]> {
    // The character's frames are in metres, Y-up already (converted once
    // on load).
    FlatFrame::all(ch.frame_count())
        .map(|f| centre_of(ch.frame(f)))
        .collect()
}

/// Floor-projected mean vertex `(x, z)` of one frame of positions
/// (metres, Y-up).
pub fn centre_of(positions: &[[f64; 3]]) -> [f64; 2] {
    let mut s = [0.0f64; 2];
    for p in positions {
        s[0] += p[0];
        s[1] += p[2];
    }
    let k = positions.len().max(1) as f64;
    [s[0] / k, s[1] / k]
}

/// The travelled distance of a frame-major sequence: the sum of the floor
/// distances between consecutive frames' centroids (Eq. 10).
pub fn travelled(positions: &[[f64; 3]], n: usize) -> f64 {
    let c: Vec<[f64; 2]> = positions.chunks(n.max(1)).map(centre_of).collect();
    c.windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}
