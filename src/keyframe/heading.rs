//! The heading target (an extension of Huang et al. 2015, Sec. 5.1): the
//! animator's final facing ([`HeadingTarget`]), the form the searches use
//! ([`Heading`]: a turn to reach, a cost per radian, sectors of turn) and
//! angles wrapped to `(−π, π]` ([`wrap`]). The exact-length search
//! ([`super::lattice`]), the walks-and-loops search ([`super::search`])
//! and the repetition programmes ([`super::repeats::Turns`]) all price a
//! path's turn with it.

/// The animator's heading target: the final facing relative to the start
/// key-frame's.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct HeadingTarget {
    /// Degrees about the vertical ([`crate::pose::measure::rotate_yaw`]'s
    /// sense: positive turns from +Z towards +X).
    pub degrees: f64,
    /// Cost per degree of error. Default in the CLI: 1/30 (a 30° error
    /// costs 1, as much as 0.3 m of distance error at the paper's
    /// `w_dist`).
    pub weight: f64,
    /// Sectors of turn the search's bins are split into. Default: 8.
    pub sectors: usize,
}

/// A heading target as the programme uses it (module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Heading {
    /// Target turn of the placement over the path (radians; the facing
    /// target minus the key-frames' own facing difference).
    pub turn: f64,
    /// Cost per radian of error.
    pub weight: f64,
    /// Sectors of turn the bins are split into. Default in the CLI: 8.
    pub sectors: usize,
}

/// `x` wrapped to `(−π, π]`.
pub fn wrap(x: f64) -> f64 {
    let t = std::f64::consts::TAU;
    let y = x.rem_euclid(t);
    if y > std::f64::consts::PI { y - t } else { y }
}

impl Heading {
    /// The heading term of a path that turns `turn` radians.
    pub fn cost(&self, turn: f64) -> f64 {
        self.weight * wrap(turn - self.turn).abs()
    }
    /// The sector of turn a path that turns `turn` radians falls in.
    pub(super) fn sector(&self, turn: f64) -> usize {
        let s = self.sectors.max(1);
        let x = (wrap(turn - self.turn) + std::f64::consts::PI) / std::f64::consts::TAU;
        ((x * s as f64) as usize).min(s - 1)
    }
}
