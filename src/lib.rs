//! # surfmotion
//!
//! Drives 4D performance-capture characters (mesh sequences of a real
//! actor, one connectivity across all frames) from skeletal motion capture
//! (Huang et al. 2015, "Hybrid Skeletal-Surface Motion Graphs for Character
//! Animation from 4D Performance Capture", ACM TOG 34(2)), and transfers
//! mocap onto static scanned meshes (de Aguiar et al. 2007, "A Simple
//! Framework for Natural Animation of Digitized Models", Confluent Motion).
//!
//! ## Modules, in pipeline order
//!
//! Input:
//! - [`mocap`]: motion-capture clips: BVH and ASF/AMC readers, BVH writer,
//!   forward kinematics, resampling, units and up axis.
//! - [`rig`]: the canonical 19-joint skeleton and the mapping of any
//!   humanoid rig onto it.
//!
//! Geometry:
//! - [`mesh`]: triangle meshes and mesh sequences, Laplacians, Poisson and
//!   harmonic solves, non-linear blending, repair, and their file formats.
//! - [`embed`]: rig embedding from landmarks on a rest mesh (joints, skin,
//!   parts, regressors), the per-frame joints read off a character's
//!   frames and the rigid skeleton fitted to them.
//! - [`pose`]: canonical poses and the rotations that explain them, their
//!   alignment and the skeletal dissimilarity `c_skel` (Huang Eq. 28)
//!   ([`pose::measure`]), and the retargeting kernel that puts a clip's
//!   poses onto a character's skeleton ([`pose::retarget`]).
//!
//! Character:
//! - [`db`]: character databases: the manifest, per-frame skeletons, and
//!   the cached similarity matrix and graph.
//! - [`similarity`]: frame-to-frame dissimilarity over a database (shape
//!   histograms, vertex, skeleton and colour measures; Huang Sec. 4.1).
//! - [`graph`]: transitions and the Surface Motion Graph (Huang Secs.
//!   4.2-4.3), with its export and picture.
//! - [`keyframe`]: key-frame animation through the graph: walks, loops and
//!   the distance/time path optimisation (Huang Sec. 5.1).
//!
//! Synthesis:
//! - [`live`]: live retargeting from a mocap stream: the fixed-lag
//!   trellis, the per-frame session, stream inputs and their sender.
//! - [`drive`]: surface synthesis driven by mocap: skeletal trellis
//!   retrieval, timeline, blending and placement (Huang Sec. 5.2).
//! - [`deform`]: skeleton-driven editing of retrieved frames: skinning
//!   constraints and the part-based PCA Laplacian deformation (Huang Eq. 32).
//! - [`parametric`]: 4D parametric motion: aligned sequences blended by
//!   speed or turn in real time, online transitions between spaces
//!   (Casas et al. 2013).
//! - [`transfer`]: Confluent Motion onto scanned meshes (de Aguiar 2007).
//!
//! Jobs:
//! - [`jobs`]: every job the CLI runs as one library call (options in,
//!   typed report out): retarget, transfer, databases, skeletons, batch.
//! - [`batch`]: batch conversion of whole mocap libraries, resumable and
//!   sharded.
//!
//! Tools:
//! - [`tools`]: [`tools::eval`], the papers' metrics (joint-velocity error)
//!   and plausibility checks of a result; [`tools::render`], a small
//!   software rasteriser for PNG views of meshes and rigs;
//!   [`tools::inspect`], what any supported file holds, what was assumed,
//!   and problems.
//! - [`web`]: the character in a web browser (Volino et al. 2015): compact
//!   4D geometry, a static site with a WebGL2 page and an animation engine
//!   over the graph, and a local server.
//! - [`synth`]: synthetic data made by the project's own code: procedural
//!   clips, the procedural humanoid and synthetic databases.
//! - [`util`]: [`util::budget`], limits on what one job may ask for,
//!   checked before allocating; [`util::fsutil`], atomic writes, bounded
//!   reads and the shared file-error shape; [`util::numfmt`], numbers in
//!   messages printed in a short form whatever their magnitude.
#![warn(missing_docs)]

// Input.
pub mod mocap;
pub mod rig;
// Geometry.
pub mod embed;
pub mod mesh;
pub mod pose;
// Character.
pub mod db;
pub mod graph;
pub mod keyframe;
pub mod live;
pub mod similarity;
// Synthesis.
pub mod deform;
pub mod drive;
pub mod parametric;
pub mod transfer;
// Jobs.
pub mod batch;
pub mod jobs;
// Tools.
pub mod synth;
pub mod tools;
pub mod util;
pub mod web;
