//! Per-frame descriptors of a whole database for each measure, built one
//! sequence at a time (so only descriptors, never all meshes, stay in
//! memory) and compared pairwise by [`super::matrix::all_pairs`].

use super::histogram::{self, DESCRIPTOR_LEN, PHI_SUB, ShapeGrid, ShapeKernel, ShapeScratch};
use super::matrix::PairDistance;
use super::vertex::{self, VertexOptions};
use crate::pose::{Pose, measure::skeleton_distance};
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// A frame dissimilarity measure (Huang et al. 2015, Sec. 4.1 and Fig. 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Measure {
    /// 3D volumetric shape histogram, minimised over rotation about the
    /// vertical (Eq. 1).
    #[default]
    Shape,
    /// Vertex positions and velocities after floor alignment (Casas 2013).
    Vertex,
    /// Canonical joint positions after floor alignment (Eq. 28); needs a rig.
    Skeleton,
    /// 6D shape-colour histogram with a pyramid EMD (Sec. 4.1); needs
    /// vertex colours.
    Colour,
}

impl Measure {
    /// Lower-case name, as in the manifest and cache files.
    pub fn name(self) -> &'static str {
        match self {
            Measure::Shape => "shape",
            Measure::Vertex => "vertex",
            Measure::Skeleton => "skeleton",
            Measure::Colour => "colour",
        }
    }
    /// Unit of the values.
    pub fn unit(self) -> &'static str {
        match self {
            Measure::Shape => "L2 of unit-sum histograms",
            Measure::Vertex => "RMS length (file units)",
            Measure::Skeleton => "sum of 19 joint distances (file units)",
            Measure::Colour => "pyramid EMD of unit-mass 6D histograms (level-0 bins)",
        }
    }
}

pub use crate::mocap::units::y_up;

/// Per-frame φ spectra of shape histograms ([`histogram::describe`]) and
/// their rotation-minimised comparison, shared by the shape and colour sets.
#[derive(Debug, Clone, Default)]
struct Spectra {
    kernel: ShapeKernel,
    desc: Vec<f32>,
    norms: Vec<[f64; PHI_SUB]>,
}

impl Spectra {
    fn len(&self) -> usize {
        self.norms.len()
    }
    /// Room for `count` more frames; returns the new frames' descriptor and
    /// norm slots.
    fn grow(&mut self, count: usize) -> (&mut [f32], &mut [[f64; PHI_SUB]]) {
        let start = self.norms.len();
        self.desc.resize((start + count) * DESCRIPTOR_LEN, 0.0);
        self.norms.resize(start + count, [0.0; PHI_SUB]);
        (
            &mut self.desc[start * DESCRIPTOR_LEN..],
            &mut self.norms[start..],
        )
    }
    /// Eq. 1 from `a` to `b`: distance and rotation.
    fn compare(&self, a: usize, b: usize) -> (f64, f64) {
        let da = &self.desc[a * DESCRIPTOR_LEN..(a + 1) * DESCRIPTOR_LEN];
        let db = &self.desc[b * DESCRIPTOR_LEN..(b + 1) * DESCRIPTOR_LEN];
        self.kernel
            .distance(da, self.norms[a][0], db, &self.norms[b])
    }
}

impl Spectra {
    /// [`histogram::magnitudes`] of frame `a`.
    fn magnitudes(&self, a: usize, out: &mut [f32]) {
        histogram::magnitudes(
            &self.desc[a * DESCRIPTOR_LEN..(a + 1) * DESCRIPTOR_LEN],
            out,
        );
    }
}

/// Shape-histogram descriptors of every frame.
#[derive(Debug, Clone)]
pub struct ShapeSet {
    /// The database-wide binning.
    pub grid: ShapeGrid,
    spectra: Spectra,
    /// Occupied voxels per frame (for reports).
    pub voxels: Vec<u32>,
}

impl ShapeSet {
    /// Voxels per body height: the grid spacing is the rest frame's vertical
    /// extent divided by this (about 6·10⁴ voxels for a human body). At 160
    /// a samba frame turned about the vertical and moved on the floor is
    /// 0.002 from itself, against 0.03 for a different pose (96: 0.005).
    pub const VOXELS_PER_HEIGHT: f64 = 160.0;

    /// Most voxels a frame of the rest frame's volume may fill: where
    /// `height / VOXELS_PER_HEIGHT` would give more, the voxel grows until
    /// the rest volume is this many voxels. About six human bodies (a samba
    /// or crane frame is 6.5-7.5·10⁴, the armadillo scan 2.8·10⁵), so only
    /// compact solids are coarsened: a unit cube at height/160 was
    /// 160³ = 4.1·10⁶ voxels and 1.3 s a frame.
    pub const VOXEL_BUDGET: f64 = 4.0e5;

    /// The binning for a database whose rest frame is `(rest, triangles)`
    /// (Y-up): voxel size from the height, coarsened so that the rest
    /// volume is at most [`Self::VOXEL_BUDGET`] voxels, and `r_max` 1.25× the
    /// rest frame's largest distance from its centroid (bigger reaches fall
    /// in the outer bin). The volume is the enclosed one (divergence
    /// theorem about the centroid), bounded by the bounding box's for an
    /// open or inconsistently oriented surface. O(V + T).
    pub fn grid_for(rest: &[DVec3], triangles: &[[u32; 3]]) -> ShapeGrid {
        let (lo, hi) = rest.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let c = rest.iter().copied().sum::<DVec3>() / rest.len().max(1) as f64;
        let r = rest.iter().map(|p| p.distance(c)).fold(0.0, f64::max);
        let height = (hi.y - lo.y).max(r).max(f64::MIN_POSITIVE);
        let enclosed = triangles
            .iter()
            .filter_map(|t| {
                let [a, b, d] = t.map(|v| rest.get(v as usize).map(|p| *p - c));
                Some(a?.dot(b?.cross(d?)))
            })
            .sum::<f64>()
            .abs()
            / 6.0;
        let boxed = if rest.is_empty() {
            0.0
        } else {
            (hi - lo).x * (hi - lo).y * (hi - lo).z
        };
        let volume = enclosed.min(boxed);
        let voxel = (height / Self::VOXELS_PER_HEIGHT).max((volume / Self::VOXEL_BUDGET).cbrt());
        ShapeGrid {
            voxel,
            r_max: 1.25 * r.max(f64::MIN_POSITIVE),
        }
    }

    /// An empty set with the given binning.
    pub fn new(grid: ShapeGrid) -> ShapeSet {
        ShapeSet {
            grid,
            spectra: Spectra::default(),
            voxels: Vec::new(),
        }
    }

    /// Adds the frames of one sequence (`frames`: frame-major positions,
    /// `n` per frame), in parallel over frames.
    pub fn push_sequence(
        &mut self,
        frames: &[[f64; 3]],
        n: usize,
        triangles: &[[u32; 3]],
        z_up: bool,
    ) {
        let count = frames.len() / n.max(1);
        let start = self.voxels.len();
        self.voxels.resize(start + count, 0);
        let grid = self.grid;
        let (desc, norms) = self.spectra.grow(count);
        desc.par_chunks_mut(DESCRIPTOR_LEN)
            .zip(norms.par_iter_mut())
            .zip(self.voxels[start..].par_iter_mut())
            .zip(frames.par_chunks(n.max(1)))
            .for_each_init(
                || (ShapeScratch::default(), Vec::with_capacity(n)),
                |(scratch, pts), (((out, norms), voxels), f)| {
                    pts.clear();
                    pts.extend(f.iter().map(|p| y_up(*p, z_up)));
                    *voxels =
                        histogram::describe(pts, triangles, &grid, scratch, out, norms) as u32;
                },
            );
    }
}

impl super::sparse::Features for ShapeSet {
    fn feature_len(&self) -> usize {
        histogram::MAGNITUDES_LEN
    }
    fn feature(&self, a: usize, out: &mut [f32]) {
        self.spectra.magnitudes(a, out);
    }
}

impl PairDistance for ShapeSet {
    fn frames(&self) -> usize {
        self.spectra.len()
    }
    fn distance(&self, a: usize, b: usize) -> f64 {
        // The fine-shift search is not exactly symmetric; take the better
        // of the two directions so the matrix is.
        self.spectra
            .compare(a, b)
            .0
            .min(self.spectra.compare(b, a).0)
    }
}

/// Vertex position-and-velocity blocks of every frame.
#[derive(Debug, Clone)]
pub struct VertexSet {
    n: usize,
    opts: VertexOptions,
    blocks: Vec<f32>,
    norms: Vec<f64>,
}

impl VertexSet {
    /// An empty set for meshes of `n` vertices.
    pub fn new(n: usize, opts: VertexOptions) -> VertexSet {
        VertexSet {
            n,
            opts,
            blocks: Vec::new(),
            norms: Vec::new(),
        }
    }

    /// Adds the frames of one sequence (velocities stay inside it).
    pub fn push_sequence(&mut self, frames: &[[f64; 3]], z_up: bool) {
        let n = self.n.max(1);
        let count = frames.len() / n;
        let start = self.norms.len();
        let len = 6 * n;
        self.blocks.resize((start + count) * len, 0.0);
        self.norms.resize(start + count, 0.0);
        let at = |t: usize| -> Vec<DVec3> {
            frames[t * n..(t + 1) * n]
                .iter()
                .map(|p| y_up(*p, z_up))
                .collect()
        };
        let opts = self.opts;
        self.blocks[start * len..]
            .par_chunks_mut(len)
            .zip(self.norms[start..].par_iter_mut())
            .enumerate()
            .for_each(|(t, (out, norm))| {
                let x = at(t);
                let (prev, next) = if t > 0 {
                    (Some(at(t - 1)), None)
                } else if count > 1 {
                    (None, Some(at(1)))
                } else {
                    (None, None)
                };
                *norm = vertex::describe(&x, prev.as_deref(), next.as_deref(), &opts, out);
            });
    }
}

impl PairDistance for VertexSet {
    fn frames(&self) -> usize {
        self.norms.len()
    }
    fn distance(&self, a: usize, b: usize) -> f64 {
        let len = 6 * self.n;
        vertex::distance(
            &self.blocks[a * len..(a + 1) * len],
            self.norms[a],
            &self.blocks[b * len..(b + 1) * len],
            self.norms[b],
            self.n,
        )
    }
}

/// Canonical skeletons of every frame (Y-up).
#[derive(Debug, Clone, Default)]
pub struct SkeletonSet {
    /// One pose per frame.
    pub poses: Vec<Pose>,
}

impl PairDistance for SkeletonSet {
    fn frames(&self) -> usize {
        self.poses.len()
    }
    fn distance(&self, a: usize, b: usize) -> f64 {
        skeleton_distance(&self.poses[a], &self.poses[b])
    }
}

/// 6D shape-colour signatures of every frame, with the surface's 3D shape
/// spectra for the rotation search ([`super::colour`]).
#[derive(Debug, Clone)]
pub struct ColourSet {
    grid: ShapeGrid,
    spectra: Spectra,
    sigs: Vec<super::colour::Signature>,
    colours: Vec<[f64; 3]>,
}

impl ColourSet {
    /// An empty set with the binning and per-vertex colours (0..1).
    pub fn new(grid: ShapeGrid, colours: Vec<[f64; 3]>) -> ColourSet {
        ColourSet {
            grid,
            spectra: Spectra::default(),
            sigs: Vec::new(),
            colours,
        }
    }

    /// Adds the frames of one sequence, in parallel over frames.
    pub fn push_sequence(
        &mut self,
        frames: &[[f64; 3]],
        n: usize,
        triangles: &[[u32; 3]],
        z_up: bool,
    ) {
        let count = frames.len() / n.max(1);
        let grid = self.grid;
        let colours = &self.colours;
        let (desc, norms) = self.spectra.grow(count);
        let sigs: Vec<super::colour::Signature> = desc
            .par_chunks_mut(DESCRIPTOR_LEN)
            .zip(norms.par_iter_mut())
            .zip(frames.par_chunks(n.max(1)))
            .map_init(
                || (Vec::with_capacity(n), Vec::new(), Vec::new()),
                |(pts, samples, fine), ((out, norms), f)| {
                    pts.clear();
                    pts.extend(f.iter().map(|p| y_up(*p, z_up)));
                    super::colour::surface_samples(pts, triangles, samples);
                    histogram::describe_weighted(samples, &grid, fine, out, norms);
                    super::colour::signature(samples, colours, &grid)
                },
            )
            .collect();
        self.sigs.extend(sigs);
    }
}

impl PairDistance for ColourSet {
    fn frames(&self) -> usize {
        self.spectra.len()
    }
    fn distance(&self, a: usize, b: usize) -> f64 {
        thread_local! {
            static SCRATCH: std::cell::RefCell<super::colour::EmdScratch> =
                std::cell::RefCell::new(Default::default());
        }
        let nfine = (histogram::PHI_BINS * PHI_SUB) as f64;
        let step = std::f64::consts::TAU / nfine;
        SCRATCH.with(|sc| {
            let sc = &mut sc.borrow_mut();
            // One direction: the matrix is filled from its upper triangle,
            // so it is symmetric by construction.
            let (_, ab) = self.spectra.compare(a, b);
            let sh = ((ab / step).round() as usize) % nfine as usize;
            super::colour::emd(&self.sigs[a], &self.sigs[b], sh, sc)
        })
    }
}
