//! Key-frames as written (`SEQUENCE:FRAME`, a clip frame or a pose file)
//! resolved to database frames.

use super::KeyframeJobError;
use crate::db::Character;
use crate::keyframe::parse_key;
use crate::keyframe::pose::{self, Resolved};
use crate::rig::LoadOptions;

/// Key-frames resolved to database frames.
#[derive(Debug, Clone, PartialEq)]
pub struct Keys {
    /// Frames, in order (start, the key-frames in between, end).
    pub ids: Vec<crate::graph::FlatFrame>,
    /// The key-frames given as poses, each with the database frame it
    /// resolved to (Eq. 28's skeleton measure), in order.
    pub resolved: Vec<Resolved>,
}

/// Resolves `keys` (start, in between, end) on `ch`: `SEQUENCE:FRAME`
/// ([`parse_key`]), or a skeleton pose (`CLIP.bvh:F`, `CLIP.amc:F` read with
/// `load` at the database's rate, or `POSE.json`), resolved to the nearest
/// database frame ([`pose::nearest_frame`]). A pose whose joints span more
/// than 100 m, or less than 1 cm, is refused.
pub fn resolve_keys(
    ch: &Character,
    keys: &[impl AsRef<str>],
    load: &LoadOptions,
) -> Result<Keys, KeyframeJobError> {
    let mut out = Keys {
        ids: Vec::with_capacity(keys.len()),
        resolved: Vec::new(),
    };
    for k in keys {
        let k = k.as_ref();
        if !pose::is_pose_key(k) {
            out.ids.push(parse_key(ch, k)?);
            continue;
        }
        let p = pose::read_pose(ch, k, load)?;
        // A pose of joints 1e308 m away resolved to walk:0 at "NaN m",
        // and 19 joints at one point to the frame least unlike a point.
        let span = p
            .iter()
            .flat_map(|a| p.iter().map(move |b| a.distance(*b)))
            .fold(0.0, f64::max);
        let bad = |msg: String| KeyframeJobError::BadPose { key: k.into(), msg };
        if !(span.is_finite() && span <= 100.0) {
            return Err(bad(format!(
                "its joints span {} m: expected a body's 19 joints in metres, Y up",
                crate::util::numfmt::Short(span)
            )));
        }
        if span <= 0.01 {
            return Err(bad(
                "its 19 joints are at one point: expected a body's joints in metres, Y up".into(),
            ));
        }
        let r = pose::nearest_frame(ch, k, &p);
        out.ids.push(r.id);
        out.resolved.push(r);
    }
    Ok(out)
}
