//! Surface quality of a result read off the mesh alone, against the
//! capture's own distribution per body region (issue 42): what a person
//! sees that the skeleton figures do not (crumpled hems, folded slivers,
//! creases, a hand through the waist).
//!
//! Seven checks, each counting *flagged* elements of a frame — elements
//! outside anything the database's captured frames show at that element
//! (or, for roughness, in that region):
//!
//! - **turned over (rest)**: triangles turned over against the rest frame
//!   ([`RestTriangles`], neighbourhoods aligned rigidly), outside the
//!   triangles the capture itself turns over grown by
//!   [`SurfaceOptions::rings`] (the samba dress folds over a thigh: up to
//!   74 triangles in one captured frame, all on the skirt);
//! - **turned over (retrieved)**: the same against the *nearest database
//!   frame* (below) instead of the rest frame, outside the capture's own
//!   zone measured the same way between captured frames;
//! - **creases**: interior edges whose bend (signed dihedral angle,
//!   [`Edges::bends`]) lies more than [`SurfaceOptions::crease_margin_deg`]
//!   outside the range the captured frames show at that edge (or any
//!   edge within [`SurfaceOptions::pool_rings`]), measured the short way
//!   round the circle (a fold of +179° is 2° from −179°);
//! - **rough**: vertices whose mean bend deviation over their edges from
//!   the nearest database frame is above the most the capture shows in
//!   their region (each captured frame against its nearest captured frame
//!   at least [`SurfaceOptions::exclude_frames`] away in its sequence),
//!   times [`SurfaceOptions::roughness_factor`];
//! - **slivers**: triangles whose shape quality
//!   ([`crate::mesh::quality::triangle_quality`]) is below
//!   [`SurfaceOptions::sliver_factor`] of the worst the capture shows at
//!   that triangle;
//! - **stretched**: edges whose length over their rest length lies beyond
//!   the captured range at that edge by more than
//!   [`SurfaceOptions::stretch_factor`] (either way);
//! - **crossings**: triangles passing through a triangle of another body
//!   part ([`crossing_pairs`]: a skirt through a leg, a hand through the
//!   waist), outside the triangles that cross in the capture grown by
//!   [`SurfaceOptions::rings`].
//!
//! The *nearest database frame* of a frame is, of the
//! [`SurfaceOptions::candidates`] database frames with the nearest
//! skeletons (Huang et al. 2015, Eq. 28, joints regressed from the
//! surface), the one whose bends differ least on average.
//!
//! Regions are the rig's body parts ([`Part`]); a triangle or an edge
//! belongs to the part of its first vertex. Everything is read in metres
//! (as the database's frames are held and `retarget` writes), and every
//! check but the turned-over ones is the same under any rigid motion and
//! uniform scale; the turned-over ones under any rigid motion.

use super::EvalError;
use super::triangles::{RestTriangles, TurnScratch};
use crate::db::Character;
use crate::deform::unflip::Adjacency;
use crate::embed::Embedding;
use crate::embed::parts::Part;
use crate::mesh::quality::{Edges, crossing_pairs, qualities};
use crate::pose::Pose;
use crate::pose::measure::skeleton_distance;
use rayon::prelude::*;
use serde::Serialize;
use std::cmp::Ordering;

/// The thresholds of the checks (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SurfaceOptions {
    /// Degrees beyond the captured bend range at an edge that make a
    /// crease. Default 30.
    pub crease_margin_deg: f64,
    /// Multiple of the capture's largest roughness in a region above which
    /// a vertex is rough. Default 1.
    pub roughness_factor: f64,
    /// Fraction of the capture's worst quality at a triangle below which it
    /// is a sliver. Default 0.5.
    pub sliver_factor: f64,
    /// Factor beyond the captured stretch range at an edge that makes it
    /// stretched (over the most, under the least). Default 1.5.
    pub stretch_factor: f64,
    /// Rings of vertices the capture's own turned-over and crossing
    /// triangles are grown by before results are held to them. Default 2.
    pub rings: usize,
    /// A captured frame's nearest frame is at least this many frames away
    /// in its own sequence (any frame of another sequence). Default 5.
    pub exclude_frames: usize,
    /// Database frames with the nearest skeletons compared surface to
    /// surface for the nearest frame. Default 5.
    pub candidates: usize,
    /// Rings of vertices over which each element's captured range (bend,
    /// quality, stretch) is pooled: an element is held to the widest range
    /// the capture shows at it or at any element within this many rings.
    /// A range read off a finite sample of frames at one element alone
    /// does not hold for the capture's other frames (leave-half-out on
    /// samba: 116 creases, 21 slivers, 12 stretched edges on one thigh
    /// with 0 rings). Default 1.
    pub pool_rings: usize,
}

impl Default for SurfaceOptions {
    fn default() -> Self {
        SurfaceOptions {
            crease_margin_deg: 30.0,
            roughness_factor: 1.0,
            sliver_factor: 0.5,
            stretch_factor: 1.5,
            rings: 2,
            exclude_frames: 5,
            candidates: 5,
            pool_rings: 1,
        }
    }
}

/// The checks, in the order of [`RegionSurface`]'s fields.
pub const CHECKS: [&str; 7] = [
    "turned over (rest)",
    "turned over (retrieved)",
    "creases",
    "rough vertices",
    "slivers",
    "stretched edges",
    "crossings",
];

const TURNED_REST: usize = 0;
const TURNED_RETRIEVED: usize = 1;
const CREASE: usize = 2;
const ROUGH: usize = 3;
const SLIVER: usize = 4;
const STRETCH: usize = 5;
const CROSSING: usize = 6;

/// The database a result is compared with: its frames (metres, Y-up),
/// where each sits in its sequence, the skeleton of each, the rest frame,
/// the connectivity and the part labels.
#[derive(Debug, Clone, Copy)]
pub struct Captured<'a> {
    /// Rest frame (metres, Y-up).
    pub rest: &'a [[f64; 3]],
    /// Triangles.
    pub triangles: &'a [[u32; 3]],
    /// The rig: part labels, and the joints regressed from a surface.
    pub rig: &'a Embedding,
    /// All captured frames, frame-major (metres, Y-up).
    pub frames: &'a [[f64; 3]],
    /// `(sequence, frame in it)` of each captured frame.
    pub ids: &'a [(u32, u32)],
}

/// Per-frame figures before any threshold.
struct Raw {
    bends: Vec<f64>,
    lengths: Vec<f64>,
    quality: Vec<f64>,
    turned_rest: Vec<u32>,
    turned_retrieved: Vec<u32>,
    /// Per vertex, radians.
    rough: Vec<f64>,
    crossing: Vec<u32>,
    nearest: u32,
}

/// The angle between two bends (radians, in [0, π]): a bend of +179°
/// and one of −179° are 2° apart (both nearly folded flat).
fn bend_difference(a: f64, b: f64) -> f64 {
    let d = (a - b).abs() % std::f64::consts::TAU;
    if d > std::f64::consts::PI {
        std::f64::consts::TAU - d
    } else {
        d
    }
}

/// How far (radians) a bend `x` lies outside the captured range
/// `lo..=hi`, the short way round the circle: bends are angles, and a
/// fold of +179° is 2° from a captured −179°, not 358° (0 inside the
/// range, NaN for a non-finite `x`).
fn bend_outside(x: f64, lo: f64, hi: f64) -> f64 {
    if !x.is_finite() {
        return f64::NAN;
    }
    if x >= lo && x <= hi {
        0.0
    } else {
        bend_difference(x, lo).min(bend_difference(x, hi))
    }
}

/// The topology and the database, read once.
struct Base<'a> {
    cap: Captured<'a>,
    n: usize,
    edges: Edges,
    vertex_part: Vec<u8>,
    tri_part: Vec<u8>,
    edge_part: Vec<u8>,
    rest: RestTriangles,
    rest_lengths: Vec<f64>,
    poses: Vec<Pose>,
    /// Edges at each vertex (CSR).
    vedge_start: Vec<usize>,
    vedge: Vec<u32>,
    adjacency: Adjacency,
}

impl<'a> Base<'a> {
    fn new(cap: Captured<'a>) -> Result<Base<'a>, EvalError> {
        let n = cap.rest.len();
        if cap.rig.labels.len() != n {
            return Err(EvalError::Labels {
                have: cap.rig.labels.len(),
                want: n,
            });
        }
        if n == 0 || cap.frames.len() % n != 0 || cap.frames.len() / n != cap.ids.len() {
            return Err(EvalError::VertexCount {
                have: if cap.ids.is_empty() {
                    0
                } else {
                    cap.frames.len() / cap.ids.len()
                },
                want: n,
            });
        }
        let rest = RestTriangles::new(cap.rest, cap.triangles)?;
        let edges = Edges::new(cap.triangles);
        let vertex_part = cap.rig.labels.clone();
        let tri_part = cap
            .triangles
            .iter()
            .map(|t| vertex_part[t[0] as usize])
            .collect();
        let edge_part = edges
            .ends
            .iter()
            .map(|e| vertex_part[e[0] as usize])
            .collect();
        let mut rest_lengths = Vec::new();
        edges.lengths(cap.rest, &mut rest_lengths);
        let poses = cap
            .frames
            .par_chunks_exact(n)
            .map(|f| cap.rig.frame_joints(f))
            .collect();
        let mut count = vec![0usize; n + 1];
        for e in &edges.ends {
            count[e[0] as usize + 1] += 1;
            count[e[1] as usize + 1] += 1;
        }
        for v in 0..n {
            count[v + 1] += count[v];
        }
        let mut fill = count.clone();
        let mut vedge = vec![0u32; count[n]];
        for (i, e) in edges.ends.iter().enumerate() {
            for &v in e {
                vedge[fill[v as usize]] = i as u32;
                fill[v as usize] += 1;
            }
        }
        Ok(Base {
            n,
            edges,
            vertex_part,
            tri_part,
            edge_part,
            rest,
            rest_lengths,
            poses,
            vedge_start: count,
            vedge,
            adjacency: Adjacency::new(n, cap.triangles),
            cap,
        })
    }

    fn frame(&self, id: usize) -> &[[f64; 3]] {
        &self.cap.frames[id * self.n..(id + 1) * self.n]
    }

    /// The figures of `frame`; `own`: the captured frame it is (its nearest
    /// frame is then taken away from it in its sequence).
    fn raw(&self, frame: &[[f64; 3]], own: Option<usize>, o: &SurfaceOptions) -> Raw {
        let mut bends = Vec::new();
        self.edges.bends(frame, &mut bends);
        let mut lengths = Vec::new();
        self.edges.lengths(frame, &mut lengths);
        let mut quality = Vec::new();
        qualities(self.cap.triangles, frame, &mut quality);
        let turned_rest = self.rest.turned_over(frame, &mut TurnScratch::default());
        // The nearest captured frame.
        let joints = self.cap.rig.frame_joints(frame);
        let far_enough = |id: usize| match own {
            None => true,
            Some(me) => {
                let (a, b) = (self.cap.ids[me], self.cap.ids[id]);
                a.0 != b.0 || a.1.abs_diff(b.1) as usize >= o.exclude_frames.max(1)
            }
        };
        let mut near: Vec<(f64, usize)> = self
            .poses
            .iter()
            .enumerate()
            .filter(|(id, _)| far_enough(*id))
            .map(|(id, p)| (skeleton_distance(&joints, p), id))
            .collect();
        let k = o.candidates.max(1).min(near.len());
        let mut rough = vec![0.0; self.n];
        let mut turned_retrieved = Vec::new();
        let mut nearest = u32::MAX;
        if k > 0 {
            near.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
            let mut other = Vec::new();
            let mut best: Option<(f64, usize, Vec<f64>)> = None;
            for &(_, id) in &near[..k] {
                self.edges.bends(self.frame(id), &mut other);
                let d: f64 = bends
                    .iter()
                    .zip(&other)
                    .map(|(a, b)| bend_difference(*a, *b))
                    .sum::<f64>();
                let d = if d.is_finite() { d } else { f64::INFINITY };
                if best.as_ref().is_none_or(|b| d < b.0) {
                    best = Some((d, id, std::mem::take(&mut other)));
                }
            }
            if let Some((_, id, theirs)) = best {
                nearest = id as u32;
                for (v, r) in rough.iter_mut().enumerate() {
                    let es = &self.vedge[self.vedge_start[v]..self.vedge_start[v + 1]];
                    if es.is_empty() {
                        continue;
                    }
                    let s: f64 = es
                        .iter()
                        .map(|&e| bend_difference(bends[e as usize], theirs[e as usize]))
                        .sum();
                    *r = s / es.len() as f64;
                }
                if let Ok(rt) = RestTriangles::new(self.frame(id), self.cap.triangles) {
                    turned_retrieved = rt.turned_over(frame, &mut TurnScratch::default());
                }
            }
        }
        let mut crossing: Vec<u32> = crossing_pairs(self.cap.triangles, frame, &self.tri_part)
            .into_iter()
            .flatten()
            .collect();
        crossing.sort_unstable();
        crossing.dedup();
        Raw {
            bends,
            lengths,
            quality,
            turned_rest,
            turned_retrieved,
            rough,
            crossing,
            nearest,
        }
    }

    /// Per-element values pooled over `rings` rings of vertices: each
    /// element (vertices `corners(e)`) takes the least (`least`) or the
    /// most of the values of every element within `rings` rings of its
    /// vertices (0: unchanged).
    fn pooled<'c>(
        &self,
        values: &[f64],
        corners: impl Fn(usize) -> &'c [u32],
        least: bool,
        rings: usize,
    ) -> Vec<f64> {
        if rings == 0 {
            return values.to_vec();
        }
        let pick = |a: f64, b: f64| if least { a.min(b) } else { a.max(b) };
        let init = if least {
            f64::INFINITY
        } else {
            f64::NEG_INFINITY
        };
        let mut at = vec![init; self.n];
        for (e, &x) in values.iter().enumerate() {
            for &v in corners(e) {
                at[v as usize] = pick(at[v as usize], x);
            }
        }
        for _ in 1..rings {
            let before = at.clone();
            for (v, a) in at.iter_mut().enumerate() {
                for &w in &self.adjacency.vertices[v] {
                    *a = pick(*a, before[w as usize]);
                }
            }
        }
        (0..values.len())
            .map(|e| {
                corners(e)
                    .iter()
                    .fold(init, |m, &v| pick(m, at[v as usize]))
            })
            .collect()
    }

    /// The triangles of `marked` grown by `rings` rings of vertices.
    fn grown(&self, marked: &[bool], rings: usize) -> Vec<bool> {
        let mut on = vec![false; self.n];
        for (t, _) in marked.iter().enumerate().filter(|x| *x.1) {
            for &v in &self.cap.triangles[t] {
                on[v as usize] = true;
            }
        }
        for _ in 1..rings {
            let before = on.clone();
            for (v, _) in before.iter().enumerate().filter(|x| *x.1) {
                for &w in &self.adjacency.vertices[v] {
                    on[w as usize] = true;
                }
            }
        }
        if rings == 0 {
            return marked.to_vec();
        }
        self.cap
            .triangles
            .iter()
            .map(|t| t.iter().any(|&v| on[v as usize]))
            .collect()
    }
}

/// The capture's own range, element by element and region by region.
#[derive(Clone)]
struct Stats {
    bend_lo: Vec<f64>,
    bend_hi: Vec<f64>,
    quality_min: Vec<f64>,
    stretch_lo: Vec<f64>,
    stretch_hi: Vec<f64>,
    turned_rest: Vec<bool>,
    turned_retrieved: Vec<bool>,
    crossing: Vec<bool>,
    rough_max: [f64; Part::COUNT],
    /// The most of each check's raw count in one frame, per region.
    raw_max: [[usize; 3]; Part::COUNT],
}

impl Stats {
    fn empty(edges: usize, triangles: usize) -> Stats {
        Stats {
            bend_lo: vec![f64::INFINITY; edges],
            bend_hi: vec![f64::NEG_INFINITY; edges],
            quality_min: vec![f64::INFINITY; triangles],
            stretch_lo: vec![f64::INFINITY; edges],
            stretch_hi: vec![f64::NEG_INFINITY; edges],
            turned_rest: vec![false; triangles],
            turned_retrieved: vec![false; triangles],
            crossing: vec![false; triangles],
            rough_max: [0.0; Part::COUNT],
            raw_max: [[0; 3]; Part::COUNT],
        }
    }

    fn absorb(mut self, b: &Base, r: &Raw) -> Stats {
        for (e, &x) in r.bends.iter().enumerate() {
            self.bend_lo[e] = self.bend_lo[e].min(x);
            self.bend_hi[e] = self.bend_hi[e].max(x);
        }
        for (e, &l) in r.lengths.iter().enumerate() {
            let s = l / b.rest_lengths[e].max(f64::MIN_POSITIVE);
            self.stretch_lo[e] = self.stretch_lo[e].min(s);
            self.stretch_hi[e] = self.stretch_hi[e].max(s);
        }
        for (t, &q) in r.quality.iter().enumerate() {
            self.quality_min[t] = self.quality_min[t].min(q);
        }
        let mut count = [[0usize; 3]; Part::COUNT];
        for (list, zone, k) in [
            (&r.turned_rest, &mut self.turned_rest, 0),
            (&r.turned_retrieved, &mut self.turned_retrieved, 1),
            (&r.crossing, &mut self.crossing, 2),
        ] {
            for &t in list {
                zone[t as usize] = true;
                count[b.tri_part[t as usize] as usize][k] += 1;
            }
        }
        for (p, c) in count.iter().enumerate() {
            for (m, x) in self.raw_max[p].iter_mut().zip(c) {
                *m = (*m).max(*x);
            }
        }
        for (v, &x) in r.rough.iter().enumerate() {
            let p = b.vertex_part[v] as usize;
            self.rough_max[p] = self.rough_max[p].max(x);
        }
        self
    }

    fn merge(mut self, o: Stats) -> Stats {
        let lo =
            |a: &mut Vec<f64>, b: &[f64]| a.iter_mut().zip(b).for_each(|(x, y)| *x = x.min(*y));
        let hi =
            |a: &mut Vec<f64>, b: &[f64]| a.iter_mut().zip(b).for_each(|(x, y)| *x = x.max(*y));
        let or = |a: &mut Vec<bool>, b: &[bool]| a.iter_mut().zip(b).for_each(|(x, y)| *x |= *y);
        lo(&mut self.bend_lo, &o.bend_lo);
        hi(&mut self.bend_hi, &o.bend_hi);
        lo(&mut self.quality_min, &o.quality_min);
        lo(&mut self.stretch_lo, &o.stretch_lo);
        hi(&mut self.stretch_hi, &o.stretch_hi);
        or(&mut self.turned_rest, &o.turned_rest);
        or(&mut self.turned_retrieved, &o.turned_retrieved);
        or(&mut self.crossing, &o.crossing);
        for p in 0..Part::COUNT {
            self.rough_max[p] = self.rough_max[p].max(o.rough_max[p]);
            for k in 0..3 {
                self.raw_max[p][k] = self.raw_max[p][k].max(o.raw_max[p][k]);
            }
        }
        self
    }
}

/// The capture's distribution a result is held to (build once per
/// database, then [`SurfaceReference::measure`] any number of results).
pub struct SurfaceReference<'a> {
    base: Base<'a>,
    stats: Stats,
    options: SurfaceOptions,
}

/// One frame's flags: per region, per check ([`CHECKS`] order).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameSurface {
    /// Flagged elements per region ([`Part::ALL`] order), per check.
    pub flags: [[usize; 7]; Part::COUNT],
    /// Raw counts per region: turned over (rest), turned over
    /// (retrieved), crossing triangles, before the capture's zones.
    pub raw: [[usize; 3]; Part::COUNT],
    /// The largest roughness per region (degrees).
    pub rough_max_deg: [f64; Part::COUNT],
    /// The largest bend beyond the captured range per region (degrees; 0
    /// inside it).
    pub bend_excess_deg: [f64; Part::COUNT],
    /// The nearest database frame (flat id; `u32::MAX` with no database
    /// frame far enough).
    pub nearest: u32,
}

impl FrameSurface {
    /// Flags of the frame, all regions and checks.
    pub fn total(&self) -> usize {
        self.flags.iter().flatten().sum()
    }
}

impl<'a> SurfaceReference<'a> {
    /// The reference of a database's captured frames.
    pub fn new(
        cap: Captured<'a>,
        options: SurfaceOptions,
    ) -> Result<SurfaceReference<'a>, EvalError> {
        let base = Base::new(cap)?;
        let (ne, nt) = (base.edges.len(), cap.triangles.len());
        let stats = (0..cap.ids.len())
            .into_par_iter()
            .fold(
                || Stats::empty(ne, nt),
                |s, id| {
                    let r = base.raw(base.frame(id), Some(id), &options);
                    s.absorb(&base, &r)
                },
            )
            .reduce(|| Stats::empty(ne, nt), Stats::merge);
        let k = options.pool_rings;
        let (ends, tris) = (&base.edges.ends, cap.triangles);
        let edge = |e: usize| -> &[u32] { &ends[e] };
        let tri = |t: usize| -> &[u32] { &tris[t] };
        let stats = Stats {
            bend_lo: base.pooled(&stats.bend_lo, edge, true, k),
            bend_hi: base.pooled(&stats.bend_hi, edge, false, k),
            stretch_lo: base.pooled(&stats.stretch_lo, edge, true, k),
            stretch_hi: base.pooled(&stats.stretch_hi, edge, false, k),
            quality_min: base.pooled(&stats.quality_min, tri, true, k),
            turned_rest: base.grown(&stats.turned_rest, options.rings),
            turned_retrieved: base.grown(&stats.turned_retrieved, options.rings),
            crossing: base.grown(&stats.crossing, options.rings),
            ..stats
        };
        Ok(SurfaceReference {
            base,
            stats,
            options,
        })
    }

    /// The options the reference was built with.
    pub fn options(&self) -> &SurfaceOptions {
        &self.options
    }

    /// The flags of one frame (the rest frame's vertex count, metres,
    /// Y-up).
    pub fn frame(&self, frame: &[[f64; 3]]) -> FrameSurface {
        self.frame_as(frame, None)
    }

    fn frame_as(&self, frame: &[[f64; 3]], own: Option<usize>) -> FrameSurface {
        let (b, s, o) = (&self.base, &self.stats, &self.options);
        let r = b.raw(frame, own, o);
        let mut out = FrameSurface {
            flags: [[0; 7]; Part::COUNT],
            raw: [[0; 3]; Part::COUNT],
            rough_max_deg: [0.0; Part::COUNT],
            bend_excess_deg: [0.0; Part::COUNT],
            nearest: r.nearest,
        };
        for (list, zone, k, c) in [
            (&r.turned_rest, &s.turned_rest, TURNED_REST, 0),
            (
                &r.turned_retrieved,
                &s.turned_retrieved,
                TURNED_RETRIEVED,
                1,
            ),
            (&r.crossing, &s.crossing, CROSSING, 2),
        ] {
            for &t in list {
                let p = b.tri_part[t as usize] as usize;
                out.raw[p][c] += 1;
                if !zone[t as usize] {
                    out.flags[p][k] += 1;
                }
            }
        }
        let margin = o.crease_margin_deg.to_radians();
        for (e, &x) in r.bends.iter().enumerate() {
            let p = b.edge_part[e] as usize;
            let excess = bend_outside(x, s.bend_lo[e], s.bend_hi[e]);
            let excess = if excess.is_nan() {
                f64::INFINITY
            } else {
                excess
            };
            out.bend_excess_deg[p] = out.bend_excess_deg[p].max(excess.to_degrees());
            if excess > margin {
                out.flags[p][CREASE] += 1;
            }
            let st = r.lengths[e] / b.rest_lengths[e].max(f64::MIN_POSITIVE);
            let f = o.stretch_factor;
            if !(st <= s.stretch_hi[e] * f && st >= s.stretch_lo[e] / f) {
                out.flags[p][STRETCH] += 1;
            }
        }
        for (v, &x) in r.rough.iter().enumerate() {
            let p = b.vertex_part[v] as usize;
            out.rough_max_deg[p] = out.rough_max_deg[p].max(x.to_degrees());
            // Above the line, or not a number.
            if !matches!(
                x.partial_cmp(&(s.rough_max[p] * o.roughness_factor)),
                Some(Ordering::Less | Ordering::Equal)
            ) {
                out.flags[p][ROUGH] += 1;
            }
        }
        for (t, &q) in r.quality.iter().enumerate() {
            if !matches!(
                q.partial_cmp(&(s.quality_min[t] * o.sliver_factor)),
                Some(Ordering::Greater | Ordering::Equal)
            ) {
                out.flags[b.tri_part[t] as usize][SLIVER] += 1;
            }
        }
        out
    }

    /// The edges (their two ends) of `frame` that [`SurfaceReference::frame`]
    /// counts as creases (a bend more than the margin outside the captured
    /// range at the edge, or not finite): where they lie, for a
    /// diagnosis (issue 42's knees).
    pub fn crease_edges(&self, frame: &[[f64; 3]]) -> Vec<[u32; 2]> {
        let (b, s) = (&self.base, &self.stats);
        let mut bends = Vec::new();
        b.edges.bends(frame, &mut bends);
        let margin = self.options.crease_margin_deg.to_radians();
        bends
            .iter()
            .enumerate()
            .filter(|&(e, &x)| {
                let excess = bend_outside(x, s.bend_lo[e], s.bend_hi[e]);
                excess.is_nan() || excess > margin
            })
            .map(|(e, _)| b.edges.ends[e])
            .collect()
    }

    /// The triangles of `frame` that [`SurfaceReference::frame`] counts as
    /// turned over against the rest frame (outside the capture's own zone):
    /// where they lie, for a diagnosis (issue 42).
    pub fn turned_rest_triangles(&self, frame: &[[f64; 3]]) -> Vec<u32> {
        let zone = &self.stats.turned_rest;
        let mut t = self
            .base
            .rest
            .turned_over(frame, &mut TurnScratch::default());
        t.retain(|&t| !zone[t as usize]);
        t
    }

    /// The flags of each captured frame of the reference itself, measured
    /// as a result would be but with its nearest frame taken away from it
    /// in its sequence (as the reference was built): 0 everywhere, by
    /// construction of the thresholds; a check that the reference is
    /// consistent.
    pub fn captured_frames(&self) -> Vec<FrameSurface> {
        (0..self.base.cap.ids.len())
            .into_par_iter()
            .map(|id| self.frame_as(self.base.frame(id), Some(id)))
            .collect()
    }

    /// The flags of every frame of `frames` (frame-major, metres, Y-up),
    /// summarised per region.
    pub fn measure(&self, frames: &[[f64; 3]]) -> Result<SurfaceReport, EvalError> {
        let n = self.base.n;
        if frames.len() % n != 0 {
            return Err(EvalError::VertexCount {
                have: frames.len(),
                want: n,
            });
        }
        let per: Vec<FrameSurface> = frames.par_chunks_exact(n).map(|f| self.frame(f)).collect();
        Ok(self.report(&per))
    }

    /// The summary of per-frame flags.
    pub fn report(&self, per: &[FrameSurface]) -> SurfaceReport {
        let s = &self.stats;
        let mut regions: Vec<RegionSurface> = Part::ALL
            .iter()
            .map(|&p| {
                let i = p.index();
                RegionSurface {
                    region: p,
                    vertices: self
                        .base
                        .vertex_part
                        .iter()
                        .filter(|&&x| x as usize == i)
                        .count(),
                    triangles: self
                        .base
                        .tri_part
                        .iter()
                        .filter(|&&x| x as usize == i)
                        .count(),
                    edges: self
                        .base
                        .edge_part
                        .iter()
                        .filter(|&&x| x as usize == i)
                        .count(),
                    checks: [CheckCount::default(); 7],
                    turned_rest_max: 0,
                    captured_turned_rest_max: s.raw_max[i][0],
                    turned_retrieved_max: 0,
                    captured_turned_retrieved_max: s.raw_max[i][1],
                    crossing_max: 0,
                    captured_crossing_max: s.raw_max[i][2],
                    rough_max_deg: 0.0,
                    captured_rough_max_deg: s.rough_max[i].to_degrees(),
                    bend_excess_max_deg: 0.0,
                }
            })
            .collect();
        let mut per_frame = Vec::with_capacity(per.len());
        for f in per {
            per_frame.push(f.total());
            for (i, r) in regions.iter_mut().enumerate() {
                for k in 0..7 {
                    let c = f.flags[i][k];
                    let x = &mut r.checks[k];
                    x.element_frames += c;
                    x.frames += (c > 0) as usize;
                    x.max_in_a_frame = x.max_in_a_frame.max(c);
                }
                r.turned_rest_max = r.turned_rest_max.max(f.raw[i][0]);
                r.turned_retrieved_max = r.turned_retrieved_max.max(f.raw[i][1]);
                r.crossing_max = r.crossing_max.max(f.raw[i][2]);
                r.rough_max_deg = r.rough_max_deg.max(f.rough_max_deg[i]);
                r.bend_excess_max_deg = r.bend_excess_max_deg.max(f.bend_excess_deg[i]);
            }
        }
        let (worst_frame, worst_flags) = per_frame
            .iter()
            .copied()
            .enumerate()
            .fold((0, 0), |b, (f, c)| if c > b.1 { (f, c) } else { b });
        SurfaceReport {
            frames: per.len(),
            flags: per_frame.iter().sum(),
            flagged_frames: per_frame.iter().filter(|&&c| c > 0).count(),
            worst_frame,
            worst_flags,
            checks: CHECKS,
            regions,
            per_frame,
            options: self.options,
        }
    }
}

/// A character's captured frames as a [`Captured`] (the rest frame in
/// metres is the caller's: [`Character::topology_metres`]).
pub fn captured_of<'a>(
    ch: &'a Character,
    rest_metres: &'a [[f64; 3]],
    ids: &'a [(u32, u32)],
) -> Captured<'a> {
    Captured {
        rest: rest_metres,
        triangles: ch.topology().triangles(),
        rig: ch.rig(),
        frames: ch.frames(),
        ids,
    }
}

/// `(sequence, frame)` of each of a character's frames (flat-id order).
pub fn frame_ids(ch: &Character) -> Vec<(u32, u32)> {
    crate::graph::FlatFrame::all(ch.frame_count())
        .map(|i| {
            let f = ch.frame_at(i);
            (f.seq, f.frame)
        })
        .collect()
}

/// One check over a sequence in one region.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct CheckCount {
    /// Flagged element-frames, summed over the frames.
    pub element_frames: usize,
    /// Frames with any flagged.
    pub frames: usize,
    /// The most flagged in one frame.
    pub max_in_a_frame: usize,
}

/// The checks of one region over a sequence, with its raw figures beside
/// the capture's.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RegionSurface {
    /// The body part.
    pub region: Part,
    /// Its vertices, triangles and interior edges.
    pub vertices: usize,
    /// Triangles (the part of their first vertex).
    pub triangles: usize,
    /// Interior edges (the part of their first end).
    pub edges: usize,
    /// Flags per check ([`CHECKS`] order).
    pub checks: [CheckCount; 7],
    /// The most triangles turned over against the rest frame in one frame
    /// (zones not subtracted), and the capture's most.
    pub turned_rest_max: usize,
    /// The capture's most turned over against the rest frame in a frame.
    pub captured_turned_rest_max: usize,
    /// The most turned over against the nearest database frame in one
    /// frame.
    pub turned_retrieved_max: usize,
    /// The capture's most, each captured frame against its nearest.
    pub captured_turned_retrieved_max: usize,
    /// The most triangles crossing another part in one frame.
    pub crossing_max: usize,
    /// The capture's most.
    pub captured_crossing_max: usize,
    /// The largest roughness of a vertex (degrees).
    pub rough_max_deg: f64,
    /// The capture's largest (the threshold before
    /// [`SurfaceOptions::roughness_factor`]).
    pub captured_rough_max_deg: f64,
    /// The largest bend beyond the captured range at an edge (degrees).
    pub bend_excess_max_deg: f64,
}

/// The surface checks of a sequence against a capture (see the module
/// docs).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SurfaceReport {
    /// Frames measured.
    pub frames: usize,
    /// Flagged element-frames, all regions and checks.
    pub flags: usize,
    /// Frames with any flag.
    pub flagged_frames: usize,
    /// The (first) frame with the most flags, and its count.
    pub worst_frame: usize,
    /// Flags in the worst frame.
    pub worst_flags: usize,
    /// The checks' names, the order of [`RegionSurface::checks`].
    pub checks: [&'static str; 7],
    /// Per region ([`Part::ALL`] order).
    pub regions: Vec<RegionSurface>,
    /// Flags of each frame.
    pub per_frame: Vec<usize>,
    /// The thresholds.
    pub options: SurfaceOptions,
}

impl SurfaceReport {
    /// A per-region table for the command line: each check's flagged
    /// element-frames (frames with any), then the raw maxima beside the
    /// capture's.
    pub fn text(&self) -> String {
        let mut s = format!(
            "surface: {} flags in {} of {} frames (worst frame {}: {})\n",
            self.flags, self.flagged_frames, self.frames, self.worst_frame, self.worst_flags
        );
        s += &format!(
            "{:<12} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}   {:>9} {:>9} {:>9} {:>11}\n",
            "region",
            "turn-rest",
            "turn-near",
            "creases",
            "rough",
            "slivers",
            "stretched",
            "crossing",
            "turn max",
            "cross max",
            "rough°",
            "crease+°"
        );
        for r in &self.regions {
            s += &format!("{:<12}", r.region.name());
            for c in &r.checks {
                s += &format!(" {:>10}", format!("{}({})", c.element_frames, c.frames));
            }
            s += &format!(
                "   {:>9} {:>9} {:>9} {:>11.0}\n",
                format!("{}/{}", r.turned_rest_max, r.captured_turned_rest_max),
                format!("{}/{}", r.crossing_max, r.captured_crossing_max),
                format!("{:.0}/{:.0}", r.rough_max_deg, r.captured_rough_max_deg),
                r.bend_excess_max_deg
            );
        }
        s += "(flagged element-frames (frames with any); maxima in one frame: result/capture; crease+°: the largest bend beyond the captured range)\n";
        s
    }
}
