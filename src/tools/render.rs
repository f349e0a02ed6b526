//! A small software rasteriser for looking at meshes: orthographic views,
//! z-buffer, Lambert shading, per-vertex colours (part labels, weights),
//! optional skeleton overlay; written as PNG. Used to check rig embeddings
//! and deformations by eye, and by `surfmotion render`.

pub mod preview;

use crate::util::fsutil::{FsError, write_atomic};
use glam::DVec3;
use std::path::Path;

/// A viewing direction: the camera looks along `forward`, with `up` upwards.
#[derive(Debug, Clone, Copy)]
pub struct View {
    /// Direction the camera looks along (from the eye into the scene).
    pub forward: DVec3,
    /// Up on the screen.
    pub up: DVec3,
}

impl View {
    /// Looking at a character that faces `facing` (Y-up), from in front of it.
    pub fn front(facing: DVec3) -> View {
        View {
            forward: -facing.normalize_or(DVec3::Z),
            up: DVec3::Y,
        }
    }

    /// From the character's left side.
    pub fn side(facing: DVec3) -> View {
        let f = facing.normalize_or(DVec3::Z);
        View {
            forward: DVec3::Y.cross(f).normalize_or(DVec3::X) * -1.0,
            up: DVec3::Y,
        }
    }
}

/// The turn that stands a mesh whose up is `up` Y-up, as the views
/// assume (`render --up`): the shortest arc from `up` to +Y, half a turn
/// about X for -Y. A bare `.pc2` from a Z-up scan carries no up of its
/// own; turned by this, it is drawn standing.
pub(crate) fn y_up_turn(up: DVec3) -> glam::DQuat {
    let u = up.normalize_or(DVec3::Y);
    if u.dot(DVec3::Y) > 1.0 - 1e-12 {
        glam::DQuat::IDENTITY
    } else if u.dot(DVec3::Y) < -1.0 + 1e-12 {
        glam::DQuat::from_rotation_x(std::f64::consts::PI)
    } else {
        glam::DQuat::from_rotation_arc(u, DVec3::Y)
    }
}

/// An RGB image.
#[derive(Debug, Clone, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Row-major RGB bytes.
    pub rgb: Vec<u8>,
}

impl Image {
    /// A blank image of one colour.
    pub fn new(width: usize, height: usize, background: [u8; 3]) -> Image {
        Image {
            width,
            height,
            rgb: background.repeat(width * height),
        }
    }

    /// Puts `other` to the right of `self`.
    pub fn beside(&self, other: &Image) -> Image {
        let h = self.height.max(other.height);
        let mut out = Image::new(self.width + other.width, h, [255; 3]);
        for (img, x0) in [(self, 0), (other, self.width)] {
            for y in 0..img.height {
                let src = &img.rgb[y * img.width * 3..(y + 1) * img.width * 3];
                let d = (y * out.width + x0) * 3;
                out.rgb[d..d + src.len()].copy_from_slice(src);
            }
        }
        out
    }

    /// Puts `other` below `self`.
    pub fn above(&self, other: &Image) -> Image {
        let w = self.width.max(other.width);
        let mut out = Image::new(w, self.height + other.height, [255; 3]);
        for (img, y0) in [(self, 0), (other, self.height)] {
            for y in 0..img.height {
                let src = &img.rgb[y * img.width * 3..(y + 1) * img.width * 3];
                let d = (y0 + y) * out.width * 3;
                out.rgb[d..d + src.len()].copy_from_slice(src);
            }
        }
        out
    }

    /// Writes a PNG atomically.
    pub fn save_png(&self, path: &Path) -> Result<(), FsError> {
        write_atomic(path, |w| {
            let mut enc = png::Encoder::new(w, self.width as u32, self.height as u32);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut wr = enc.write_header().map_err(std::io::Error::other)?;
            wr.write_image_data(&self.rgb)
                .map_err(std::io::Error::other)?;
            wr.finish().map_err(std::io::Error::other)
        })
    }
}

/// What to draw.
pub struct Scene<'a> {
    /// Vertex positions.
    pub positions: &'a [[f64; 3]],
    /// Triangles.
    pub triangles: &'a [[u32; 3]],
    /// Per-vertex colour (grey when absent).
    pub colours: Option<&'a [[u8; 3]]>,
    /// Line segments drawn on top (e.g. bones), with their colour.
    pub lines: &'a [([f64; 3], [f64; 3], [u8; 3])],
}

/// Where a view is placed in its image: pixels per unit and the view
/// coordinates (right, up) drawn at the image centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Framing {
    /// Pixels per unit of length.
    pub scale: f64,
    /// View coordinates (along the screen's right and up) of the centre.
    pub centre: [f64; 2],
}

/// The screen axes (right, up, forward) of a view.
fn axes(view: View) -> (DVec3, DVec3, DVec3) {
    let f = view.forward.normalize_or(DVec3::NEG_Z);
    let up = (view.up - f * view.up.dot(f)).normalize_or(DVec3::Y);
    (f.cross(up), up, f)
}

/// Bounds `([min right, min up], [max right, max up])` of `positions` seen
/// along `view`.
pub(crate) fn view_bounds(positions: &[[f64; 3]], view: View) -> ([f64; 2], [f64; 2]) {
    let (right, up, _) = axes(view);
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &p in positions {
        let p = DVec3::from_array(p);
        let (x, y) = (p.dot(right), p.dot(up));
        lo = [lo[0].min(x), lo[1].min(y)];
        hi = [hi[0].max(x), hi[1].max(y)];
    }
    (lo, hi)
}

impl Framing {
    /// The framing that fits `positions` seen along `view` into a square of
    /// `size` pixels (92 % of it).
    pub fn fit(positions: &[[f64; 3]], view: View, size: usize) -> Framing {
        let (lo, hi) = view_bounds(positions, view);
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        let extent = if extent.is_finite() {
            extent.max(1e-12)
        } else {
            1.0
        };
        Framing {
            scale: 0.92 * size as f64 / extent,
            centre: [(lo[0] + hi[0]) * 0.5, (lo[1] + hi[1]) * 0.5],
        }
    }
}

/// Renders `scene` seen along `view` into a `size × size` image, fitted to
/// the mesh's extent.
pub fn render(scene: &Scene, view: View, size: usize) -> Image {
    render_framed(scene, view, size, Framing::fit(scene.positions, view, size))
}

/// Renders `scene` seen along `view` into a `size × size` image placed by
/// `framing` (so that several panels can share one scale).
pub(crate) fn render_framed(scene: &Scene, view: View, size: usize, framing: Framing) -> Image {
    let (right, up, f) = axes(view);
    let project = |p: [f64; 3]| {
        let p = DVec3::from_array(p);
        (p.dot(right), p.dot(up), p.dot(f))
    };
    let mut img = Image::new(size, size, [255; 3]);
    if !(framing.scale.is_finite() && framing.centre.iter().all(|c| c.is_finite())) {
        return img;
    }
    let (scale, centre) = (framing.scale, framing.centre);
    let to_px = |p: [f64; 3]| {
        let (x, y, z) = project(p);
        (
            size as f64 * 0.5 + (x - centre[0]) * scale,
            size as f64 * 0.5 - (y - centre[1]) * scale,
            z,
        )
    };
    let mut depth = vec![f64::INFINITY; size * size];
    let light = (-f + up * 0.5 + right * 0.3).normalize();
    for tri in scene.triangles {
        let [a, b, c] = tri.map(|v| scene.positions[v as usize]);
        let n = (DVec3::from_array(b) - DVec3::from_array(a))
            .cross(DVec3::from_array(c) - DVec3::from_array(a))
            .normalize_or_zero();
        let shade = 0.35 + 0.65 * n.dot(light).abs();
        let col = |v: u32| {
            scene
                .colours
                .and_then(|c| c.get(v as usize))
                .copied()
                .unwrap_or([200, 200, 200])
        };
        let cols = tri.map(col);
        let avg: [f64; 3] =
            std::array::from_fn(|k| cols.iter().map(|c| c[k] as f64).sum::<f64>() / 3.0);
        let rgb = avg.map(|v| (v * shade).clamp(0.0, 255.0) as u8);
        let p = [to_px(a), to_px(b), to_px(c)];
        fill_triangle(&mut img, &mut depth, p, rgb);
    }
    for &(a, b, rgb) in scene.lines {
        let (pa, pb) = (to_px(a), to_px(b));
        let steps = ((pb.0 - pa.0).abs().max((pb.1 - pa.1).abs()) as usize).max(1);
        for s in 0..=steps {
            let t = s as f64 / steps as f64;
            let (x, y) = (pa.0 + (pb.0 - pa.0) * t, pa.1 + (pb.1 - pa.1) * t);
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                put(&mut img, x as i64 + dx, y as i64 + dy, rgb);
            }
        }
    }
    img
}

fn put(img: &mut Image, x: i64, y: i64, rgb: [u8; 3]) {
    if x >= 0 && y >= 0 && (x as usize) < img.width && (y as usize) < img.height {
        let i = (y as usize * img.width + x as usize) * 3;
        img.rgb[i..i + 3].copy_from_slice(&rgb);
    }
}

fn fill_triangle(img: &mut Image, depth: &mut [f64], p: [(f64, f64, f64); 3], rgb: [u8; 3]) {
    // Pixel bounds of the triangle, clipped to the image.
    let span = |c: fn(&(f64, f64, f64)) -> f64, limit: usize| {
        let lo = p.iter().map(c).fold(f64::INFINITY, f64::min);
        let hi = p.iter().map(c).fold(f64::NEG_INFINITY, f64::max);
        (lo.floor().max(0.0), hi.ceil().min(limit as f64 - 1.0))
    };
    let (xmin, xmax) = span(|q| q.0, img.width);
    let (ymin, ymax) = span(|q| q.1, img.height);
    let area = (p[1].0 - p[0].0) * (p[2].1 - p[0].1) - (p[2].0 - p[0].0) * (p[1].1 - p[0].1);
    if area.abs() < 1e-12 || xmin > xmax || ymin > ymax {
        return;
    }
    for y in ymin as usize..=ymax as usize {
        for x in xmin as usize..=xmax as usize {
            let (px, py) = (x as f64 + 0.5, y as f64 + 0.5);
            let e = |a: (f64, f64, f64), b: (f64, f64, f64)| {
                ((b.0 - a.0) * (py - a.1) - (px - a.0) * (b.1 - a.1)) / area
            };
            let (w0, w1, w2) = (e(p[1], p[2]), e(p[2], p[0]), e(p[0], p[1]));
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * p[0].2 + w1 * p[1].2 + w2 * p[2].2;
            let i = y * img.width + x;
            if z < depth[i] {
                depth[i] = z;
                img.rgb[i * 3..i * 3 + 3].copy_from_slice(&rgb);
            }
        }
    }
}

/// The direction a Y-up character faces, from its mesh alone.
///
/// The axis is the horizontal axis of least spread of the *shoulder band*
/// (75-85 % of the height): a body is wider across the shoulders than deep
/// there, whatever its legs and hands do (over the whole mesh a stride or
/// a swinging arm is deeper than the body is wide, and mid-stride frames
/// of walks came out side-on: wrong on 60-90 % of the frames of synthetic
/// walks and runs, against 0-7 % with the band). The sign is
/// [`facing_vote`]'s. `+z` when the mesh gives no answer (empty, or no
/// horizontal spread).
pub fn facing_of(positions: &[[f64; 3]]) -> DVec3 {
    let Some((axis, _)) = shoulder_axis(positions) else {
        return DVec3::Z;
    };
    if facing_vote(positions, axis) < 0.0 {
        -axis
    } else {
        axis
    }
}

/// The facing of frame `at` of a sequence: each frame's shoulder axis
/// ([`facing_of`]), its sign carried from frame to frame by continuity
/// (a body turns far less than a quarter turn between two frames), and
/// the sign of the whole chain decided by the sum of every frame's
/// [`facing_vote`]: one frame's knees and feet can mislead (a leg kicked
/// back, a foot pointing down), hundreds of frames together do not.
pub fn facing_of_frames(frames: &[&[[f64; 3]]], at: usize) -> DVec3 {
    let Some(here) = frames.get(at) else {
        return DVec3::Z;
    };
    let Some((axis_at, _)) = shoulder_axis(here) else {
        return DVec3::Z;
    };
    // Chain outwards from `at` in both directions; `axis_at` has sign +1.
    let mut vote = facing_vote(here, axis_at);
    for dir in [-1isize, 1] {
        let mut prev = axis_at;
        let mut i = at as isize + dir;
        while i >= 0 && (i as usize) < frames.len() {
            if let Some((a, _)) = shoulder_axis(frames[i as usize]) {
                let a = if a.dot(prev) < 0.0 { -a } else { a };
                vote += facing_vote(frames[i as usize], a);
                prev = a;
            }
            i += dir;
        }
    }
    if vote < 0.0 { -axis_at } else { axis_at }
}

/// The horizontal axes of least and most spread of the band at 75-85 % of
/// the height (the whole mesh if the band holds fewer than 3 points).
fn shoulder_axis(positions: &[[f64; 3]]) -> Option<(DVec3, DVec3)> {
    let (lo, hi) = positions
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[1]), b.max(p[1]))
        });
    let (from, to) = (lo + 0.75 * (hi - lo), lo + 0.85 * (hi - lo));
    let in_band = |p: &&[f64; 3]| (from..=to).contains(&p[1]);
    let band = positions.iter().filter(in_band).count();
    let pick = |p: &&[f64; 3]| band < 3 || in_band(p);
    let (mut n, mut c) = (0usize, DVec3::ZERO);
    for p in positions.iter().filter(pick) {
        n += 1;
        c += DVec3::from_array(*p);
    }
    if n == 0 {
        return None;
    }
    let c = c / n as f64;
    let (mut xx, mut xz, mut zz) = (0.0, 0.0, 0.0);
    for p in positions.iter().filter(pick) {
        let (x, z) = (p[0] - c.x, p[2] - c.z);
        xx += x * x;
        xz += x * z;
        zz += z * z;
    }
    // Eigenvector of the smaller eigenvalue of [[xx, xz], [xz, zz]].
    let half = 0.5 * (xx - zz);
    let r = (half * half + xz * xz).sqrt();
    if !(r.is_finite() && xx + zz > 0.0) {
        return None;
    }
    let small = 0.5 * (xx + zz) - r;
    let axis = if xz.abs() > 1e-12 * (xx + zz) {
        DVec3::new(xz, 0.0, small - xx)
    } else if xx < zz {
        DVec3::X
    } else {
        DVec3::Z
    }
    .normalize_or(DVec3::Z);
    Some((axis, DVec3::new(-axis.z, 0.0, axis.x)))
}

/// Evidence (metres, signed) that a Y-up body faces `+axis` rather than
/// `-axis`: each leg's knee (the middle of the leg's height) lies in front
/// of the line from its hip to its ankle, since knees bend forward; the
/// legs are the two halves of the lower body split by the lateral axis.
/// Plus the soles: a foot reaches forward of its shin.
fn facing_vote(positions: &[[f64; 3]], axis: DVec3) -> f64 {
    let (lo, hi) = positions
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[1]), b.max(p[1]))
        });
    let h = hi - lo;
    if !(h > 0.0 && h.is_finite()) {
        return 0.0;
    }
    let lateral = DVec3::new(-axis.z, 0.0, axis.x);
    let lower = |p: &&[f64; 3]| p[1] <= lo + 0.5 * h;
    let (mut n, mut c) = (0usize, DVec3::ZERO);
    for p in positions.iter().filter(lower) {
        n += 1;
        c += DVec3::from_array(*p);
    }
    let c = c / n.max(1) as f64;
    let mut knees = 0.0;
    for side in [1.0, -1.0] {
        let leg: Vec<DVec3> = positions
            .iter()
            .filter(lower)
            .map(|p| DVec3::from_array(*p))
            .filter(|p| side * (*p - c).dot(lateral) > 0.0)
            .collect();
        let (ll, lh) = leg
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
                (a.min(p.y), b.max(p.y))
            });
        let mean = |a: f64, b: f64| {
            let (from, to) = (ll + a * (lh - ll), ll + b * (lh - ll));
            let pts: Vec<&DVec3> = leg.iter().filter(|p| (from..=to).contains(&p.y)).collect();
            (!pts.is_empty()).then(|| pts.iter().copied().sum::<DVec3>() / pts.len() as f64)
        };
        if let (Some(ankle), Some(knee), Some(hip)) =
            (mean(0.1, 0.2), mean(0.45, 0.6), mean(0.85, 1.0))
        {
            knees += (knee - 0.5 * (ankle + hip)).dot(axis);
        }
    }
    // Soles (bottom 3 % of the height) against the shins above them (6-12
    // %), always counted: on straight legs the knees say next to nothing
    // and may say it wrongly (the calves bulge back: the SMPL template's
    // T-pose gave -0.4 cm against its feet's +11 cm, and its back was
    // drawn as its front).
    let band = |a: f64, b: f64| {
        let (from, to) = (lo + a * h, lo + b * h);
        let pts: Vec<DVec3> = positions
            .iter()
            .filter(|p| (from..=to).contains(&p[1]))
            .map(|p| DVec3::from_array(*p))
            .collect();
        pts.iter().sum::<DVec3>() / pts.len().max(1) as f64
    };
    knees + (band(0.0, 0.03) - band(0.06, 0.12)).dot(axis)
}

/// The floor line of a panel: a grey segment at height `y` (along Y)
/// across the whole `size`-pixel panel seen along `view` placed by
/// `framing`.
pub(crate) fn floor_line(
    view: View,
    framing: Framing,
    y: f64,
    size: usize,
) -> ([f64; 3], [f64; 3], [u8; 3]) {
    let (right, _, _) = axes(view);
    let half = 0.5 * size as f64 / framing.scale;
    let mid = right * framing.centre[0] + DVec3::Y * y;
    (
        (mid - right * half).to_array(),
        (mid + right * half).to_array(),
        [150, 150, 150],
    )
}

/// One scale for many panels: a framing per panel of view-space `bounds`
/// (min, max), all at one scale (the largest extent fills 92 % of `size`
/// pixels) and one vertical centre, each centred horizontally on its own
/// bounds. Also returns the extent (view units). Shared by contact sheets
/// and `surfmotion render`.
pub(crate) fn shared_framing(bounds: &[([f64; 2], [f64; 2])], size: usize) -> (Vec<Framing>, f64) {
    let (mut ylo, mut yhi, mut width) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for b in bounds {
        ylo = ylo.min(b.0[1]);
        yhi = yhi.max(b.1[1]);
        width = width.max(b.1[0] - b.0[0]);
    }
    let extent = (yhi - ylo).max(width);
    let extent = if extent.is_finite() {
        extent.max(1e-12)
    } else {
        1.0
    };
    let scale = 0.92 * size as f64 / extent;
    let framings = bounds
        .iter()
        .map(|b| Framing {
            scale,
            centre: [(b.0[0] + b.1[0]) * 0.5, (ylo + yhi) * 0.5],
        })
        .collect();
    (framings, extent)
}

/// A contact sheet: the frames `frames` (each a full set of positions on
/// `triangles`) side by side, front views in the top row and left-side
/// views below, every panel `size` pixels square and all at ONE scale (the
/// largest extent over all frames and both views), so that sizes and
/// heights compare across panels. Each panel is centred horizontally on its
/// own frame; vertically all share one centre, so the floor is one line.
/// Frame `i` is seen facing `facings[i]` (the last one for frames beyond
/// it; +Z when empty). `floor` (height along Y) draws a grey floor line.
pub(crate) fn contact_sheet(
    frames: &[&[[f64; 3]]],
    triangles: &[[u32; 3]],
    colours: Option<&[[u8; 3]]>,
    facings: &[DVec3],
    floor: Option<f64>,
    size: usize,
) -> Image {
    let views_of = |i: usize| {
        let facing = facings
            .get(i)
            .or(facings.last())
            .copied()
            .unwrap_or(DVec3::Z);
        [View::front(facing), View::side(facing)]
    };
    let bounds: Vec<[([f64; 2], [f64; 2]); 2]> = frames
        .iter()
        .enumerate()
        .map(|(i, f)| views_of(i).map(|v| view_bounds(f, v)))
        .collect();
    let flat: Vec<([f64; 2], [f64; 2])> = bounds.iter().flatten().copied().collect();
    let (framings, extent) = shared_framing(&flat, size);
    let mut rows: [Option<Image>; 2] = [None, None];
    for (i, f) in frames.iter().enumerate() {
        for (k, view) in views_of(i).into_iter().enumerate() {
            let framing = framings[2 * i + k];
            let (right, _, _) = axes(view);
            let lines: Vec<([f64; 3], [f64; 3], [u8; 3])> = floor
                .filter(|y| y.is_finite())
                .map(|y| {
                    let half = 0.5 * extent;
                    let mid = right * framing.centre[0] + DVec3::Y * y;
                    vec![(
                        (mid - right * half).to_array(),
                        (mid + right * half).to_array(),
                        [150, 150, 150],
                    )]
                })
                .unwrap_or_default();
            let scene = Scene {
                positions: f,
                triangles,
                colours,
                lines: &lines,
            };
            let img = render_framed(&scene, view, size, framing);
            rows[k] = Some(match rows[k].take() {
                None => img,
                Some(r) => r.beside(&img),
            });
        }
    }
    match rows {
        [Some(a), Some(b)] => a.above(&b),
        _ => Image::new(size, size, [255; 3]),
    }
}

/// Frame indices for a contact sheet: `count` evenly spaced over `frames`
/// (first and last included; fewer when the sequence is shorter).
pub(crate) fn sheet_frames(frames: usize, count: usize) -> Vec<usize> {
    if frames == 0 || count == 0 {
        return Vec::new();
    }
    let k = count.min(frames);
    if k == 1 {
        return vec![0];
    }
    (0..k).map(|i| i * (frames - 1) / (k - 1)).collect()
}

/// A distinct colour for label `k` (golden-angle hues).
pub(crate) fn label_colour(k: usize) -> [u8; 3] {
    let h = (k as f64 * 137.508) % 360.0;
    let (s, v) = (0.65, 0.95);
    let c = v * s;
    let x = c * (1.0 - ((h / 60.0) % 2.0 - 1.0).abs());
    let (r, g, b) = match (h / 60.0) as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = v - c;
    [r, g, b].map(|u| ((u + m) * 255.0).round() as u8)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_axis_is_turned_onto_y() {
        for up in [
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::Z,
            DVec3::NEG_Z,
        ] {
            let q = y_up_turn(up);
            assert!((q * up - DVec3::Y).length() < 1e-12, "{up}");
            // A turn, not a reflection: the character's left stays its left.
            let (a, b) = (q * DVec3::X, q * DVec3::Z);
            assert!((a.cross(b) - q * DVec3::X.cross(DVec3::Z)).length() < 1e-12);
        }
    }

    #[test]
    fn renders_a_shape_and_round_trips_png() {
        let m = crate::mesh::subdivide::icosahedron();
        let img = render(
            &Scene {
                positions: m.positions(),
                triangles: m.triangles(),
                colours: None,
                lines: &[],
            },
            View::front(DVec3::Z),
            64,
        );
        // The centre is covered, the corner is background.
        let at = |x: usize, y: usize| &img.rgb[(y * 64 + x) * 3..(y * 64 + x) * 3 + 3];
        assert_ne!(at(32, 32), &[255, 255, 255]);
        assert_eq!(at(0, 0), &[255, 255, 255]);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        img.beside(&img).save_png(&p).unwrap();
        let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&p).unwrap()));
        let reader = dec.read_info().unwrap();
        assert_eq!(reader.info().width, 128);
    }

    #[test]
    fn facing_from_the_mesh_follows_a_turn() {
        let mesh = crate::synth::humanoid::humanoid_mesh(crate::synth::humanoid::DEMO_GRID);
        let lm = crate::synth::humanoid::humanoid_landmarks(&mesh);
        let rig = crate::embed::Embedding::new(&mesh, &lm, None).unwrap();
        let want = DVec3::from_array(rig.facing);
        for turn in [0.0, 1.0, 2.5, -2.0] {
            let q = glam::DQuat::from_rotation_y(turn);
            let p: Vec<[f64; 3]> = mesh
                .positions()
                .iter()
                .map(|x| (q * DVec3::from_array(*x)).to_array())
                .collect();
            let f = facing_of(&p);
            assert!(f.dot(q * want) > 0.95, "turn {turn}: {f} vs {}", q * want);
        }
    }

    /// A walker mid-stride, facing +z: a shoulder box wider than deep, and
    /// two legs a long stride apart (the whole body deeper than wide),
    /// knees bent forward, feet pointing forward. `phase` in [-1, 1] swings
    /// the legs.
    fn walker(phase: f64) -> Vec<[f64; 3]> {
        let mut p = Vec::new();
        let mut line = |a: DVec3, b: DVec3, n: usize| {
            for i in 0..=n {
                p.push(a.lerp(b, i as f64 / n as f64).to_array());
            }
        };
        for k in 0..=10 {
            let y = 0.95 + 0.06 * k as f64;
            for (x, z) in [(-0.2, -0.1), (0.2, -0.1), (0.2, 0.1), (-0.2, 0.1)] {
                line(DVec3::new(x, y, z), DVec3::new(-z * 2.0, y, x * 0.5), 8);
            }
        }
        line(DVec3::new(0.0, 1.55, 0.0), DVec3::new(0.0, 1.75, 0.0), 10);
        for (x, s) in [(0.1, 1.0), (-0.1, -1.0)] {
            let foot = DVec3::new(x, 0.05, 0.45 * s * phase);
            let hip = DVec3::new(x, 0.95, 0.0);
            let knee = (hip + foot) * 0.5 + DVec3::new(0.0, 0.0, 0.08);
            line(hip, knee, 20);
            line(knee, foot, 20);
            line(
                foot - DVec3::new(0.0, 0.05, 0.05),
                foot + DVec3::new(0.0, -0.05, 0.2),
                10,
            );
        }
        p
    }

    #[test]
    fn facing_holds_mid_stride() {
        let spread = |p: &[[f64; 3]], i: usize| {
            let (a, b) = p
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), q| {
                    (a.min(q[i]), b.max(q[i]))
                });
            b - a
        };
        let stride = walker(1.0);
        assert!(
            spread(&stride, 2) > spread(&stride, 0),
            "the test's walker must be deeper than wide"
        );
        let frames: Vec<Vec<[f64; 3]>> = (0..40).map(|f| walker((f as f64 * 0.3).sin())).collect();
        for turn in [0.0, 0.7, 2.0, -2.6] {
            let q = glam::DQuat::from_rotation_y(turn);
            let turned: Vec<Vec<[f64; 3]>> = frames
                .iter()
                .map(|p| {
                    p.iter()
                        .map(|x| (q * DVec3::from_array(*x)).to_array())
                        .collect()
                })
                .collect();
            let want = q * DVec3::Z;
            for (i, p) in turned.iter().enumerate() {
                let f = facing_of(p);
                assert!(f.dot(want) > 0.95, "turn {turn}, frame {i}: {f} vs {want}");
            }
            let refs: Vec<&[[f64; 3]]> = turned.iter().map(Vec::as_slice).collect();
            for at in [0, 17, 39] {
                let f = facing_of_frames(&refs, at);
                assert!(
                    f.dot(want) > 0.95,
                    "turn {turn}, sequence at {at}: {f} vs {want}"
                );
            }
        }
        assert_eq!(facing_of_frames(&[], 3), DVec3::Z);
    }

    #[test]
    fn contact_sheet_panels_share_one_scale() {
        let m = crate::mesh::subdivide::icosahedron();
        let small: Vec<[f64; 3]> = m.positions().iter().map(|p| p.map(|x| 0.5 * x)).collect();
        let sheet = contact_sheet(
            &[m.positions(), &small],
            m.triangles(),
            None,
            &[DVec3::Z],
            None,
            64,
        );
        assert_eq!((sheet.width, sheet.height), (128, 128));
        let covered = |x0: usize| {
            (0..64)
                .flat_map(|y| (x0..x0 + 64).map(move |x| (x, y)))
                .filter(|&(x, y)| sheet.rgb[(y * 128 + x) * 3..(y * 128 + x) * 3 + 3] != [255; 3])
                .count() as f64
        };
        // Half the size: a quarter of the pixels (not refitted to the panel).
        let ratio = covered(64) / covered(0);
        assert!((ratio - 0.25).abs() < 0.05, "{ratio}");
        assert_eq!(sheet_frames(175, 5), vec![0, 43, 87, 130, 174]);
        assert_eq!(sheet_frames(2, 5), vec![0, 1]);
    }
}
