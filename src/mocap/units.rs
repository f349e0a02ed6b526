//! Deciding a clip's length unit and up axis when the file does not say.
//!
//! BVH stores neither. The unit is chosen from the rest skeleton's extent
//! (its largest span, which is the standing height or the arm span of a
//! T-pose; both ≈ 1.7 m for an adult) as the candidate unit that brings it
//! nearest 1.7 m. The up axis is the dominant axis of head − pelvis over a
//! few frames (the rest pose of some rigs lies down: Bandai Namco).

use super::clip::JointId;
use super::clip::{Clip, Units, UpAxis};
use glam::DVec3;

/// A point of a file in Y-up coordinates (`z_up` files are turned so that
/// +Z becomes +Y, right-handed: `(x, y, z) → (x, z, −y)`). The axis
/// conversion beside the units: scale by `metres_per_unit` after it.
pub fn y_up(p: [f64; 3], z_up: bool) -> DVec3 {
    if z_up {
        DVec3::new(p[0], p[2], -p[1])
    } else {
        DVec3::from_array(p)
    }
}

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

/// Dominant axis of a direction: `Some(Y)` or `Some(Z)` when that axis is the
/// largest component and positive, `None` otherwise.
fn dominant_up(d: DVec3) -> Option<UpAxis> {
    let a = d.abs();
    if a.z > a.y && a.z > a.x && d.z > 0.0 {
        Some(UpAxis::Z)
    } else if a.y >= a.x && a.y >= a.z && d.y > 0.0 {
        Some(UpAxis::Y)
    } else {
        None
    }
}

/// Guesses the up axis from head − pelvis averaged over up to 16 frames of
/// the motion (world positions, so a root rotation that stands a lying rest
/// pose up is taken into account). `head` (or the neck when the head is
/// derived) and `pelvis` are the clip's joints, as the rig map names them
/// ([`crate::rig::guess_up`] finds them). Returns the axis and the reason.
pub fn up_from_joints(
    clip: &Clip,
    head: Option<JointId>,
    pelvis: Option<JointId>,
) -> (UpAxis, String) {
    let (Some(h), Some(p)) = (head, pelvis) else {
        return (
            UpAxis::Y,
            "assumed Y-up (no head/pelvis joint recognised)".into(),
        );
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
    let (rest, _) = clip.rest_positions();
    let rest_up = dominant_up(rest[h.idx()] - rest[p.idx()]);
    match dominant_up(d) {
        Some(up) => {
            let axis = if up == UpAxis::Y { "+Y" } else { "+Z" };
            let note = match rest_up {
                Some(r) if r == up => String::new(),
                Some(r) => format!("; the rest pose is {r:?}-up and the root rotation turns it"),
                None => "; the rest pose is not upright and the root rotation stands it up".into(),
            };
            (
                up,
                format!("head above pelvis along {axis} in the motion{note}"),
            )
        }
        None => (
            UpAxis::Y,
            format!(
                "assumed Y-up; head − pelvis points along ({:.2} {:.2} {:.2})",
                d.x, d.y, d.z
            ),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mocap::bvh::{BvhOptions, parse_bvh};
    use std::path::Path;

    /// A Z-up, centimetre skeleton (as 3ds Max or iClone write them).
    const ZUP: &str = "HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 95\nCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\nJOINT Spine\n{\nOFFSET 0 0 20\nCHANNELS 3 Zrotation Yrotation Xrotation\nJOINT Head\n{\nOFFSET 0 0 50\nCHANNELS 3 Zrotation Yrotation Xrotation\nEnd Site\n{\nOFFSET 0 0 15\n}\n}\n}\nJOINT LeftUpLeg\n{\nOFFSET 10 0 0\nCHANNELS 3 Zrotation Yrotation Xrotation\nJOINT LeftLeg\n{\nOFFSET 0 0 -45\nCHANNELS 3 Zrotation Yrotation Xrotation\nEnd Site\n{\nOFFSET 0 0 -45\n}\n}\n}\n}\nMOTION\nFrames: 1\nFrame Time: 0.04\n0 0 95 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n";

    #[test]
    fn z_up_centimetres_are_detected_and_normalised() {
        let mut c = parse_bvh(ZUP, Path::new("z.bvh"), &BvhOptions::default()).unwrap();
        c.units = guess_units(&c, false);
        assert_eq!(c.units.name, "cm");
        let (up, why) = crate::rig::guess_up(&c, None);
        assert_eq!(up, UpAxis::Z, "{why}");
        c.up = up;
        c.to_metres_y_up();
        let p = c.world_positions(0);
        let head = c.joint("Head").unwrap().idx();
        // Head at 95 + 20 + 50 = 165 cm above the floor, now along +Y in metres.
        assert!(
            (p[head] - DVec3::new(0.0, 1.65, 0.0)).length() < 1e-12,
            "{:?}",
            p[head]
        );
        // Rest pose is upright in the new frame too.
        let (rest, _) = c.rest_positions();
        assert!(rest[head].y > rest[0].y);
    }

    #[test]
    fn parse_unit_names_and_numbers() {
        assert_eq!(parse_unit("cm").unwrap().metres_per_unit, 0.01);
        assert!((parse_unit("cmu").unwrap().metres_per_unit - 0.0254 / 0.45).abs() < 1e-15);
        assert_eq!(parse_unit("0.3048").unwrap().metres_per_unit, 0.3048);
        assert!(parse_unit("-1").is_none() && parse_unit("furlong").is_none());
    }
}
