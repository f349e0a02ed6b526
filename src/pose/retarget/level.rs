//! The line the reference's torso is stood upright on (issue 44).
//!
//! The kernel measures the torso's rotations from its reference stood
//! upright (the kernel's `level_torso`): the least
//! rotation taking a line of the reference's trunk onto the vertical.
//! The character's trunk then leans, in every frame, as that line of the
//! clip does; two files of one performance drive it alike only if both
//! rigs put the line at the same place in the body. The kernel's line is
//! the pelvis → chest one, and the pelvis is the root joint: a rig that
//! puts its root elsewhere in the body (the Reallusion CC rig's hips 9 cm
//! higher and 4.5 cm back against the ASF's root, CMU 02_03) turns it,
//! and every torso rotation with it (a generated walk's root moved so
//! turned it 10.5° and 5.2°; session 35).
//!
//! A [`Level`] names the line: the kernel's ([`Level::Chest`], the
//! default), the hips' midpoint → the shoulders' midpoint
//! ([`Level::Midpoints`]: the thighs' and upper arms' heads, which no rig
//! puts at its root), or the least-squares line through the whole trunk
//! ([`Level::Trunk`]). The others are an option ([`LEVEL_ENV`]), off by
//! default. Measured (session 36, `pose::level`; CMU 02_01 / 02_02 /
//! 02_03 as AMC and as CC-rig BVH on one character, % of the height):
//! the midpoints line is the one the two rigs place most alike (per
//! aligned frame 1.3-1.6° apart, the pelvis → chest line 2.8-3.6°), and
//! it takes the posture (each frame's best translation) 0.74 / 0.86 /
//! 0.96 → 0.65 / 0.72 / 1.00 and a generated walk's moved root's to
//! zero; but with the kernel's placement the results as placed move
//! apart (1.81 / 2.06 / 2.12 → 2.13 / 2.44 / 2.35, the head 1.5-2.2 →
//! 2.6-2.9 while the pelvises stay 2.15-2.43; session 25 found the CC
//! result's body about its pelvis ahead of its trailing pelvis, the two
//! offsets cancelling in part), and with the body's placement
//! (`joints,stance`) they are mixed (1.74 / 2.02 / 1.98 → 1.73 / 1.99 /
//! 2.06; `root,stance` 1.53 / 1.64 / 1.98). And the shoulders are not
//! placed alike by every conversion: CMU 01_01's cgspeed BVH drops the
//! thorax's length and hangs them lower on the same rotations, and its
//! result, the AMC's exactly with the kernel's line, is 0.79 % apart with
//! this one. The trunk's line does worse on every pair (posture 0.92 /
//! 1.05 / 1.34): the pelvis and the neck, its ends, weigh most.

use crate::pose::Pose;
use crate::rig::Canonical;
use glam::{DMat3, DVec3};

use Canonical as C;

/// The line of the reference's trunk stood upright.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Level {
    /// The pelvis (root) → chest line: the kernel's rule.
    #[default]
    Chest,
    /// The hips' midpoint → the shoulders' midpoint.
    Midpoints,
    /// The least-squares line (the principal axis) through the pelvis,
    /// the hips' midpoint, the spine, the chest, the neck and the
    /// shoulders' midpoint, each one point of equal weight (a pair of
    /// joints enters by its midpoint: the trunk's width does not pull the
    /// line sideways), pointing from the hips to the shoulders.
    Trunk,
    /// The hips' midpoint → the shoulders' midpoint brought down the
    /// vertical to the chest's height (the shoulders read on the chest's
    /// axis, which stands near the vertical in a reference: the rest's
    /// T- or A-pose, or the clip's mean carriage). A conversion that drops
    /// the thorax's length (CMU 01_01's cgspeed BVH) hangs the shoulders
    /// lower along that axis, which moves the midpoints line and not this
    /// one; its lean is the shoulders' place ahead of or behind the hips,
    /// not the chest joint's (placed ~11° off by the Reallusion CC rig).
    /// Measured (session 37, `pose::stride`): 01_01's AMC against cgspeed
    /// BVH 0.79 % (midpoints) → 0.19 (the kernel's 0.00; the conversion's
    /// clavicles also move the shoulders' midpoint 1.2 mm); the CC pairs'
    /// posture (each frame's best translation) 0.74 / 0.86 / 0.96 → 0.68 /
    /// 0.64 / 1.07, as placed 1.81 / 2.06 / 2.12 → 2.16 / 2.17 / 2.12; the
    /// yardstick's 131_01 head p95 14.1 → 15.1° (its line 15.8),
    /// penetration 1.45 → 1.73 cm. Off by default.
    Shoulders,
}

/// The environment variable that chooses the levelling line (a
/// measurement option, issue 44): `chest` (the default), `midpoints`,
/// `trunk` or `shoulders`. Read once per process; another value warns and
/// is the default.
pub const LEVEL_ENV: &str = "SURFMOTION_LEVEL";

/// The line [`LEVEL_ENV`] chooses (read once per process).
pub(super) fn level_from_env() -> Level {
    static ON: std::sync::OnceLock<Level> = std::sync::OnceLock::new();
    *ON.get_or_init(|| {
        let v = std::env::var(LEVEL_ENV).ok();
        level_rule(v.as_deref()).unwrap_or_else(|why| {
            tracing::warn!("{LEVEL_ENV}: {why}; the pelvis → chest line is levelled");
            Level::default()
        })
    })
}

/// [`LEVEL_ENV`]'s value read; `Err` naming a value that is not a rule.
fn level_rule(value: Option<&str>) -> Result<Level, String> {
    match value.map(str::trim).unwrap_or("") {
        "" | "chest" => Ok(Level::Chest),
        "midpoints" => Ok(Level::Midpoints),
        "trunk" => Ok(Level::Trunk),
        "shoulders" => Ok(Level::Shoulders),
        v => Err(format!(
            "'{v}': expected chest, midpoints, trunk or shoulders"
        )),
    }
}

fn mid(p: &Pose, a: C, b: C) -> DVec3 {
    0.5 * (p[a.index()] + p[b.index()])
}

/// The unit direction of `r`'s levelling line by `level` (zero when it has
/// no length or is not finite).
pub(crate) fn levelling_line(r: &Pose, level: Level) -> DVec3 {
    let hips = mid(r, C::LHip, C::RHip);
    let shoulders = mid(r, C::LShoulder, C::RShoulder);
    let v = match level {
        Level::Chest => r[C::Chest.index()] - r[C::Pelvis.index()],
        Level::Midpoints => shoulders - hips,
        Level::Shoulders => DVec3::new(shoulders.x, r[C::Chest.index()].y, shoulders.z) - hips,
        Level::Trunk => {
            let pts = [
                r[C::Pelvis.index()],
                hips,
                r[C::Spine.index()],
                r[C::Chest.index()],
                r[C::Neck.index()],
                shoulders,
            ];
            principal_axis(&pts, shoulders - hips)
        }
    };
    if v.is_finite() {
        v.normalize_or_zero()
    } else {
        DVec3::ZERO
    }
}

/// The principal axis of `pts` (the direction of the least-squares line
/// through them: the covariance's leading eigenvector, by power
/// iteration from `guess`), signed along `guess`. `guess` itself when the
/// points do not spread.
fn principal_axis(pts: &[DVec3], guess: DVec3) -> DVec3 {
    let n = pts.len() as f64;
    let c = pts.iter().copied().sum::<DVec3>() / n;
    let mut m = DMat3::ZERO;
    for p in pts {
        let d = *p - c;
        m += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
    }
    let mut v = guess.normalize_or_zero();
    if v == DVec3::ZERO {
        return v;
    }
    for _ in 0..64 {
        let w = (m * v).normalize_or_zero();
        if w == DVec3::ZERO {
            return guess;
        }
        v = w;
    }
    if v.dot(guess) < 0.0 { -v } else { v }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    /// A trunk standing along `up` (unit), its hips and shoulders across
    /// it, its root `root_off` off the hips' midpoint.
    fn trunk(up: DVec3, root_off: DVec3) -> Pose {
        let left = up.cross(DVec3::Z).normalize();
        let mut p = [DVec3::ZERO; Canonical::COUNT];
        let at = |h: f64, side: f64| 0.9 * DVec3::Y + h * up + side * left;
        p[C::LHip.index()] = at(0.0, 0.1);
        p[C::RHip.index()] = at(0.0, -0.1);
        p[C::Pelvis.index()] = at(0.0, 0.0) + root_off;
        p[C::Spine.index()] = at(0.15, 0.0);
        p[C::Chest.index()] = at(0.3, 0.0);
        p[C::Neck.index()] = at(0.5, 0.0);
        p[C::LShoulder.index()] = at(0.45, 0.18);
        p[C::RShoulder.index()] = at(0.45, -0.18);
        p
    }

    #[test]
    fn the_rule_reads_each_line_and_names_any_other() {
        assert_eq!(level_rule(None), Ok(Level::Chest));
        assert_eq!(level_rule(Some(" chest ")), Ok(Level::Chest));
        assert_eq!(level_rule(Some("midpoints")), Ok(Level::Midpoints));
        assert_eq!(level_rule(Some("trunk")), Ok(Level::Trunk));
        assert_eq!(level_rule(Some("shoulders")), Ok(Level::Shoulders));
        let e = level_rule(Some("neck")).unwrap_err();
        assert!(e.contains("'neck'"), "{e}");
    }

    #[test]
    fn each_line_follows_the_trunk_and_only_the_chest_line_the_root() {
        let up = DQuat::from_rotation_x(0.2) * DVec3::Y;
        let still = trunk(up, DVec3::ZERO);
        // The root moved up and back: the pelvis → chest line turns, the
        // others do not.
        let moved = trunk(up, DVec3::new(0.0, 0.09, -0.045));
        for level in [Level::Chest, Level::Midpoints, Level::Trunk] {
            let a = levelling_line(&still, level);
            assert!(a.angle_between(up) < 1e-9, "{level:?}: {a}");
        }
        assert!(levelling_line(&moved, Level::Chest).angle_between(up) > 0.1);
        assert!(levelling_line(&moved, Level::Midpoints).angle_between(up) < 1e-9);
        // The shoulders' line: the root's place does not move it, nor
        // the shoulders (and neck) slid down the vertical (a dropped
        // thorax); the midpoints line turns with them.
        let lean = |p: &Pose| levelling_line(p, Level::Shoulders);
        assert_eq!(lean(&moved), lean(&still));
        let mut dropped = still;
        for c in [C::LShoulder, C::RShoulder, C::Neck] {
            dropped[c.index()].y -= 0.117;
        }
        assert!(lean(&dropped).angle_between(lean(&still)) < 1e-12);
        let m = |p: &Pose| levelling_line(p, Level::Midpoints);
        assert!(m(&dropped).angle_between(m(&still)) > 0.01);
        // It leans as the shoulders do ahead of the hips.
        let a = lean(&still);
        assert!(
            a.z > 0.0 && (a.z / a.y - (0.45 * up.z) / (0.3 * up.y)).abs() < 1e-9,
            "{a}"
        );
        // The trunk's line: one point of six moved, so turned less than
        // the chest line (not zero).
        let t = levelling_line(&moved, Level::Trunk).angle_between(up);
        let c = levelling_line(&moved, Level::Chest).angle_between(up);
        assert!(t < 0.5 * c, "{t} against {c}");
        // A trunk with no length has no line.
        let flat = [DVec3::ONE; Canonical::COUNT];
        for level in [
            Level::Chest,
            Level::Midpoints,
            Level::Trunk,
            Level::Shoulders,
        ] {
            assert_eq!(levelling_line(&flat, level), DVec3::ZERO);
        }
    }
}
