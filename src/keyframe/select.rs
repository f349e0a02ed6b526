//! Key-frame transitions chosen by their measured distortion (Huang et al.
//! 2015, Sec. 4.2, Eqs. 2-5, with the geometric dissimilarity of Sec. 6.1).
//!
//! The Surface Motion Graph keeps, per ordered sequence pair, the top `N`
//! local minima of the shape-histogram matrix (Eq. 5 on `C`). The
//! histogram is blind to where the limbs are: on the samba capture its
//! third-best transition pairs frames 18 cm apart (surface Hausdorff
//! distance of the centre frames). Sec. 4.2 defines the optimal
//! transition as the one of least distortion of the overlapping frames;
//! here the distortion of every candidate is *measured* as Sec. 6.1 does
//! (the α′(k)-weighted surface Hausdorff distance of the overlapping
//! frames after the floor alignment, [`super::smoothness`]) instead of
//! approximated by the histogram:
//!
//! 1. candidates: up to [`SelectOptions::candidates`] local minima of `C`
//!    per sequence pair that has an edge in the graph (so `forbid` edits
//!    hold; single `remove` edits are dropped too), as the graph finds
//!    them;
//! 2. screen: the Hausdorff distance of the centre frames on every
//!    [`SelectOptions::stride`]-th vertex (cheap, a lower bound);
//! 3. the best `N` per pair (`2N` within one sequence: a loop and a skip
//!    per frame pair, as the graph) get their full profile, and the window
//!    `L ∈ [min_window, max_window]` minimising the weighted distance
//!    (Eq. 5 with the measured distance, per frame) is kept, with that
//!    distance as the transition's cost (Eq. 8, metres).
//!
//! Only the key-frame search uses them ([`super::TransitionSet::Measured`]);
//! the graph (and so `retarget`) is unchanged.

use super::smoothness::{Surface, hausdorff_surface_stride, profile, weighted};
use crate::db::Character;
use crate::graph::FlatFrame;
use crate::graph::transitions::{self, TransitionOptions};
use rayon::prelude::*;

/// Options of the measured selection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectOptions {
    /// Local minima of `C` considered per ordered sequence pair. Default: 48.
    pub candidates: usize,
    /// Vertex stride of the screening distance. Default: 8.
    pub stride: usize,
    /// Largest half-window L. Default: 8.
    pub max_window: usize,
}

impl Default for SelectOptions {
    fn default() -> Self {
        SelectOptions {
            candidates: 48,
            stride: 8,
            max_window: 8,
        }
    }
}

/// A chosen transition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chosen {
    /// Frame left.
    pub from: FlatFrame,
    /// Frame entered (`frame entered − 1` pairs with `from`).
    pub to: FlatFrame,
    /// Blend half-window.
    pub window: usize,
    /// Weighted surface Hausdorff distance (metres).
    pub smoothness: f64,
}

/// The transitions of the character's graph re-chosen by measured
/// distortion (module docs), best first within each sequence pair.
pub fn measured(ch: &Character, opts: &SelectOptions) -> Vec<Chosen> {
    measured_with(ch, opts, &mut |_, _| {})
}

/// [`measured`], telling `progress(done, total)` the sequence pairs done.
pub(crate) fn measured_with(
    ch: &Character,
    opts: &SelectOptions,
    progress: &mut dyn FnMut(usize, usize),
) -> Vec<Chosen> {
    let g = ch.graph();
    let topts = g.options();
    let lo = topts.min_window.max(1);
    let hi = opts.max_window.max(lo);
    let surface = Surface::new(ch.topology().triangles(), ch.n());
    let fopts = TransitionOptions {
        top_n: opts.candidates,
        max_window: hi,
        min_window: lo,
        min_gap: topts.min_gap,
    };
    let mut pairs: Vec<(usize, usize)> = g.edges().iter().map(|e| (e.from, e.to)).collect();
    pairs.sort_unstable();
    pairs.dedup();
    let mut out = Vec::new();
    let total = pairs.len();
    for (done, (i, j)) in pairs.into_iter().enumerate() {
        progress(done, total);
        let c = |r: usize, s: usize| ch.matrix().between(i, r, j, s);
        let (li, lj) = (g.sequences()[i].len, g.sequences()[j].len);
        let cands: Vec<(usize, usize)> = transitions::find(&c, li, lj, i == j, &fopts)
            .into_iter()
            .map(|(m, n, _, _)| (m, n))
            .filter(|&(m, n)| n + 1 < lj && !removed(ch, i, m, j, n))
            .collect();
        let mut screened: Vec<((usize, usize), f64)> = cands
            .par_iter()
            .map(|&(m, n)| {
                let (a, b) = (g.flat_id(i, m), g.flat_id(j, n).next());
                (
                    (m, n),
                    hausdorff_surface_stride(ch, &surface, a, b, opts.stride),
                )
            })
            .collect();
        screened.sort_by(|a, b| a.1.total_cmp(&b.1));
        let keep = if i == j { 2 * topts.top_n } else { topts.top_n };
        let mut kept: Vec<(usize, usize)> = Vec::new();
        for ((m, n), _) in screened {
            if kept.len() >= keep {
                break;
            }
            // Not within the blend window of a kept one (as the graph).
            let clash = kept
                .iter()
                .any(|k| k.0.abs_diff(m) <= hi && k.1.abs_diff(n) <= hi && i != j);
            if !clash {
                kept.push((m, n));
            }
        }
        let mut chosen: Vec<Chosen> = kept
            .par_iter()
            .map(|&(m, n)| {
                let (a, b) = (g.flat_id(i, m), g.flat_id(j, n).next());
                let fit = m.min(n).min(li - 1 - m).min(lj - 1 - n).clamp(lo, hi);
                let h = profile(ch, &surface, a, b, fit, false);
                let (window, smoothness) = (lo..=fit)
                    .rev()
                    .map(|l| (l, weighted(&h[fit - l..=fit + l], l, |x| x.0)))
                    .min_by(|x, y| x.1.total_cmp(&y.1))
                    .unwrap_or((lo, f64::INFINITY));
                Chosen {
                    from: a,
                    to: b,
                    window,
                    smoothness,
                }
            })
            .collect();
        chosen.sort_by(|a, b| a.smoothness.total_cmp(&b.smoothness));
        out.extend(chosen);
    }
    progress(total, total);
    out
}

/// True when a `remove` edit of the graph dropped `(i, m) → (j, n)`.
fn removed(ch: &Character, i: usize, m: usize, j: usize, n: usize) -> bool {
    let s = ch.graph().sequences();
    let text = format!("{}:{} -> {}:{}", s[i].name, m, s[j].name, n);
    ch.graph().removed().contains(&text)
}
