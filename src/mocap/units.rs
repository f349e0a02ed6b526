//! Deciding a clip's length unit and up axis when the file does not say.
//!
//! BVH stores neither. For a humanoid the unit is chosen from the body's
//! stature estimated from its limb bones ([`units_from_stature`]: thigh +
//! shin and upper arm + forearm, bone lengths that no pose changes, so a
//! crouching, lying or folded rest skeleton, or a zero rest whose frames
//! carry the offsets, gives the same answer), as the unit among those real
//! suites write (mm, cm, inch, dm, ft, m; CMU's 1/0.45 inch for CMU rigs)
//! that makes it a plausible human stature (MMD's 8 cm unit instead of dm
//! for a rig with MMD's bone names; scaled to an adult's stature when no
//! unit gives a human one). Without a humanoid the rest
//! skeleton's extent decides ([`guess_units`]). The up axis is the dominant
//! axis of head − pelvis over a few frames (the rest pose of some rigs lies
//! down: Bandai Namco).

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
pub(crate) const CMU_UNIT_M: f64 = 0.0254 / 0.45;

/// A unit name users may give (`m`, `cm`, `mm`, `dm`, `inch`, `ft`, `cmu`,
/// `mmd`) or a
/// plain number of metres per file unit.
pub fn parse_unit(s: &str) -> Option<Units> {
    let (m, name) = match s.to_ascii_lowercase().as_str() {
        "m" | "metre" | "metres" | "meter" | "meters" => (1.0, "m"),
        "dm" => (0.1, "dm"),
        "cm" => (0.01, "cm"),
        "mm" => (0.001, "mm"),
        "in" | "inch" | "inches" => (0.0254, "inch"),
        "ft" | "foot" | "feet" => (0.3048, "ft"),
        "cmu" => (CMU_UNIT_M, "CMU (1/0.45 inch)"),
        "mmd" => (MMD_UNIT_M, "MMD (8 cm)"),
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
pub(crate) fn rest_extent(clip: &Clip) -> f64 {
    let (pos, ends) = clip.rest_positions();
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in pos.iter().chain(&ends) {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    (hi - lo).max_element().max(0.0)
}

/// Guesses the unit of a BVH clip from its rest skeleton's extent (the
/// fallback when no humanoid's limbs are found: [`units_from_stature`] is
/// the rule for humanoids). `cmu` says the names follow a CMU convention.
pub(crate) fn guess_units(clip: &Clip, cmu: bool) -> Units {
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

/// The units BVH files from real suites are written in, metres per unit:
/// millimetres (some optical systems), centimetres (MotionBuilder, Maya,
/// Xsens, Bandai, LAFAN1), inches (Biovision, Poser/Daz, Second Life),
/// decimetres, feet and metres (Blender, SMPL exporters).
pub const BVH_UNITS: [(f64, &str); 6] = [
    (0.001, "mm"),
    (0.01, "cm"),
    (0.0254, "inch"),
    (0.1, "dm"),
    (0.3048, "ft"),
    (1.0, "m"),
];

/// The stature (m) the unit choice centres on, in log scale: the unit that
/// brings the estimate nearest it wins. 1.3 m puts the boundary between
/// centimetres and inches (a factor 2.54) at 0.82 m read as centimetres,
/// 2.07 m read as inches: children from about 0.85 m (3 years) in
/// centimetres and adults up to about 2.0 m in inches are read right.
/// Between metres and feet the boundary is 0.72 m read as metres.
pub(crate) const STATURE_CENTRE_M: f64 = 1.3;

/// Statures (m) for which a CMU-named rig keeps CMU's unit: the CMU
/// database's subjects are adults (1.50 and 1.60 m by [`stature_from_limbs`]
/// on subjects 131 and 01). Narrow on purpose: Xsens MVN carries every CMU
/// 3dsMax name, and an Xsens body of 1.49 m written in decimetres reads
/// 0.84 m in CMU units.
pub(crate) const CMU_STATURE_M: (f64, f64) = (1.2, 2.2);

/// The fractions of the stature `H` the limb bones span (Drillis & Contini
/// 1966, joint centre to joint centre): thigh 0.245 H + shin 0.246 H, and
/// upper arm 0.186 H + forearm 0.146 H.
pub(crate) const LEG_OF_STATURE: f64 = 0.491;
/// See [`LEG_OF_STATURE`].
pub(crate) const ARM_OF_STATURE: f64 = 0.332;

/// A humanoid's stature from its limb bones, in file units: (thigh + shin,
/// mean of both legs) and (upper arm + forearm, mean of both arms) summed
/// over [`LEG_OF_STATURE`] + [`ARM_OF_STATURE`]. `None` unless both are
/// positive and finite.
pub(crate) fn stature_from_limbs(leg: f64, arm: f64) -> Option<f64> {
    let h = (leg + arm) / (LEG_OF_STATURE + ARM_OF_STATURE);
    (leg > 0.0 && arm > 0.0 && h.is_finite()).then_some(h)
}

/// MikuMikuDance's length unit, 8 cm per unit (a PMX figure 20 units tall
/// is 1.6 m). Not in [`BVH_UNITS`]: a body alone cannot tell it from
/// decimetres (20.5 units is 1.64 m in MMD units, 2.05 m in dm, both
/// human statures), so it replaces dm among the candidates only when the
/// rig carries MMD's standard trunk bones ([`crate::rig::names::mmd_rig`]:
/// MMD exports are never written in dm, MakeHuman's dm rigs carry no MMD
/// name).
pub(crate) const MMD_UNIT_M: f64 = 0.08;

/// Statures (m) of human bodies, toddlers to the tallest adults: a unit is
/// chosen only if it gives one. When none of the candidate units does (a
/// game rig in an arbitrary unit), the clip is scaled to
/// [`NOMINAL_STATURE_M`] instead, and the reason says so.
pub(crate) const HUMAN_STATURE_M: (f64, f64) = (0.75, 2.2);

/// The stature (m) a humanoid whose unit no candidate explains is scaled
/// to: an adult's (the mean of men and women, about 1.70 m).
pub(crate) const NOMINAL_STATURE_M: f64 = 1.7;

/// Which family of exporters a rig's names point to, for the unit
/// candidates of [`units_from_stature`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnitFamily {
    /// CMU names: CMU's 1/0.45 inch for an adult's stature.
    Cmu,
    /// MikuMikuDance's standard bones: [`MMD_UNIT_M`] instead of dm.
    Mmd,
    /// Any other rig: [`BVH_UNITS`].
    Other,
}

/// The unit of a humanoid clip whose stature is `h` file units (`basis`
/// says what it was measured from), decided by the body: among the
/// candidate units (those of [`BVH_UNITS`]; for an MMD rig, MMD's 8 cm
/// instead of dm) the ones that give a human stature ([`HUMAN_STATURE_M`]),
/// and of those the one that brings the stature nearest
/// [`STATURE_CENTRE_M`] in log scale. A CMU rig keeps CMU's unit when
/// that gives an adult's stature ([`CMU_STATURE_M`]). When no candidate
/// gives a human stature, the clip is scaled to [`NOMINAL_STATURE_M`]. The
/// reason names the stature, what the reader assumed and why, the
/// runner-up and what `--input-units` does.
pub fn units_from_stature(h: f64, basis: &str, family: UnitFamily) -> Units {
    let off = |u: f64| (h * u / STATURE_CENTRE_M).ln().abs();
    let mut ranked: Vec<(f64, &str)> = BVH_UNITS.to_vec();
    if family == UnitFamily::Mmd {
        ranked.retain(|u| u.1 != "dm");
        ranked.push((MMD_UNIT_M, "MMD (8 cm)"));
    }
    ranked.sort_by(|a, b| off(a.0).total_cmp(&off(b.0)));
    let human = |u: f64| (HUMAN_STATURE_M.0..=HUMAN_STATURE_M.1).contains(&(h * u));
    let names: Vec<&str> = ranked.iter().map(|u| u.1).collect();
    let (lo, hi) = CMU_STATURE_M;
    let cmu_h = h * CMU_UNIT_M;
    let mmd = if family == UnitFamily::Mmd {
        "; MMD bone names: MMD's 8 cm unit replaces dm"
    } else {
        ""
    };
    let (best, why) = if family == UnitFamily::Cmu && (lo..=hi).contains(&cmu_h) {
        (
            (CMU_UNIT_M, "CMU (1/0.45 inch)".to_string()),
            "CMU rig names and an adult's stature".to_string(),
        )
    } else if let Some(u) = ranked.iter().find(|u| human(u.0)) {
        (
            (u.0, u.1.to_string()),
            format!(
                "of {}, the unit giving a human stature ({}-{} m) nearest a {STATURE_CENTRE_M} m centre{mmd}",
                names.join(", "),
                HUMAN_STATURE_M.0,
                HUMAN_STATURE_M.1
            ),
        )
    } else {
        let k = NOMINAL_STATURE_M / h.max(f64::MIN_POSITIVE);
        (
            (k, format!("{k:.4} m")),
            format!(
                "none of {} gives a human stature ({}-{} m): scaled to a {NOMINAL_STATURE_M} m adult{mmd}",
                names.join(", "),
                HUMAN_STATURE_M.0,
                HUMAN_STATURE_M.1
            ),
        )
    };
    let runner = ranked
        .iter()
        .find(|u| u.1 != best.1)
        .map(|u| format!("; in {} it would be {:.2} m", u.1, h * u.0))
        .unwrap_or_default();
    Units {
        metres_per_unit: best.0,
        name: best.1.clone(),
        reason: format!(
            "stature {:.2} m in {} ({h:.3} file units from {basis}; {why}){runner}; `LoadOptions::units` overrides",
            h * best.0,
            best.1
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
pub(crate) fn up_from_joints(
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

/// The up axis of a clip with no humanoid to read it from (a T-rex, a
/// quadruped, a legs-only rig), from what a rest skeleton reliably shows:
/// its feet on the ground. An axis (+Y or +Z) is supported when at least
/// two end points (End Sites and leaf joints) share the lowest level along
/// it (within 2% of the rest extent) and the root stands at least 10% of
/// the extent above that level. One supported axis is the answer; of two,
/// the one with more end points on the ground, else the one along which
/// the root stands higher (by 1.5×) above them; otherwise the rest pose
/// does not say, and BVH's own convention
/// (Y-up) is assumed and the reason says the axis is unknown. Head − pelvis
/// is not used: a horizontal body's head lies ahead of its pelvis.
pub(crate) fn up_from_ground(clip: &Clip) -> (UpAxis, String) {
    let (pos, mut ends) = clip.rest_positions();
    let mut parent_of = vec![false; pos.len()];
    for j in &clip.joints {
        if let Some(p) = j.parent {
            parent_of[p.idx()] = true;
        }
    }
    for (j, jt) in clip.joints.iter().enumerate() {
        if !parent_of[j] && jt.tail.is_none() {
            ends.push(pos[j]);
        }
    }
    let extent = rest_extent(clip);
    let root = pos.first().copied().unwrap_or(DVec3::ZERO);
    let on_ground = |axis: DVec3| -> Option<(usize, f64)> {
        let lo = ends
            .iter()
            .map(|e| e.dot(axis))
            .fold(f64::INFINITY, f64::min);
        let feet = ends
            .iter()
            .filter(|e| e.dot(axis) <= lo + 0.02 * extent)
            .count();
        let above = root.dot(axis) - lo;
        (extent > 0.0 && feet >= 2 && above >= 0.1 * extent).then_some((feet, above / extent))
    };
    let say = |axis: &str, (n, h): (usize, f64)| {
        format!(
            "no humanoid; {n} end points share the lowest level along {axis} and the root stands {:.0}% of the rest extent above them (as feet on the ground)",
            100.0 * h
        )
    };
    let unknown = |what: &str| {
        (
            UpAxis::Y,
            format!(
                "unknown: no humanoid, and the rest pose shows feet on the ground along {what}; assumed Y-up (BVH's convention)"
            ),
        )
    };
    match (on_ground(DVec3::Y), on_ground(DVec3::Z)) {
        (Some(y), None) => (UpAxis::Y, say("+Y", y)),
        (None, Some(z)) => (UpAxis::Z, say("+Z", z)),
        // Both: more feet on the ground, else the root standing clearly
        // higher above them (a body is taller than its toes reach forward).
        (Some(y), Some(z)) if y.0 > z.0 || (y.0 == z.0 && y.1 > 1.5 * z.1) => (
            UpAxis::Y,
            say("+Y", y) + &format!(" (along +Z only {} and {:.0}%)", z.0, 100.0 * z.1),
        ),
        (Some(y), Some(z)) if z.0 > y.0 || (y.0 == z.0 && z.1 > 1.5 * y.1) => (
            UpAxis::Z,
            say("+Z", z) + &format!(" (along +Y only {} and {:.0}%)", y.0, 100.0 * y.1),
        ),
        (Some(_), Some(_)) => unknown("+Y and +Z alike"),
        (None, None) => unknown("neither +Y nor +Z"),
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
