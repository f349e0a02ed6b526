//! `surfmotion live`: the arguments ([`super::live::Args`]) checked, the
//! session ([`surfmotion::jobs::live::run_live`]) run, its report printed.

use super::live::{Args, Cmd};
use std::sync::atomic::AtomicBool;
use surfmotion::jobs::live::{Listening, LiveInput, run_live};
use surfmotion::jobs::live_checks;

/// Runs `live`.
pub fn run(a: Args) -> anyhow::Result<()> {
    if let Some(Cmd::Send(s)) = a.send {
        return super::live_send::run(s);
    }
    super::malloc::one_arena();
    let db =
        a.db.clone()
            .ok_or_else(|| anyhow::anyhow!("--db is required"))?;
    let input = match (&a.replay, a.bvh_tcp, a.vmc, a.rokoko) {
        (Some(p), ..) => LiveInput::Replay(p.clone()),
        (None, Some(addr), ..) => LiveInput::BvhTcp(addr),
        (None, None, Some(addr), _) => LiveInput::Vmc(addr),
        (None, None, None, Some(addr)) => LiveInput::Rokoko(addr),
        (None, None, None, None) => {
            anyhow::bail!("give --replay CLIP, --bvh-tcp ADDR:PORT, --vmc or --rokoko")
        }
    };
    let reachable = [a.bvh_tcp, a.vmc, a.rokoko, a.serve].into_iter().flatten();
    for warning in live_checks::exposed(reachable) {
        eprintln!("{warning}");
    }
    match &a.record {
        Some(out) => a.glb.refuse_other_formats(out)?,
        None => anyhow::ensure!(
            !(a.glb.glb_quantize || a.glb.glb_no_normals || a.glb.usd_no_normals),
            "--glb-quantize, --glb-no-normals and --usd-no-normals apply to the --record output: give --record OUT or leave them out"
        ),
    }
    if let Some(out) = &a.record {
        let (replay, rig_map) = (a.replay.as_deref(), a.clip.rig_map.as_deref());
        live_checks::check_record(out, &db, replay, rig_map)?;
    }
    let opts = super::live::options(&a)?;
    let stop = AtomicBool::new(false);
    let report = run_live(
        &db,
        &input,
        a.record.as_deref(),
        &opts,
        &super::Bars::new(),
        &stop,
        &mut |l| match l {
            Listening::Stream(addr) => eprintln!("listening for {} on {addr}", input.protocol()),
            Listening::Page(url) => eprintln!("live page at {url}"),
        },
        &mut |_| {},
    )?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else if a.report {
        print!("{}", report.text());
    } else {
        println!("{}", report.line());
    }
    for f in &report.recorded {
        println!("wrote {}", f.display());
    }
    Ok(())
}
