//! `demo`: the main job end to end on an embedded character, no files needed.

use crate::db::{BuildProgress, Character};
use crate::drive::{DriveOptions, synthesise};
use crate::mesh::MeshSequence;
use crate::mesh::io::save_sequence;
use crate::pose::retarget::clip_poses;
use crate::synth::humanoid::humanoid_landmarks;
use crate::synth::{Gait, gait_clip};
use crate::tools::eval::velocity_error;
use crate::tools::render::{Scene, View, render};
use std::path::{Path, PathBuf};
use std::time::Instant;

use super::{JobError, SynthCharacter, SynthClip, SynthOptions, write_synthetic_database};

/// Seconds of each step of the demo.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DemoSeconds {
    /// Synthesising the database.
    pub database: f64,
    /// Building its graph.
    pub graph: f64,
    /// Retargeting the query.
    pub retarget: f64,
}

/// What the demo made.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DemoReport {
    /// The demo's folder.
    pub output: PathBuf,
    /// The character's vertices.
    pub vertices: usize,
    /// Frames of its database.
    pub database_frames: usize,
    /// Transitions of its graph.
    pub transitions: usize,
    /// Frames of the query (and of the result).
    pub query_frames: usize,
    /// Mean joint-velocity error of the result (cm/frame).
    pub velocity_error_cm_per_frame: f64,
    /// Timings.
    pub seconds: DemoSeconds,
    /// The result (GLB).
    pub result: PathBuf,
    /// Landmarks the rig was embedded from.
    #[serde(skip)]
    pub landmarks: usize,
    /// Transitions the result took.
    #[serde(skip)]
    pub used: usize,
    /// Cuts of the result.
    #[serde(skip)]
    pub cuts: usize,
    /// Standard deviation of the velocity error (cm/frame).
    #[serde(skip)]
    pub velocity_error_std: f64,
    /// The database folder.
    #[serde(skip)]
    pub database: PathBuf,
    /// The picture of 5 frames.
    #[serde(skip)]
    pub picture: PathBuf,
    /// The query clip (BVH).
    #[serde(skip)]
    pub query: PathBuf,
}

/// Runs the demo into `dir`: a procedural humanoid (surface nets over
/// capsules) gets a rig from its landmarks; a 4D database of it walking
/// and running is synthesised from procedural clips (skinning plus
/// soft-tissue lag); its Surface Motion Graph is built; and a procedural
/// walk along a curve — a motion not in the database — drives it through
/// the graph. Writes the database, the result (GLB), a report and a
/// picture.
pub fn run_demo(dir: &Path, progress: &dyn BuildProgress) -> Result<DemoReport, JobError> {
    let db = dir.join("database");
    let t0 = Instant::now();
    let fps = 30.0;
    let character = SynthCharacter::humanoid()?;
    let mesh = &character.rest;
    let lm = humanoid_landmarks(mesh);
    let mut clips = Vec::new();
    for (g, seconds) in [(Gait::Walk, 6.0), (Gait::Run, 4.0)] {
        clips.push(SynthClip::from_clip(g.name(), &gait_clip(g, seconds, fps))?);
    }
    let opts = SynthOptions {
        fps,
        name: Some("demo".into()),
        truth: false,
        plausibility: false,
        force: true,
        ..Default::default()
    };
    write_synthetic_database(&db, &character, &clips, &opts, &mut |_, _| {})?;
    let t_db = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let ch = Character::load(&db, progress)?;
    let t_graph = t1.elapsed().as_secs_f64();
    // The query: walking along a curve (not in the database).
    let query_clip = gait_clip(Gait::Turn, 5.0, fps);
    let map = crate::rig::detect(&query_clip.point_names()).map;
    let mocap = clip_poses(&query_clip, &map)?;
    let query = dir.join("query_turn.bvh");
    crate::mocap::bvh::write_bvh(&query_clip, &query)?;
    let t2 = Instant::now();
    let out = synthesise(
        &ch,
        &mocap.poses,
        &mocap.reference,
        fps,
        &DriveOptions::default(),
    )?;
    let t_retarget = t2.elapsed().as_secs_f64();
    let result = dir.join("turn.glb");
    let seq = MeshSequence::new(ch.topology_metres(), out.positions.clone(), Some(fps))?;
    save_sequence(&seq, &result, Some(fps))?;
    let r = &out.report;
    crate::util::fsutil::write_bytes_atomic(
        &dir.join("turn.report.json"),
        serde_json::to_string_pretty(r)?.as_bytes(),
    )?;
    let skel: Vec<_> = out
        .positions
        .chunks(ch.n())
        .map(|f| ch.rig().frame_joints(f))
        .collect();
    let err = velocity_error(&out.query, &skel);
    // A strip of frames, seen from the side of the path.
    let n = ch.n();
    let frames = r.frames;
    let mut strip: Option<crate::tools::render::Image> = None;
    for k in [
        0,
        frames / 4,
        frames / 2,
        3 * frames / 4,
        frames.saturating_sub(1),
    ] {
        let p = &out.positions[k * n..(k + 1) * n];
        let img = render(
            &Scene {
                positions: p,
                triangles: mesh.triangles(),
                colours: None,
                lines: &[],
            },
            View::front(glam::DVec3::Z),
            320,
        );
        strip = Some(match strip {
            None => img,
            Some(s) => s.beside(&img),
        });
    }
    let picture = dir.join("turn.png");
    if let Some(s) = strip {
        s.save_png(&picture)?;
    }
    Ok(DemoReport {
        output: dir.to_path_buf(),
        vertices: n,
        database_frames: ch.frame_count(),
        transitions: ch.graph().transitions().len(),
        query_frames: frames,
        velocity_error_cm_per_frame: err.mean_cm,
        seconds: DemoSeconds {
            database: t_db,
            graph: t_graph,
            retarget: t_retarget,
        },
        result,
        landmarks: lm.marks.len(),
        used: r.jumps.iter().filter(|j| j.transition).count(),
        cuts: r.retrieval.cuts.len(),
        velocity_error_std: err.std_cm,
        database: db,
        picture,
        query,
    })
}
