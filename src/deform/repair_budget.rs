//! The fold repair's work limit a frame ([`RepairBudget`]), its preset for
//! live sessions ([`RepairBudget::LIVE`]) and its text form
//! (`none`, `live`, or `projections=N,patch=N,...`; [`std::str::FromStr`]
//! and [`std::fmt::Display`] round-trip).
//!
//! The work counted is [`unflip::Work`]'s: projections of the untangling
//! ([`super::untangle`]) and unknowns of the Poisson patch repair
//! ([`super::unflip`]). Counts, not time: the same budget bounds the same
//! frames on a loaded and an idle machine.

use super::unflip;

/// The fold repair's work limit on one frame ([`unflip::Work`]).
///
/// Each repair of a frame (the skin's turns, each round against the
/// surface's own turns, the cloth fallback's repair again from the blend)
/// that starts from `b` triangles turned over may do `per_triangle × b`;
/// all the frame's repairs together may do `most`. A step that would go
/// past either is not started ([`unflip::Work::stopped`] counts it), and
/// that repair ends there: no later pass or adaptive retry (each would
/// build its steps again only to refuse them; measured on 02_02, session
/// 51: without this rule a bounded frame cost more CPU than an unbounded
/// one). When what `most` left, not the share, bound the repair that
/// stopped, the frame's repair ends: no later surface round or cloth
/// fallback starts. So a frame's repair costs at most `most` whatever the
/// fold; the triangles it could not turn back are counted as left
/// ([`super::TurnedOver::after`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RepairBudget {
    /// Work allowed per triangle turned over before a repair.
    pub per_triangle: unflip::WorkLimit,
    /// The most work on any frame, all its repairs together.
    pub most: unflip::WorkLimit,
    /// The most work of the frame's first repair, against the skin's turns
    /// (or the cloth stitch's): what `most` leaves after it is kept for
    /// the repair against the surface's own turns, the one that turns
    /// back what the surface measure and the eye see as folds
    /// ([`super::near_turns`]). A first repair stopped by this limit does
    /// not end the frame's repair.
    pub skin: unflip::WorkLimit,
}

impl RepairBudget {
    /// No limit (the repair as it was before the budget).
    pub const NONE: RepairBudget = RepairBudget {
        per_triangle: unflip::WorkLimit::NONE,
        most: unflip::WorkLimit::NONE,
        skin: unflip::WorkLimit::NONE,
    };

    /// The live sessions' default (`live --repair-budget live`): 30,000
    /// projections and 4,000 patch unknowns a frame at most, 1,000 and 60
    /// per triangle turned over (session 22's bound, now over the whole
    /// frame), all of it spent on the repair against the surface's own
    /// turns: the skin's repair is its closing smoothing alone
    /// ([`RepairBudget::skips_skin`]). Measured (session 52, README *Live*:
    /// `live --speed 0 --lossless --record` then `eval --surface`, the real
    /// samba capture): triangle-frames turned over against the rest frame
    /// with the skin's repair in the budget → without, CMU 02_02 1,602 →
    /// 99, 131_01 3,248 → 358, 131_02 46 → 22, Bandai walk_happy 112 → 40
    /// (unbounded: 114, 292, 44, 112), and the deformation's CPU less.
    pub const LIVE: RepairBudget = RepairBudget {
        per_triangle: unflip::WorkLimit {
            projections: 1_000,
            patch_vertices: 60,
        },
        most: unflip::WorkLimit {
            projections: 30_000,
            patch_vertices: 4_000,
        },
        skin: unflip::WorkLimit {
            projections: 0,
            patch_vertices: 0,
        },
    };

    /// The limit of a repair starting from `bad` triangles turned over,
    /// on its own: `per_triangle × bad`, at most `most`.
    pub fn limit(&self, bad: usize) -> unflip::WorkLimit {
        self.limit_after(bad, &unflip::Work::default())
    }

    /// Whether [`RepairBudget::skin`] allows the skin's repair no work at
    /// all: it is then the patch repair's closing smoothing alone, and the
    /// budget goes whole to the repair against the surface's own turns.
    pub fn skips_skin(&self) -> bool {
        self.skin.projections == 0 && self.skin.patch_vertices == 0
    }

    /// [`RepairBudget::limit_after`] for the frame's first repair (against
    /// the skin's turns), also within [`RepairBudget::skin`].
    pub fn skin_limit_after(&self, bad: usize, spent: &unflip::Work) -> unflip::WorkLimit {
        let l = self.limit_after(bad, spent);
        unflip::WorkLimit {
            projections: l.projections.min(self.skin.projections),
            patch_vertices: l.patch_vertices.min(self.skin.patch_vertices),
        }
    }

    /// Whether `limit` ([`RepairBudget::limit_after`] of a repair starting
    /// from `bad` triangles turned over) is below the repair's share
    /// (`per_triangle × bad`) in either count: the frame's `most`, not the
    /// share, bounds that repair.
    pub fn frame_bound(&self, bad: usize, limit: &unflip::WorkLimit) -> bool {
        let p = &self.per_triangle;
        limit.projections < p.projections.saturating_mul(bad)
            || limit.patch_vertices < p.patch_vertices.saturating_mul(bad)
    }

    /// The limit of a repair starting from `bad` triangles turned over on
    /// a frame whose repairs have already done `spent`: `per_triangle ×
    /// bad`, at most what `most` leaves after `spent`. An unbounded key
    /// stays unbounded (`usize::MAX`), so [`RepairBudget::NONE`] gives
    /// [`unflip::WorkLimit::NONE`] whatever was spent.
    pub fn limit_after(&self, bad: usize, spent: &unflip::Work) -> unflip::WorkLimit {
        let (p, m) = (&self.per_triangle, &self.most);
        let left = |most: usize, spent: usize| match most {
            usize::MAX => usize::MAX,
            _ => most.saturating_sub(spent),
        };
        unflip::WorkLimit {
            projections: p
                .projections
                .saturating_mul(bad)
                .min(left(m.projections, spent.projections)),
            patch_vertices: p
                .patch_vertices
                .saturating_mul(bad)
                .min(left(m.patch_vertices, spent.patch_vertices)),
        }
    }
}

impl Default for RepairBudget {
    /// No limit: the repair as before the budget, offline's default (the
    /// bound trades folds left for time; see [`RepairBudget::LIVE`]).
    /// Measured (session 22, `tools::surface_repair`, the real samba
    /// capture, the bound then on each repair rather than the frame):
    /// 30,000 projections and 4,000 patch unknowns a frame at most (1,000
    /// and 60 per triangle turned over) brought `live --report`'s
    /// deformation CPU p99 from 71.8 to 27.3 ms on CMU 02_02 and from 91.1
    /// to 28.1 ms on 131_01, but left 11 (02_02) and 9,136 (131_01)
    /// triangle-frames turned over that the unbounded repair turns back.
    fn default() -> Self {
        RepairBudget::NONE
    }
}

/// Why a repair budget's text could not be read; each quotes what it
/// could not read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RepairBudgetError {
    /// Nothing given.
    #[error("empty repair budget: give none, live or {KEYS}")]
    Empty,
    /// A part that is not `key=N`.
    #[error("{part:?} is not key=N (give none, live or {KEYS})")]
    NotAPair {
        /// The part as given.
        part: String,
    },
    /// A key not known.
    #[error("unknown key {key:?} in {part:?} (keys: {KEYS})")]
    UnknownKey {
        /// The key as given.
        key: String,
        /// The part it is in.
        part: String,
    },
    /// A value that is not a whole number.
    #[error("{value:?} in {part:?} is not a whole number")]
    NotACount {
        /// The value as given.
        value: String,
        /// The part it is in.
        part: String,
    },
    /// A key given twice.
    #[error("{key:?} given twice")]
    Repeated {
        /// The key.
        key: String,
    },
}

/// The keys of the text form, in the order [`std::fmt::Display`] writes them.
const KEYS: &str = "projections=N,patch=N[,per-triangle-projections=N,per-triangle-patch=N,skin-projections=N,skin-patch=N]";

/// The text form's keys and the limit each sets.
const NAMES: [&str; 6] = [
    "projections",
    "patch",
    "per-triangle-projections",
    "per-triangle-patch",
    "skin-projections",
    "skin-patch",
];

impl RepairBudget {
    /// The limit the text form's key `NAMES[k]` sets.
    fn slot(&mut self, k: usize) -> &mut usize {
        match k {
            0 => &mut self.most.projections,
            1 => &mut self.most.patch_vertices,
            2 => &mut self.per_triangle.projections,
            3 => &mut self.per_triangle.patch_vertices,
            4 => &mut self.skin.projections,
            _ => &mut self.skin.patch_vertices,
        }
    }
}

impl std::str::FromStr for RepairBudget {
    type Err = RepairBudgetError;

    /// `none` ([`RepairBudget::NONE`]), `live` ([`RepairBudget::LIVE`]) or
    /// comma-separated `key=N` with the keys of [`NAMES`]; a key left out
    /// is not bounded. Spaces around parts are ignored.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        match text.trim() {
            "" => return Err(RepairBudgetError::Empty),
            "none" => return Ok(RepairBudget::NONE),
            "live" => return Ok(RepairBudget::LIVE),
            _ => {}
        }
        let mut b = RepairBudget::NONE;
        let mut seen = [false; NAMES.len()];
        for part in text.split(',').map(str::trim) {
            let Some((key, value)) = part.split_once('=') else {
                let part = part.to_string();
                return Err(RepairBudgetError::NotAPair { part });
            };
            let (key, value) = (key.trim(), value.trim());
            let Some(k) = NAMES.iter().position(|&n| n == key) else {
                let (key, part) = (key.to_string(), part.to_string());
                return Err(RepairBudgetError::UnknownKey { key, part });
            };
            if std::mem::replace(&mut seen[k], true) {
                let key = key.to_string();
                return Err(RepairBudgetError::Repeated { key });
            }
            *b.slot(k) = value.parse().map_err(|_| RepairBudgetError::NotACount {
                value: value.to_string(),
                part: part.to_string(),
            })?;
        }
        Ok(b)
    }
}

impl std::fmt::Display for RepairBudget {
    /// `none` when nothing is bounded, else the bounded keys as `key=N`,
    /// in [`NAMES`]' order (what [`std::str::FromStr`] reads back).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut b = *self;
        let mut first = true;
        for (k, name) in NAMES.iter().enumerate() {
            let v = *b.slot(k);
            if v == usize::MAX {
                continue;
            }
            let sep = if first { "" } else { "," };
            write!(f, "{sep}{name}={v}")?;
            first = false;
        }
        if first {
            write!(f, "none")?;
        }
        Ok(())
    }
}

impl serde::Serialize for RepairBudget {
    /// As its text form ([`std::fmt::Display`]).
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Session 22's measured budget, every key given.
    const SESSION_22: &str =
        "projections=30000,patch=4000,per-triangle-projections=1000,per-triangle-patch=60";

    /// The text form reads back what it writes, for the presets and a
    /// budget with some keys left out; a key left out is not bounded.
    #[test]
    fn the_text_form_round_trips() {
        let half = RepairBudget {
            per_triangle: unflip::WorkLimit::NONE,
            most: unflip::WorkLimit {
                projections: 5,
                patch_vertices: usize::MAX,
            },
            skin: unflip::WorkLimit::NONE,
        };
        let skin: RepairBudget = "projections=9,skin-patch=4".parse().unwrap();
        assert_eq!(
            (
                skin.most.projections,
                skin.skin.patch_vertices,
                skin.skin.projections
            ),
            (9, 4, usize::MAX)
        );
        for b in [
            skin,
            RepairBudget {
                skin: half.most,
                ..RepairBudget::LIVE
            },
        ] {
            let text = b.to_string();
            assert_eq!(text.parse::<RepairBudget>(), Ok(b), "{text}");
        }
        for b in [RepairBudget::NONE, RepairBudget::LIVE, half] {
            let text = b.to_string();
            assert_eq!(text.parse::<RepairBudget>(), Ok(b), "{text}");
        }
        assert_eq!(RepairBudget::NONE.to_string(), "none");
        assert_eq!(half.to_string(), "projections=5");
        assert_eq!("projections=5".parse::<RepairBudget>(), Ok(half));
        let s22: RepairBudget = SESSION_22.parse().unwrap();
        assert_eq!(s22.to_string(), SESSION_22);
        assert_eq!(
            (s22.most.projections, s22.per_triangle.patch_vertices),
            (30_000, 60)
        );
        let spaced = " patch = 7 , projections=5 ".parse::<RepairBudget>();
        assert_eq!(spaced.map(|b| b.most.patch_vertices), Ok(7));
    }

    /// Text that is not a budget is refused with the part it could not
    /// read quoted.
    #[test]
    fn bad_text_is_refused_with_the_part_quoted() {
        let e = |t: &str| t.parse::<RepairBudget>().unwrap_err();
        assert_eq!(e(" "), RepairBudgetError::Empty);
        assert!(matches!(e("fast"), RepairBudgetError::NotAPair { part } if part == "fast"));
        assert!(
            matches!(e("projections=5,rings=3"), RepairBudgetError::UnknownKey { key, .. } if key == "rings")
        );
        let m = e("patch=lots").to_string();
        assert!(
            m.contains("\"lots\"") && m.contains("\"patch=lots\""),
            "{m}"
        );
        assert!(matches!(e("patch=-1"), RepairBudgetError::NotACount { .. }));
        assert!(
            matches!(e("patch=1,patch=2"), RepairBudgetError::Repeated { key } if key == "patch")
        );
    }

    /// A frame's repairs together stay within `most`; each within its
    /// triangles' share; nothing spent leaves the plain limit.
    #[test]
    fn the_frame_limit_shrinks_with_what_was_spent() {
        let b: RepairBudget = SESSION_22.parse().unwrap();
        assert_eq!(b.limit(3).projections, 3_000);
        assert_eq!(b.limit(100).patch_vertices, 4_000);
        let spent = unflip::Work {
            projections: 29_500,
            patch_vertices: 4_000,
            ..Default::default()
        };
        let l = b.limit_after(100, &spent);
        assert_eq!((l.projections, l.patch_vertices), (500, 0));
        assert!(b.frame_bound(100, &l));
        assert!(b.frame_bound(100, &b.limit(100)), "4,000 < 60 × 100");
        assert!(!b.frame_bound(3, &b.limit(3)));
        let none = RepairBudget::NONE;
        assert!(!none.frame_bound(9, &none.limit_after(9, &spent)));
        assert_eq!(
            RepairBudget::NONE.limit_after(9, &spent),
            unflip::WorkLimit::NONE
        );
        // The skin's repair: within its own limit too, and the frame's.
        let skin = RepairBudget {
            skin: unflip::WorkLimit {
                projections: 10_000,
                patch_vertices: usize::MAX,
            },
            ..b
        };
        let l = skin.skin_limit_after(100, &unflip::Work::default());
        assert_eq!((l.projections, l.patch_vertices), (10_000, 4_000));
        let l = skin.skin_limit_after(100, &spent);
        assert_eq!((l.projections, l.patch_vertices), (500, 0));
        assert_eq!(b.skin_limit_after(7, &spent), b.limit_after(7, &spent));
    }
}
