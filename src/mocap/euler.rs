//! Euler-angle channel sequences to and from quaternions.
//!
//! BVH and ASF compose rotation channels left to right: `CHANNELS 3 Zrotation
//! Yrotation Xrotation` means `R = Rz(a) · Ry(b) · Rx(c)`, an intrinsic ZYX
//! rotation. Angles are in degrees in files and radians here.

use super::clip::Channel;
use glam::{DQuat, DVec3, EulerRot};

/// Composes rotations about the given axes (0 = x, 1 = y, 2 = z), in order,
/// with angles in radians: `R = R_axes[0](a0) · R_axes[1](a1) · ...` (the
/// unit tests' reference for the readers' conversions).
#[cfg(test)]
pub(crate) fn compose(axes: &[usize], radians: &[f64]) -> DQuat {
    let mut q = DQuat::IDENTITY;
    for (&a, &r) in axes.iter().zip(radians) {
        q *= axis_rotation(a, r);
    }
    q
}

/// Rotation of `r` radians about axis `a` (0 = x, 1 = y, 2 = z).
pub(crate) fn axis_rotation(a: usize, r: f64) -> DQuat {
    match a {
        0 => DQuat::from_rotation_x(r),
        1 => DQuat::from_rotation_y(r),
        _ => DQuat::from_rotation_z(r),
    }
}

/// The glam intrinsic Euler order for three rotation axes, if it is one.
pub(crate) fn euler_order(axes: [usize; 3]) -> Option<EulerRot> {
    Some(match axes {
        [2, 1, 0] => EulerRot::ZYX,
        [2, 0, 1] => EulerRot::ZXY,
        [1, 0, 2] => EulerRot::YXZ,
        [1, 2, 0] => EulerRot::YZX,
        [0, 1, 2] => EulerRot::XYZ,
        [0, 2, 1] => EulerRot::XZY,
        [2, 1, 2] => EulerRot::ZYZ,
        [2, 0, 2] => EulerRot::ZXZ,
        [1, 0, 1] => EulerRot::YXY,
        [1, 2, 1] => EulerRot::YZY,
        [0, 1, 0] => EulerRot::XYX,
        [0, 2, 0] => EulerRot::XZX,
        _ => return None,
    })
}

/// The rotation channels a writer can emit for `channels`: the joint's own
/// order when it is a full three-angle sequence, else Z Y X.
pub(crate) fn writable_rotation_order(channels: &[Channel]) -> [usize; 3] {
    let axes: Vec<usize> = channels
        .iter()
        .filter(|c| c.is_rotation())
        .map(|c| c.axis())
        .collect();
    if let [a, b, c] = axes[..]
        && euler_order([a, b, c]).is_some()
    {
        return [a, b, c];
    }
    [2, 1, 0]
}

/// Decomposes `q` into three angles (degrees) about `axes`, so that
/// [`compose`] of them (in radians) gives `q` back.
pub(crate) fn decompose_degrees(q: DQuat, axes: [usize; 3]) -> DVec3 {
    let order = euler_order(axes).unwrap_or(EulerRot::ZYX);
    let (a, b, c) = q.normalize().to_euler(order);
    DVec3::new(a.to_degrees(), b.to_degrees(), c.to_degrees())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_order_round_trips() {
        let orders = [
            [2, 1, 0],
            [2, 0, 1],
            [1, 0, 2],
            [1, 2, 0],
            [0, 1, 2],
            [0, 2, 1],
            [2, 1, 2],
            [0, 1, 0],
        ];
        let angles = [
            [10.0, -35.0, 80.0],
            [170.0, 5.0, -120.0],
            [0.0, 89.0, 30.0],
            [-45.0, 60.0, 10.0],
        ];
        for axes in orders {
            for a in angles {
                let rad: Vec<f64> = a.iter().map(|d: &f64| d.to_radians()).collect();
                let q = compose(&axes, &rad);
                let d = decompose_degrees(q, axes);
                let back = compose(
                    &axes,
                    &[d.x.to_radians(), d.y.to_radians(), d.z.to_radians()],
                );
                assert!(q.dot(back).abs() > 1.0 - 1e-12, "{axes:?} {a:?} -> {d:?}");
            }
        }
    }

    #[test]
    fn zyx_channels_mean_rz_ry_rx() {
        let (z, y, x) = (0.3, -0.2, 0.9);
        let q = compose(&[2, 1, 0], &[z, y, x]);
        let m = DQuat::from_rotation_z(z) * DQuat::from_rotation_y(y) * DQuat::from_rotation_x(x);
        assert!(q.dot(m).abs() > 1.0 - 1e-15);
    }
}
