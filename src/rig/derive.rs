//! The rules that place a canonical joint a clip has no joint for (a
//! [`super::RigMap`]'s derived joints, chosen by name or by
//! [`super::structure`]).

use super::canonical::Canonical;
use serde::{Deserialize, Serialize};

/// How to place a canonical joint for which the clip has no joint. Rules
/// are evaluated in [`Canonical::ALL`] order on the frame's canonical
/// positions, so a rule may use joints (or earlier derived joints) only.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "rule", rename_all = "snake_case")]
pub enum Derive {
    /// The End Site (bone tail) of the named joint, e.g. the head from a
    /// leaf neck or the toe from a leaf ankle.
    EndSite {
        /// Joint name in the file.
        joint: String,
    },
    /// `from + t · (to − from)`: the chest half-way from spine to neck
    /// (`t = 0.5`), the head a third of a neck length above the neck along
    /// chest→neck (`from = chest, to = neck, t = 4/3`).
    Between {
        /// Start joint.
        from: Canonical,
        /// End joint.
        to: Canonical,
        /// Fraction along from→to (may exceed 1).
        t: f64,
    },
    /// A toe forward of and below the ankle: `ankle + fraction · |knee −
    /// ankle| · (cos 20° · forward − sin 20° · up)`, with up = pelvis→neck
    /// and forward = (l_hip − r_hip) × up (the body's left × up).
    ToeFromAnkle {
        /// The ankle (`l_ankle` or `r_ankle`); the knee is its parent.
        ankle: Canonical,
        /// Toe distance as a fraction of the shin length (0.35 ≈ foot
        /// length 0.152 H over shin 0.246 H · 0.57 for the toe base).
        fraction: f64,
    },
}
