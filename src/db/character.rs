//! A character database loaded for synthesis (Huang et al. 2015, Sec. 5.2):
//! every frame's positions, its extracted skeleton, the similarity matrix
//! and the Surface Motion Graph.
//!
//! Frames and skeletons are converted once, on load, to metres, Y-up (the
//! crate's convention); the topology and the rig stay in the files' units
//! and axes (the rig is embedded on the file's rest frame), and
//! [`Character::topology_metres`] gives the topology for output.
//!
//! Which skeleton each stage reads: [`CharacterOptions::skeleton`]
//! (default [`SkeletonKind::Regressor`], the joints as measured) feeds the
//! graph-side consumers of [`Character::poses`] — trellis retrieval (Eq. 28),
//! placement, deformation binding and the plausibility checks. The graph's
//! `skeleton` measure reads the regressor joints in `db build`; `db
//! skeleton` writes [`SkeletonKind::Rigid`] by default.

use crate::db::build::{BuildOptions, BuildProgress, build_opened_staged};
use crate::db::examples::ExampleMemo;
use crate::db::frames::{CacheInputs, Conversion, FrameStore, open_or_build};
use crate::db::rig_cache::{RigSource, embed_rig_cached};
use crate::db::{DbError, MANIFEST, Manifest};
use crate::embed::Embedding;
use crate::embed::frames::SkeletonKind;
use crate::graph::{FlatFrame, FrameAdjacency, FrameId, SurfaceMotionGraph};
use crate::mesh::Mesh;
use crate::mocap::units::y_up;
use crate::pose::Pose;
use crate::similarity::Similarity;
use crate::similarity::skeleton_index::PoseIndex;
use crate::util::stages::Stages;
use glam::DVec3;
use std::path::Path;

/// Options of [`Character::load_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CharacterOptions {
    /// How each frame's skeleton is read off its surface (see the module
    /// docs for which stage reads it). Default: [`SkeletonKind::Regressor`]
    /// (the measured joints; whether retrieval gains from the rigid
    /// skeleton is not yet measured). Note that [`SkeletonKind::default`]
    /// is `Rigid`, the default of `db skeleton`.
    pub skeleton: SkeletonKind,
}

impl Default for CharacterOptions {
    fn default() -> Self {
        CharacterOptions {
            skeleton: crate::db::frames::LOAD_SKELETON,
        }
    }
}

/// A loaded character. Built by [`Character::load`] (or
/// [`Character::load_with`]); read through its accessors.
pub struct Character {
    /// The manifest.
    manifest: Manifest,
    /// Topology (file units and axes).
    topology: Mesh,
    /// The rig embedded on the topology's rest frame.
    rig: Embedding,
    /// All frames of all sequences, frame-major, metres, Y-up (converted
    /// once, into the memory-mapped frame cache).
    frames: FrameStore,
    /// Vertices per frame.
    n: usize,
    /// Skeleton of every frame (metres, Y-up).
    poses: Vec<Pose>,
    /// The rig's rest joints (metres, Y-up).
    rest_pose: Pose,
    /// The similarity matrix of the graph's measure.
    matrix: Similarity,
    /// Each frame's dissimilarity to its natural successor (NaN for a
    /// sequence's last frame): [`Character::dissimilarity`].
    steps: Vec<f32>,
    /// The Surface Motion Graph.
    graph: SurfaceMotionGraph,
    /// Its frame-level adjacency.
    adjacency: FrameAdjacency,
    /// Constraint vertices given in the manifest (`[deform] constraints`).
    constraint_override: Option<Vec<u32>>,
    /// Example frames given in the manifest (`[deform] examples`).
    example_override: Option<Vec<FlatFrame>>,
    /// Metres per file unit.
    metres_per_unit: f64,
    /// The files are Z-up.
    z_up: bool,
    /// The database folder.
    dir: std::path::PathBuf,
    /// The key of the frames, the rig and the skeleton kind (the skeleton
    /// cache's).
    cache_key: u64,
    /// Whether the rig was read from the database's cache.
    rig_source: RigSource,
    /// The part deformation's example frames, chosen once per database
    /// (`cache/examples.json`).
    examples: ExampleMemo,
    /// The k-nearest index over the skeletons, made on first use
    /// ([`Character::pose_index`]).
    pose_index: std::sync::OnceLock<PoseIndex>,
    /// The median positive frame-to-next dissimilarity, made on first use
    /// ([`Character::step_median`]).
    step_median: std::sync::OnceLock<f64>,
}

/// The manifest's deformation overrides: constraint vertices, example
/// frames.
type Overrides = (Option<Vec<u32>>, Option<Vec<FlatFrame>>);

/// The manifest's deformation overrides: the constraint vertices (from
/// `[deform] constraints`, each below `n`) and the example frames (from
/// `[deform] examples`, `SEQUENCE:FRAME` in `graph`).
fn deform_overrides(
    dir: &Path,
    manifest: &Manifest,
    graph: &SurfaceMotionGraph,
    n: usize,
) -> Result<Overrides, DbError> {
    let bad = |msg: String| DbError::Manifest {
        path: dir.join(MANIFEST),
        msg: format!("[deform] {msg}"),
    };
    let constraint_override = match &manifest.deform.constraints {
        None => None,
        Some(p) => {
            let p = Manifest::resolve(dir, p);
            let text = crate::util::fsutil::read_text(&p)?;
            let ids: Vec<u32> = serde_json::from_str(&text).map_err(|e| {
                bad(format!(
                    "{}: expected a JSON array of vertex ids ({e})",
                    p.display()
                ))
            })?;
            if let Some(v) = ids.iter().find(|&&v| v as usize >= n) {
                return Err(bad(format!(
                    "{}: vertex {v} is out of range (the topology has {n})",
                    p.display()
                )));
            }
            Some(ids)
        }
    };
    let example_override = if manifest.deform.examples.is_empty() {
        None
    } else {
        let mut ids = Vec::new();
        for e in &manifest.deform.examples {
            let (name, f) = e
                .rsplit_once(':')
                .ok_or_else(|| bad(format!("example '{e}': expected SEQUENCE:FRAME")))?;
            let s = graph
                .sequences()
                .iter()
                .position(|q| q.name == name.trim())
                .ok_or_else(|| bad(format!("example '{e}': no sequence '{name}'")))?;
            let id = f
                .trim()
                .parse()
                .ok()
                .and_then(|frame| {
                    graph.checked_flat_id(FrameId {
                        seq: s as u32,
                        frame,
                    })
                })
                .ok_or_else(|| bad(format!("example '{e}': no frame '{f}' in '{name}'")))?;
            ids.push(id);
        }
        Some(ids)
    };
    Ok((constraint_override, example_override))
}

impl Character {
    /// Loads the database in `dir`, building (or reading from the cache) its
    /// matrix and graph, with the default [`CharacterOptions`].
    pub fn load(dir: &Path, progress: &dyn BuildProgress) -> Result<Character, DbError> {
        Self::load_with(dir, progress, &CharacterOptions::default())
    }

    /// [`Character::load`] with options.
    pub fn load_with(
        dir: &Path,
        progress: &dyn BuildProgress,
        opts: &CharacterOptions,
    ) -> Result<Character, DbError> {
        Self::load_staged(dir, progress, opts, &mut Stages::start())
    }

    /// [`Character::load_with`], each stage of the load timed into
    /// `stages` (issue 43: what a retarget spends before its first frame):
    /// `manifest` (and the topology), `similarity` (its key and cache),
    /// `graph`, `rig`, `frames` (the frame and skeleton caches mapped and
    /// read), `links` (adjacency, successor steps, the manifest's
    /// overrides).
    pub fn load_staged(
        dir: &Path,
        progress: &dyn BuildProgress,
        opts: &CharacterOptions,
        stages: &mut Stages,
    ) -> Result<Character, DbError> {
        // The topology read once: the size check and the character share it.
        let (manifest, topology) = Manifest::open(dir)?;
        stages.lap("manifest");
        let (matrix, graph, _, steps) = build_opened_staged(
            dir,
            &manifest,
            &BuildOptions::default(),
            progress,
            Some(&mut *stages),
        )?;
        // The rig from the cache (`cache/rig.json`) when it is current, else
        // embedded from only the frames the skin's motion fit reads (the
        // graph's spans give each sequence's length) and cached: a load with
        // its caches current reads no sequence file (issue 43).
        let spans = graph.sequences();
        let same = spans.len() == manifest.sequences.len()
            && spans
                .iter()
                .zip(&manifest.sequences)
                .all(|(a, b)| a.name == b.name);
        let lens: Vec<usize> = spans.iter().map(|s| s.len).collect();
        let (rig, rig_source) =
            embed_rig_cached(dir, &manifest, &topology, same.then_some(&lens[..]))?;
        stages.lap("rig");
        let n = topology.vertex_count();
        let conversion = Conversion::of(&manifest);
        let Conversion {
            metres_per_unit,
            z_up,
        } = conversion;
        let conv = |p: DVec3| y_up(p.to_array(), z_up) * metres_per_unit;
        // Frames in metres, Y-up, memory-mapped from the cache (written on
        // the first load, a sequence at a time), and the skeletons read off
        // the file-unit frames (the rig was embedded on them), cached too.
        let (frames, poses, cache_key) = open_or_build(&CacheInputs {
            dir,
            manifest: &manifest,
            rig: &rig,
            n,
            count: matrix.len(),
            conv: conversion,
            kind: opts.skeleton,
        })?;
        stages.lap("frames");
        let rest_pose = rig.joints.map(|j| conv(DVec3::from_array(j)));
        let examples = ExampleMemo::new(dir, cache_key, poses.len());
        let adjacency = graph.adjacency();
        let (constraint_override, example_override) = deform_overrides(dir, &manifest, &graph, n)?;
        stages.lap("links");
        Ok(Character {
            manifest,
            topology,
            rig,
            frames,
            n,
            poses,
            rest_pose,
            matrix,
            steps,
            graph,
            adjacency,
            constraint_override,
            example_override,
            metres_per_unit,
            z_up,
            dir: dir.to_path_buf(),
            cache_key,
            rig_source,
            examples,
            pose_index: std::sync::OnceLock::new(),
            step_median: std::sync::OnceLock::new(),
        })
    }

    /// The database folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// The key of everything the character's frames and skeletons were
    /// made from (the sequences, the rig, the skeleton kind): a cache
    /// derived from them (the plausibility reference) is current while
    /// its key includes this one.
    pub(crate) fn cache_key(&self) -> u64 {
        self.cache_key
    }

    /// The part deformation's example frames of this database, chosen
    /// once and kept in its cache ([`crate::db::examples`]).
    pub fn examples(&self) -> &ExampleMemo {
        &self.examples
    }

    /// Whether the rig was read from the database's rig cache
    /// ([`crate::db::rig_cache`]) or embedded by this load.
    pub fn rig_source(&self) -> RigSource {
        self.rig_source
    }

    /// The manifest.
    pub fn manifest(&self) -> &Manifest {
        &self.manifest
    }

    /// The topology (file units and axes; [`Character::topology_metres`]
    /// for metres, Y-up).
    pub fn topology(&self) -> &Mesh {
        &self.topology
    }

    /// The rig embedded on the topology's rest frame (file units and axes).
    pub fn rig(&self) -> &Embedding {
        &self.rig
    }

    /// All frames of all sequences, frame-major (`n` positions a frame),
    /// metres, Y-up (memory-mapped: reading them all pages in the whole
    /// frame cache; [`Character::frame`] reads one).
    pub fn frames(&self) -> &[[f64; 3]] {
        self.frames.all()
    }

    /// The frame store (memory-mapped frame cache).
    pub fn frame_store(&self) -> &FrameStore {
        &self.frames
    }

    /// The lowest Y of frame `id` (metres), kept with the frame cache so
    /// that no scan of every frame is needed.
    pub fn lowest(&self, id: FlatFrame) -> f64 {
        self.frames.lowest(id)
    }

    /// Vertices per frame.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The skeleton of every frame (metres, Y-up), indexed by flat id
    /// ([`FlatFrame::index`]).
    pub fn poses(&self) -> &[Pose] {
        &self.poses
    }

    /// The exact k-nearest index over [`Character::poses`] for the
    /// skeletal dissimilarity ([`crate::similarity::skeleton_index`]), built on the first
    /// call and kept with the character (issue 43: retrieval's candidates
    /// without a scan of every frame).
    pub fn pose_index(&self) -> &PoseIndex {
        self.pose_index.get_or_init(|| PoseIndex::new(&self.poses))
    }

    /// The median of the positive dissimilarities between a frame and its
    /// natural successor (`None` when there is none): retrieval's edge
    /// scale `s_edge`, the same value
    /// [`crate::drive::trellis::retrieve`] takes over
    /// [`Character::successor`] and [`Character::dissimilarity`], computed
    /// once per character.
    pub fn step_median(&self) -> Option<f64> {
        let m = *self.step_median.get_or_init(|| {
            let mut steps: Vec<f64> = FlatFrame::all(self.poses.len())
                .filter_map(|f| self.successor(f).map(|g| self.dissimilarity(f, g) as f64))
                .filter(|c| *c > 0.0)
                .collect();
            steps.sort_by(f64::total_cmp);
            steps.get(steps.len() / 2).copied().unwrap_or(f64::NAN)
        });
        (!m.is_nan()).then_some(m)
    }

    /// The skeleton of frame `id` (metres, Y-up).
    pub fn pose(&self, id: FlatFrame) -> &Pose {
        &self.poses[id.index()]
    }

    /// The rig's rest joints (metres, Y-up).
    pub fn rest_pose(&self) -> &Pose {
        &self.rest_pose
    }

    /// The similarity of the graph's measure (dense or sparse).
    pub fn matrix(&self) -> &Similarity {
        &self.matrix
    }

    /// The dissimilarity of frames `a` and `b` ([`Similarity::get`]), a
    /// frame and its natural successor's read once on loading (issue 43:
    /// retrieval scales its edge costs by the median of these over every
    /// frame, a pass that mapped all 0.5 GB of a 10⁴-frame database's
    /// sparse similarity into the process; the same values).
    pub fn dissimilarity(&self, a: FlatFrame, b: FlatFrame) -> f32 {
        if b.get() == a.get().wrapping_add(1)
            && let Some(&v) = self.steps.get(a.index())
            && !v.is_nan()
        {
            return v;
        }
        self.matrix.get(a.index(), b.index())
    }

    /// The Surface Motion Graph.
    pub fn graph(&self) -> &SurfaceMotionGraph {
        &self.graph
    }

    /// The graph's frame-level adjacency.
    pub fn adjacency(&self) -> &FrameAdjacency {
        &self.adjacency
    }

    /// Constraint vertices given in the manifest (`[deform] constraints`).
    pub(crate) fn constraint_override(&self) -> Option<&[u32]> {
        self.constraint_override.as_deref()
    }

    /// Example frames (flat ids) given in the manifest (`[deform]
    /// examples`).
    pub(crate) fn example_override(&self) -> Option<&[FlatFrame]> {
        self.example_override.as_deref()
    }

    /// Metres per file unit.
    pub fn metres_per_unit(&self) -> f64 {
        self.metres_per_unit
    }

    /// True when the files are Z-up.
    pub fn z_up(&self) -> bool {
        self.z_up
    }

    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.poses.len()
    }

    /// The flat id of a database frame (`None` when out of range).
    pub fn checked_flat_id(&self, f: FrameId) -> Option<FlatFrame> {
        self.graph.checked_flat_id(f)
    }

    /// The sequence and frame of a flat id.
    pub fn frame_at(&self, id: FlatFrame) -> FrameId {
        self.graph.frame_at(id)
    }

    /// Frame `id`'s positions (metres, Y-up, `n` of them).
    pub fn frame(&self, id: FlatFrame) -> &[[f64; 3]] {
        self.frames.frame(id)
    }

    /// Asks for frames `ids` to be read from the frame cache now, at once
    /// ([`FrameStore::prefetch`]): before a scattered read of many frames.
    pub fn prefetch_frames(&self, ids: &[FlatFrame]) {
        self.frames.prefetch(ids);
    }

    /// Frame `id`'s positions in metres, Y-up, copied to `out` (kept for
    /// callers that own a buffer; [`Character::frame`] borrows instead).
    pub fn frame_metres(&self, id: FlatFrame, out: &mut [[f64; 3]]) {
        out.copy_from_slice(self.frame(id));
    }

    /// The topology in metres, Y-up.
    pub fn topology_metres(&self) -> Mesh {
        let p: Vec<[f64; 3]> = self
            .topology
            .positions()
            .iter()
            .map(|p| (y_up(*p, self.z_up) * self.metres_per_unit).to_array())
            .collect();
        self.topology
            .with_positions(&p)
            .unwrap_or_else(|_| self.topology.clone())
    }

    /// The natural successor of a frame (the next frame of its sequence).
    pub fn successor(&self, id: FlatFrame) -> Option<FlatFrame> {
        let (s, t) = self.graph.frame_of(id);
        (t + 1 < self.graph.sequences()[s].len).then_some(id.next())
    }
}
