//! `surfmotion eval`.

use std::path::PathBuf;
use surfmotion::db::Character;

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

/// Runs `eval` ([`surfmotion::jobs::eval::evaluate`]): the joint-velocity
/// error of Huang et al. 2015, Sec. 6.2, and the plausibility of the result
/// (metres, Y-up, as `retarget` writes) against the database's own frames;
/// with `--surface`, the surface checks per body region.
pub fn run(a: Args) -> anyhow::Result<()> {
    let ch = Character::load(&a.db, &super::Bars::new())?;
    let load = match &a.mocap {
        Some(_) => Some(a.clip.load_options()?),
        None => None,
    };
    let mocap = a.mocap.as_deref().zip(load.as_ref());
    let r = surfmotion::jobs::eval::evaluate(&ch, mocap, &a.result, a.surface)?;
    super::report_with(a.json, || Ok(r.to_json()?), || r.text())
}
