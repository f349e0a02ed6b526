//! Parsers of option values: each refuses what the option cannot take
//! with one line saying what it takes.

use std::path::PathBuf;

/// A mesh argument (a file, a folder of frames or `SEQ.pc2:FRAME`): not
/// empty. (An empty one named the current folder: "`: a character
/// database folder`" or "no .obj files in the folder".)
pub fn mesh_spec(s: &str) -> Result<String, String> {
    if s.trim().is_empty() {
        Err("expected a mesh file (.obj .ply .pc2 .mdd .gltf .glb), a folder of .obj frames or SEQ.pc2:FRAME; got nothing".into())
    } else {
        Ok(s.to_string())
    }
}

/// A frame rate on the command line: a finite number in
/// [[`MIN_FPS`](surfmotion::util::budget::MIN_FPS),
/// [`MAX_FPS`](surfmotion::util::budget::MAX_FPS)] (1-1000). (A typo such as
/// `--input-fps 1e-4` or `--fps 1e9` would otherwise ask for billions of
/// frames; issue 18, item 12.)
pub fn frame_rate(s: &str) -> Result<f64, String> {
    use surfmotion::util::budget::{MAX_FPS, MIN_FPS, is_frame_rate};
    let v = number(s)?;
    if is_frame_rate(v) {
        Ok(v)
    } else {
        Err(format!(
            "{s} frames per second: expected a frame rate in [{MIN_FPS}, {MAX_FPS}]"
        ))
    }
}

/// `s` as a number (spaces around it allowed), or "'s' is not a number".
fn number(s: &str) -> Result<f64, String> {
    s.trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))
}

/// `v` when it is at most `max`, else the error `err()`: the upper bound
/// of an option whose lower bound [`positive`], [`non_negative`] or
/// [`finite`] checked.
fn at_most(v: f64, max: f64, err: impl FnOnce() -> String) -> Result<f64, String> {
    if v <= max { Ok(v) } else { Err(err()) }
}

/// A duration or size on the command line: a finite number > 0.
pub fn positive(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{s}: expected a finite number > 0"))
    }
}

/// A fraction on the command line: a finite number in [0, 1].
pub fn fraction(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v.is_finite() && (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{s}: expected a number in [0, 1]"))
    }
}

/// An angle or signed quantity on the command line: any finite number
/// (NaN or infinity would make every cost NaN; issue 18, item 13).
pub fn finite(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{s}: expected a finite number"))
    }
}

/// A weight or distance on the command line: a finite number ≥ 0 (NaN made
/// the trellis panic; issue 18, item 13).
pub fn non_negative(s: &str) -> Result<f64, String> {
    let v = number(s)?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("{s}: expected a finite number ≥ 0"))
    }
}

/// A cost weight of Eq. 7 (`--w-dist`, `--w-time`, `--w-heading`): finite,
/// ≥ 0 and at most 1e6. Larger weights overflow the search's costs to
/// infinity (`--w-time 1e308` reported "no path" for a reachable target).
pub fn weight(s: &str) -> Result<f64, String> {
    at_most(non_negative(s)?, 1e6, || {
        format!("{s}: a weight above 1e6 overflows the path costs")
    })
}

/// `--max-error` of `web`: millimetres in (0, 100]. (It took any number:
/// NaN, negative, or 1e308, whose quantisation step overflowed and was
/// reported as a "max vertex error 0.000 mm", exit 0.)
pub fn max_error_mm(s: &str) -> Result<f64, String> {
    at_most(positive(s)?, 100.0, || {
        format!("{s}: expected millimetres in (0, 100]")
    })
}

/// `--dynamics` of `synth`: a scale in `[0, 2]`. Renders of the demo
/// character's walk at 1 are smooth; at 3 a seam tears at the waist, at 10
/// the torso and arms are jagged.
pub fn dynamics_amount(s: &str) -> Result<f64, String> {
    at_most(non_negative(s)?, 2.0, || {
        format!("{s}: the dynamics scale is at most 2 (from about 3 the springs tear the surface)")
    })
}

/// `--seconds` of `play`: a length in (0,
/// [`MAX_SECONDS`](surfmotion::parametric::script::MAX_SECONDS)], as a
/// script's times (`--seconds 1e12` was refused only by the memory
/// budget, naming the script).
pub fn session_seconds(s: &str) -> Result<f64, String> {
    use surfmotion::parametric::script::MAX_SECONDS;
    at_most(positive(s)?, MAX_SECONDS, || {
        format!("{s}: expected seconds in (0, {MAX_SECONDS}]")
    })
}

/// `--t-skel` of `retarget` and `batch`: metres summed over 19 joints,
/// finite, ≥ 0 and at most 1000 (every frame is admitted long before;
/// `--t-skel 1e308` printed a 309-digit threshold).
pub fn t_skel(s: &str) -> Result<f64, String> {
    at_most(non_negative(s)?, 1e3, || {
        format!("{s}: expected metres in [0, 1000]")
    })
}

/// `--horizon` of `keyframe`: seconds in [0,
/// [`MAX_TARGET_SECONDS`](surfmotion::keyframe::MAX_TARGET_SECONDS)]
/// (`--horizon 1e7` aborted on a 216 GB allocation).
pub fn horizon(s: &str) -> Result<f64, String> {
    use surfmotion::keyframe::MAX_TARGET_SECONDS;
    at_most(non_negative(s)?, MAX_TARGET_SECONDS, || {
        format!("{s}: at most {MAX_TARGET_SECONDS} seconds")
    })
}

/// `--heading` of `keyframe`: degrees in [-360, 360] (`--heading 1e308`
/// was taken and printed back as a 309-digit target).
pub fn heading(s: &str) -> Result<f64, String> {
    let v = finite(s)?;
    at_most(v.abs(), 360.0, || {
        format!("{s}: expected degrees in [-360, 360]")
    })?;
    Ok(v)
}

/// `--distance`/`--time` of `keyframe` (`what` names the option): a
/// number or a comma list. A value above the
/// search's bound is refused here, quoted as typed (`--distance 1e308` was
/// printed back as 309 digits).
pub fn targets(what: &str, s: &str) -> anyhow::Result<Vec<f64>> {
    use surfmotion::keyframe::{MAX_TARGET_METRES, MAX_TARGET_SECONDS};
    let (max, unit) = if what == "distance" {
        (MAX_TARGET_METRES, "m")
    } else {
        (MAX_TARGET_SECONDS, "s")
    };
    s.split(',')
        .map(|x| {
            let v = x.trim().parse::<f64>().map_err(|_| {
                anyhow::anyhow!("--{what} '{s}': expected a number or a comma list")
            })?;
            anyhow::ensure!(
                v.is_nan() || v <= max,
                "--{what} {}: at most {max} {unit} (the search's horizon grows with the target)",
                x.trim()
            );
            Ok(v)
        })
        .collect()
}

/// A picture output on the command line: a name ending in `.png`, or an
/// existing device or pipe (`/dev/stdout`). Any other name had a PNG
/// written into it (`render -o r.txt`, `graph --matrix m.obj`, exit 0).
pub fn png_path(s: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(s);
    let png = p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
    let special = std::fs::metadata(&p).is_ok_and(|m| !m.is_file() && !m.is_dir());
    if png || special {
        Ok(p)
    } else {
        Err(format!(
            "{s}: expected a .png file name (a PNG picture is written)"
        ))
    }
}

/// `--min-confidence` (automatic landmarks), checked after parsing: 0 to 1.
pub fn confidence(v: f64) -> anyhow::Result<()> {
    anyhow::ensure!(
        (0.0..=1.0).contains(&v),
        "--min-confidence {v}: expected 0 to 1"
    );
    Ok(())
}

/// A count on the command line (pixels, frames) in `[lo, hi]`: clap's
/// "0 is not in 16..=8192" instead of a silent clamp (`render --size 0`
/// drew 16 pixels).
pub fn bounded_count(lo: u64, hi: u64) -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::<usize>::new().range(lo..=hi)
}

/// Metres per unit a length unit given as a number may have: a
/// micrometre to a kilometre. (`--input-units 1e300` printed joint
/// positions of 1e300 metres, exit 0.)
pub const UNIT_RANGE: std::ops::RangeInclusive<f64> = 1e-6..=1e3;

/// A length unit on the command line (`flag` names the option): a name
/// or a number of metres per unit in [`UNIT_RANGE`].
pub fn length_unit(flag: &str, u: &str) -> anyhow::Result<surfmotion::mocap::Units> {
    let units = surfmotion::mocap::units::parse_unit(u).ok_or_else(|| {
        anyhow::anyhow!("{flag} '{u}': expected m, cm, mm, dm, inch, cmu or a number")
    })?;
    if !UNIT_RANGE.contains(&units.metres_per_unit) {
        anyhow::bail!(
            "{flag} '{u}': {:e} metres per unit is not a length unit (expected {:e} to {})",
            units.metres_per_unit,
            UNIT_RANGE.start(),
            UNIT_RANGE.end()
        );
    }
    Ok(units)
}
