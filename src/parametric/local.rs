//! Body frames of a sequence: every frame with its horizontal centroid
//! removed and turned about the vertical to face +Z, and the root motion
//! (horizontal travel and heading) kept apart.
//!
//! Casas et al. 2013 (Sec. 3.1) blend sequences "centered at the origin"
//! and use "the original rotation and displacement of each mesh" to place
//! the character; this kernel makes that split. The heading of a frame is
//! the direction of the centroid's travel over a centred window of up to one second
//! (the chord of a circle at its middle is the tangent there, so a turning
//! walk gets its true heading); a frame whose window travels less than
//! 0.15 m/s takes the heading of the nearest frame that travels, and a
//! sequence that never travels keeps heading 0 (its own facing).
//!
//! Conventions: metres, Y-up; heading `θ` faces `(sin θ, 0, cos θ)`;
//! `local = R_y(−θ)(p − c)` with `c` the horizontal centroid.

use glam::{DVec2, DVec3};

/// Lowest travel speed (m/s) at which the heading follows the travel.
pub(crate) const MIN_TRAVEL_SPEED: f64 = 0.15;

/// The root motion of a sequence, per frame.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct RootTrack {
    /// Horizontal centroid `(x, z)` per frame (metres).
    pub centre: Vec<DVec2>,
    /// Heading per frame (radians, unwrapped: continuous across ±π).
    pub heading: Vec<f64>,
}

/// Rotates `(x, z)` about the vertical by `a` (`+Z` goes to `(sin a, cos a)`).
#[inline]
pub(crate) fn rotate(v: DVec2, a: f64) -> DVec2 {
    let (s, c) = a.sin_cos();
    DVec2::new(v.x * c + v.y * s, -v.x * s + v.y * c)
}

/// The root track of `frames` (frame-major, `n` vertices a frame, metres,
/// Y-up) at `fps`.
pub(crate) fn root_track(frames: &[[f64; 3]], n: usize, fps: f64) -> RootTrack {
    let count = frames.len() / n.max(1);
    let centre: Vec<DVec2> = (0..count)
        .map(|f| {
            let s: DVec3 = frames[f * n..(f + 1) * n]
                .iter()
                .map(|p| DVec3::from_array(*p))
                .sum();
            let c = s / n.max(1) as f64;
            DVec2::new(c.x, c.z)
        })
        .collect();
    let half = ((fps * 0.5).round() as usize).max(1);
    let mut raw: Vec<Option<f64>> = Vec::with_capacity(count);
    for f in 0..count {
        // Centred where the sequence allows (the chord's direction is the
        // tangent at its middle); one frame either side at the ends.
        let h = half.min(f).min(count - 1 - f).max(1);
        let a = f.saturating_sub(h);
        let b = (f + h).min(count - 1);
        let d = centre[b] - centre[a];
        let secs = (b - a) as f64 / fps;
        raw.push(if secs > 0.0 && d.length() / secs >= MIN_TRAVEL_SPEED {
            Some(d.x.atan2(d.y))
        } else {
            None
        });
    }
    // Fill still frames from the nearest travelling one.
    let mut heading = vec![0.0; count];
    let moving: Vec<usize> = (0..count).filter(|&f| raw[f].is_some()).collect();
    if !moving.is_empty() {
        let mut j = 0;
        for (f, h) in heading.iter_mut().enumerate() {
            while j + 1 < moving.len() && moving[j + 1].abs_diff(f) <= moving[j].abs_diff(f) {
                j += 1;
            }
            *h = raw[moving[j]].unwrap_or(0.0);
        }
    }
    // Unwrap.
    for f in 1..count {
        let mut d = heading[f] - heading[f - 1];
        d -= (d / std::f64::consts::TAU).round() * std::f64::consts::TAU;
        heading[f] = heading[f - 1] + d;
    }
    RootTrack { centre, heading }
}

/// Frame `f` of `frames` in its body frame, written to `out` (`n` entries).
pub(crate) fn local_frame(
    frames: &[[f64; 3]],
    n: usize,
    track: &RootTrack,
    f: usize,
    out: &mut [[f64; 3]],
) {
    let c = track.centre[f];
    let h = track.heading[f];
    for (o, p) in out.iter_mut().zip(&frames[f * n..(f + 1) * n]) {
        let v = rotate(DVec2::new(p[0] - c.x, p[2] - c.y), -h);
        *o = [v.x, p[1], v.y];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A body walking along a circle: the heading is the tangent, and the
    /// body frames of every frame coincide.
    #[test]
    fn circle_walk_gets_the_tangent_and_one_body_frame() {
        let body = [
            [0.1, 1.0, 0.0],
            [-0.1, 1.0, 0.0],
            [0.0, 0.0, 0.2],
            [0.0, 0.5, -0.2],
        ];
        let (r, fps, w) = (2.0, 30.0, 0.7);
        let n = body.len();
        let mut frames = Vec::new();
        for f in 0..90 {
            let a = w * f as f64 / fps;
            // Centre on the circle, heading the tangent a + π/2 from +Z... :
            // position (r sin a, r cos a) travels along (cos a, −sin a), heading a + π/2.
            let c = DVec2::new(r * a.sin(), r * a.cos());
            let h = a + std::f64::consts::FRAC_PI_2;
            for p in &body {
                let v = rotate(DVec2::new(p[0], p[2]), h) + c;
                frames.push([v.x, p[1], v.y]);
            }
        }
        let t = root_track(&frames, n, fps);
        let mut out = vec![[0.0; 3]; n];
        for f in 10..80 {
            let a = w * f as f64 / fps + std::f64::consts::FRAC_PI_2;
            let d = (t.heading[f] - a + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            assert!(d.abs() < 1e-6, "frame {f}: heading off by {d}");
            local_frame(&frames, n, &t, f, &mut out);
            // The body's own centroid is not at the origin: compare shapes.
            let mean: DVec3 = body.iter().map(|p| DVec3::from_array(*p)).sum::<DVec3>() / 4.0;
            for (o, p) in out.iter().zip(&body) {
                let e = DVec3::from_array(*o)
                    - (DVec3::from_array(*p) - DVec3::new(mean.x, 0.0, mean.z));
                assert!(e.length() < 1e-9, "frame {f}: {e}");
            }
        }
    }
}
