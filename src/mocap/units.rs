//! Deciding a clip's length unit and up axis when the file does not say.
//!
//! BVH stores neither. The unit is chosen from the rest skeleton's extent
//! (its largest span, which is the standing height or the arm span of a
//! T-pose; both ≈ 1.7 m for an adult) as the candidate unit that brings it
//! nearest 1.7 m. The up axis is the dominant axis of head − pelvis over a
//! few frames (the rest pose of some rigs lies down: Bandai Namco).

use super::clip::{Clip, Units, UpAxis};
use crate::rig::{Canonical, detect};
use glam::DVec3;

/// CMU's length unit: 1/0.45 inch.
pub const CMU_UNIT_M: f64 = 0.0254 / 0.45;

/// A unit name users may give (`m`, `cm`, `mm`, `dm`, `inch`, `cmu`) or a
/// plain number of metres per file unit.
pub fn parse_unit(s: &str) -> Option<Units> {
    let (m, name) = match s.to_ascii_lowercase().as_str() {
        "m" | "metre" | "metres" | "meter" | "meters" => (1.0, "m"),
        "dm" => (0.1, "dm"),
        "cm" => (0.01, "cm"),
        "mm" => (0.001, "mm"),
        "in" | "inch" | "inches" => (0.0254, "inch"),
        "cmu" => (CMU_UNIT_M, "CMU (1/0.45 inch)"),
        other => {
            let v: f64 = other
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite() && *v > 0.0)?;
            return Some(Units {
                metres_per_unit: v,
                name: format!("{v} m"),
                reason: "given by the user".into(),
            });
        }
    };
    Some(Units {
        metres_per_unit: m,
        name: name.into(),
        reason: "given by the user".into(),
    })
}

/// Largest span of the rest skeleton (joints and end sites), in file units.
pub fn rest_extent(clip: &Clip) -> f64 {
    let (pos, ends) = clip.rest_positions();
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in pos.iter().chain(&ends) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    (hi - lo).max_element().max(0.0)
}

/// Guesses the unit of a BVH clip. `cmu` says the names follow a CMU convention.
pub fn guess_units(clip: &Clip, cmu: bool) -> Units {
    let h = rest_extent(clip);
    let mut cands: Vec<(f64, &str)> = vec![(1.0, "m"), (0.01, "cm"), (0.001, "mm")];
    if cmu {
        cands.push((CMU_UNIT_M, "CMU (1/0.45 inch)"));
    }
    let target: f64 = 1.7;
    let best = cands
        .iter()
        .copied()
        .min_by(|a, b| {
            let da = (h * a.0 / target).ln().abs();
            let db = (h * b.0 / target).ln().abs();
            da.total_cmp(&db)
        })
        .unwrap_or((1.0, "m"));
    Units {
        metres_per_unit: best.0,
        name: best.1.into(),
        reason: format!(
            "rest skeleton spans {h:.3} file units, {:.2} m in {}{}",
            h * best.0,
            best.1,
            if cmu { " (CMU rig names)" } else { "" }
        ),
    }
}

/// Guesses the up axis from head − pelvis averaged over up to 16 frames.
/// Returns the axis and the reason.
pub fn guess_up(clip: &Clip) -> (UpAxis, String) {
    let det = detect(&clip.point_names());
    let (Some(h), Some(p)) = (
        det.map.joints.get(&Canonical::Head),
        det.map.joints.get(&Canonical::Pelvis),
    ) else {
        return (
            UpAxis::Y,
            "assumed Y-up (no head/pelvis joint recognised)".into(),
        );
    };
    let (Some(h), Some(p)) = (clip.joint(h), clip.joint(p)) else {
        return (UpAxis::Y, "assumed Y-up".into());
    };
    let frames = clip.frame_count();
    let step = (frames / 16).max(1);
    let mut d = DVec3::ZERO;
    let mut k = 0;
    while k < frames {
        let w = clip.world_positions(k);
        d += (w[h.idx()] - w[p.idx()]).normalize_or_zero();
        k += step;
    }
    let a = d.abs();
    if a.z > a.y && a.z > a.x && d.z > 0.0 {
        (
            UpAxis::Z,
            format!(
                "head above pelvis along +Z (mean direction {:.2} {:.2} {:.2})",
                d.x, d.y, d.z
            ),
        )
    } else if a.y >= a.x && a.y >= a.z && d.y > 0.0 {
        (UpAxis::Y, "head above pelvis along +Y".into())
    } else {
        (
            UpAxis::Y,
            format!(
                "assumed Y-up; head − pelvis points along ({:.2} {:.2} {:.2})",
                d.x, d.y, d.z
            ),
        )
    }
}
