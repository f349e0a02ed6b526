//! The fold repair's options and its budget of work per frame
//! (`unflip`, `untangle`).

/// The repair's work on one frame, counted, and the most it may do
/// (`Deformer::repair`'s budget): projections of `untangle` and
/// patch unknowns of `unflip` (each round's patch, free and fixed
/// vertices, summed over the rounds). A step that would go past a limit is
/// not started; what was done is still counted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct Work {
    /// Projections made by the untangling.
    pub projections: usize,
    /// Patch unknowns solved by the Poisson repair.
    pub patch_vertices: usize,
    /// Patch systems factored (one a round of [`unflip_within`]).
    pub patches: usize,
    /// Of `patches`, those of the surface repair's rounds (the repair
    /// against the surface's own turns, after the skin's).
    pub surface_patches: usize,
    /// Of `patches`, those of the adaptive retry (the repair again from
    /// the deformed frame with the adaptive untangling budget).
    pub retry_patches: usize,
    /// Of `patches`, those of the second and later repair passes.
    pub later_pass_patches: usize,
    /// Rounds not solved again because a pass that did not help had
    /// solved them from the same state (`unflip::Replay`): factorisations saved.
    pub replayed_rounds: usize,
    /// Steps not started because they would have gone past the budget
    /// (`RepairBudget`; an untangling sweep cut short, a patch not
    /// solved): 0 on a frame the budget did not bind.
    pub stopped: usize,
}

/// Limits of a frame's [`Work`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WorkLimit {
    /// Most projections.
    pub projections: usize,
    /// Most patch unknowns.
    pub patch_vertices: usize,
}

impl WorkLimit {
    /// No limit.
    pub const NONE: WorkLimit = WorkLimit {
        projections: usize::MAX,
        patch_vertices: usize::MAX,
    };
}

/// A frame's work so far against its limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Budget {
    /// Done so far.
    pub done: Work,
    /// The limit.
    pub limit: WorkLimit,
}

impl Budget {
    /// Nothing done yet, within `limit`.
    pub fn new(limit: WorkLimit) -> Budget {
        Budget {
            done: Work::default(),
            limit,
        }
    }

    /// Projections left.
    pub(crate) fn projections_left(&self) -> usize {
        self.limit.projections.saturating_sub(self.done.projections)
    }

    /// Patch unknowns left.
    pub(crate) fn patch_left(&self) -> usize {
        self.limit
            .patch_vertices
            .saturating_sub(self.done.patch_vertices)
    }
}

/// Options of `unflip`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RepairOptions {
    /// Poisson rounds, the patch doubling each round from 2 rings. 0 turns
    /// the repair off. Default 3 (up to 8 rings).
    pub rounds: usize,
    /// Most rings a patch grows around its turned-over triangles: the
    /// doubling stops here and later rounds solve patches of this many
    /// rings around what is still turned over. Default unbounded
    /// (`usize::MAX`, the repair as before). Measured (session 32, live
    /// `--replay` of CMU 02_02 at lag 0 onto the real samba capture,
    /// three interleaved pairs at load 13-15): 8 rings cut the patch
    /// unknowns a frame from 5,074 to 4,063 and the deformation's CPU from
    /// 28.5-30.4 to 24.5-25.9 ms a frame (p99 110-127 → 50-69 ms), but
    /// `eval --surface` flags 2 % more (22,822 → 23,290; creases 6,474 →
    /// 6,695, turned over against the rest frame 118 → 125), so it is not
    /// the default; CMU 131_02 is unchanged.
    pub most_rings: usize,
    /// A triangle whose unit normal has a dot product with its turned source
    /// normal below this is rebuilt towards its source shape; the others
    /// keep their deformed shape. Default 0.3.
    pub healthy_cos: f64,
    /// Weight of a rebuilt triangle's edges against a kept one's. Default 4.
    pub weight: f64,
    /// Most umbrella-smoothing steps on the vertices of triangles still
    /// turned over after the rounds. Default 20.
    pub smooth: usize,
    /// Take a pass's rounds that the pass before solved from the same
    /// state from that pass (`unflip::Replay`) instead of solving them again.
    /// The result is the same bit for bit (the rounds are deterministic);
    /// off only to measure what it saves. Default true.
    pub replay: bool,
}

impl Default for RepairOptions {
    fn default() -> Self {
        RepairOptions {
            rounds: 3,
            most_rings: usize::MAX,
            healthy_cos: 0.3,
            weight: 4.0,
            smooth: 20,
            replay: true,
        }
    }
}
