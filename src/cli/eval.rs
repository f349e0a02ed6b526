//! `surfmotion eval`.

use std::path::PathBuf;
use surfmotion::db::Character;
use surfmotion::jobs::retarget::evaluate_result;

/// Arguments of `eval`.
#[derive(clap::Args)]
pub struct Args {
    /// The character database the result was made from.
    #[arg(long)]
    pub db: PathBuf,
    /// The mocap clip that drove it.
    #[arg(long)]
    pub mocap: PathBuf,
    /// The result (any sequence format `retarget` writes).
    #[arg(long)]
    pub result: PathBuf,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub clip: super::ClipOpts,
}

/// Runs `eval`: the joint-velocity error of Huang et al. 2015, Sec. 6.2,
/// and the plausibility of the result (metres, Y-up, as `retarget` writes)
/// against the database's own frames.
pub fn run(a: Args) -> anyhow::Result<()> {
    let ch = Character::load(&a.db, &super::Bars::new())?;
    let r = evaluate_result(&ch, &a.mocap, &a.result, &a.clip.load_options()?)?;
    if a.json {
        let v = serde_json::to_value(&r)?;
        return super::emit(&(serde_json::to_string_pretty(&v)? + "\n"));
    }
    // A velocity needs two frames: with fewer the figure is not a
    // measurement (it printed "-0.00 ± -0.00 cm/frame over 0 frames").
    let mut s = if r.velocity_frames == 0 {
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
    super::emit(&s)
}
