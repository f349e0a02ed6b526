//! The body's up direction and the axis nearest a direction: the
//! vertical rig embedding works about, read by the landmarks' checks, the
//! joint placement, skin import and their callers.

use glam::DVec3;

/// The body's up from its groin-to-chin direction `body`: the nearest of
/// the six axis directions (±X, ±Y, ±Z) when within 45° of it (a scan
/// stands along an axis of its file: Y-up, Z-up as many scanners write, or
/// any other; the groin-chin line leans with the pose, 9° on samba), else
/// `body` itself (a body lying or tilted off every axis).
///
/// Every axis is treated alike, so the embedding of a scan turned by a
/// rotation that maps axes to axes (any up, any yaw about it), moved,
/// scaled or mirrored is the turned (moved, scaled, mirrored) embedding.
/// Before, only +Y was snapped to, and the samba scan turned Z-up was
/// embedded about its leaning groin-chin line: joints up to 3.2 cm (1.8 %
/// of the height) from the turned Y-up ones.
pub(crate) fn body_up(body: DVec3) -> DVec3 {
    let body = body.normalize_or(DVec3::Y);
    let best = nearest_axis(body);
    if best.dot(body) > 0.7 { best } else { body }
}

/// The nearest of the six axis directions (±X, ±Y, ±Z) to `v` (+Y first on
/// a tie; +Y for a zero or non-finite `v`).
pub(crate) fn nearest_axis(v: DVec3) -> DVec3 {
    [
        DVec3::Y,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::NEG_Z,
        DVec3::X,
        DVec3::NEG_X,
    ]
    .into_iter()
    .reduce(|a, b| if b.dot(v) > a.dot(v) { b } else { a })
    .unwrap_or(DVec3::Y)
}
