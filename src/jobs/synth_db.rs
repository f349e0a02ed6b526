//! Writing a synthetic 4D database: a rest mesh with its embedded rig,
//! driven by clips ([`crate::synth::database::drive`]: the clip retargeted
//! onto the character's skeleton, linear blend skinning, a damped-spring
//! lag on soft regions). Used by `synth` and `demo`.
//!
//! The folder gets `character.toml`, `topology.obj`, `landmarks.json`, one
//! PC2 per clip and (optionally) `truth/SEQ.skeleton.json`, the skeleton
//! that drove each sequence ([`super::SkeletonFile`]).

use super::{JobError, SkeletonFile};
use crate::db::{Manifest, RigSpec, SequenceEntry};
use crate::embed::Embedding;
use crate::mesh::io::save_sequence;
use crate::mesh::{Mesh, MeshSequence};
use crate::pose::Pose;
use crate::pose::retarget::{ClipNeutral, ClipPoses};
use crate::rig::LoadOptions;
use crate::synth::database::{Dynamics, drive};
use crate::tools::eval::{Checker, Plausibility};
use serde::Serialize;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One clip of a synthetic database.
pub enum SynthClip {
    /// A mocap file (BVH or AMC), read with [`SynthOptions::load`] at
    /// [`SynthOptions::fps`]; the sequence is named after the file stem.
    File(PathBuf),
    /// Canonical poses already made (metres, Y-up, at the database's rate).
    Poses {
        /// Sequence name.
        name: String,
        /// What the poses came from (for the report).
        source: PathBuf,
        /// The poses and their neutral reference.
        poses: Box<ClipPoses>,
    },
}

impl SynthClip {
    /// A clip in memory (metres, Y-up, at the database's rate; e.g.
    /// [`crate::synth::gait_clip`]) as canonical poses, its rig convention
    /// detected from the joint names.
    pub fn from_clip(name: &str, clip: &crate::mocap::Clip) -> Result<SynthClip, JobError> {
        let map = crate::rig::detect(&clip.point_names()).map;
        Ok(SynthClip::Poses {
            name: name.to_string(),
            source: PathBuf::from(name),
            poses: Box::new(crate::pose::retarget::clip_poses(clip, &map)?),
        })
    }
}

/// Options of [`write_synthetic_database`].
#[derive(Debug, Clone)]
pub struct SynthOptions {
    /// Frame rate of the database. Default: 30.
    pub fps: f64,
    /// Use at most this many seconds of each clip. Default: all.
    pub seconds: Option<f64>,
    /// Secondary dynamics. Default: [`Dynamics::default`] (2.5 Hz, damping
    /// 0.35, full strength).
    pub dynamics: Dynamics,
    /// Database name in the manifest. Default: the folder's name.
    pub name: Option<String>,
    /// Write `truth/SEQ.skeleton.json`. Default: true.
    pub truth: bool,
    /// Measure each sequence's plausibility against the rest frame.
    /// Default: true.
    pub plausibility: bool,
    /// Overwrite a database already in the folder. Default: false.
    pub force: bool,
    /// How clip files are read. Default: decide from the file.
    pub load: LoadOptions,
}

impl Default for SynthOptions {
    fn default() -> Self {
        SynthOptions {
            fps: 30.0,
            seconds: None,
            dynamics: Dynamics::default(),
            name: None,
            truth: true,
            plausibility: true,
            force: false,
            load: LoadOptions::default(),
        }
    }
}

/// One sequence of the report.
#[derive(Debug, Clone, Serialize)]
pub struct SynthSequence {
    /// Sequence name (unique in the database).
    pub sequence: String,
    /// The clip it came from.
    pub source: PathBuf,
    /// Frames.
    pub frames: usize,
    /// Plausibility against absolute limits (no capture to compare with);
    /// `None` when not measured.
    pub plausibility: Option<Plausibility>,
}

/// The report of [`write_synthetic_database`].
#[derive(Debug, Clone, Serialize)]
pub struct SynthReport {
    /// The database folder.
    pub output: PathBuf,
    /// Time to embed the rig (set by whoever embedded it; 0 when the rig
    /// was given).
    pub embed_seconds: f64,
    /// Time to synthesise and write the sequences.
    pub synth_seconds: f64,
    /// Frames in all.
    pub frames: usize,
    /// Per sequence.
    pub sequences: Vec<SynthSequence>,
}

/// The character of a synthetic database: its rest mesh (metres, Y-up),
/// the rig embedded on it, and the landmarks file it was embedded from
/// (copied into the database).
pub struct SynthCharacter {
    /// The rest mesh.
    pub rest: Mesh,
    /// Its rig.
    pub rig: Embedding,
    /// The landmarks JSON (bytes of `landmarks.json`).
    pub landmarks_json: Vec<u8>,
}

impl SynthCharacter {
    /// The procedural humanoid of `demo` ([`crate::synth::humanoid`]) with
    /// its rig embedded from its landmarks.
    pub fn humanoid() -> Result<SynthCharacter, JobError> {
        use crate::synth::humanoid::{
            DEMO_GRID, humanoid_landmarks, humanoid_landmarks_json, humanoid_mesh,
        };
        let rest = humanoid_mesh(DEMO_GRID);
        let rig = Embedding::new(&rest, &humanoid_landmarks(&rest), None)?;
        Ok(SynthCharacter {
            rest,
            rig,
            landmarks_json: humanoid_landmarks_json().into_bytes(),
        })
    }
}

/// Writes a synthetic database of `character` driven by `clips` into
/// `dir`. `each` is called after every sequence with its report row and
/// positions (frame-major), e.g. for a progress bar or a preview.
///
/// The steps: `prepare_folder` (refuse an existing database, write the
/// topology and landmarks), then per clip `clip_poses` (read and cut),
/// `unique_name`, `drive`, `write_sequence` (the PC2, its plausibility and
/// truth skeleton), and last `write_manifest`.
pub fn write_synthetic_database(
    dir: &Path,
    character: &SynthCharacter,
    clips: &[SynthClip],
    opts: &SynthOptions,
    each: &mut dyn FnMut(&SynthSequence, &[[f64; 3]]),
) -> Result<SynthReport, JobError> {
    let rest = &character.rest;
    prepare_folder(dir, character, opts)?;
    let fps = opts.fps;
    let t1 = Instant::now();
    let (mut sequences, mut rows, mut names) = (Vec::new(), Vec::new(), BTreeSet::new());
    let mut frames_total = 0usize;
    for clip in clips {
        let (stem, source, poses, reference) = clip_poses(clip, opts)?;
        // Skinned frames, their dynamics copy and the sequence: refuse a
        // clip that cannot fit before allocating (issue 18, item 12).
        crate::util::budget::check_frames(
            &format!("{}", source.display()),
            poses.len(),
            rest.vertex_count(),
            3,
        )?;
        let out = drive(rest, &character.rig, &poses, &reference, fps, opts.dynamics);
        let name = unique_name(&stem, &mut names);
        let frames = out.poses.len();
        frames_total += frames;
        let (seq, entry, row) = write_sequence(
            dir,
            character,
            opts,
            Driven {
                name,
                source,
                poses: &poses,
                reference: &reference,
                out,
            },
        )?;
        sequences.push(entry);
        each(&row, seq.all_positions());
        rows.push(row);
    }
    let synth_seconds = t1.elapsed().as_secs_f64();
    write_manifest(dir, opts, sequences)?;
    Ok(SynthReport {
        output: dir.to_path_buf(),
        embed_seconds: 0.0,
        synth_seconds,
        frames: frames_total,
        sequences: rows,
    })
}

/// Refuses a database already in `dir` (unless `opts.force`), makes the
/// folder and writes the topology and the landmarks.
fn prepare_folder(
    dir: &Path,
    character: &SynthCharacter,
    opts: &SynthOptions,
) -> Result<(), JobError> {
    if dir.join(crate::db::MANIFEST).exists() && !opts.force {
        return Err(JobError::Input {
            path: dir.to_path_buf(),
            msg: "a database exists there already; pass `force` to overwrite it".into(),
        });
    }
    std::fs::create_dir_all(dir).map_err(|e| JobError::Input {
        path: dir.to_path_buf(),
        msg: e.to_string(),
    })?;
    save_sequence(
        &MeshSequence::single(character.rest.clone()),
        &dir.join("topology.obj"),
        None,
    )?;
    crate::util::fsutil::write_bytes_atomic(
        &dir.join("landmarks.json"),
        &character.landmarks_json[..],
    )?;
    Ok(())
}

/// A clip's name stem, source, poses and reference at `opts.fps`, cut to
/// `opts.seconds`.
fn clip_poses(
    clip: &SynthClip,
    opts: &SynthOptions,
) -> Result<(String, PathBuf, Vec<Pose>, ClipNeutral), JobError> {
    let fps = opts.fps;
    let (stem, source, mut poses, reference) = match clip {
        SynthClip::File(path) => {
            let c = crate::drive::query::load_mocap(path, &opts.load, fps)?;
            let stem = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "clip".into());
            (stem, path.clone(), c.poses, c.reference)
        }
        SynthClip::Poses {
            name,
            source,
            poses,
        } => (
            name.clone(),
            source.clone(),
            poses.poses.clone(),
            poses.reference.clone(),
        ),
    };
    let mut reference = reference;
    if let Some(s) = opts.seconds {
        poses.truncate(((s * fps).round() as usize).max(1));
        // The clip's joint rotations go with their poses.
        reference.rotations = reference
            .rotations
            .iter()
            .take(poses.len())
            .copied()
            .collect();
    }
    Ok((stem, source, poses, reference))
}

/// `stem`, or `stem_2`, `stem_3`, … : the first not in `names` (added).
fn unique_name(stem: &str, names: &mut BTreeSet<String>) -> String {
    let mut name = stem.to_string();
    let mut k = 2;
    while !names.insert(name.clone()) {
        name = format!("{stem}_{k}");
        k += 1;
    }
    name
}

/// One clip driven onto the character, named.
struct Driven<'a> {
    name: String,
    source: PathBuf,
    poses: &'a [Pose],
    reference: &'a ClipNeutral,
    out: crate::synth::database::Synthesised,
}

/// Writes a driven clip's PC2, measures its plausibility (when asked) and
/// writes its truth skeleton (when asked): the sequence, its manifest
/// entry and its report row.
fn write_sequence(
    dir: &Path,
    character: &SynthCharacter,
    opts: &SynthOptions,
    driven: Driven<'_>,
) -> Result<(MeshSequence, SequenceEntry, SynthSequence), JobError> {
    let (rest, rig) = (&character.rest, &character.rig);
    let fps = opts.fps;
    let Driven {
        name,
        source,
        poses,
        reference,
        out,
    } = driven;
    let frames = out.poses.len();
    let seq = MeshSequence::new(rest.clone(), out.positions, Some(fps))?;
    let file = format!("{name}.pc2");
    save_sequence(&seq, &dir.join(&file), Some(fps))?;
    let plausibility = if opts.plausibility {
        Checker::new(rest, rig, glam::DVec3::Y, None, fps, Default::default())
            .and_then(|c| {
                let clip = crate::pose::retarget::clip_head_trunk_deg(reference, poses);
                // Floating from the clip's own ground under each foot
                // (raised on a step), from the kernel's run that drove the
                // frames.
                let raised = &out.foot_grounds;
                Ok(
                    c.measure_on(seq.all_positions(), rest.vertex_count(), None, Some(raised))?
                        .with_clip_head(&clip, &c.opts.limits)
                        .logged(),
                )
            })
            .map_err(|e| tracing::warn!("{name}: plausibility not measured: {e}"))
            .ok()
    } else {
        None
    };
    if opts.truth {
        SkeletonFile {
            source: Some(source.clone()),
            ..SkeletonFile::new(&name, fps, &out.poses)
        }
        .save(&dir.join("truth").join(format!("{name}.skeleton.json")))?;
    }
    let entry = SequenceEntry {
        name: name.clone(),
        path: PathBuf::from(file),
        fps: None,
    };
    let row = SynthSequence {
        sequence: name,
        source,
        frames,
        plausibility,
    };
    Ok((seq, entry, row))
}

/// Writes the database's manifest: its name (`opts.name`, else the
/// folder's), the topology, landmarks and `sequences`.
fn write_manifest(
    dir: &Path,
    opts: &SynthOptions,
    sequences: Vec<SequenceEntry>,
) -> Result<(), JobError> {
    let name = opts.name.clone().unwrap_or_else(|| {
        dir.file_name()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "synthetic".into())
    });
    Manifest {
        name,
        topology: PathBuf::from("topology.obj"),
        fps: opts.fps,
        units: "m".into(),
        up: "y".into(),
        human_sized: true,
        colors: None,
        sequences,
        rig: RigSpec {
            landmarks: Some(PathBuf::from("landmarks.json")),
            ..Default::default()
        },
        graph: Default::default(),
        deform: Default::default(),
        spaces: Vec::new(),
    }
    .save(dir)?;
    Ok(())
}
