//! The environment variable that overrides, for measurement, how the
//! part solve holds its regions' constraints ([`HOLD_ENV`]), as
//! [`super::cloth::CLOTH_ENV`] does the cloth stitch's options.

use super::dqs::ConstraintSkin;
use super::options::DeformOptions;
use super::step_zone::StepZone;

/// `SURFMOTION_HOLD`, e.g. `skin=dq` ([`with_overrides`]).
pub(crate) const HOLD_ENV: &str = "SURFMOTION_HOLD";

/// `opts` with [`HOLD_ENV`]'s overrides (a warning, and none taken, when
/// they cannot be read).
pub(crate) fn with_env(opts: &DeformOptions) -> DeformOptions {
    super::options::with_env_overrides(opts, HOLD_ENV, "hold", with_overrides)
}

/// `opts` with the comma-separated `name=value` pairs of `text`: `skin`
/// (`linear`, `dq` or `rigid`, [`DeformOptions::constraint_skin`]), `joints`
/// ([`DeformOptions::hold_joints`]), `by_weight`
/// ([`DeformOptions::hold_by_weight`]), `spread`
/// ([`DeformOptions::hold_spread`]) and `seams_by_weight`
/// ([`DeformOptions::seam_by_weight`]): `on`/`off`; `steps`
/// ([`DeformOptions::local_steps`], a count); `zone` (`everywhere`,
/// `knees` or `limbs`, [`DeformOptions::step_zone`]), `reach`
/// ([`DeformOptions::step_reach`], a number) and `bend`
/// ([`DeformOptions::bend_examples`], a number, 0 off). An error names the
/// pair it could not read and every name accepted.
pub fn with_overrides(opts: &DeformOptions, text: &str) -> Result<DeformOptions, String> {
    const NAMES: &str = "skin=linear|dq|rigid, joints=on|off, by_weight=on|off, spread=on|off, seams_by_weight=on|off, steps=N, zone=everywhere|knees|limbs, reach=F, bend=F";
    let mut o = *opts;
    for p in super::overrides::pairs(text, NAMES) {
        let p = p?;
        match p.name {
            "skin" => {
                o.constraint_skin = match p.value {
                    "linear" | "lbs" => ConstraintSkin::Linear,
                    "dq" | "dqs" => ConstraintSkin::DualQuaternion,
                    "rigid" => ConstraintSkin::Rigid,
                    _ => return Err(p.bad("the value is not linear, dq or rigid")),
                }
            }
            "joints" => o.hold_joints = p.switch()?,
            "by_weight" => o.hold_by_weight = p.switch()?,
            "spread" => o.hold_spread = p.switch()?,
            "seams_by_weight" => o.seam_by_weight = p.switch()?,
            "steps" => o.local_steps = p.count()?,
            "zone" => {
                o.step_zone = match p.value {
                    "everywhere" | "all" => StepZone::Everywhere,
                    "knees" => StepZone::Knees,
                    "limbs" => StepZone::Limbs,
                    _ => return Err(p.bad("the value is not everywhere, knees or limbs")),
                }
            }
            "reach" => o.step_reach = p.number()?,
            "bend" => o.bend_examples = p.number()?,
            _ => return p.unknown(),
        }
    }
    Ok(o)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every name sets its option and nothing else; a bad pair is refused
    /// with the pair quoted and the names listed.
    #[test]
    fn hold_overrides_set_what_they_name() {
        let d = DeformOptions::default();
        assert_eq!(with_overrides(&d, "").unwrap(), d);
        let o = with_overrides(
            &d,
            "skin=dq, joints=off,by_weight=on,spread=1,seams_by_weight=true,steps=2,zone=knees,reach=0.3,bend=0.5",
        )
        .unwrap();
        assert_eq!(o.constraint_skin, ConstraintSkin::DualQuaternion);
        assert!(!o.hold_joints && o.hold_by_weight && o.hold_spread && o.seam_by_weight);
        assert_eq!(o.local_steps, 2);
        assert_eq!(o.step_zone, StepZone::Knees);
        assert_eq!(o.step_reach, 0.3);
        assert_eq!(o.bend_examples, 0.5);
        let back = DeformOptions {
            constraint_skin: d.constraint_skin,
            hold_joints: d.hold_joints,
            hold_by_weight: d.hold_by_weight,
            hold_spread: d.hold_spread,
            seam_by_weight: d.seam_by_weight,
            local_steps: d.local_steps,
            step_zone: d.step_zone,
            step_reach: d.step_reach,
            bend_examples: d.bend_examples,
            ..o
        };
        assert_eq!(back, d, "an override set another option");
        for bad in [
            "skin",
            "skin=quat",
            "joints=maybe",
            "speed=2",
            "steps=-1",
            "zone=hips",
            "reach=-1",
            "reach=nan",
            "bend=-1",
            "bend=x",
        ] {
            let e = with_overrides(&d, bad).unwrap_err();
            assert!(
                e.contains(&format!("'{bad}'")) && e.contains("skin=linear|dq|rigid"),
                "{bad}: {e}"
            );
        }
    }
}
