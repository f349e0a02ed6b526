//! The `eval` job: a result scored against its clip and its database —
//! the joint-velocity error of Huang et al. 2015, Sec. 6.2, with the
//! plausibility against the database's frames ([`evaluate_result`]), and
//! on request the surface against the captured frames
//! ([`crate::tools::eval::surface`]) and the joints regressed from the
//! result's surface against the clip's ([`joint_follow`]).

use super::JobError;
use super::retarget::{EvalReport, evaluate_result};
use crate::db::Character;
use crate::drive::query::{QueryError, load_mocap, to_database};
use crate::mesh::io::{LoadOptions as SeqLoad, load_sequence};
use crate::mesh::{MeshError, MeshSequence};
use crate::rig::LoadOptions;
use crate::tools::eval::EvalError;
use crate::tools::eval::surface::{
    SurfaceOptions, SurfaceReference, SurfaceReport, captured_of, frame_ids,
};
use crate::tools::eval::surface_follow::{JointFollow, joint_follow};
use std::path::{Path, PathBuf};

/// What can go wrong scoring a result.
#[derive(Debug, thiserror::Error)]
pub enum EvalJobError {
    /// Reading the clip or the result, or the velocity error.
    #[error(transparent)]
    Job(#[from] JobError),
    /// The clip, read for the joint-follow.
    #[error(transparent)]
    Query(#[from] QueryError),
    /// The result, read for the surface.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The surface reference or measure.
    #[error(transparent)]
    Eval(#[from] EvalError),
    /// The result does not have the character's vertices.
    #[error("{}: {vertices} vertices, the character has {expected}", .path.display())]
    Vertices {
        /// The result.
        path: PathBuf,
        /// Its vertex count.
        vertices: usize,
        /// The character's.
        expected: usize,
    },
}

/// The scores of one result ([`evaluate`]).
#[derive(Debug)]
pub struct EvalScores {
    /// The result scored.
    pub result: PathBuf,
    /// The joint-velocity error and plausibility (with a clip).
    pub velocity: Option<EvalReport>,
    /// The surface against the captured frames (on request).
    pub surface: Option<SurfaceReport>,
    /// The regressed joints against the clip's (surface and clip).
    pub joint_follow: Option<JointFollow>,
}

/// Scores `result` on `ch`: with `mocap` (read with `load`) its
/// joint-velocity error and plausibility; with `surface` its surface
/// against the captured frames, and with both the joint-follow.
pub fn evaluate(
    ch: &Character,
    mocap: Option<(&Path, &LoadOptions)>,
    result: &Path,
    surface: bool,
) -> Result<EvalScores, EvalJobError> {
    let velocity = match mocap {
        Some((m, load)) => Some(evaluate_result(ch, m, result, load)?),
        None => None,
    };
    let (surface, joint_follow) = if surface {
        let res = load_result(ch, result)?;
        let follow = match mocap {
            Some((m, load)) => Some(follow(ch, m, load, &res)?),
            None => None,
        };
        (Some(measure_surface(ch, &res)?), follow)
    } else {
        (None, None)
    };
    Ok(EvalScores {
        result: result.to_path_buf(),
        velocity,
        surface,
        joint_follow,
    })
}

/// The result's frames, with the character's vertex count.
fn load_result(ch: &Character, result: &Path) -> Result<MeshSequence, EvalJobError> {
    let res = load_sequence(&result.to_string_lossy(), &SeqLoad::default())?;
    if res.mesh().vertex_count() != ch.n() {
        return Err(EvalJobError::Vertices {
            path: result.to_path_buf(),
            vertices: res.mesh().vertex_count(),
            expected: ch.n(),
        });
    }
    Ok(res)
}

/// The joint-follow of `res` against the clip `mocap` retargeted onto the
/// character (the query `retarget` deforms towards).
fn follow(
    ch: &Character,
    mocap: &Path,
    load: &LoadOptions,
    res: &MeshSequence,
) -> Result<JointFollow, EvalJobError> {
    let m = load_mocap(mocap, load, ch.manifest().fps)?;
    let query = to_database(ch, &m.reference, &m.poses);
    let out: Vec<_> = (0..res.frame_count())
        .map(|f| ch.rig().frame_joints(res.frame(f)))
        .collect();
    Ok(joint_follow(&query, &out))
}

/// The surface report of `res` against the database's captured frames.
fn measure_surface(ch: &Character, res: &MeshSequence) -> Result<SurfaceReport, EvalJobError> {
    let rest = ch.topology_metres();
    let ids = frame_ids(ch);
    let reference = SurfaceReference::new(
        captured_of(ch, rest.positions(), &ids),
        SurfaceOptions::default(),
    )?;
    Ok(reference.measure(res.all_positions())?)
}

impl EvalScores {
    /// `eval --json`: the velocity report (or the result alone), with
    /// `surface` and `joint_follow` added when measured.
    pub fn to_json(&self) -> Result<serde_json::Value, serde_json::Error> {
        let mut v = match &self.velocity {
            Some(r) => serde_json::to_value(r)?,
            None => serde_json::json!({ "result": self.result }),
        };
        if let (Some(s), Some(o)) = (&self.surface, v.as_object_mut()) {
            o.insert("surface".into(), serde_json::to_value(s)?);
        }
        if let (Some(f), Some(o)) = (&self.joint_follow, v.as_object_mut()) {
            o.insert("joint_follow".into(), serde_json::to_value(f)?);
        }
        Ok(v)
    }

    /// The text `eval` prints: the velocity error (or why it is not
    /// measured), the plausibility, the surface and the joint-follow.
    pub fn text(&self) -> String {
        let mut s = String::new();
        if let Some(r) = &self.velocity {
            // A velocity needs two frames: with fewer the figure is not a
            // measurement (it printed "-0.00 ± -0.00 cm/frame over 0 frames").
            s = if r.velocity_frames == 0 {
                format!(
                    "joint-velocity error: not measured (a velocity needs two frames; query {} frames, result {})\n",
                    r.query_frames, r.result_frames
                )
            } else {
                format!(
                    "joint-velocity error {:.2} ± {:.2} cm/frame over {} frames (query {} frames, result {})\n",
                    r.velocity_error_cm_per_frame,
                    r.std_cm_per_frame,
                    r.velocity_frames,
                    r.query_frames,
                    r.result_frames
                )
            };
            if let Some(p) = &r.plausibility {
                s += &p.text();
            }
        }
        if let Some(x) = &self.surface {
            s += &x.text();
        }
        if let Some(f) = &self.joint_follow {
            s += &f.text();
        }
        s
    }
}
