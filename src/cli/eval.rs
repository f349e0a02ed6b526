//! `surfmotion eval`.

use std::path::PathBuf;
use surfmotion::db::Character;
use surfmotion::drive::query::{load_mocap, to_database};
use surfmotion::jobs::retarget::evaluate_result;
use surfmotion::mesh::MeshSequence;
use surfmotion::mesh::io::{LoadOptions, load_sequence};
use surfmotion::tools::eval::surface::{
    SurfaceOptions, SurfaceReference, SurfaceReport, captured_of, frame_ids,
};
use surfmotion::tools::eval::surface_follow::{JointFollow, joint_follow};

/// Arguments of `eval`.
#[derive(clap::Args)]
pub struct Args {
    /// The character database the result was made from.
    #[arg(long)]
    pub db: PathBuf,
    /// The mocap clip that drove it (not needed with `--surface` alone).
    #[arg(long, required_unless_present = "surface")]
    pub mocap: Option<PathBuf>,
    /// The result (any sequence format `retarget` writes).
    #[arg(long)]
    pub result: PathBuf,
    /// Also measure the surface against the database's captured frames,
    /// per body region: triangles turned over against the rest frame and
    /// against the nearest database frame, creases (bends far outside the
    /// captured range at an edge), rough vertices (bends off the nearest
    /// database frame's more than the capture's own), slivers, stretched
    /// edges, and triangles of one part passing through another. Each
    /// counts only what lies outside the capture's own distribution, so
    /// the capture's frames read 0. Without `--mocap`, only this; with
    /// it, also the joint-follow: the joints regressed from the result's
    /// surface against the clip's skeleton retargeted onto the character,
    /// per body part (median, p95, max in cm, pelvis on pelvis).
    #[arg(long)]
    pub surface: bool,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub clip: super::ClipOpts,
}

/// The result's frames, with the character's vertex count.
fn load_result(ch: &Character, result: &std::path::Path) -> anyhow::Result<MeshSequence> {
    let res = load_sequence(&result.to_string_lossy(), &LoadOptions::default())?;
    if res.mesh().vertex_count() != ch.n() {
        anyhow::bail!(
            "{}: {} vertices, the character has {}",
            result.display(),
            res.mesh().vertex_count(),
            ch.n()
        );
    }
    Ok(res)
}

/// The joint-follow of `res` against the clip `mocap` retargeted onto the
/// character (the query `retarget` deforms towards).
fn follow(
    ch: &Character,
    mocap: &std::path::Path,
    clip: &super::ClipOpts,
    res: &MeshSequence,
) -> anyhow::Result<JointFollow> {
    let m = load_mocap(mocap, &clip.load_options()?, ch.manifest().fps)?;
    let query = to_database(ch, &m.reference, &m.poses);
    let out: Vec<_> = (0..res.frame_count())
        .map(|f| ch.rig().frame_joints(res.frame(f)))
        .collect();
    Ok(joint_follow(&query, &out))
}

/// The surface report of `res` against the database's captured frames.
fn surface(ch: &Character, res: &MeshSequence) -> anyhow::Result<SurfaceReport> {
    let rest = ch.topology_metres();
    let ids = frame_ids(ch);
    let reference = SurfaceReference::new(
        captured_of(ch, rest.positions(), &ids),
        SurfaceOptions::default(),
    )?;
    Ok(reference.measure(res.all_positions())?)
}

/// Runs `eval`: the joint-velocity error of Huang et al. 2015, Sec. 6.2,
/// and the plausibility of the result (metres, Y-up, as `retarget` writes)
/// against the database's own frames; with `--surface`, the surface
/// checks per body region.
pub fn run(a: Args) -> anyhow::Result<()> {
    let ch = Character::load(&a.db, &super::Bars::new())?;
    let r = match &a.mocap {
        Some(m) => Some(evaluate_result(&ch, m, &a.result, &a.clip.load_options()?)?),
        None => None,
    };
    let (surf, fol) = if a.surface {
        let res = load_result(&ch, &a.result)?;
        let fol = match &a.mocap {
            Some(m) => Some(follow(&ch, m, &a.clip, &res)?),
            None => None,
        };
        (Some(surface(&ch, &res)?), fol)
    } else {
        (None, None)
    };
    if a.json {
        let mut v = match &r {
            Some(r) => serde_json::to_value(r)?,
            None => serde_json::json!({ "result": a.result }),
        };
        if let (Some(s), Some(o)) = (&surf, v.as_object_mut()) {
            o.insert("surface".into(), serde_json::to_value(s)?);
        }
        if let (Some(f), Some(o)) = (&fol, v.as_object_mut()) {
            o.insert("joint_follow".into(), serde_json::to_value(f)?);
        }
        return super::emit(&(serde_json::to_string_pretty(&v)? + "\n"));
    }
    let mut s = String::new();
    if let Some(r) = &r {
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
    if let Some(x) = &surf {
        s += &x.text();
    }
    if let Some(f) = &fol {
        s += &f.text();
    }
    super::emit(&s)
}
