//! Where the body is put (issue 44): the travel of a point of the body
//! that does not depend on where a rig puts its root.
//!
//! The kernel places the character's root where the clip's root goes, its
//! travel scaled by the ratio of leg lengths (Huang et al. 2015, Sec. 5.2
//! copy the root's translation; the scale is this project's), and stands
//! the feet on the ground ([`place_feet_into`](super::feet::place_feet_into)). Two
//! files of one performance put their roots elsewhere in the body (CMU
//! 02_03's CC-rig BVH conversion: the hips 9 cm higher and 4.5 cm back
//! against the ASF's root) and scale it differently (the conversion's
//! travel 1.146 times the AMC's, its legs 1.164 times), so the two
//! results' pelvises stood 2.15-2.42 % of the height apart while each
//! frame's best translation left 0.74-0.96 % (`pose::data_floor`).
//!
//! A [`Placement`] names the point ([`Anchor`]: the root, the hips'
//! midpoint, the mean of the nineteen canonical joints) whose travel the
//! character's same point follows, and the scale of that travel
//! ([`TravelScale`]: the legs' lengths, or the standing hip height, which
//! reads the motion rather than the rig's bones). The default is the
//! kernel's own (root, legs), bit for bit; the others are an option
//! ([`PLACEMENT_ENV`]), off by default.

use super::reference::leg_length;
use super::stride::stride_scale;
use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DQuat, DVec3};

use Canonical as C;

/// The point of the body whose travel places the character.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Anchor {
    /// The root (the canonical pelvis joint): the kernel's rule.
    #[default]
    Root,
    /// The midpoint of the two canonical hip joints (every rig puts them
    /// at the thighs' heads, wherever its root is).
    Hips,
    /// The mean of the nineteen canonical joints.
    Joints,
}

/// What scales the clip's travel (and the anchor's height) onto the
/// character.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TravelScale {
    /// The character's legs over the reference's (the kernel's rule).
    #[default]
    Legs,
    /// The character's standing hip height over the clip's: the hips'
    /// midpoint over the lowest foot joint, the character's rest against
    /// the clip's 90th percentile over its frames (a conversion that
    /// lengthens the legs but not the motion stands its hips lower than
    /// its legs reach); held within 15 % of the legs' ratio.
    Stance,
    /// The stride's: the ratio under which the character's planted feet
    /// stay where they are (the least-squares ratio of the character's
    /// planted foot's motion against its anchor to the clip's; see
    /// [`stride`](super::stride)); held within 15 % of the legs' ratio.
    Stride,
}

/// Whether the character's feet are put on the clip's footfalls.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Footfalls {
    /// The feet go where the limbs' directions put them (the kernel's
    /// rule).
    #[default]
    Free,
    /// Each planted foot of the clip becomes a target on the character
    /// (its position during the contact, mapped by the travel's scale),
    /// reached by two-bone leg IK, the body shifted where a planted foot
    /// would be out of reach ([`footfall`](super::footfall)).
    Targets,
}

/// How the kernel places the body: [`Anchor`], [`TravelScale`] and
/// [`Footfalls`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Placement {
    /// The point whose travel the character's follows.
    pub anchor: Anchor,
    /// The scale of that travel.
    pub scale: TravelScale,
    /// Whether the feet are put on the clip's footfalls (default: no).
    pub footfalls: Footfalls,
}

/// The environment variable that chooses the placement (a measurement
/// option, issue 44): `root` (the default), `hips` or `joints`, each
/// optionally followed by `,stance` (the travel scaled by the standing
/// hip height, [`TravelScale::Stance`]) or `,stride` (by the stride,
/// [`TravelScale::Stride`]; `,legs` is the default), and optionally by
/// `,feet` (the feet on the clip's footfalls, [`Footfalls::Targets`]):
/// `root,feet`, `root,stance,feet`. Read once per process; another value
/// warns and is the default.
pub const PLACEMENT_ENV: &str = "SURFMOTION_PLACEMENT";

/// The placement [`PLACEMENT_ENV`] chooses (read once per process).
pub(super) fn placement_from_env() -> Placement {
    static ON: std::sync::OnceLock<Placement> = std::sync::OnceLock::new();
    *ON.get_or_init(|| {
        let v = std::env::var(PLACEMENT_ENV).ok();
        placement_rule(v.as_deref()).unwrap_or_else(|why| {
            tracing::warn!("{PLACEMENT_ENV}: {why}; the root is placed");
            Placement::default()
        })
    })
}

/// [`PLACEMENT_ENV`]'s value read; `Err` naming a value that is not a rule.
fn placement_rule(value: Option<&str>) -> Result<Placement, String> {
    let v = value.map(str::trim).unwrap_or("");
    if v.is_empty() {
        return Ok(Placement::default());
    }
    let bad = || format!("'{v}': expected root, hips or joints[,legs|,stance|,stride][,feet]");
    let mut parts = v.split(',').map(str::trim);
    let anchor = match parts.next() {
        Some("root") => Anchor::Root,
        Some("hips") => Anchor::Hips,
        Some("joints") => Anchor::Joints,
        _ => return Err(bad()),
    };
    let mut p = Placement {
        anchor,
        ..Placement::default()
    };
    let (mut scaled, mut feet) = (false, false);
    for part in parts {
        match part {
            "legs" | "stance" | "stride" if !scaled && !feet => {
                scaled = true;
                p.scale = match part {
                    "legs" => TravelScale::Legs,
                    "stance" => TravelScale::Stance,
                    _ => TravelScale::Stride,
                };
            }
            "feet" if !feet => {
                feet = true;
                p.footfalls = Footfalls::Targets;
            }
            _ => return Err(bad()),
        }
    }
    Ok(p)
}

/// The anchor's point of the pose `p`.
pub(crate) fn anchor_of(p: &Pose, a: Anchor) -> DVec3 {
    match a {
        Anchor::Root => p[C::Pelvis.index()],
        Anchor::Hips => 0.5 * (p[C::LHip.index()] + p[C::RHip.index()]),
        Anchor::Joints => p.iter().copied().sum::<DVec3>() / Canonical::COUNT as f64,
    }
}

/// The hips' midpoint's height over the lowest foot joint (ankle or toe)
/// of `p`.
pub(crate) fn hip_height(p: &Pose) -> f64 {
    let low = [C::LAnkle, C::LToe, C::RAnkle, C::RToe]
        .iter()
        .map(|c| p[c.index()].y)
        .fold(f64::INFINITY, f64::min);
    anchor_of(p, Anchor::Hips).y - low
}

/// The clip's standing hip height: the 90th percentile over its frames of
/// [`hip_height`] (`None` with no finite frame).
pub(crate) fn standing_hip_height(mocap: &[Pose]) -> Option<f64> {
    let mut h: Vec<f64> = mocap
        .iter()
        .map(hip_height)
        .filter(|x| x.is_finite())
        .collect();
    h.sort_by(f64::total_cmp);
    let i = (0.9 * (h.len().max(1) - 1) as f64).round() as usize;
    h.get(i).copied()
}

/// The scale of the travel: `s` (the legs' ratio) for [`TravelScale::Legs`];
/// the standing hip heights' ratio (character's rest over the clip's),
/// held within 15 % of `s`, for [`TravelScale::Stance`] (`s` where either
/// height is not positive); for [`TravelScale::Stride`] the stride's
/// ratio of `out` (the character's poses before placement) with anchor
/// `a` ([`stride_scale`]).
pub(crate) fn travel_scale(
    character: &Pose,
    mocap: &[Pose],
    s: f64,
    scale: TravelScale,
    (out, a): (&[(Pose, [DQuat; Canonical::COUNT])], Anchor),
) -> f64 {
    match scale {
        TravelScale::Legs => s,
        TravelScale::Stride => {
            let at = |p: &Pose| anchor_of(p, a);
            stride_scale(mocap, out, &at, s, leg_length(character) / s)
        }
        TravelScale::Stance => {
            let c = hip_height(character);
            match standing_hip_height(mocap) {
                Some(m) if m > 0.0 && c > 0.0 && (c / m).is_finite() => {
                    (c / m).clamp(0.85 * s, 1.15 * s)
                }
                _ => s,
            }
        }
    }
}

/// Moves every pose of `out` (the character's, before its feet are put on
/// the ground) so that its anchor follows the clip's: horizontally from
/// the character's rest anchor at the first frame, the clip's travel since
/// its first frame scaled; vertically the clip's anchor's height over its
/// floor, scaled, over the character's floor (`floors`: the clip's, the
/// character's). With the default placement nothing moves (the kernel
/// placed the root so already). Returns the travel's scale (`s` with
/// the default anchor and scale).
pub(super) fn place_anchor(
    character: &Pose,
    mocap: &[Pose],
    placement: Placement,
    s: f64,
    floors: (f64, f64),
    out: &mut [(Pose, [DQuat; Canonical::COUNT])],
) -> f64 {
    let kernel = Placement {
        footfalls: Footfalls::Free,
        ..placement
    };
    if kernel == Placement::default() || mocap.is_empty() {
        return s;
    }
    let (clip_floor, char_floor) = floors;
    let a = placement.anchor;
    let k = travel_scale(character, mocap, s, placement.scale, (out, a));
    let rest = anchor_of(character, a);
    let first = anchor_of(&mocap[0], a);
    for (m, (t, _)) in mocap.iter().zip(out.iter_mut()) {
        let c = anchor_of(m, a);
        let want = DVec3::new(
            rest.x + (c.x - first.x) * k,
            char_floor + (c.y - clip_floor) * k,
            rest.z + (c.z - first.z) * k,
        );
        let d = want - anchor_of(t, a);
        if !d.is_finite() {
            continue;
        }
        for p in t.iter_mut() {
            *p += d;
        }
    }
    k
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rule_reads_each_anchor_and_scale_and_names_any_other() {
        let p = |anchor, scale| -> Result<Placement, String> {
            Ok(Placement {
                anchor,
                scale,
                ..Placement::default()
            })
        };
        assert_eq!(placement_rule(None), p(Anchor::Root, TravelScale::Legs));
        assert_eq!(
            placement_rule(Some(" ")),
            p(Anchor::Root, TravelScale::Legs)
        );
        assert_eq!(
            placement_rule(Some("hips")),
            p(Anchor::Hips, TravelScale::Legs)
        );
        assert_eq!(
            placement_rule(Some("joints, stance")),
            p(Anchor::Joints, TravelScale::Stance)
        );
        assert_eq!(
            placement_rule(Some("root,stance")),
            p(Anchor::Root, TravelScale::Stance)
        );
        let e = placement_rule(Some("feet")).unwrap_err();
        assert!(e.contains("'feet'"), "{e}");
        assert_eq!(
            placement_rule(Some("root,stride")),
            p(Anchor::Root, TravelScale::Stride)
        );
        assert!(placement_rule(Some("hips,knees")).is_err());
        let feet = |anchor, scale| {
            Ok(Placement {
                anchor,
                scale,
                footfalls: Footfalls::Targets,
            })
        };
        assert_eq!(
            placement_rule(Some("root,feet")),
            feet(Anchor::Root, TravelScale::Legs)
        );
        assert_eq!(
            placement_rule(Some("root, stance ,feet")),
            feet(Anchor::Root, TravelScale::Stance)
        );
        for wrong in [
            "root,feet,stance",
            "root,feet,feet",
            "root,legs,stride",
            "root,",
        ] {
            assert!(placement_rule(Some(wrong)).is_err(), "{wrong}");
        }
    }

    #[test]
    fn the_stance_scale_reads_the_hips_over_the_feet_and_stays_near_the_legs() {
        let mut p = [DVec3::ZERO; Canonical::COUNT];
        p[C::LHip.index()] = DVec3::new(0.1, 0.9, 0.0);
        p[C::RHip.index()] = DVec3::new(-0.1, 0.9, 0.0);
        for c in [C::LAnkle, C::RAnkle] {
            p[c.index()].y = 0.08;
        }
        for c in [C::LToe, C::RToe] {
            p[c.index()].y = 0.02;
        }
        assert!((hip_height(&p) - 0.88).abs() < 1e-12);
        // A clip whose hips stand at 0.9 of the character's: 1.11, within
        // 15 % of a legs' ratio of 1.
        let low: Vec<Pose> = (0..10)
            .map(|i| p.map(|x| DVec3::new(x.x, x.y * (0.9 - 0.01 * (i % 2) as f64), x.z)))
            .collect();
        let k = travel_scale(&p, &low, 1.0, TravelScale::Stance, (&[], Anchor::Root));
        assert!((k - 1.0 / 0.9).abs() < 1e-9, "{k}");
        assert_eq!(
            travel_scale(&p, &low, 1.0, TravelScale::Legs, (&[], Anchor::Root)),
            1.0
        );
        // Held within 15 %.
        let crouched: Vec<Pose> = low.iter().map(|q| q.map(|x| x * 0.5)).collect();
        assert!(
            (travel_scale(&p, &crouched, 1.0, TravelScale::Stance, (&[], Anchor::Root)) - 1.15)
                .abs()
                < 1e-12
        );
        assert_eq!(
            travel_scale(&p, &[], 1.0, TravelScale::Stance, (&[], Anchor::Root)),
            1.0
        );
    }
}
