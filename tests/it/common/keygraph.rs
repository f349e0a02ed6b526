//! Random frame graphs for the key-frame tests (tests/keyframe.rs,
//! tests/keyframe_smoothest.rs): a small deterministic generator and
//! sequences walking at different speeds joined by random transitions.

use surfmotion::graph::FlatFrame;
use surfmotion::keyframe::graph::KeyGraph;

/// A small deterministic generator (no dependency).
pub struct Lcg(pub u64);

impl Lcg {
    /// Uniform in [0, 1).
    pub fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in 0..n.
    pub fn below(&mut self, n: usize) -> usize {
        ((self.next() * n as f64) as usize).min(n - 1)
    }
}

/// The shape of a random graph: sequence lengths `frames.0 ..
/// frames.0 + frames.1`, transition costs `cost.0 + cost.1 · u`; with
/// `distinct`, a transition already present is not added again.
pub struct Shape {
    pub frames: (usize, usize),
    pub cost: (f64, f64),
    pub distinct: bool,
}

/// `seqs` sequences walking at different speeds (with a lateral sway) and
/// `jumps` random transitions, as `shape` says.
pub fn random_graph(r: &mut Lcg, seqs: usize, jumps: usize, shape: &Shape) -> KeyGraph {
    let mut centre = Vec::new();
    let mut sequence = Vec::new();
    let mut starts = Vec::new();
    for s in 0..seqs {
        let len = shape.frames.0 + r.below(shape.frames.1);
        let speed = 0.01 + 0.08 * r.next();
        starts.push((centre.len(), len));
        for f in 0..len {
            centre.push([f as f64 * speed, 0.02 * (f as f64 * 0.7).sin()]);
            sequence.push(s as u32);
        }
    }
    let n = centre.len();
    let mut succ: Vec<Vec<(FlatFrame, f64)>> = vec![Vec::new(); n];
    for f in 0..n - 1 {
        if sequence[f] == sequence[f + 1] {
            succ[f].push((FlatFrame::from_index(f + 1), 0.0));
        }
    }
    for _ in 0..jumps {
        let (a0, la) = starts[r.below(seqs)];
        let (b0, lb) = starts[r.below(seqs)];
        let m = a0 + r.below(la);
        let to = b0 + 1 + r.below(lb - 1);
        let seen = shape.distinct && succ[m].iter().any(|&(t, _)| t.index() == to);
        if to != m + 1 && !seen {
            succ[m].push((
                FlatFrame::from_index(to),
                shape.cost.0 + shape.cost.1 * r.next(),
            ));
        }
    }
    KeyGraph::new(&succ, centre, sequence)
}
