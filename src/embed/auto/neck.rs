//! Whether the body's highest extremity is a head (issue 41, partial
//! bodies): a head is a bulge that narrows into a neck before the
//! shoulders; a body cut at the neck is as wide as the cut at its top and
//! widens straight into the shoulders.
//!
//! Read on sections across `up`, every [`STEP`] of the height down from
//! the top, of the vertices within [`REACH`] of the height of the top
//! along the surface (the hands stay out however the arms are held): each
//! section's width is its greatest horizontal distance between two of its
//! vertices. Samba, crane and the SMPL template: the crown 4-5 % of the
//! height across, the head 12.7-13.7 %, the neck 7.6-10.5 %, the trunk
//! wider than [`TRUNK_WIDTH`] 15-18 % of the height below the top; the
//! captures cut at the chin: 10.9-11.8 % across at the cut, wider than
//! [`TRUNK_WIDTH`] 4-5 % of the height below it.

use super::body::Body;
use super::humanoid::geodesic;
use glam::DVec3;

/// The sections' spacing, a fraction of the height.
const STEP: f64 = 0.01;
/// Sections read below the top.
const SECTIONS: usize = 26;
/// Only the vertices this far from the top along the surface (a fraction
/// of the height) are read.
const REACH: f64 = 0.3;
/// A section wider than this (a fraction of the height) is the shoulders
/// or the trunk: a head is narrower.
const TRUNK_WIDTH: f64 = 0.18;
/// A head and neck reach at least this many sections above the trunk.
const MIN_SECTIONS: usize = 8;
/// A neck is at most this share of the head's widest section.
const NECK_SHARE: f64 = 0.9;

/// The widths of the sections below `top` (a fraction of the height
/// each; 0 for a section with no vertex).
pub(crate) fn section_widths(body: &Body, top: u32) -> Vec<f64> {
    let (rest, up, height) = (body.rest, body.up, body.height);
    let (from_top, _) = geodesic(rest, body.nb, &[top]);
    let top_h = DVec3::from_array(rest[top as usize]).dot(up);
    let mut sections: Vec<Vec<DVec3>> = vec![Vec::new(); SECTIONS];
    for (q, d) in rest.iter().zip(&from_top) {
        if *d > REACH * height {
            continue;
        }
        let q = DVec3::from_array(*q);
        let k = ((top_h - q.dot(up)) / (STEP * height)).round();
        if k >= 0.0 && k < SECTIONS as f64 {
            sections[k as usize].push(q - up * q.dot(up));
        }
    }
    sections
        .iter()
        .map(|s| {
            let mut w2 = 0.0f64;
            for (i, a) in s.iter().enumerate() {
                for b in &s[i + 1..] {
                    w2 = w2.max(a.distance_squared(*b));
                }
            }
            w2.sqrt() / height
        })
        .collect()
}

/// Why the top of the body is a cut and no head, from its section
/// widths ([`section_widths`]); `None` when a head narrows into a neck
/// above the trunk.
pub(crate) fn cut_at_neck(widths: &[f64]) -> Option<String> {
    let stop = widths
        .iter()
        .position(|&w| w > TRUNK_WIDTH)
        .unwrap_or(widths.len());
    if stop < MIN_SECTIONS {
        return Some(format!(
            "the top of the body is {:.0}% of the height across and {:.0}% of the height below it the body is {:.0}% across: no head and neck above the shoulders",
            100.0 * widths.first().copied().unwrap_or(0.0),
            100.0 * STEP * stop as f64,
            100.0 * widths.get(stop).copied().unwrap_or(0.0)
        ));
    }
    let (at, widest) = widths[..stop]
        .iter()
        .enumerate()
        .fold((0, 0.0f64), |b, (i, &w)| if w > b.1 { (i, w) } else { b });
    let neck = widths[at..stop]
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    (neck > NECK_SHARE * widest).then(|| {
        format!(
            "nothing narrows below the top of the body into a neck (widest {:.0}% of the height across, narrowest below it {:.0}%)",
            100.0 * widest,
            100.0 * neck
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sections of samba, crane, SMPL and the captures cut at the
    /// chin (the module's figures, every 1 % of the height).
    #[test]
    fn heads_narrow_into_a_neck_and_cuts_do_not() {
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
        assert!(cut_at_neck(&samba).is_none());
        assert!(cut_at_neck(&crane).is_none());
        assert!(cut_at_neck(&samba_cut).is_some());
        assert!(cut_at_neck(&crane_cut).is_some());
        // A column as wide as a head down to the trunk: no neck.
        let column = [0.12; 12];
        let mut with_trunk = column.to_vec();
        with_trunk.push(0.25);
        assert!(cut_at_neck(&with_trunk).unwrap().contains("narrows"));
        // Scale-free: widths are fractions of the height already.
        assert!(cut_at_neck(&[]).is_some());
    }
}
