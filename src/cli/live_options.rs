//! `live`'s arguments read into the session's options: the flags'
//! conversions (millimetres to metres, clamps to at least one frame, 0
//! for "decide anew") over [`LiveOptions::default`].

use super::live::Args;
use surfmotion::jobs::live::LiveOptions;

/// The session's options from the arguments.
pub(super) fn options(a: &Args) -> anyhow::Result<LiveOptions> {
    let d = LiveOptions::default();
    let mut retarget = d.retarget;
    if let Some(b) = a.repair_budget {
        retarget.deform_options.repair_budget = b;
    }
    Ok(LiveOptions {
        retarget,
        lag: a.lag,
        speed: a.speed,
        seconds: a.seconds,
        until_idle: a.until_idle,
        lossless: a.lossless,
        overlap: a.overlap.into(),
        serve: a.serve,
        analysis_window: a.analysis_window.max(1),
        floor_step: a.floor_step.map(|mm| mm / 1000.0),
        lift_settle: a.lift_settle.or(d.lift_settle),
        keep_ground: a
            .keep_ground
            .map_or(d.keep_ground, |n| (n > 0).then_some(n)),
        open_end: d.open_end || a.open_end,
        history: a.history.max(1),
        loops: a.loops,
        actor: a.actor.clone(),
        sample_every: a.sample_every,
        load: a.clip.load_options()?,
        glb: a.glb.options(),
        usd: a.glb.usd_options(),
        ..d
    })
}
