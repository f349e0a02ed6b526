//! Whether the body's highest extremity is a head (issue 41, partial
//! bodies): below a head the body stays narrow down the head and the neck
//! before it widens into the shoulders; a body cut at the neck widens into
//! the shoulders at once.
//!
//! Read on sections across `up`, every [`STEP`] of the height down from
//! the top, of the vertices within [`REACH`] of the height of the top
//! along the surface (the hands stay out however the arms are held): a
//! section's width is the greatest distance across `up` between two of its
//! vertices. The **trunk's depth** is how far below the top the first
//! section wider than [`TRUNK_WIDTH`] lies. Session 34 measured whole
//! bodies (samba, crane, SMPL) at 14-18 % of the height and bodies cut at
//! the chin at 4-5 %; it also read whether a neck narrows below the head,
//! which read a whole crane (frames 130, 170) as cut and was dropped. The
//! measurements of this rule on whole and cut bodies are in the README
//! (`autorig_eval headless`) and `embed::auto_headless`.

use super::humanoid::geodesic;
use glam::DVec3;

/// The sections' spacing, a fraction of the height.
pub const STEP: f64 = 0.01;
/// Sections read below the top.
const SECTIONS: usize = 30;
/// Only the vertices this far from the top along the surface (a fraction
/// of the height) are read.
const REACH: f64 = 0.3;
/// A section wider than this (a fraction of the height) is the shoulders
/// or the trunk: a head and a neck are narrower.
pub const TRUNK_WIDTH: f64 = 0.18;
/// A trunk less deep than this below the top (a fraction of the height)
/// has no head above it: midway between the deepest cut measured (4 %)
/// and the shallowest whole body (crane, 10 %, some frames), so a whole
/// body read a little shallower keeps its head (session 36: 9.5 % left a
/// margin of half a section to crane's whole frames).
pub const MIN_DEPTH: f64 = 0.07;

/// What the sections below the body's top read.
#[derive(Debug, Clone)]
pub struct NeckReading {
    /// Each section's width (a fraction of the height; 0 for a section
    /// with no vertex), the top's first.
    pub widths: Vec<f64>,
    /// The trunk's depth below the top (a fraction of the height; the
    /// sections' reach when none is wider than [`TRUNK_WIDTH`]).
    pub trunk_depth: f64,
}

impl NeckReading {
    /// The sections below vertex `top` of `rest` (neighbours `nb`, up
    /// `up`, height `height` along it).
    pub fn read(rest: &[[f64; 3]], nb: &[Vec<u32>], up: DVec3, height: f64, top: u32) -> Self {
        let (from_top, _) = geodesic(rest, nb, &[top]);
        let top_h = DVec3::from_array(rest[top as usize]).dot(up);
        let mut sections: Vec<Vec<DVec3>> = vec![Vec::new(); SECTIONS];
        for (q, d) in rest.iter().zip(&from_top) {
            if d.is_nan() || *d > REACH * height {
                continue;
            }
            let q = DVec3::from_array(*q);
            let k = ((top_h - q.dot(up)) / (STEP * height)).round();
            if k >= 0.0 && k < SECTIONS as f64 {
                sections[k as usize].push(q - up * q.dot(up));
            }
        }
        let widths: Vec<f64> = sections.iter().map(|s| width(s) / height).collect();
        let trunk_depth = widths
            .iter()
            .position(|&w| w > TRUNK_WIDTH)
            .unwrap_or(SECTIONS) as f64
            * STEP;
        NeckReading {
            widths,
            trunk_depth,
        }
    }

    /// Why the top of the body is a cut and no head (the trunk less than
    /// [`MIN_DEPTH`] below it); `None` for a head.
    pub fn cut(&self) -> Option<String> {
        (self.trunk_depth < MIN_DEPTH).then(|| {
            format!(
                "the body is wider than {:.0}% of its height {:.0}% below its top (a head and neck reach {:.1}% or more before the shoulders; the top is {:.0}% across)",
                100.0 * TRUNK_WIDTH,
                100.0 * self.trunk_depth,
                100.0 * MIN_DEPTH,
                100.0 * self.widths.first().copied().unwrap_or(0.0)
            )
        })
    }
}

/// The top of a body with four branches (the feet and the hands, no
/// head: a body cut at the neck below the chin leaves a stump too short to
/// be a branch, [`super::branches`]): its highest vertex along up (the
/// feet on the floor, [`super::up::find_up`] over `frames`) near the
/// body's axis and away from the four tips ([`on_the_trunk`]), when the
/// sections below it read a cut ([`NeckReading::cut`]); `None` otherwise
/// (a raised hand near the axis is the top: the body is refused as
/// before).
pub(crate) fn headless_top(
    rest: &[[f64; 3]],
    nb: &[Vec<u32>],
    frames: &[&[[f64; 3]]],
    four: &[(u32, f64)],
) -> Option<u32> {
    let (up, _) = super::up::find_up(rest, frames, four).ok()?;
    let h = |v: usize| DVec3::from_array(rest[v]).dot(up);
    let lo = (0..rest.len()).map(h).fold(f64::INFINITY, f64::min);
    let hi = (0..rest.len()).map(h).fold(f64::NEG_INFINITY, f64::max);
    let trunk = on_the_trunk(rest, nb, up, hi - lo, four);
    let top = (0..rest.len())
        .filter(|&v| trunk[v])
        .max_by(|&a, &b| h(a).total_cmp(&h(b)))?;
    let reading = NeckReading::read(rest, nb, up, h(top) - lo, top as u32);
    reading.cut().map(|_| top as u32)
}

/// How far from the body's axis (the vertical through the vertices'
/// centroid) a headless body's top may lie, a fraction of the height.
/// Session 36's rule took the highest vertex: on the SMPL template in its
/// T-pose cut at the neck joint (`autorig_eval … confusion`) that was the
/// left hand, 45 % of the height off the axis, a little higher than the
/// cut: the hand was rigged as the head and the left arm from the stump
/// (elbow 14-24 %, wrist 34-37 % of the height off, parts 68-76 %).
pub const TOP_AXIS: f64 = 0.12;
/// A headless body's top lies farther along the surface than this from
/// each of the four tips (a fraction of the height: a hand and forearm,
/// 0.108 + 0.146 of it after Drillis & Contini 1966).
pub const TOP_FROM_TIPS: f64 = 0.25;

/// The vertices of `rest` that may top a headless body (up `up`, height
/// `height`): within [`TOP_AXIS`] of the axis and farther than
/// [`TOP_FROM_TIPS`] along the surface from each of `four` tips.
fn on_the_trunk(
    rest: &[[f64; 3]],
    nb: &[Vec<u32>],
    up: DVec3,
    height: f64,
    four: &[(u32, f64)],
) -> Vec<bool> {
    let v3 = |q: [f64; 3]| DVec3::from_array(q);
    let c = rest.iter().map(|q| v3(*q)).sum::<DVec3>() / rest.len().max(1) as f64;
    let tips: Vec<u32> = four.iter().map(|t| t.0).collect();
    let (from_tips, _) = geodesic(rest, nb, &tips);
    rest.iter()
        .zip(&from_tips)
        .map(|(q, d)| {
            let off = v3(*q) - c;
            (off - up * off.dot(up)).length() < TOP_AXIS * height && *d > TOP_FROM_TIPS * height
        })
        .collect()
}

/// The greatest distance between two of `s`.
fn width(s: &[DVec3]) -> f64 {
    let mut w2 = 0.0f64;
    for (i, a) in s.iter().enumerate() {
        for b in &s[i + 1..] {
            w2 = w2.max(a.distance_squared(*b));
        }
    }
    w2.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn reading(widths: &[f64]) -> NeckReading {
        let trunk_depth = widths
            .iter()
            .position(|&w| w > TRUNK_WIDTH)
            .unwrap_or(widths.len()) as f64
            * STEP;
        NeckReading {
            widths: widths.to_vec(),
            trunk_depth,
        }
    }

    /// Session 34's sections of samba, crane and the captures cut at the
    /// chin (every 1 % of the height).
    #[test]
    fn heads_keep_the_trunk_low_and_cuts_do_not() {
        let samba = [
            0.042, 0.086, 0.120, 0.135, 0.137, 0.137, 0.128, 0.126, 0.132, 0.131, 0.116, 0.108,
            0.102, 0.098, 0.096, 0.076, 0.111, 0.152, 0.193, 0.221,
        ];
        let crane = [
            0.047, 0.077, 0.091, 0.103, 0.112, 0.116, 0.124, 0.127, 0.119, 0.116, 0.111, 0.105,
            0.107, 0.109, 0.162, 0.217, 0.251,
        ];
        let samba_cut = [0.109, 0.107, 0.094, 0.128, 0.175, 0.217, 0.242];
        let crane_cut = [0.118, 0.118, 0.122, 0.174, 0.236, 0.265];
        assert!(reading(&samba).cut().is_none());
        assert!(reading(&crane).cut().is_none());
        let why = reading(&samba_cut).cut().unwrap();
        assert!(why.contains("5% below its top"), "{why}");
        assert!(reading(&crane_cut).cut().is_some());
        // A point on a column wider than the trunk at once.
        assert!(reading(&[0.3; 4]).cut().is_some());
    }

    /// The widths read off a generated column: a head-wide cylinder on a
    /// wide block, rotated off the axes; the block's top is the trunk.
    #[test]
    fn a_generated_head_on_a_block_reads_its_depth() {
        let up = DVec3::new(0.3, 1.0, -0.2).normalize();
        let a = up.any_orthonormal_vector();
        let b = up.cross(a);
        let mut p = Vec::new();
        // 1 high: a column 0.12 across from 1.0 down to 0.85, then 0.4 across.
        for k in 0..=60 {
            let h = 1.0 - 0.005 * k as f64;
            let r = if h > 0.85 { 0.06 } else { 0.2 };
            for j in 0..16 {
                let t = std::f64::consts::TAU * j as f64 / 16.0;
                p.push((up * h + a * (r * t.cos()) + b * (r * t.sin())).to_array());
            }
        }
        p.push((up * 1.0).to_array());
        let top = (p.len() - 1) as u32;
        // Every vertex joined to the top: its distance along the surface
        // is its distance.
        let mut nb: Vec<Vec<u32>> = vec![vec![top]; p.len()];
        nb[top as usize] = (0..top).collect();
        let r = NeckReading::read(&p, &nb, up, 1.0, top);
        assert!((r.trunk_depth - 0.15).abs() < 0.011, "{:?}", r.widths);
        assert!(r.cut().is_none());
        assert!((r.widths[5] - 0.12).abs() < 0.01, "{:?}", r.widths);
    }
}
