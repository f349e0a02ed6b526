//! What `inspect` says about an FBX clip beyond the clip itself: the
//! file's version, declared unit, axes, frame rate and every take
//! (animation stack), marking the one read. The unit the clip is read in
//! (the declared one, or the body's when it is missing or contradicts the
//! body) is the report's `units`, with its reason.

use crate::mocap::fbx::fbx_info;
use crate::util::numfmt::Short;
use std::path::Path;

/// The report's `format` for an FBX file: `fbx 7700 binary; units …; axes
/// …; takes: 'Take 001' (0-3.33 s, no keyed curves), 'mixamo.com' (0-19.8
/// s, 53 curves, read)`. `take` is the take asked for (default: the
/// reader's choice). Plain `fbx` if the file cannot be listed.
pub fn describe(path: &Path, take: Option<&str>) -> String {
    let Ok(i) = fbx_info(path) else {
        return "fbx".into();
    };
    let read = match take {
        Some(t) => i.takes.iter().position(|k| k.name == t),
        None => i.default_take,
    };
    let takes: Vec<String> = i
        .takes
        .iter()
        .enumerate()
        .map(|(k, t)| {
            format!(
                "'{}' ({}-{} s, {}{})",
                t.name,
                Short(t.start),
                Short(t.stop),
                if t.curves == 0 {
                    "no keyed curves".to_string()
                } else {
                    format!("{} curves", t.curves)
                },
                if Some(k) == read { ", read" } else { "" }
            )
        })
        .collect();
    format!(
        "fbx {} {}; {}; axes {}; {} fps; {} LimbNodes; takes: {}",
        i.version,
        if i.ascii { "ascii" } else { "binary" },
        if i.unit_declared {
            format!(
                "UnitScaleFactor {} ({} m per unit)",
                Short(i.metres_per_unit * 100.0),
                Short(i.metres_per_unit)
            )
        } else {
            "no UnitScaleFactor".to_string()
        },
        i.axes,
        Short(i.fps),
        i.joints,
        if takes.is_empty() {
            "none".to_string()
        } else {
            takes.join(", ")
        }
    )
}
